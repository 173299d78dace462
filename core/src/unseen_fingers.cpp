#include "handtrack/core/unseen_fingers.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace handtrack {

namespace {

// c_f of unseen_fingers.hpp for the fingers index..little (0 for the thumb): how much each finger
// is curled as in a fist, by how far the segmented hand reaches beyond its knuckle.
std::array<double, kNumFingers> fist_curl(const DepthInput& input, const PosedHand& hand) {
  std::array<double, kNumFingers> curl{};
  const auto pixels = static_cast<size_t>(input.camera.width) * static_cast<size_t>(input.camera.height);
  if (pixels == 0 || input.hand_mask.size() != pixels || input.filtered_mm.size() != pixels) return curl;
  // Each finger's knuckle, its direction in the palm plane (the proximal bone without its flexion,
  // on the fingers' side; the hand's own axis where that is more than about 45 deg off it or the
  // bone stands nearly square to the palm) and the direction across it.
  const Eigen::Vector3d normal = hand.camera_R_hand().col(2);
  const Eigen::Vector3d fingers = hand.camera_R_hand().col(1);
  std::array<Eigen::Vector3d, kNumFingers> knuckle;
  std::array<Eigen::Vector3d, kNumFingers> along;
  std::array<Eigen::Vector3d, kNumFingers> across;
  for (int f = kIndex; f < kNumFingers; ++f) {
    const auto i = static_cast<size_t>(f);
    knuckle[i] = hand.joints()[static_cast<size_t>(joint_index(f, 0))];
    const Eigen::Vector3d bone = (hand.joints()[static_cast<size_t>(joint_index(f, 1))] - knuckle[i]).normalized();
    Eigen::Vector3d in_plane = bone - normal * normal.dot(bone);
    if (in_plane.dot(fingers) < 0.0) in_plane = -in_plane;
    const bool usable = in_plane.norm() > 0.3 && in_plane.normalized().dot(fingers) > 0.7;
    along[i] = usable ? Eigen::Vector3d(in_plane.normalized()) : fingers;
    across[i] = normal.cross(along[i]).normalized();
  }
  // Over the segmented hand's pixels within kReachBandMm across each finger's line, the farthest
  // along it.
  std::array<double, kNumFingers> reach{};
  for_each_hand_point(input, [&](const Eigen::Vector3d& point) {
    for (int f = kIndex; f < kNumFingers; ++f) {
      const auto i = static_cast<size_t>(f);
      const Eigen::Vector3d q = point - knuckle[i];
      if (std::abs(q.dot(across[i])) <= kReachBandMm) reach[i] = std::max(reach[i], q.dot(along[i]));
    }
  });
  for (int f = kIndex; f < kNumFingers; ++f) {
    const auto i = static_cast<size_t>(f);
    curl[i] = std::clamp((kOpenReachMm - reach[i]) / (kOpenReachMm - kCurledReachMm), 0.0, 1.0);
  }
  return curl;
}

}  // namespace

UnseenFingers unseen_fingers(const DepthInput& input, const PosedHand& previous) {
  UnseenFingers unseen;
  // Per label value, over the image: the labels are 0 off the hand (most of the image), so eight
  // at a time are skipped while they are all 0.
  std::array<int, 256> pixels{};
  const std::vector<uint8_t>& labels = input.pixel_labels;
  size_t i = 0;
  for (; i + 8 <= labels.size(); i += 8) {
    uint64_t eight = 0;
    std::memcpy(&eight, labels.data() + i, 8);
    if (eight == 0) continue;
    for (size_t k = i; k < i + 8; ++k) ++pixels[labels[k]];
  }
  for (; i < labels.size(); ++i) ++pixels[labels[i]];
  std::array<int, kNumFingers> seen{};
  int labelled = 0;
  for (int label = kPalm; label <= kLittleDistal; ++label) {
    labelled += pixels[static_cast<size_t>(label)];
    const int finger = part_finger(label);
    if (finger >= 0) seen[static_cast<size_t>(finger)] += pixels[static_cast<size_t>(label)];
  }
  if (labelled == 0) return unseen;
  // Columns of camera_R_hand: the hand's y axis runs along the fingers, its z axis out of the palm.
  const Eigen::Matrix3d& r = previous.camera_R_hand();
  const double facing = r.col(2).z() * r.col(2).z();
  const double across_view = facing * (1.0 - std::abs(r.col(1).z()));
  const double from_behind = std::max(0.0, r.col(2).z()) * std::max(0.0, r.col(1).z());
  // Seen from behind, a fist's fingers go toward the relaxed fist instead of the half curl.
  std::array<double, kNumFingers> curl{};
  if (from_behind > 0.0) curl = fist_curl(input, previous);
  double fist = 0.0;
  for (int f = kIndex; f < kNumFingers; ++f) fist += curl[static_cast<size_t>(f)] / 4.0;
  for (int f = kIndex; f < kNumFingers; ++f) {
    const auto k = static_cast<size_t>(f);
    const double share = static_cast<double>(seen[k]) / labelled;
    const double curled = curl[k] * fist;
    unseen.weight[k] = across_view * (1.0 - std::min(1.0, share / kSeenFingerShare)) + from_behind * curled;
    unseen.held[k] = from_behind * (1.0 - curled);
  }
  return unseen;
}

double unseen_finger_energy(const UnseenFingers& unseen, const PoseParams& params, PoseGradient* gradient) {
  double energy = 0.0;
  // One finger's sum_d w (theta_{f,d} - target_d)^2 and its gradient.
  const auto pull = [&](int f, double w, const std::array<double, 3>& target) {
    if (w == 0.0) return;
    for (int d = 1; d <= 3; ++d) {
      const int j = angle_param(f, d);
      const double a = params[j] - target[static_cast<size_t>(d - 1)];
      energy += w * a * a;
      if (gradient != nullptr) (*gradient)[j] += 2.0 * w * a;
    }
  };
  for (int f = kIndex; f < kNumFingers; ++f) {
    pull(f, unseen.weight[static_cast<size_t>(f)], kCurledFlexion);
    pull(f, unseen.held[static_cast<size_t>(f)], kHalfCurlFlexion);
  }
  return energy;
}

}  // namespace handtrack
