#include "recorder.hpp"

#include "throttle.hpp"

#include "handtrack/common/clock.hpp"
#include "logging.hpp"

namespace handtrack::daemon {

Recorder::Recorder(std::string dir, PipelineTally& tally) : dir_(std::move(dir)), tally_(tally) {
  for (size_t i = 0; i < kBuffers; ++i) {
    pool_.push_back(std::make_unique<Buffer>());
    free_.push(pool_.back().get());
  }
}

void Recorder::offer(const RawFrame& frame, uint64_t seq) {
  Buffer* b = nullptr;
  if (!free_.pop(b)) {
    tally_.records_dropped.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  b->camera = frame.camera;
  b->frame = seq;
  b->image.width = frame.camera.width;
  b->image.height = frame.camera.height;
  b->image.channels = 1;
  b->image.pixels.assign(frame.depth_raw.begin(), frame.depth_raw.end());
  full_.push(b);
  bell_.ring();
}

void Recorder::write(const Buffer& b) {
  if (!writer_) {
    writer_.emplace(dir_, b.camera);
    camera_ = b.camera;
    log().info("recording raw depth to {} ({}x{})", dir_, b.camera.width, b.camera.height);
  }
  if (b.camera.width != camera_.width || b.camera.height != camera_.height) {
    if (!size_warned_) log().warn("--record: frames of a new resolution are not recorded (one camera.json per directory)");
    size_warned_ = true;
    tally_.records_dropped.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  writer_->write_depth_raw(static_cast<int>(b.frame), b.image);
  tally_.frames_recorded.fetch_add(1, std::memory_order_relaxed);
}

void Recorder::run(const std::function<bool()>& done) {
  Throttle write_log;
  for (;;) {
    const uint32_t ticket = bell_.ticket();
    Buffer* b = nullptr;
    if (!full_.pop(b)) {
      if (done()) break;  // drained
      bell_.wait(ticket, Doorbell::kIdleWaitNs);
      continue;
    }
    try {
      write(*b);
    } catch (const std::exception& e) {
      tally_.records_dropped.fetch_add(1, std::memory_order_relaxed);
      if (write_log.allow(monotonic_ns())) log().error("--record: {}", e.what());
    }
    free_.push(b);
  }
  if (writer_) {
    try {
      writer_->flush();
    } catch (const std::exception& e) {
      log().error("--record: {}", e.what());
    }
  }
}

}  // namespace handtrack::daemon
