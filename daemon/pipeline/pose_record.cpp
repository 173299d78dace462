#include "pose_record.hpp"

#include <type_traits>

namespace handtrack::daemon {

namespace {

template <typename Array>
constexpr int extent = static_cast<int>(std::extent_v<Array>);

using Record = ipc::PoseRecord;
static_assert(extent<decltype(Record::params)> == kNumPoseParams, "PoseRecord::params: one per pose parameter");
static_assert(extent<decltype(Record::joints_mm)> == kNumJoints, "PoseRecord::joints_mm: one per joint");
static_assert(extent<decltype(Record::fingertips_mm)> == kNumFingers, "PoseRecord::fingertips_mm: one per finger");
static_assert(std::is_same_v<std::remove_extent_t<decltype(Record::params)>, PoseParams::Scalar>,
              "params travel at the optimizer's precision");

constexpr bool same(TrackingState core, ipc::TrackingState ipc) {
  return static_cast<int>(core) == static_cast<int>(ipc);
}
static_assert(same(TrackingState::kNoHand, ipc::TrackingState::kNoHand));
static_assert(same(TrackingState::kTracking, ipc::TrackingState::kTracking));
static_assert(same(TrackingState::kRecovering, ipc::TrackingState::kRecovering));

void put(const Eigen::Vector3d& v, float (&out)[3]) {
  for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(v[k]);
}

}  // namespace

ipc::TrackingState to_ipc(TrackingState state) {
  // The values agree (asserted above); the cast is the whole conversion.
  return static_cast<ipc::TrackingState>(static_cast<int>(state));
}

void fill_pose(const TrackerOutput& o, const HandScale& scale, ipc::PoseRecord& p) {
  p.state = static_cast<int32_t>(to_ipc(o.state));
  p.confidence = static_cast<float>(o.confidence);
  p.energy = static_cast<float>(o.energy);
  for (int i = 0; i < kNumPoseParams; ++i) p.params[i] = o.params[i];
  for (int j = 0; j < kNumJoints; ++j) put(o.joints[static_cast<size_t>(j)], p.joints_mm[j]);
  for (int t = 0; t < kNumFingers; ++t) put(o.fingertips[static_cast<size_t>(t)], p.fingertips_mm[t]);
  put(o.palm_centre, p.palm_center_mm);
  put(o.palm_normal, p.palm_normal);
  p.pinch_distance_mm = static_cast<float>(o.pinch_distance_mm);
  p.pinch_strength = static_cast<float>(o.pinch_strength);
  p.hand_scale[0] = static_cast<float>(scale.length);
  p.hand_scale[1] = static_cast<float>(scale.width);
  p.hand_scale[2] = static_cast<float>(scale.sigma);
}

}  // namespace handtrack::daemon
