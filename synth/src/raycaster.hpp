#pragma once
// Private: exact ray casting of cone-spheres, spheres and bounded planes into a z-buffer.
// Each primitive is culled to the screen rectangle of its projected bounding box, so a frame costs
// roughly (covered pixels x primitives covering them) ray tests.

#include "handtrack/core/camera.hpp"
#include "handtrack/synth/hand_model.hpp"

#include <cstdint>
#include <vector>

namespace handtrack::synth {

// A planar patch: points p with (p - origin).dot(axis_u) in [-half_u, half_u] and likewise for
// axis_v (infinite when half_* <= 0). `normal` must be unit and orthogonal to axis_u, axis_v.
struct PlanePatch {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d axis_u = Eigen::Vector3d::UnitX();
  Eigen::Vector3d axis_v = Eigen::Vector3d::UnitY();
  double half_u = 0.0;
  double half_v = 0.0;
  int label = kBackground;
};

class Raycaster {
 public:
  explicit Raycaster(const CameraIntrinsics& camera);

  // Empties the z-buffer (depth = +inf, label 0, incidence 1).
  void clear();
  void draw(const ConeSphere& primitive);
  void draw(const PlanePatch& plane);

  // Per pixel (row-major): depth z in mm (+inf where nothing was hit), part label, and
  // |cos| of the angle between the viewing ray and the surface normal (for grazing dropouts).
  [[nodiscard]] const std::vector<float>& depth_mm() const { return depth_; }
  [[nodiscard]] const std::vector<uint8_t>& labels() const { return labels_; }
  [[nodiscard]] const std::vector<float>& incidence_cos() const { return incidence_; }

 private:
  bool sphere_screen_bound(const Eigen::Vector3d& c, double r, Eigen::Vector2d& centre, double& radius) const;
  void write(size_t index, double z, const Eigen::Vector3d& ray, const Eigen::Vector3d& normal, int label);

  CameraIntrinsics camera_;
  std::vector<double> ray_x_;  // (u - cx) / fx: the ray through pixel (u, v) is (ray_x[u], ray_y[v], 1)
  std::vector<double> ray_y_;
  std::vector<float> depth_;
  std::vector<uint8_t> labels_;
  std::vector<float> incidence_;
};

}  // namespace handtrack::synth
