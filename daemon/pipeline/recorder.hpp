#pragma once
// Recorder (--record): writes the raw depth of every grabbed frame to a sequence directory
// (SPEC.md "Sequence directory") on its own thread, so that the disk never slows the grab stage.
// The grab stage offers each frame; when the recorder is behind (all its buffers in flight) the
// frame is not recorded and counted in records_dropped. The directory's camera.json is that of
// the first frame; frames of another resolution are not recorded (one camera.json per directory).
//
// Thread roles: offer() from the grab thread; run() on the recorder's own thread; wake() from any
// thread. The queues are single-producer/single-consumer between those two threads.
#include "doorbell.hpp"
#include "pipeline_tally.hpp"

#include "handtrack/core/sequence.hpp"
#include "handtrack/daemon/depth_source.hpp"

#include <boost/lockfree/spsc_queue.hpp>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace handtrack::daemon {

class Recorder {
 public:
  static constexpr size_t kBuffers = 32;  // frames in flight to the disk

  Recorder(std::string dir, PipelineTally& tally);  // allocates every buffer
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Copies `frame` (daemon frame number `seq`) for the recorder thread; never blocks.
  void offer(const RawFrame& frame, uint64_t seq);
  // The recorder thread's loop: writes what is offered until `done()` is true and nothing is
  // left, then flushes the writer.
  void run(const std::function<bool()>& done);
  void wake() { bell_.ring(); }

 private:
  struct Buffer {
    Gray16Image image;
    CameraIntrinsics camera;
    uint64_t frame = 0;
  };
  using Queue = boost::lockfree::spsc_queue<Buffer*>;

  void write(const Buffer& b);

  std::string dir_;
  PipelineTally& tally_;
  std::vector<std::unique_ptr<Buffer>> pool_;
  Queue full_{kBuffers};   // grab -> recorder
  Queue free_{kBuffers};   // recorder -> grab
  Doorbell bell_;
  // Recorder thread only.
  std::optional<SequenceWriter> writer_;
  CameraIntrinsics camera_;  // of the directory's camera.json
  bool size_warned_ = false;
};

}  // namespace handtrack::daemon
