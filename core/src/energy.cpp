#include "handtrack/core/energy.hpp"

#include "fast_exp.hpp"
#include "target_clones.hpp"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <numbers>

namespace handtrack {

using Eigen::Vector3d;

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// Slices are widened by this much so that the exact test |d_p - d_q| < reach decides at the edge.
constexpr double kSliceMarginMm = 1e-6;

// A model Gaussian projected to the image (Sec. 3.2): mean (px), sigma_p (px) and sigma_p^2, d_p
// (mm), and the depth factor's reach (mm).
struct ProjectedGaussian {
  double u = 0.0;
  double v = 0.0;
  double sigma = 0.0;
  double sigma2 = 0.0;
  double depth_mm = 0.0;
  double reach_mm = 1.0;
};

// The sums over image Gaussians q that E_sim and its gradient need for one model Gaussian p, with
// D = D_pq, S = sigma_p^2 + sigma_q^2, r^2 = |mu_p - mu_q|^2 (see energy.hpp), over the q that are
// open (below their coverage cap; all without one):
struct PairSums {
  double overlap = 0.0;     // sum Delta D
  double weight = 0.0;      // sum Delta D / S
  double weight_du = 0.0;   // sum Delta D (u_p - u_q) / S
  double weight_dv = 0.0;   // sum Delta D (v_p - v_q) / S
  double weight_r2 = 0.0;   // sum Delta D r^2 / S^2
  double depth_sign = 0.0;  // sum over |d_p - d_q| < reach of D sign(d_p - d_q)
};

// One model Gaussian p against the Gaussians q of a slice, with everything the loops below read in
// members that the compiler keeps in registers: it then sees unit-stride loads, not gathers. at(k)
// is one pair q = k, branch-free:
//   Delta = 1 - |d_p - d_q| / reach where |d_p - d_q| < reach, else 0 (the depth factor),
//   D = D_pq = 2 pi sigma_p^2 sigma_q^2 / S exp(-r^2 / 2S)   (Sec. 3.2, the 2D form of eq. 8);
// place(k) its image-plane geometry alone.
struct PairLoop {
  struct Place {
    double du;     // u_p - u_q
    double dv;     // v_p - v_q
    double r2;     // r^2
    double inv_s;  // 1 / S
  };
  struct Pair : Place {
    double delta_d;   // Delta D_pq (0 out of reach)
    double signed_d;  // D_pq sign(d_p - d_q) where |d_p - d_q| < reach, else 0
  };

  PairLoop(const ProjectedGaussian& p, const ImageMixtureSlice& q)
      : q_u(q.u), q_v(q.v), q_sigma2(q.sigma2), q_depth(q.depth_mm), n(q.size), u(p.u), v(p.v),
        sigma2(p.sigma2), depth(p.depth_mm), reach(p.reach_mm), inv_reach(1.0 / p.reach_mm) {}

  [[gnu::always_inline]] Place place(std::size_t k) const {
    Place place;
    place.du = u - q_u[k];
    place.dv = v - q_v[k];
    place.r2 = place.du * place.du + place.dv * place.dv;
    place.inv_s = 1.0 / (sigma2 + q_sigma2[k]);
    return place;
  }

  [[gnu::always_inline]] Pair at(std::size_t k) const {
    Pair pair{place(k), 0.0, 0.0};
    const double depth_diff = depth - q_depth[k];
    const double abs_diff = std::abs(depth_diff);
    const bool in_reach = abs_diff < reach;
    const double d =
        kTwoPi * sigma2 * q_sigma2[k] * pair.inv_s * detail::exp_nonpositive(-0.5 * pair.r2 * pair.inv_s);
    pair.delta_d = in_reach ? (1.0 - abs_diff * inv_reach) * d : 0.0;
    pair.signed_d = in_reach ? (depth_diff > 0.0 ? d : -d) : 0.0;
    return pair;
  }

  // PairSums over the slice's pairs, pair k as pair(k) (a Pair: its Place, Delta D_pq and signed
  // D_pq). Inline, so that each kernel below vectorises its own loop.
  template <class PairAt>
  [[gnu::always_inline]] PairSums sum(const PairAt& pair_at) const {
    double overlap = 0.0;
    double weight = 0.0;
    double weight_du = 0.0;
    double weight_dv = 0.0;
    double weight_r2 = 0.0;
    double depth_sign = 0.0;
#pragma omp simd reduction(+ : overlap, weight, weight_du, weight_dv, weight_r2, depth_sign)
    for (std::size_t k = 0; k < n; ++k) {
      const Pair pair = pair_at(k);
      const double w = pair.delta_d * pair.inv_s;
      overlap += pair.delta_d;
      weight += w;
      weight_du += w * pair.du;
      weight_dv += w * pair.dv;
      weight_r2 += w * pair.r2 * pair.inv_s;
      depth_sign += pair.signed_d;
    }
    return {overlap, weight, weight_du, weight_dv, weight_r2, depth_sign};
  }

  const double* const q_u;
  const double* const q_v;
  const double* const q_sigma2;
  const double* const q_depth;
  const std::size_t n;
  const double u;
  const double v;
  const double sigma2;
  const double depth;
  const double reach;
  const double inv_reach;
};

// The loops are branch-free so that gcc vectorises them: 2 doubles per SSE2 register on any
// x86-64, 4 with fused multiply-adds in the x86-64-v3 (AVX2, FMA) clone and 8 in the x86-64-v4
// (AVX-512) clone, which the loader picks on CPUs that have them.

// Eq. 6: every pair of the slice counts.
HANDTRACK_TARGET_CLONES PairSums pair_sums(const ProjectedGaussian& p, const ImageMixtureSlice& q) {
  const PairLoop loop(p, q);
  return loop.sum([&](std::size_t k) { return loop.at(k); });
}

// The first pass of a capped E_sim: covered[k] += Delta D_pq for each Gaussian q = k of the slice;
// add_and_keep_overlaps also keeps each pair's Delta D_pq and signed D_pq in `kept` (2 x the
// slice's size: all the one, then all the other) for the second pass.
static_assert(kMaxModelGaussians <= ImageMixture::kMaxPairedModelGaussians, "pair_scratch() has room for every pair");
HANDTRACK_TARGET_CLONES void add_overlaps(const ProjectedGaussian& p, const ImageMixtureSlice& q, double* covered) {
  const PairLoop loop(p, q);
#pragma omp simd
  for (std::size_t k = 0; k < loop.n; ++k) covered[k] += loop.at(k).delta_d;
}
HANDTRACK_TARGET_CLONES void add_and_keep_overlaps(const ProjectedGaussian& p, const ImageMixtureSlice& q,
                                                   double* covered, double* kept) {
  const PairLoop loop(p, q);
  double* const delta_d = kept;
  double* const signed_d = kept + loop.n;
#pragma omp simd
  for (std::size_t k = 0; k < loop.n; ++k) {
    const PairLoop::Pair pair = loop.at(k);
    covered[k] += pair.delta_d;
    delta_d[k] = pair.delta_d;
    signed_d[k] = pair.signed_d;
  }
}

// The second pass: the pairs kept by the first (no exp again) whose q is open (`open`: 1 or 0 per
// Gaussian of the slice).
HANDTRACK_TARGET_CLONES PairSums open_pair_sums(const ProjectedGaussian& p, const ImageMixtureSlice& q,
                                                const double* open, const double* kept) {
  const PairLoop loop(p, q);
  const double* const delta_d = kept;
  const double* const signed_d = kept + loop.n;
  return loop.sum([&](std::size_t k) {
    return PairLoop::Pair{loop.place(k), open[k] * delta_d[k], open[k] * signed_d[k]};
  });
}

// The 3D overlap of eq. 8 for one pair of isotropic Gaussians, E_col's and E_hand's, from the
// squared distance of the centres and the two sigma^2:
//   D = (2 pi)^(3/2) (s_a^2 s_b^2 / S)^(3/2) exp(-|mu_a - mu_b|^2 / 2S),  S = s_a^2 + s_b^2,
// with D / S, the factor of the gradient dD/dmu_a = -D (mu_a - mu_b) / S. Pairs further apart than
// exp(-30) ~ 1e-13 count 0. Inline and branch-free, for the vectorised loops below.
constexpr double kMaxOverlapExponent = 30.0;
struct Overlap3d {
  double d = 0.0;
  double d_over_s = 0.0;
};
inline Overlap3d overlap_3d_pair(double dist2, double sigma2_a, double sigma2_b, double norm_3d) {
  const double inv_s = 1.0 / (sigma2_a + sigma2_b);
  const double exponent = 0.5 * dist2 * inv_s;
  const double k3 = sigma2_a * sigma2_b * inv_s;
  const double d =
      exponent > kMaxOverlapExponent ? 0.0 : norm_3d * k3 * std::sqrt(k3) * detail::exp_nonpositive(-exponent);
  return {d, d * inv_s};
}

// E_col's pairs go in chunks: their overlaps vectorised into a small buffer, then scattered to
// the centres' gradients.
constexpr size_t kCollisionChunk = 128;

// D_ab of each pair (eq. 8, overlap_3d_pair), with the Gaussians' centres and sigma^2 as arrays;
// returns sum D_ab and stores each pair's dE/dmu_a = -D_ab / S (mu_a - mu_b) / E(C_h, C_h)
// (`inv_norm`) in `de` (3 x kCollisionChunk: x, then y, then z), vectorised with the rest.
HANDTRACK_TARGET_CLONES double collision_overlaps(const CollisionPair* pairs, size_t count, const double* x,
                                                  const double* y, const double* z, const double* sigma2,
                                                  double inv_norm, double* de) {
  const double norm_3d = std::pow(2.0 * std::numbers::pi, 1.5);
  double* const de_x = de;
  double* const de_y = de + kCollisionChunk;
  double* const de_z = de + 2 * kCollisionChunk;
  double energy = 0.0;
#pragma omp simd reduction(+ : energy)
  for (size_t k = 0; k < count; ++k) {
    const int a = pairs[k].a;
    const int b = pairs[k].b;
    const double dx = x[a] - x[b];
    const double dy = y[a] - y[b];
    const double dz = z[a] - z[b];
    const Overlap3d o = overlap_3d_pair(dx * dx + dy * dy + dz * dz, sigma2[a], sigma2[b], norm_3d);
    energy += o.d;
    const double s = -o.d_over_s * inv_norm;
    de_x[k] = s * dx;
    de_y[k] = s * dy;
    de_z[k] = s * dz;
  }
  return energy;
}

// E_hand's sums for one model Gaussian p against every Gaussian q of the other hand; the weights
// are -dE_hand/dmu_p before normalising:
struct ObstacleSums {
  double overlap = 0.0;    // sum_q D_pq
  double weight_dx = 0.0;  // sum_q D_pq (x_p - x_q) / S_pq
  double weight_dy = 0.0;  // sum_q D_pq (y_p - y_q) / S_pq
  double weight_dz = 0.0;  // sum_q D_pq (z_p - z_q) / S_pq
};

HANDTRACK_TARGET_CLONES ObstacleSums obstacle_sums(const Vector3d& centre, double sigma2,
                                                   const HandObstacle& other) {
  const double norm_3d = std::pow(2.0 * std::numbers::pi, 1.5);
  const double* const q_x = other.x_mm();
  const double* const q_y = other.y_mm();
  const double* const q_z = other.z_mm();
  const double* const q_sigma2 = other.sigma2_mm2();
  const auto n = static_cast<size_t>(other.size());
  const double x = centre.x();
  const double y = centre.y();
  const double z = centre.z();
  double overlap = 0.0;
  double weight_dx = 0.0;
  double weight_dy = 0.0;
  double weight_dz = 0.0;
#pragma omp simd reduction(+ : overlap, weight_dx, weight_dy, weight_dz)
  for (size_t k = 0; k < n; ++k) {
    const double dx = x - q_x[k];
    const double dy = y - q_y[k];
    const double dz = z - q_z[k];
    const Overlap3d o = overlap_3d_pair(dx * dx + dy * dy + dz * dz, sigma2, q_sigma2[k], norm_3d);
    overlap += o.d;
    weight_dx += o.d_over_s * dx;
    weight_dy += o.d_over_s * dy;
    weight_dz += o.d_over_s * dz;
  }
  return {overlap, weight_dx, weight_dy, weight_dz};
}

// A term differentiated with respect to the model Gaussians' centres, chained to Theta in one pass
// through the kinematic chain (PosedHand::add_centre_gradients).
template <class CentresTerm>
double chain_to_pose(const PosedHand& hand, PoseGradient* gradient, const CentresTerm& evaluate_centres) {
  if (gradient == nullptr) return evaluate_centres(nullptr);
  CentreGradients dE_dcentres = CentreGradients::Zero(3, hand.gaussian_count());
  const double energy = evaluate_centres(&dE_dcentres);
  hand.add_centre_gradients(dE_dcentres, *gradient);
  return energy;
}

}  // namespace

double SimilarityTerm::evaluate(const HandModel& model, const PosedHand& hand, const DepthInput& input,
                                PoseGradient* gradient) const {
  return chain_to_pose(hand, gradient,
                       [&](CentreGradients* dE_dcentres) { return evaluate_centres(model, hand, input, dE_dcentres); });
}

double SimilarityTerm::evaluate_centres(const HandModel& model, const PosedHand& hand, const DepthInput& input,
                                        CentreGradients* dE_dcentres, const SurfaceFronts* fronts) const {
  if (input.gaussians.empty() || input.self_similarity <= 0.0) return 0.0;
  assert(input.mixture.size() == input.gaussians.size() && "DepthInput::mixture must be assigned");
  const auto& cam = input.camera;
  const double f = cam.focal();
  const double inv_norm = 1.0 / input.self_similarity;
  const auto& gaussians = model.gaussians();
  const bool capped = coverage_cap_ > 0.0;
  const bool by_label = factor_ == SimilarityFactor::kLabel;
  // With a cap: S_q, and 1 where q is open (below its cap: its pairs count), 0 where not; with the
  // gradient too, each pair's values from the first pass, 2 x its slice's size from kept_at[i].
  const std::size_t n = input.mixture.size();
  const ImageMixture::Coverage coverage = input.mixture.coverage_scratch();
  const bool keep = capped && dE_dcentres != nullptr;
  double* const kept =
      keep ? input.mixture.pair_scratch(2 * n * static_cast<std::size_t>(hand.gaussian_count())) : nullptr;
  std::array<std::size_t, kMaxModelGaussians> kept_at{};
  std::size_t kept_size = 0;
  if (capped) std::fill_n(coverage.covered, n, 0.0);
  // Each model Gaussian projected: u = fx x/z + cx, v = fy y/z + cy, sigma_p = sigma_h f/z,
  // d_p = z - k_p sigma_h; with a cap, its overlaps added to the coverage S_q.
  std::array<ProjectedGaussian, kMaxModelGaussians> projected;
  std::array<ImageMixtureSlice, kMaxModelGaussians> slices{};
  for (int i = 0; i < hand.gaussian_count(); ++i) {
    const Vector3d& mu = hand.centre(i);
    const double z = mu.z();
    if (z < 1.0) continue;  // behind or at the camera: no projection
    const auto& g = gaussians[static_cast<size_t>(i)];
    const double sigma_h = g.sigma_mm;
    ProjectedGaussian& p = projected[static_cast<size_t>(i)];
    p.u = cam.fx * mu.x() / z + cam.cx;
    p.v = cam.fy * mu.y() / z + cam.cy;
    p.sigma = sigma_h * f / z;
    p.sigma2 = p.sigma * p.sigma;
    p.depth_mm = z - (fronts != nullptr ? fronts->sigmas[static_cast<size_t>(i)] : 1.0) * sigma_h;
    p.reach_mm = by_label ? 2.0 * label_radius_mm_ : 2.0 * sigma_h;
    const double lo = p.depth_mm - p.reach_mm - kSliceMarginMm;
    const double hi = p.depth_mm + p.reach_mm + kSliceMarginMm;
    ImageMixtureSlice& slice = slices[static_cast<size_t>(i)];
    slice = by_label ? input.mixture.label_slice(g.label, lo, hi) : input.mixture.depth_slice(lo, hi);
    if (slice.size == 0 || !capped) continue;
    if (keep) {
      kept_at[static_cast<size_t>(i)] = kept_size;
      add_and_keep_overlaps(p, slice, coverage.covered + slice.first, kept + kept_size);
      kept_size += 2 * slice.size;
    } else {
      add_overlaps(p, slice, coverage.covered + slice.first);
    }
  }
  double energy = 0.0;
  if (capped) {
    // sum_q min(S_q, c D_qq); a q at its cap is closed: its pairs leave the gradient's sums.
    const double* sigma2 = by_label ? input.mixture.sigma2_by_label() : input.mixture.sigma2_by_depth();
    for (std::size_t k = 0; k < n; ++k) {
      const double cap = coverage_cap_ * std::numbers::pi * sigma2[k];
      const bool open = coverage.covered[k] < cap;
      energy += open ? coverage.covered[k] : cap;
      coverage.open[k] = open ? 1.0 : 0.0;
    }
    if (dE_dcentres == nullptr) return energy * inv_norm;
  }
  for (int i = 0; i < hand.gaussian_count(); ++i) {
    const ImageMixtureSlice& slice = slices[static_cast<size_t>(i)];
    if (slice.size == 0) continue;
    const ProjectedGaussian& p = projected[static_cast<size_t>(i)];
    const PairSums sums =
        capped ? open_pair_sums(p, slice, coverage.open + slice.first, kept + kept_at[static_cast<size_t>(i)])
               : pair_sums(p, slice);
    if (!capped) energy += sums.overlap;
    if (dE_dcentres == nullptr) continue;
    const Vector3d& mu = hand.centre(i);
    const double z = mu.z();
    const double sigma_h = gaussians[static_cast<size_t>(i)].sigma_mm;
    const double sp = p.sigma;
    const double de_du = -sums.weight_du;
    const double de_dv = -sums.weight_dv;
    const double de_ds = sums.overlap * 2.0 / sp - 2.0 * sp * sums.weight + sp * sums.weight_r2;
    const double de_dd = -sums.depth_sign / p.reach_mm;  // dDelta/dd_p = -sign(d_p - d_q) / reach
    // Chain through the projection to the 3D mean.
    Vector3d de_dmu;
    de_dmu.x() = de_du * cam.fx / z;
    de_dmu.y() = de_dv * cam.fy / z;
    de_dmu.z() = -de_du * cam.fx * mu.x() / (z * z) - de_dv * cam.fy * mu.y() / (z * z) - de_ds * sigma_h * f / (z * z) +
                 de_dd;
    dE_dcentres->col(i) += de_dmu * inv_norm;
  }
  return energy * inv_norm;
}

double CollisionTerm::evaluate(const HandModel& model, const PosedHand& hand, PoseGradient* gradient) const {
  return chain_to_pose(hand, gradient,
                       [&](CentreGradients* dE_dcentres) { return evaluate_centres(model, hand, dE_dcentres); });
}

double CollisionTerm::evaluate_centres(const HandModel& model, const PosedHand& hand,
                                       CentreGradients* dE_dcentres) const {
  const auto& gaussians = model.gaussians();
  const auto n = static_cast<size_t>(hand.gaussian_count());
  std::array<double, kMaxModelGaussians> x{};
  std::array<double, kMaxModelGaussians> y{};
  std::array<double, kMaxModelGaussians> z{};
  std::array<double, kMaxModelGaussians> sigma2{};
  for (size_t i = 0; i < n; ++i) {
    const Vector3d& c = hand.centre(static_cast<int>(i));
    x[i] = c.x();
    y[i] = c.y();
    z[i] = c.z();
    sigma2[i] = gaussians[i].sigma_mm * gaussians[i].sigma_mm;
  }
  const double inv_norm = 1.0 / model.self_similarity();
  const auto& pairs = model.collision_pairs();
  // Each chunk's dE/dmu_a per pair (x, y, z), then scattered to the columns: into three arrays,
  // each sum in the pairs' order as into the columns themselves. The pairs come ordered by a (then
  // b, HandModel), so a's sums run in registers along each run of pairs of one a.
  std::array<double, 3 * kCollisionChunk> de;
  std::array<double, kMaxModelGaussians> gx{};
  std::array<double, kMaxModelGaussians> gy{};
  std::array<double, kMaxModelGaussians> gz{};
  const bool want = dE_dcentres != nullptr;
  if (want) {
    for (size_t i = 0; i < n; ++i) {
      gx[i] = (*dE_dcentres)(0, static_cast<Eigen::Index>(i));
      gy[i] = (*dE_dcentres)(1, static_cast<Eigen::Index>(i));
      gz[i] = (*dE_dcentres)(2, static_cast<Eigen::Index>(i));
    }
  }
  double energy = 0.0;
  for (size_t begin = 0; begin < pairs.size(); begin += kCollisionChunk) {
    const size_t count = std::min(kCollisionChunk, pairs.size() - begin);
    energy += collision_overlaps(pairs.data() + begin, count, x.data(), y.data(), z.data(), sigma2.data(), inv_norm,
                                 de.data());
    if (!want) continue;
    size_t k = 0;
    while (k < count) {
      const auto a = static_cast<size_t>(pairs[begin + k].a);
      double ax = gx[a];
      double ay = gy[a];
      double az = gz[a];
      for (; k < count && static_cast<size_t>(pairs[begin + k].a) == a; ++k) {
        const auto b = static_cast<size_t>(pairs[begin + k].b);
        ax += de[k];
        ay += de[kCollisionChunk + k];
        az += de[2 * kCollisionChunk + k];
        gx[b] -= de[k];
        gy[b] -= de[kCollisionChunk + k];
        gz[b] -= de[2 * kCollisionChunk + k];
      }
      gx[a] = ax;
      gy[a] = ay;
      gz[a] = az;
    }
  }
  if (want) {
    for (size_t i = 0; i < n; ++i) {
      (*dE_dcentres)(0, static_cast<Eigen::Index>(i)) = gx[i];
      (*dE_dcentres)(1, static_cast<Eigen::Index>(i)) = gy[i];
      (*dE_dcentres)(2, static_cast<Eigen::Index>(i)) = gz[i];
    }
  }
  return energy * inv_norm;
}

void HandObstacle::assign(const HandModel& model, const PosedHand& hand, bool mirror_x) {
  const auto n = static_cast<size_t>(hand.gaussian_count());
  assert(model.gaussians().size() == n && "the posed hand is of this model");
  x_mm_.resize(n);
  y_mm_.resize(n);
  z_mm_.resize(n);
  sigma_mm_.resize(n);
  sigma2_mm2_.resize(n);
  const double sign_x = mirror_x ? -1.0 : 1.0;
  Vector3d sum = Vector3d::Zero();
  max_sigma_mm_ = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const Vector3d& c = hand.centre(static_cast<int>(i));
    x_mm_[i] = sign_x * c.x();
    y_mm_[i] = c.y();
    z_mm_[i] = c.z();
    const double sigma = model.gaussians()[i].sigma_mm;
    sigma_mm_[i] = sigma;
    sigma2_mm2_[i] = sigma * sigma;
    max_sigma_mm_ = std::max(max_sigma_mm_, sigma);
    sum += centre(static_cast<int>(i));
  }
  bound_centre_mm_ = n == 0 ? Vector3d::Zero() : Vector3d(sum / static_cast<double>(n));
  bound_radius_mm_ = 0.0;
  for (size_t i = 0; i < n; ++i) {
    bound_radius_mm_ = std::max(bound_radius_mm_, (centre(static_cast<int>(i)) - bound_centre_mm_).norm());
  }
}

void HandObstacle::clear() {
  x_mm_.clear();
  y_mm_.clear();
  z_mm_.clear();
  sigma_mm_.clear();
  sigma2_mm2_.clear();
  bound_centre_mm_.setZero();
  bound_radius_mm_ = 0.0;
  max_sigma_mm_ = 0.0;
}

double InterHandCollisionTerm::evaluate(const HandModel& model, const PosedHand& hand, const HandObstacle& other,
                                        PoseGradient* gradient) const {
  return chain_to_pose(hand, gradient, [&](CentreGradients* dE_dcentres) {
    return evaluate_centres(model, hand, other, dE_dcentres);
  });
}

double InterHandCollisionTerm::evaluate_centres(const HandModel& model, const PosedHand& hand,
                                                const HandObstacle& other, CentreGradients* dE_dcentres) const {
  if (other.empty()) return 0.0;
  const auto& gaussians = model.gaussians();
  const double inv_norm = 1.0 / model.self_similarity();
  const double max_sigma2 = other.max_sigma_mm() * other.max_sigma_mm();
  double energy = 0.0;
  for (int i = 0; i < hand.gaussian_count(); ++i) {
    const Vector3d& c = hand.centre(i);
    const double sigma = gaussians[static_cast<size_t>(i)].sigma_mm;
    const double sigma2 = sigma * sigma;
    // Every pair of this Gaussian counts 0 (|mu_p - mu_q|^2 > 2 S kMaxOverlapExponent) when its
    // reach, grown by a hair against rounding, misses the other hand's bounding sphere.
    const double reach_mm = std::sqrt(2.0 * kMaxOverlapExponent * (sigma2 + max_sigma2)) * (1.0 + 1e-9);
    if ((c - other.bound_centre_mm()).norm() > other.bound_radius_mm() + reach_mm) continue;
    const ObstacleSums sums = obstacle_sums(c, sigma2, other);
    energy += sums.overlap;
    if (dE_dcentres != nullptr) {
      dE_dcentres->col(i) -= inv_norm * Vector3d(sums.weight_dx, sums.weight_dy, sums.weight_dz);
    }
  }
  return energy * inv_norm;
}

namespace {
constexpr double kFreeSpaceSlackMm = 5.0;   // s of E_free
constexpr double kFreeSpaceScaleMm = 10.0;  // l of E_free
}  // namespace

double FreeSpaceTerm::evaluate(const PosedHand& hand, const DepthInput& input, PoseGradient* gradient) const {
  return chain_to_pose(hand, gradient,
                       [&](CentreGradients* dE_dcentres) { return evaluate_centres(hand, input, dE_dcentres); });
}

double FreeSpaceTerm::evaluate_centres(const PosedHand& hand, const DepthInput& input,
                                       CentreGradients* dE_dcentres) const {
  const FreeSpaceMap& map = input.free_space;
  const int n = hand.gaussian_count();
  if (map.empty() || n == 0) return 0.0;
  const auto& cam = input.camera;
  const double f = cam.focal();
  const double inv_norm = 1.0 / (n * kFreeSpaceScaleMm * kFreeSpaceScaleMm);
  double energy = 0.0;
  for (int i = 0; i < n; ++i) {
    const Vector3d& mu = hand.centre(i);
    const double z = mu.z();
    if (z < 1.0) continue;  // behind or at the camera: no projection
    const Eigen::Vector2d uv = cam.project(mu);
    const FreeSpaceMap::Sample d = map.sample(uv.x(), uv.y());
    const double excess = d.distance_px * z / f - kFreeSpaceSlackMm;
    if (excess <= 0.0) continue;
    energy += excess * excess;
    if (dE_dcentres == nullptr) continue;
    const double de_dr = 2.0 * excess * inv_norm;
    const double dr_du = z / f * d.d_du;
    const double dr_dv = z / f * d.d_dv;
    Vector3d dr_dmu;
    dr_dmu.x() = dr_du * cam.fx / z;
    dr_dmu.y() = dr_dv * cam.fy / z;
    dr_dmu.z() = d.distance_px / f - dr_du * cam.fx * mu.x() / (z * z) - dr_dv * cam.fy * mu.y() / (z * z);
    dE_dcentres->col(i) += de_dr * dr_dmu;
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

PoseEnergy::PoseEnergy(SimilarityFactor factor, const EnergyWeights& weights, double label_share)
    : factor_(factor),
      weights_(weights),
      similarity_(factor == SimilarityFactor::kDepthAndLabel ? SimilarityFactor::kDepth : factor, weights.label_radius_mm,
                  weights.coverage_cap),
      label_similarity_(SimilarityFactor::kLabel, weights.label_radius_mm, weights.coverage_cap),
      label_share_(label_share),
      smoothness_(weights.smoothness_translation_per_mm) {}

double PoseEnergy::evaluate(const EnergyFrame& frame, const PoseParams& params, PosedHand& hand,
                            PoseGradient* gradient, EnergyBreakdown* breakdown) const {
  hand.update(*frame.model, params);
  // E_sim and E_col are differentiated with respect to the model Gaussians' centres and chained to
  // Theta once, together.
  const int n = hand.gaussian_count();
  CentreGradients g_sim = CentreGradients::Zero(3, n);
  CentreGradients g_col = CentreGradients::Zero(3, n);
  PoseGradient g_lim = PoseGradient::Zero();
  PoseGradient g_smo = PoseGradient::Zero();
  const bool want = gradient != nullptr;
  EnergyBreakdown e;
  e.similarity = similarity_.evaluate_centres(*frame.model, hand, *frame.input, want ? &g_sim : nullptr, frame.fronts);
  if (factor_ == SimilarityFactor::kDepthAndLabel) {
    CentreGradients g_label = CentreGradients::Zero(3, n);
    const double label =
        label_similarity_.evaluate_centres(*frame.model, hand, *frame.input, want ? &g_label : nullptr, frame.fronts);
    e.similarity = (1.0 - label_share_) * e.similarity + label_share_ * label;
    g_sim = (1.0 - label_share_) * g_sim + label_share_ * g_label;
  }
  if (weights_.collision != 0.0) e.collision = collision_.evaluate_centres(*frame.model, hand, want ? &g_col : nullptr);
  if (weights_.limits != 0.0) e.limits = limits_.evaluate(*frame.model, params, want ? &g_lim : nullptr);
  if (weights_.smoothness != 0.0 && frame.previous != nullptr && frame.before_previous != nullptr) {
    e.smoothness = smoothness_.evaluate(params, *frame.previous, *frame.before_previous, want ? &g_smo : nullptr);
  }
  CentreGradients g_free;
  if (weights_.free_space != 0.0) {
    if (want) g_free = CentreGradients::Zero(3, n);
    e.free_space = free_space_.evaluate_centres(hand, *frame.input, want ? &g_free : nullptr);
  }
  // E_hand only with another hand: without one, the sums (and their rounding) are exactly eq. 2's.
  const bool other_hand = frame.other_hand != nullptr && weights_.inter_hand != 0.0;
  CentreGradients g_hand;
  if (other_hand) {
    if (want) g_hand = CentreGradients::Zero(3, n);
    e.inter_hand = inter_hand_.evaluate_centres(*frame.model, hand, *frame.other_hand, want ? &g_hand : nullptr);
  }
  e.total = e.similarity - weights_.collision * e.collision - weights_.limits * e.limits -
            weights_.smoothness * e.smoothness;
  if (other_hand) e.total -= weights_.inter_hand * e.inter_hand;
  if (weights_.free_space != 0.0) e.total -= weights_.free_space * e.free_space;
  PoseGradient g_unseen = PoseGradient::Zero();
  if (weights_.unseen_fingers != 0.0 && frame.unseen != nullptr) {
    e.unseen = unseen_finger_energy(*frame.unseen, params, want ? &g_unseen : nullptr);
    e.total -= weights_.unseen_fingers * e.unseen;
  }
  if (want) {
    *gradient = -weights_.limits * g_lim - weights_.smoothness * g_smo - weights_.unseen_fingers * g_unseen;
    g_sim -= weights_.collision * g_col;
    if (other_hand) g_sim -= weights_.inter_hand * g_hand;
    if (weights_.free_space != 0.0) g_sim -= weights_.free_space * g_free;
    hand.add_centre_gradients(g_sim, *gradient);
  }
  if (breakdown != nullptr) *breakdown = e;
  return e.total;
}

}  // namespace handtrack
