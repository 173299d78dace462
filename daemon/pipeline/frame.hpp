#pragma once
// Frame: one entry of the pipeline's frame pool and everything a stage writes into it as the
// frame travels grab -> preprocess -> optimize -> publish. Pool entries are allocated at start();
// their buffers are sized by the first frame of a resolution and then reused.
//
// Thread roles: a Frame belongs to exactly one stage at a time; handing its pointer through a
// FrameQueue hands over the whole entry (the queue's push/pop order the accesses).
#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/hands_tracker.hpp"
#include "handtrack/daemon/depth_source.hpp"

#include <boost/lockfree/spsc_queue.hpp>

#include <cstdint>

namespace handtrack::daemon {

struct Frame {
  RawFrame raw;
  DepthImage depth;                    // mm
  HandsInputs inputs;                  // per frame: frame t+1 is preprocessed while t is optimized
  uint64_t inputs_generation = 0;      // the TrackerReload generation `inputs` was made for
  bool has_input = false;              // false: no depth in the working volume, or malformed
  bool empty = false;                  // nothing in the working volume: published as no_hand
  bool malformed = false;              // buffer does not match its intrinsics: skipped
  bool resolution_changed = false;     // first frame of a new resolution: the tracker restarts
  HandsOutput output;
  uint64_t seq = 0;                    // daemon frame number (FrameRecord::frame)
  int64_t capture_ns = 0;
  int64_t grab_end_ns = 0;
  int64_t preprocess_start_ns = 0;
  int64_t preprocess_end_ns = 0;
  int64_t optimize_start_ns = 0;
  int64_t optimize_end_ns = 0;
};

// Single-producer/single-consumer queue of pool entries (Boost.Lockfree: wait-free push and pop).
using FrameQueue = boost::lockfree::spsc_queue<Frame*>;

}  // namespace handtrack::daemon
