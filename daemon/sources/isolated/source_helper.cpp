// handtrack-source-helper: runs one OpenNI2 source (a camera or an .oni recording) for handtrackd
// in a process of its own, so that a crash, a bad_alloc or a hang inside OpenNI2 or its drivers
// ends this process and not the daemon (docs/SECURITY.md). Started by handtrackd only, with the
// conversation socket as file descriptor 3 (helper_channel.hpp); it serves open, grab and close
// requests until the daemon closes the socket or dies.
#include "helper_channel.hpp"

#include "../source_factories.hpp"
#include "logging.hpp"

#include <exception>
#include <memory>
#include <string>

#include <csignal>
#include <sys/prctl.h>

namespace {

using namespace handtrack::daemon;
using namespace handtrack::daemon::isolated;

constexpr int kChannelFd = 3;

void reply_status(Channel& channel, int status, const std::string& text) {
  const StatusReply reply{.status = status};
  const std::string clipped = text.substr(0, kMaxText);
  channel.send(Kind::kStatus, &reply, sizeof reply, clipped.data(), clipped.size());
}

// The daemon's log level, which every request carries (a SIGHUP may have changed it); anything
// else is ignored.
void follow_log_level(std::int32_t level) {
  if (level >= spdlog::level::trace && level < spdlog::level::n_levels) {
    log().set_level(static_cast<spdlog::level::level_enum>(level));
  }
}

std::unique_ptr<DepthSource> open_source(Channel& channel, std::uint32_t payload) {
  OpenRequest request;
  std::string spec;
  if (payload < sizeof request || channel.receive(&request, sizeof request, -1) != Io::kOk ||
      channel.receive_text(&spec, payload - sizeof request, -1) != Io::kOk) {
    return nullptr;
  }
  follow_log_level(request.log_level);
  SourceOptions options;
  options.loop = request.loop != 0;
  options.as_fast_as_possible = request.as_fast_as_possible != 0;
  options.width = request.width;
  options.height = request.height;
  options.fps = request.fps;
  std::unique_ptr<DepthSource> source;
  std::string why;
  try {
    source = make_driver_source(spec, options);
  } catch (const std::exception& e) {
    reply_status(channel, -1, e.what());
    return nullptr;
  }
  if (!source->open(&why)) {
    reply_status(channel, -1, why);
    return nullptr;
  }
  const handtrack::CameraIntrinsics cam = source->camera();
  const CameraReply reply{cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy, cam.depth_scale_mm, cam.fps};
  channel.send(Kind::kOpened, &reply, sizeof reply);
  return source;
}

void serve(Channel& channel) {
  std::unique_ptr<DepthSource> source;
  RawFrame frame;
  for (;;) {
    Header header;
    if (channel.receive_header(&header, -1) != Io::kOk) return;
    switch (static_cast<Kind>(header.kind)) {
      case Kind::kOpen:
        source = open_source(channel, header.payload_bytes);
        if (!source) return;  // one source per helper: the daemon starts a new one to retry
        break;
      case Kind::kGrab: {
        GrabRequest request;
        if (!source || header.payload_bytes != sizeof request ||
            channel.receive(&request, sizeof request, -1) != Io::kOk) {
          return;
        }
        follow_log_level(request.log_level);
        const GrabStatus status = source->grab(frame, std::chrono::milliseconds(request.timeout_ms));
        if (status != GrabStatus::kFrame) {
          reply_status(channel, static_cast<int>(status), source->last_error());
          break;
        }
        const FrameReply reply{frame.frame_number, frame.capture_ns, frame.camera.width, frame.camera.height};
        channel.send(Kind::kFrame, &reply, sizeof reply, frame.depth_raw.data(),
                     frame.depth_raw.size() * sizeof(std::uint16_t));
        break;
      }
      case Kind::kClose:
      default:
        return;
    }
  }
}

}  // namespace

int main() {
  // Die with the daemon even when a driver hangs: a helper must never outlive it holding the
  // camera. (A daemon gone before this line closed the socket: serve() returns at once.)
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  // OpenNI2's lines go to the daemon's stderr in the daemon's format, at the level each request
  // carries (follow_log_level).
  setup_logging(LogLevel::kInfo);
  Channel channel(kChannelFd);
  serve(channel);
  return 0;
}
