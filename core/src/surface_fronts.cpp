#include "handtrack/core/surface_fronts.hpp"

#include <algorithm>
#include <cmath>

namespace handtrack {

using Eigen::Vector3d;

SurfaceFronts surface_fronts(const HandModel& model, const PosedHand& previous, double max_ratio) {
  SurfaceFronts fronts;
  fronts.sigmas.fill(1.0);
  // Column 2 of camera_R_hand: the hand's z axis, out of the palm.
  const Vector3d normal = previous.camera_R_hand().col(2);
  const auto& gaussians = model.gaussians();
  for (int i = 0; i < previous.gaussian_count(); ++i) {
    const Vector3d& centre = previous.centre(i);
    if (centre.z() < 1.0) continue;  // not projected (SimilarityTerm)
    const Vector3d ray = centre.normalized();
    const int bone = gaussians[static_cast<size_t>(i)].bone;
    double cos = 1.0;
    if (bone == kPalmBone) {
      cos = std::abs(normal.dot(ray));
    } else {
      // Bone b of finger f runs from joint (f, b) to joint (f, b + 1).
      const int finger = bone / kBonesPerFinger;
      const int segment = bone % kBonesPerFinger;
      const Vector3d axis =
          (previous.joints()[joint_index(finger, segment + 1)] - previous.joints()[joint_index(finger, segment)])
              .normalized();
      const double along = axis.dot(ray);
      if (along > 0.0) cos = std::sqrt(std::max(0.0, 1.0 - along * along));
    }
    fronts.sigmas[static_cast<size_t>(i)] = cos * max_ratio > 1.0 ? 1.0 / cos : max_ratio;
  }
  return fronts;
}

}  // namespace handtrack
