#pragma once
// The core -> ipc seam: one frame's TrackerOutput as the hands of the FrameRecord clients read. The
// two vocabularies (core's TrackingState, Handedness and array sizes, the C API's
// handtrack_tracking_state, handtrack_handedness and HANDTRACK_NUM_*) meet here only;
// pose_record.cpp static_asserts where they agree and converts where they differ.
#include "handtrack/core/hands_tracker.hpp"
#include "handtrack/ipc/pose_record.hpp"

namespace handtrack::daemon {

ipc::TrackingState to_ipc(TrackingState state);
ipc::Handedness to_ipc(Handedness hand);

// Fills the hands of `record` from the tracker's output: hand_count hands (0 and hands[] zero when
// it sees none: SPEC.md's "hands" empty), each with its id, handedness, state, confidence, energy,
// params, joints, fingertips, palm, pinch, hand scale (its own: TrackerOutput::scale) and its own
// optimize time. The frame's own fields (frame number, timings) are the publisher's; epoch and
// publish_ns the ring writer's. Allocates nothing.
void fill_hands(const HandsOutput& output, ipc::FrameRecord& record);
// The frame's state for the ring header and the log: tracking when any hand tracks, else
// recovering when any hand recovers, else no hand.
TrackingState frame_state(const HandsOutput& output);

}  // namespace handtrack::daemon
