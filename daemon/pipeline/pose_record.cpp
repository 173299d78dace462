#include "pose_record.hpp"

#include <type_traits>

namespace handtrack::daemon {

namespace {

template <typename Array>
constexpr int extent = static_cast<int>(std::extent_v<Array>);

using Hand = ipc::HandRecord;
static_assert(extent<decltype(Hand::params)> == kNumPoseParams, "HandRecord::params: one per pose parameter");
static_assert(extent<decltype(Hand::joints_mm)> == kNumJoints, "HandRecord::joints_mm: one per joint");
static_assert(extent<decltype(Hand::fingertips_mm)> == kNumFingers, "HandRecord::fingertips_mm: one per finger");
static_assert(std::is_same_v<std::remove_extent_t<decltype(Hand::params)>, PoseParams::Scalar>,
              "params travel at the optimizer's precision");
static_assert(std::is_same_v<decltype(Hand::hand_id), decltype(TrackerOutput::hand_id)>,
              "hand ids cross unchanged (0: no hand on both sides)");

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

ipc::Handedness to_ipc(Handedness hand) {
  // The values differ (core: right 0, left 1; the ABI: 0 is "unknown"), so each is named.
  switch (hand) {
    case Handedness::kLeft: return ipc::Handedness::kLeft;
    case Handedness::kRight: return ipc::Handedness::kRight;
  }
  return ipc::Handedness::kUnknown;
}

void fill_hands(const HandsOutput& output, ipc::FrameRecord& record) {
  static_assert(kMaxHands <= extent<decltype(ipc::FrameRecord::hands)>, "every hand of a frame has its record");
  for (Hand& h : record.hands) h = Hand{};
  record.hand_count = 0;
  for (int k = 0; k < output.count; ++k) {
    const TrackerOutput& o = output.hands[static_cast<size_t>(k)];
    if (o.state == TrackingState::kNoHand) continue;
    Hand& h = record.hands[record.hand_count++];
    h.hand_id = o.hand_id;
    h.handedness = static_cast<int32_t>(to_ipc(o.handedness));
    h.handedness_confidence = static_cast<float>(o.handedness_confidence);
    h.state = static_cast<int32_t>(to_ipc(o.state));
    h.confidence = static_cast<float>(o.confidence);
    h.energy = static_cast<float>(o.energy);
    h.optimize_ms = static_cast<float>(output.optimize_ms[static_cast<size_t>(k)]);
    for (int i = 0; i < kNumPoseParams; ++i) h.params[i] = o.params[i];
    for (int j = 0; j < kNumJoints; ++j) put(o.joints[static_cast<size_t>(j)], h.joints_mm[j]);
    for (int t = 0; t < kNumFingers; ++t) put(o.fingertips[static_cast<size_t>(t)], h.fingertips_mm[t]);
    put(o.palm_centre, h.palm_center_mm);
    put(o.palm_normal, h.palm_normal);
    h.pinch_distance_mm = static_cast<float>(o.pinch_distance_mm);
    h.pinch_strength = static_cast<float>(o.pinch_strength);
    h.hand_scale[0] = static_cast<float>(o.scale.length);
    h.hand_scale[1] = static_cast<float>(o.scale.width);
    h.hand_scale[2] = static_cast<float>(o.scale.sigma);
  }
}

TrackingState frame_state(const HandsOutput& output) {
  TrackingState state = TrackingState::kNoHand;
  for (int k = 0; k < output.count; ++k) {
    const TrackingState s = output.hands[static_cast<size_t>(k)].state;
    if (s == TrackingState::kTracking) return s;
    if (s == TrackingState::kRecovering) state = s;
  }
  return state;
}

}  // namespace handtrack::daemon
