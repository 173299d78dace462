// oni:FILE.oni: a recording played through OpenNI2's own OniFile driver, at its own frame rate
// unless as fast as possible. See docs/OPENNI2.md.
#include "../openni2/openni2_source_base.hpp"

#include "../source_factories.hpp"

#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace handtrack::daemon {

namespace {

using namespace openni2;

// A recording whose length OpenNI2 does not report has ended when no frame came for this long.
constexpr int64_t kRecordingSilenceNs = 3'000'000'000;

class OniRecording final : public OpenNi2SourceBase {
 public:
  OniRecording(std::string file, const SourceOptions& options) : file_(std::move(file)), options_(options) {}
  ~OniRecording() override { close(); }

  [[nodiscard]] std::string describe() const override { return "oni:" + file_; }
  [[nodiscard]] bool is_live() const override { return false; }

  GrabStatus grab(RawFrame& frame, std::chrono::milliseconds timeout) override {
    if (!stream_) return bad_frame("not open");
    if (ended_) return GrabStatus::kEndOfStream;
    switch (wait_ready(timeout, nullptr)) {
      case Wait::kReady:
        break;
      case Wait::kTimeout:
        // Normally the end is known from the frame count; without one, silence ends a recording.
        if (!options_.loop && frame_count_ == 0 && monotonic_ns() - last_frame_ns_ > kRecordingSilenceNs) {
          ended_ = true;
          return GrabStatus::kEndOfStream;
        }
        return GrabStatus::kTimeout;
      case Wait::kLost:
      case Wait::kError:
        return bad_frame(with_detail("waitForAnyStream failed"));
    }
    int index = 0;
    const GrabStatus status = read_ready_frame(frame, &index);
    if (status != GrabStatus::kFrame) return status;
    last_frame_ns_ = frame.capture_ns;
    ++frames_read_;
    // OniFile numbers a stream's frames 1..N. With repeat off nothing follows frame N (a
    // readFrame would block for ever), so the end is known from the count, not from a timeout.
    if (!options_.loop && frame_count_ > 0 && (index >= frame_count_ || frames_read_ >= frame_count_)) ended_ = true;
    return GrabStatus::kFrame;
  }

 private:
  bool open_impl(std::string* why) override {
    close();
    ended_ = false;
    frames_read_ = 0;
    frame_count_ = 0;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file_, ec)) {
      *why = "no such file";
      return false;
    }
    if (!std::ifstream(file_, std::ios::binary).good()) {
      *why = "cannot read the file";
      return false;
    }
    if (!runtime_) {
      runtime_ = Runtime::acquire(why);
      if (!runtime_) return false;
    }
    device_ = std::make_unique<openni::Device>();
    if (device_->open(file_.c_str()) != openni::STATUS_OK) {
      *why = with_detail("OpenNI2 cannot play it (not an .oni recording, or corrupt)");
      return false;
    }
    if (!device_->isFile() || device_->getPlaybackControl() == nullptr) {
      *why = "OpenNI2 did not open it as a recording";
      return false;
    }
    if (!open_depth_stream(why)) return false;
    last_frame_ns_ = monotonic_ns();
    log().info("{}: {} depth frames {}x{} at {} fps, f {:.1f}/{:.1f} px, depth unit {} mm{}{}", describe(),
               frame_count_, camera_.width, camera_.height, camera_.fps, camera_.fx, camera_.fy,
               camera_.depth_scale_mm, options_.loop ? ", looped" : "",
               options_.as_fast_as_possible ? ", as fast as possible" : "");
    return true;
  }

  // Playback set before the stream starts: speed -1 ("manual": OpenNI2 hands out the next frame
  // when the reader waits for it, so none is dropped) when as fast as possible, else 1.0 (the
  // recording's own frame rate); repeat when looping, and also in manual playback of a recording
  // whose frame count is known. Without repeat, OniFile's player thread spins at the end of the
  // file over its list of streams, unlocked, and destroying our stream then crashes it (close()
  // after a manual playback to the end: 3 crashes in 40 reopen tests on a busy machine). With
  // repeat it rewinds and waits for the next read instead, and grab() still ends after
  // frame_count_ frames. At the recording's own rate repeat is no cure: the rewound frame 1 follows
  // the last frame at once and can replace it before it is read.
  bool configure(std::string* why) override {
    openni::PlaybackControl* playback = device_->getPlaybackControl();
    const float speed = options_.as_fast_as_possible ? -1.0F : 1.0F;
    if (playback->setSpeed(speed) != openni::STATUS_OK) {
      *why = with_detail("cannot set the playback speed");
      return false;
    }
    frame_count_ = std::max(0, playback->getNumberOfFrames(*stream_));
    const bool repeat = options_.loop || (options_.as_fast_as_possible && frame_count_ > 0);
    if (playback->setRepeatEnabled(repeat) != openni::STATUS_OK) {
      *why = with_detail("cannot set playback repeat");
      return false;
    }
    return true;
  }

  std::string file_;
  SourceOptions options_;
  int frame_count_ = 0;
  int frames_read_ = 0;
  int64_t last_frame_ns_ = 0;
  bool ended_ = false;
};

}  // namespace

std::unique_ptr<DepthSource> make_oni_recording(const std::string& file, const SourceOptions& options) {
  if (file.empty()) throw std::invalid_argument("oni: needs a file name (oni:FILE.oni)");
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) throw std::invalid_argument("oni:" + file + ": no such file");
  return std::make_unique<OniRecording>(file, options);
}

}  // namespace handtrack::daemon
