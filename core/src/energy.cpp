#include "handtrack/core/energy.hpp"

#include <cmath>
#include <numbers>

namespace handtrack {

using Eigen::Vector3d;

double SimilarityTerm::evaluate(const HandModel& model, const PosedHand& hand, const DepthInput& input,
                                PoseGradient* gradient) const {
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
    const double reach = factor_ == SimilarityFactor::kDepth ? 2.0 * sigma_h : 2.0 * label_radius_mm_;

    double de_du = 0.0;  // dE/du_p, dE/dv_p, dE/dsigma_p, dE/dd_p
    double de_dv = 0.0;
    double de_ds = 0.0;
    double de_dd = 0.0;
    for (const auto& q : input.gaussians) {
      if (factor_ == SimilarityFactor::kLabel && q.label != g.label) continue;
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

double CollisionTerm::evaluate(const HandModel& model, const PosedHand& hand, PoseGradient* gradient) const {
  const auto& gaussians = model.gaussians();
  const double inv_norm = 1.0 / model.self_similarity();
  double energy = 0.0;
  for (const auto& pair : model.collision_pairs()) {
    const double sa = gaussians[static_cast<size_t>(pair.a)].sigma_mm;
    const double sb = gaussians[static_cast<size_t>(pair.b)].sigma_mm;
    const double s = sa * sa + sb * sb;
    const Vector3d delta = hand.centre(pair.a) - hand.centre(pair.b);
    const double dist2 = delta.squaredNorm();
    if (dist2 > 2.0 * s * 30.0) continue;  // exp(-30) ~ 1e-13: no contribution at double precision
    const double d = overlap_3d(dist2, sa, sb);
    energy += d;
    if (gradient == nullptr) continue;
    const Vector3d de_da = -d * delta / s * inv_norm;
    hand.add_point_gradient(pair.a, de_da, *gradient);
    hand.add_point_gradient(pair.b, -de_da, *gradient);
  }
  return energy * inv_norm;
}

double JointLimitTerm::evaluate(const HandModel& model, const PoseParams& params, PoseGradient* gradient) const {
  double energy = 0.0;
  for (int j = 0; j < kNumJointAngles; ++j) {
    const auto& lim = model.limits()[static_cast<size_t>(j)];
    const double theta = params[kFirstAngleParam + j];
    double excess = 0.0;
    if (theta < lim.lo) excess = theta - lim.lo;
    if (theta > lim.hi) excess = theta - lim.hi;
    energy += excess * excess;
    if (gradient != nullptr) (*gradient)[kFirstAngleParam + j] += 2.0 * excess;
  }
  return energy;
}

double SmoothnessTerm::evaluate(const PoseParams& params, const PoseParams& previous,
                                const PoseParams& before_previous, PoseGradient* gradient) const {
  double energy = 0.0;
  for (int j = 0; j < kNumPoseParams; ++j) {
    const double unit = param_kind(j) == ParamKind::kTranslation ? translation_per_mm_ : 1.0;
    const double a = unit * (0.5 * (before_previous[j] + params[j]) - previous[j]);
    energy += a * a;
    if (gradient != nullptr) (*gradient)[j] += a * unit;  // d/dTheta_j of a^2 = 2 a * 0.5 unit
  }
  return energy;
}

PoseEnergy::PoseEnergy(SimilarityFactor factor, const EnergyWeights& weights)
    : factor_(factor),
      weights_(weights),
      similarity_(factor, weights.label_radius_mm),
      smoothness_(weights.smoothness_translation_per_mm) {}

double PoseEnergy::evaluate(const EnergyFrame& frame, const PoseParams& params, PosedHand& hand,
                            PoseGradient* gradient, EnergyBreakdown* breakdown) const {
  hand.update(*frame.model, params);
  PoseGradient g_sim = PoseGradient::Zero();
  PoseGradient g_col = PoseGradient::Zero();
  PoseGradient g_lim = PoseGradient::Zero();
  PoseGradient g_smo = PoseGradient::Zero();
  const bool want = gradient != nullptr;
  EnergyBreakdown e;
  e.similarity = similarity_.evaluate(*frame.model, hand, *frame.input, want ? &g_sim : nullptr);
  if (weights_.collision != 0.0) e.collision = collision_.evaluate(*frame.model, hand, want ? &g_col : nullptr);
  if (weights_.limits != 0.0) e.limits = limits_.evaluate(*frame.model, params, want ? &g_lim : nullptr);
  if (weights_.smoothness != 0.0 && frame.previous != nullptr && frame.before_previous != nullptr) {
    e.smoothness = smoothness_.evaluate(params, *frame.previous, *frame.before_previous, want ? &g_smo : nullptr);
  }
  e.total = e.similarity - weights_.collision * e.collision - weights_.limits * e.limits -
            weights_.smoothness * e.smoothness;
  if (want) {
    *gradient = g_sim - weights_.collision * g_col - weights_.limits * g_lim - weights_.smoothness * g_smo;
  }
  if (breakdown != nullptr) *breakdown = e;
  return e.total;
}

}  // namespace handtrack
