#include "handtrack/core/palm_hollow.hpp"

#include "handtrack/core/hand_layout.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>

namespace handtrack {
namespace {

// The palm region, in the fit's frame: from 0.2 to 0.85 of the way from the wrist to the middle
// finger's knuckle (clear of the wrist, where the segmentation cuts the forearm off, and of the
// knuckles' bumps), and within 0.9 of the half distance between the index and little knuckles.
constexpr double kRegionFromWrist = 0.2;
constexpr double kRegionToKnuckles = 0.85;
constexpr double kRegionAcross = 0.9;
// A pixel more than this off the fit's palm plane (its bones' plane, about 10 mm inside the hand)
// is something else over the palm region: a finger folded onto the palm, the thumb.
constexpr double kPalmHollowReachMm = 25.0;
// Too few pixels to fit four coefficients to.
constexpr int kMinPalmHollowPixels = 50;
// The share of the palm region's pixels that must lie near its plane: below it the palm is covered
// (fingers folded over it) or seen edge-on.
constexpr double kMinPalmHollowNear = 0.8;

// A region corner nearer than this (or behind the camera) is not projected.
constexpr double kMinCornerDepthMm = 1.0;

bool fit_finite(const TrackerOutput& fit) {
  return std::all_of(fit.joints.begin(), fit.joints.end(), [](const Eigen::Vector3d& j) { return j.allFinite(); }) &&
         fit.palm_normal.allFinite() && fit.palm_centre.allFinite();
}

}  // namespace

std::optional<double> palm_hollow_mm(const DepthInput& input, const TrackerOutput& fit) {
  if (!fit_finite(fit) || input.hand_mask.empty()) return std::nullopt;
  const Eigen::Vector3d& wrist = fit.joints[kWristJoint];
  const Eigen::Vector3d& middle = fit.joints[joint_index(kMiddle, 0)];
  const Eigen::Vector3d& index = fit.joints[joint_index(kIndex, 0)];
  const Eigen::Vector3d& little = fit.joints[joint_index(kLittle, 0)];
  Eigen::Vector3d toward_camera = fit.palm_normal.normalized();
  if (toward_camera.dot(fit.palm_centre) > 0.0) toward_camera = -toward_camera;
  const double length = (middle - wrist).norm();
  const Eigen::Vector3d along = (middle - wrist) / length;
  const Eigen::Vector3d across = toward_camera.cross(along).normalized();
  const double half_width = 0.5 * std::abs((index - little).dot(across));
  if (!(length > 0.0 && half_width > 0.0)) return std::nullopt;
  const Eigen::Vector3d centre = wrist + 0.5 * length * along;

  // The pixels to look at: the box of the region's corners, projected (clamped to the image before
  // any conversion to int).
  const CameraIntrinsics& cam = input.camera;
  double u_min = cam.width;
  double v_min = cam.height;
  double u_max = -1.0;
  double v_max = -1.0;
  for (const double a : {kRegionFromWrist, kRegionToKnuckles}) {
    for (const double x : {-kRegionAcross, kRegionAcross}) {
      const Eigen::Vector3d corner = wrist + a * length * along + x * half_width * across;
      if (corner.z() < kMinCornerDepthMm) return std::nullopt;  // not projectable: no fit of a hand in view
      const Eigen::Vector2d p = cam.project(corner);
      u_min = std::min(u_min, p.x());
      v_min = std::min(v_min, p.y());
      u_max = std::max(u_max, p.x());
      v_max = std::max(v_max, p.y());
    }
  }
  const auto pixel = [](double p, int size) { return static_cast<int>(std::clamp(p, 0.0, size - 1.0)); };
  const int u0 = pixel(std::floor(u_min), cam.width);
  const int v0 = pixel(std::floor(v_min), cam.height);
  const int u1 = pixel(std::ceil(u_max), cam.width);
  const int v1 = pixel(std::ceil(v_max), cam.height);

  // Least squares of h = a + b x + c x^2 + e y over the region's pixels near the palm's plane.
  Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
  Eigen::Vector4d rhs = Eigen::Vector4d::Zero();
  int in_region = 0;
  int near = 0;
  for (int v = v0; v <= v1; ++v) {
    for (int u = u0; u <= u1; ++u) {
      const size_t i = static_cast<size_t>(v) * static_cast<size_t>(cam.width) + static_cast<size_t>(u);
      if (input.hand_mask[i] == 0 || input.filtered_mm[i] <= 0.0F) continue;
      const Eigen::Vector3d d = cam.unproject(u, v, input.filtered_mm[i]) - centre;
      const double y = d.dot(along) / length;  // -0.5 at the wrist, 0.5 at the knuckle
      const double x = d.dot(across) / half_width;
      if (y < kRegionFromWrist - 0.5 || y > kRegionToKnuckles - 0.5 || std::abs(x) > kRegionAcross) continue;
      ++in_region;
      const double h = d.dot(toward_camera);
      if (std::abs(h) > kPalmHollowReachMm) continue;
      ++near;
      const Eigen::Vector4d f(1.0, x, x * x, y);
      normal += f * f.transpose();
      rhs += f * h;
    }
  }
  if (near < kMinPalmHollowPixels || near < kMinPalmHollowNear * in_region) return std::nullopt;
  const Eigen::LDLT<Eigen::Matrix4d> solve(normal);
  if (solve.info() != Eigen::Success) return std::nullopt;
  const Eigen::Vector4d coefficients = solve.solve(rhs);
  if (!std::isfinite(coefficients(2))) return std::nullopt;
  return coefficients(2);
}

}  // namespace handtrack
