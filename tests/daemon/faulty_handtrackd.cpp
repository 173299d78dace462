// handtrackd as built for tests: the real daemon (run_handtrackd) with one more source that a
// production build does not have, to inject faults the real sources cannot be made to show.
//
//   hang-after:N:SECONDS   the synthetic camera (pinch) for N frames, then a grab() that does not
//                          return for SECONDS: a camera driver that hangs (OpenNI2's readFrame
//                          after an unplug can block like this), so the watchdog must notice.
#include "handtrackd.hpp"

#include "handtrack/daemon/depth_source.hpp"

#include <chrono>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

namespace {

using namespace handtrack;
using namespace handtrack::daemon;

class HangingSource final : public DepthSource {
 public:
  HangingSource(uint64_t frames_before, std::chrono::seconds hang, std::unique_ptr<DepthSource> inner)
      : frames_before_(frames_before), hang_(hang), inner_(std::move(inner)) {}
  [[nodiscard]] std::string describe() const override { return "hang-after:" + std::to_string(frames_before_); }
  bool open(std::string* why) override { return inner_->open(why); }
  void close() override { inner_->close(); }
  GrabStatus grab(RawFrame& frame, std::chrono::milliseconds timeout) override {
    if (grabbed_ < frames_before_) {
      const GrabStatus status = inner_->grab(frame, timeout);
      if (status == GrabStatus::kFrame) ++grabbed_;
      return status;
    }
    std::this_thread::sleep_for(hang_);  // ignores `timeout`: that is the fault
    return GrabStatus::kEndOfStream;
  }
  [[nodiscard]] CameraIntrinsics camera() const override { return inner_->camera(); }
  [[nodiscard]] bool is_live() const override { return false; }

 private:
  uint64_t frames_before_;
  std::chrono::seconds hang_;
  std::unique_ptr<DepthSource> inner_;
  uint64_t grabbed_ = 0;
};

std::unique_ptr<DepthSource> make_test_source(const std::string& spec, const SourceOptions& options) {
  const std::string scheme = "hang-after:";
  if (spec.rfind(scheme, 0) != 0) return make_source(spec, options);
  const auto colon = spec.find(':', scheme.size());
  if (colon == std::string::npos) throw std::invalid_argument(spec + ": expected hang-after:N:SECONDS");
  const auto frames = std::stoull(spec.substr(scheme.size(), colon - scheme.size()));
  const auto seconds = std::stoll(spec.substr(colon + 1));
  return std::make_unique<HangingSource>(frames, std::chrono::seconds(seconds), make_source("synthetic:pinch", options));
}

}  // namespace

int main(int argc, char** argv) { return run_handtrackd(argc, argv, make_test_source); }
