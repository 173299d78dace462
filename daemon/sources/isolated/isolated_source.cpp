// A DepthSource whose driver runs in handtrack-source-helper, a child process (docs/SECURITY.md):
// OpenNI2 and its drivers are third-party C++ that a corrupt .oni recording or a misbehaving
// device can crash (SIGSEGV, an uncaught std::bad_alloc) or hang. Here such a fault ends the
// helper; the daemon sees the socket close or the answer not come, reaps the helper, reports
// GrabStatus::kFailed with what happened, and goes on (the pipeline sets the ring's state to
// "error"; a live camera is reopened with a fresh helper).
//
// Why a process and not a validator of .oni files: the faults are in OpenNI2's decoders and in
// camera drivers, not only in the container; a validator would have to know every way they break,
// and would not help a live camera at all. The price is one copy of each frame over a socket
// (about 0.1 ms for 320x240; see docs/SECURITY.md).
#include "helper_channel.hpp"

#include "../source_factories.hpp"

#include "handtrack/common/clock.hpp"
#include "logging.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <thread>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace handtrack::daemon {

namespace {

using namespace isolated;
namespace fs = std::filesystem;

constexpr const char* kHelperName = "handtrack-source-helper";
constexpr const char* kHelperVariable = "HANDTRACK_SOURCE_HELPER";
constexpr int kHelperChannelFd = 3;  // source_helper.cpp's kChannelFd
// Opening enumerates devices (USB) or parses a recording: generous.
constexpr std::int64_t kOpenDeadlineNs = 20'000'000'000;
// A grab answers within its timeout; a helper silent this much longer hangs (a stuck driver).
constexpr std::int64_t kAnswerGraceNs = 2'000'000'000;
// A helper told to stop (socket closed) gets this long to close its device before SIGKILL.
constexpr std::int64_t kExitGraceNs = 2'000'000'000;

// The helper program: $HANDTRACK_SOURCE_HELPER, else beside this executable (the build tree),
// else in ../libexec/handtrack from it (an install under any prefix), else where this build
// installs it.
std::string find_helper(std::string* looked) {
  if (const char* env = std::getenv(kHelperVariable); env != nullptr && *env != '\0') return env;
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  std::vector<fs::path> places;
  if (!ec) {
    places.push_back(self.parent_path() / kHelperName);
    places.push_back(self.parent_path().parent_path() / "libexec" / "handtrack" / kHelperName);
  }
  places.emplace_back(HANDTRACK_INSTALLED_SOURCE_HELPER);
  for (const auto& place : places) {
    if (::access(place.c_str(), X_OK) == 0) return place.string();
    *looked += (looked->empty() ? "" : ", ") + place.string();
  }
  return {};
}

std::string describe_exit(int status) {
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    return "was killed by signal " + std::to_string(sig) + " (" + ::strsignal(sig) + ")";
  }
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  return "ended";
}

class IsolatedSource final : public DepthSource {
 public:
  IsolatedSource(std::string spec, std::string name, bool live, const SourceOptions& options)
      : spec_(std::move(spec)), name_(std::move(name)), live_(live), options_(options) {}
  ~IsolatedSource() override { close(); }
  IsolatedSource(const IsolatedSource&) = delete;
  IsolatedSource& operator=(const IsolatedSource&) = delete;

  [[nodiscard]] std::string describe() const override { return name_; }
  [[nodiscard]] bool is_live() const override { return live_; }
  [[nodiscard]] CameraIntrinsics camera() const override { return camera_; }
  [[nodiscard]] std::string last_error() const override { return last_error_; }

  bool open(std::string* why) override {
    close();
    std::string reason;
    if (!spawn(&reason) || !start_source(&reason)) {
      close();
      if (why != nullptr) *why = reason;
      return false;
    }
    last_error_.clear();
    return true;
  }

  void close() override {
    channel_.close();  // the helper reads end-of-file, closes its device and exits
    if (pid_ > 0) reap(kExitGraceNs);
  }

  GrabStatus grab(RawFrame& frame, std::chrono::milliseconds timeout) override {
    if (pid_ <= 0) {  // never opened, or closed: what the in-process sources say
      last_error_ = "not open";
      return live_ ? GrabStatus::kDisconnected : GrabStatus::kError;
    }
    const GrabRequest request{.timeout_ms = timeout.count(), .log_level = static_cast<std::int32_t>(log().level())};
    if (channel_.send(Kind::kGrab, &request, sizeof request) != Io::kOk) return failed(helper_ended("grabbing"));
    const std::int64_t deadline = monotonic_ns() + timeout.count() * 1'000'000 + kAnswerGraceNs;
    Header header;
    const Io io = channel_.receive_header(&header, deadline);
    if (io == Io::kTimeout) return failed(hung("grabbing"));
    if (io != Io::kOk) return failed(helper_ended("grabbing"));
    if (static_cast<Kind>(header.kind) == Kind::kStatus) return status_reply(header, deadline);
    if (static_cast<Kind>(header.kind) != Kind::kFrame) return failed(broke_protocol("a frame"));
    return frame_reply(header, deadline, frame);
  }

 private:
  bool spawn(std::string* why) {
    std::string looked;
    const std::string helper = find_helper(&looked);
    if (helper.empty()) {
      *why = name_ + ": cannot find " + kHelperName + " (looked at " + looked + "; set " + kHelperVariable + ")";
      return false;
    }
    int fds[2];
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) {
      *why = name_ + ": socketpair: " + std::strerror(errno);
      return false;
    }
    int child_end = fds[1];
    if (child_end == kHelperChannelFd) {  // dup2(fd, fd) would keep close-on-exec set
      child_end = ::fcntl(fds[1], F_DUPFD_CLOEXEC, kHelperChannelFd + 1);
      ::close(fds[1]);
    }
    posix_spawn_file_actions_t actions;
    posix_spawnattr_t attributes;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, child_end, kHelperChannelFd);
    posix_spawn_file_actions_addclosefrom_np(&actions, kHelperChannelFd + 1);
    posix_spawnattr_init(&attributes);
    // The daemon blocks its stop signals in every thread and ignores SIGPIPE: the helper gets the
    // defaults. Its own process group keeps a terminal's Ctrl-C for the daemon, which stops it.
    sigset_t none;
    sigset_t defaults;
    sigemptyset(&none);
    sigemptyset(&defaults);
    for (const int sig : {SIGPIPE, SIGTERM, SIGINT, SIGHUP}) sigaddset(&defaults, sig);
    posix_spawnattr_setsigmask(&attributes, &none);
    posix_spawnattr_setsigdefault(&attributes, &defaults);
    posix_spawnattr_setpgroup(&attributes, 0);
    posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETPGROUP);
    char* argv[] = {const_cast<char*>(helper.c_str()), nullptr};
    const int rc = ::posix_spawn(&pid_, helper.c_str(), &actions, &attributes, argv, environ);
    posix_spawn_file_actions_destroy(&actions);
    posix_spawnattr_destroy(&attributes);
    ::close(child_end);
    if (rc != 0) {
      ::close(fds[0]);
      pid_ = -1;
      *why = name_ + ": cannot start " + helper + ": " + std::strerror(rc);
      return false;
    }
    channel_ = Channel(fds[0]);
    return true;
  }

  bool start_source(std::string* why) {
    const OpenRequest request{options_.loop ? 1 : 0, options_.as_fast_as_possible ? 1 : 0, options_.width,
                              options_.height, options_.fps, static_cast<std::int32_t>(log().level())};
    if (channel_.send(Kind::kOpen, &request, sizeof request, spec_.data(), spec_.size()) != Io::kOk) {
      *why = name_ + ": " + helper_ended("opening");
      return false;
    }
    const std::int64_t deadline = monotonic_ns() + kOpenDeadlineNs;
    Header header;
    const Io io = channel_.receive_header(&header, deadline);
    if (io == Io::kTimeout) {
      *why = name_ + ": " + hung("opening");
    } else if (io != Io::kOk) {
      *why = name_ + ": " + helper_ended("opening");
    } else if (static_cast<Kind>(header.kind) == Kind::kStatus) {
      StatusReply reply;
      std::string text;
      if (header.payload_bytes < sizeof reply || channel_.receive(&reply, sizeof reply, deadline) != Io::kOk ||
          channel_.receive_text(&text, header.payload_bytes - sizeof reply, deadline) != Io::kOk) {
        *why = name_ + ": " + broke_protocol("an answer to open");
      } else {
        *why = text;  // the source's own reason, already naming it
      }
    } else if (static_cast<Kind>(header.kind) != Kind::kOpened || header.payload_bytes != sizeof(CameraReply)) {
      *why = name_ + ": " + broke_protocol("an answer to open");
    } else {
      CameraReply reply;
      if (channel_.receive(&reply, sizeof reply, deadline) != Io::kOk) {
        *why = name_ + ": " + helper_ended("opening");
        return false;
      }
      camera_ = CameraIntrinsics{reply.width, reply.height, reply.fx, reply.fy, reply.cx, reply.cy,
                                 reply.depth_scale_mm, reply.fps};
      const std::string problem = camera_.problem();
      if (problem.empty() && reply.width <= kMaxSide && reply.height <= kMaxSide) return true;
      *why = name_ + ": the source helper reported unusable intrinsics: " + problem;
    }
    return false;
  }

  GrabStatus status_reply(const Header& header, std::int64_t deadline) {
    StatusReply reply;
    std::string text;
    if (header.payload_bytes < sizeof reply || channel_.receive(&reply, sizeof reply, deadline) != Io::kOk ||
        channel_.receive_text(&text, header.payload_bytes - sizeof reply, deadline) != Io::kOk) {
      return failed(broke_protocol("a grab status"));
    }
    const auto status = static_cast<GrabStatus>(reply.status);
    switch (status) {
      case GrabStatus::kTimeout:
      case GrabStatus::kEndOfStream:
      case GrabStatus::kDisconnected:
      case GrabStatus::kError:
        last_error_ = std::move(text);
        return status;
      case GrabStatus::kFrame:
      case GrabStatus::kFailed:
        break;
    }
    return failed(broke_protocol("a grab status"));
  }

  GrabStatus frame_reply(const Header& header, std::int64_t deadline, RawFrame& frame) {
    const auto pixels = static_cast<std::size_t>(camera_.width) * static_cast<std::size_t>(camera_.height);
    FrameReply reply;
    if (header.payload_bytes != sizeof reply + pixels * sizeof(std::uint16_t)) return failed(broke_protocol("a frame"));
    if (channel_.receive(&reply, sizeof reply, deadline) != Io::kOk) return failed(helper_ended("grabbing"));
    if (reply.width != camera_.width || reply.height != camera_.height) return failed(broke_protocol("a frame"));
    frame.depth_raw.resize(pixels);  // in place: the pool's frames already have the source's size
    if (channel_.receive(frame.depth_raw.data(), pixels * sizeof(std::uint16_t), deadline) != Io::kOk) {
      return failed(helper_ended("grabbing"));
    }
    const std::int64_t now = monotonic_ns();
    frame.camera = camera_;
    frame.frame_number = reply.frame_number;
    frame.capture_ns = reply.capture_ns > 0 && reply.capture_ns <= now ? reply.capture_ns : now;
    return GrabStatus::kFrame;
  }

  // Ends the helper (at once, or after `grace` for one that was asked to stop) and returns how it
  // ended.
  std::string reap(std::int64_t grace) {
    const std::int64_t deadline = monotonic_ns() + grace;
    int status = 0;
    pid_t done = 0;
    while ((done = ::waitpid(pid_, &status, WNOHANG)) == 0 && monotonic_ns() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (done == 0) {
      ::kill(pid_, SIGKILL);
      done = ::waitpid(pid_, &status, 0);
    }
    const pid_t pid = pid_;
    pid_ = -1;
    channel_.close();
    return done == pid ? describe_exit(status) : "could not be waited for";
  }

  // The messages below say what became of the helper, without the source's name: grab()'s
  // last_error() is logged after describe(), and open() adds the name itself.
  // The socket closed or failed: the helper died (or is dying). Its exit, for the message.
  std::string helper_ended(const char* doing) {
    const pid_t pid = pid_;
    const std::string how = pid > 0 ? reap(200'000'000) : "was not running";
    return "the source helper (pid " + std::to_string(pid) + ") " + how + " while " + doing +
           " (a driver fault, or a corrupt recording)";
  }

  std::string hung(const char* doing) {
    const pid_t pid = pid_;
    reap(0);
    return "the source helper (pid " + std::to_string(pid) + ") stopped answering while " + doing +
           " and was killed (a hung driver)";
  }

  std::string broke_protocol(const char* expected) {
    const pid_t pid = pid_;
    reap(0);
    return "the source helper (pid " + std::to_string(pid) + ") sent something other than " + expected +
           " and was killed";
  }

  GrabStatus failed(std::string what) {
    if (pid_ > 0) reap(0);
    last_error_ = std::move(what);
    return GrabStatus::kFailed;
  }

  std::string spec_;
  std::string name_;
  bool live_;
  SourceOptions options_;
  CameraIntrinsics camera_;
  std::string last_error_;
  pid_t pid_ = -1;
  Channel channel_;
};

}  // namespace

std::unique_ptr<DepthSource> make_isolated_source(const std::string& spec, const SourceOptions& options) {
  // Built here only to check the spec and learn its name and kind; it never opens.
  const auto probe = make_driver_source(spec, options);
  return std::make_unique<IsolatedSource>(spec, probe->describe(), probe->is_live(), options);
}

}  // namespace handtrack::daemon
