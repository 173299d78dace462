#include "reference_energy.hpp"

#include <cmath>
#include <numbers>

namespace handtrack::reference {

using Eigen::Vector3d;

double similarity(const HandModel& model, const PosedHand& hand, const DepthInput& input, SimilarityFactor factor,
                  double label_radius_mm, PoseGradient* gradient) {
  if (input.gaussians.empty() || input.self_similarity <= 0.0) return 0.0;
  const auto& cam = input.camera;
  const double f = cam.focal();
  const double inv_norm = 1.0 / input.self_similarity;
  const auto& gaussians = model.gaussians();
  double energy = 0.0;
  for (int p = 0; p < hand.gaussian_count(); ++p) {
    const Vector3d& mu = hand.centre(p);
    const double z = mu.z();
    if (z < 1.0) continue;  // behind or at the camera: no projection
    const auto& g = gaussians[static_cast<size_t>(p)];
    const double sigma_h = g.sigma_mm;
    const double up = cam.fx * mu.x() / z + cam.cx;
    const double vp = cam.fy * mu.y() / z + cam.cy;
    const double sp = sigma_h * f / z;
    const double dp = z - sigma_h;
    const double sp2 = sp * sp;
    const double reach = factor == SimilarityFactor::kLabel ? 2.0 * label_radius_mm : 2.0 * sigma_h;

    double de_du = 0.0;  // dE/du_p, dE/dv_p, dE/dsigma_p, dE/dd_p
    double de_dv = 0.0;
    double de_ds = 0.0;
    double de_dd = 0.0;
    for (const auto& q : input.gaussians) {
      if (factor == SimilarityFactor::kLabel && q.label != g.label) continue;
      const double depth_diff = dp - q.depth_mm;
      const double abs_diff = std::abs(depth_diff);
      if (abs_diff >= reach) continue;  // Delta = 0
      const double delta = 1.0 - abs_diff / reach;
      const double du = up - q.u;
      const double dv = vp - q.v;
      const double dist2 = du * du + dv * dv;
      const double sq2 = q.sigma_px * q.sigma_px;
      const double s = sp2 + sq2;
      const double d = 2.0 * std::numbers::pi * sp2 * sq2 / s * std::exp(-dist2 / (2.0 * s));
      energy += delta * d;
      if (gradient == nullptr) continue;
      de_du += delta * (-d * du / s);
      de_dv += delta * (-d * dv / s);
      de_ds += delta * d * (2.0 / sp - 2.0 * sp / s + dist2 * sp / (s * s));
      de_dd += d * (depth_diff > 0.0 ? -1.0 : 1.0) / reach;
    }
    if (gradient == nullptr) continue;
    // Chain through the projection: u = fx x/z + cx, v = fy y/z + cy, sigma_p = sigma_h f/z, d_p = z - sigma_h.
    Vector3d de_dmu;
    de_dmu.x() = de_du * cam.fx / z;
    de_dmu.y() = de_dv * cam.fy / z;
    de_dmu.z() = -de_du * cam.fx * mu.x() / (z * z) - de_dv * cam.fy * mu.y() / (z * z) - de_ds * sigma_h * f / (z * z) +
                 de_dd;
    hand.add_point_gradient(p, de_dmu * inv_norm, *gradient);
  }
  return energy * inv_norm;
}

double inter_hand(const HandModel& model, const PosedHand& hand, const HandObstacle& other, PoseGradient* gradient) {
  const double inv_norm = 1.0 / model.self_similarity();
  double energy = 0.0;
  for (int p = 0; p < hand.gaussian_count(); ++p) {
    const double sigma_p = model.gaussians()[static_cast<size_t>(p)].sigma_mm;
    Vector3d de_dmu = Vector3d::Zero();
    for (int q = 0; q < other.size(); ++q) {
      const Vector3d diff = hand.centre(p) - other.centre(q);
      const double d = overlap_3d(diff.squaredNorm(), sigma_p, other.sigma_mm(q));
      energy += d;
      // dD/dmu_p = -D (mu_p - mu_q) / S
      de_dmu -= d * diff / (sigma_p * sigma_p + other.sigma_mm(q) * other.sigma_mm(q));
    }
    if (gradient != nullptr) hand.add_point_gradient(p, de_dmu * inv_norm, *gradient);
  }
  return energy * inv_norm;
}

}  // namespace handtrack::reference
