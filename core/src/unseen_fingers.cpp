#include "handtrack/core/unseen_fingers.hpp"

#include "handtrack/core/kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace handtrack {

UnseenFingers unseen_fingers(const DepthInput& input, const PoseParams& previous) {
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
  const Eigen::Matrix3d r = hand_rotation(previous);
  const double facing = r.col(2).z() * r.col(2).z();
  const double across_view = facing * (1.0 - std::abs(r.col(1).z()));
  const double from_behind = std::max(0.0, r.col(2).z()) * std::max(0.0, r.col(1).z());
  for (int f = kIndex; f < kNumFingers; ++f) {
    const double share = static_cast<double>(seen[static_cast<size_t>(f)]) / labelled;
    unseen.weight[static_cast<size_t>(f)] = across_view * (1.0 - std::min(1.0, share / kSeenFingerShare));
    unseen.held[static_cast<size_t>(f)] = from_behind;
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
