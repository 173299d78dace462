#pragma once
// The core -> ipc seam: one frame's TrackerOutput as the PoseRecord clients read. The two
// vocabularies (core's TrackingState and array sizes, the C API's handtrack_tracking_state and
// HANDTRACK_NUM_*) meet here only; pose_record.cpp static_asserts that they agree.
#include "handtrack/core/tracker.hpp"
#include "handtrack/ipc/pose_record.hpp"

namespace handtrack::daemon {

ipc::TrackingState to_ipc(TrackingState state);

// Fills the pose fields of `record` (state, confidence, energy, params, joints, fingertips, palm,
// pinch, hand scale). Frame number and timings are the publisher's; epoch and publish_ns the
// ring writer's. Allocates nothing.
void fill_pose(const TrackerOutput& output, const HandScale& scale, ipc::PoseRecord& record);

}  // namespace handtrack::daemon
