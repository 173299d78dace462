// seq:DIR: a sequence directory (SPEC.md) played at its camera.json fps, or as fast as possible.
#include "../pacer.hpp"
#include "../source_factories.hpp"

#include "handtrack/common/clock.hpp"
#include "handtrack/core/png_io.hpp"
#include "handtrack/core/sequence.hpp"

#include <optional>
#include <string>

namespace handtrack::daemon {

namespace {

class SequenceSource final : public DepthSource {
 public:
  SequenceSource(std::string dir, const SourceOptions& options) : dir_(std::move(dir)), options_(options) {}

  [[nodiscard]] std::string describe() const override { return "seq:" + dir_; }

  bool open(std::string* why) override {
    try {
      reader_.emplace(dir_, SequenceReader::Annotations::kIgnore);  // handtrackd never scores
    } catch (const std::exception& e) {
      if (why != nullptr) *why = e.what();
      return false;
    }
    if (reader_->frame_count() == 0) {
      if (why != nullptr) *why = dir_ + "/depth: no frames (NNNNNN.png) in the sequence directory";
      reader_.reset();
      return false;
    }
    index_ = 0;
    pacer_.start(options_.as_fast_as_possible ? 0.0 : reader_->camera().fps);
    return true;
  }
  void close() override { reader_.reset(); }

  GrabStatus grab(RawFrame& frame, std::chrono::milliseconds timeout) override {
    if (!reader_) return GrabStatus::kEndOfStream;
    if (index_ >= reader_->frame_count()) {
      if (!options_.loop) return GrabStatus::kEndOfStream;
      index_ = 0;
    }
    if (!pacer_.wait(timeout)) return GrabStatus::kTimeout;
    const auto& camera = reader_->camera();
    const int number = reader_->frame_number(index_++);
    const auto file = frame_file(reader_->dir() / "depth", number);
    frame.capture_ns = monotonic_ns();
    try {
      // The size is checked against camera.json from the header, before anything is allocated.
      image_ = read_png_gray16(file, PngSize{camera.width, camera.height});
    } catch (const std::exception& e) {
      last_error_ = e.what();
      return GrabStatus::kError;
    }
    frame.camera = camera;
    frame.depth_raw.assign(image_.pixels.begin(), image_.pixels.end());  // same size: no reallocation
    frame.frame_number = static_cast<uint64_t>(number);
    return GrabStatus::kFrame;
  }

  [[nodiscard]] CameraIntrinsics camera() const override { return reader_ ? reader_->camera() : CameraIntrinsics{}; }
  [[nodiscard]] bool is_live() const override { return false; }
  [[nodiscard]] std::string last_error() const override { return last_error_; }

 private:
  std::string dir_;
  SourceOptions options_;
  std::optional<SequenceReader> reader_;
  Gray16Image image_;
  std::string last_error_;
  Pacer pacer_;
  size_t index_ = 0;
};

}  // namespace

std::unique_ptr<DepthSource> make_sequence_source(const std::string& dir, const SourceOptions& options) {
  return std::make_unique<SequenceSource>(dir, options);
}

}  // namespace handtrack::daemon
