#include "reference_energy.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

namespace handtrack::reference {

using Eigen::Vector3d;

double similarity(const HandModel& model, const PosedHand& hand, const DepthInput& input, SimilarityFactor factor,
                  double label_radius_mm, PoseGradient* gradient, double coverage_cap) {
  if (input.gaussians.empty() || input.self_similarity <= 0.0) return 0.0;
  const auto& cam = input.camera;
  const double f = cam.focal();
  const double inv_norm = 1.0 / input.self_similarity;
  const auto& gaussians = model.gaussians();
  // Delta(p,q) D_pq and the pieces of its gradient for one pair; false where Delta = 0.
  struct Pair {
    double delta_d, d, du, dv, dist2, s, depth_diff;
  };
  const auto pair = [&](int p, const ImageGaussian& q, Pair& out) {
    const Vector3d& mu = hand.centre(p);
    const double z = mu.z();
    if (z < 1.0) return false;  // behind or at the camera: no projection
    const auto& g = gaussians[static_cast<size_t>(p)];
    if (factor == SimilarityFactor::kLabel && q.label != g.label) return false;
    const double sigma_h = g.sigma_mm;
    const double sp = sigma_h * f / z;
    const double reach = factor == SimilarityFactor::kLabel ? 2.0 * label_radius_mm : 2.0 * sigma_h;
    out.depth_diff = (z - sigma_h) - q.depth_mm;
    if (std::abs(out.depth_diff) >= reach) return false;  // Delta = 0
    out.du = cam.fx * mu.x() / z + cam.cx - q.u;
    out.dv = cam.fy * mu.y() / z + cam.cy - q.v;
    out.dist2 = out.du * out.du + out.dv * out.dv;
    const double sq2 = q.sigma_px * q.sigma_px;
    out.s = sp * sp + sq2;
    out.d = 2.0 * std::numbers::pi * sp * sp * sq2 / out.s * std::exp(-out.dist2 / (2.0 * out.s));
    out.delta_d = (1.0 - std::abs(out.depth_diff) / reach) * out.d;
    return true;
  };
  // With a cap: S_q = sum_p Delta D_pq, E = sum_q min(S_q, c pi sigma_q^2); only the q below their
  // cap have a gradient.
  const size_t n = input.gaussians.size();
  std::vector<double> covered(n, 0.0);
  std::vector<bool> open(n, true);
  Pair pq{};
  for (size_t k = 0; coverage_cap > 0.0 && k < n; ++k) {
    for (int p = 0; p < hand.gaussian_count(); ++p) {
      if (pair(p, input.gaussians[k], pq)) covered[k] += pq.delta_d;
    }
  }
  double energy = 0.0;
  for (size_t k = 0; coverage_cap > 0.0 && k < n; ++k) {
    const double sq = input.gaussians[k].sigma_px;
    const double cap = coverage_cap * std::numbers::pi * sq * sq;
    open[k] = covered[k] < cap;
    energy += std::min(covered[k], cap);
  }
  for (int p = 0; p < hand.gaussian_count(); ++p) {
    const Vector3d& mu = hand.centre(p);
    const double z = mu.z();
    const double sigma_h = gaussians[static_cast<size_t>(p)].sigma_mm;
    const double sp = sigma_h * f / z;
    const double reach = factor == SimilarityFactor::kLabel ? 2.0 * label_radius_mm : 2.0 * sigma_h;
    double de_du = 0.0;  // dE/du_p, dE/dv_p, dE/dsigma_p, dE/dd_p
    double de_dv = 0.0;
    double de_ds = 0.0;
    double de_dd = 0.0;
    for (size_t k = 0; k < n; ++k) {
      if (!pair(p, input.gaussians[k], pq)) continue;
      if (coverage_cap <= 0.0) energy += pq.delta_d;
      if (gradient == nullptr || !open[k]) continue;
      de_du += pq.delta_d * (-pq.du / pq.s);
      de_dv += pq.delta_d * (-pq.dv / pq.s);
      de_ds += pq.delta_d * (2.0 / sp - 2.0 * sp / pq.s + pq.dist2 * sp / (pq.s * pq.s));
      de_dd += pq.d * (pq.depth_diff > 0.0 ? -1.0 : 1.0) / reach;
    }
    if (gradient == nullptr || z < 1.0) continue;
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
