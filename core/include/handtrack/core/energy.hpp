#pragma once
// The pose fitting energy of Sec. 4.1, maximised over the pose Theta:
//
//   E(Theta) = E_sim - w_c E_col - w_l E_lim - w_s E_smo                    (paper eq. 2)
//
// minus w_f E_free (ours): model parts over the background, which E_sim does not see; minus w_u
// E_unseen (ours, unseen_fingers.hpp): fingers the labels do not see on a hand facing the camera
// are curled; and, where another hand is tracked at the same time (issue 14; ours, the paper has
// one hand), minus w_h E_hand, the same Gaussian overlap as E_col between this hand and the other
// (fixed) one.
//
// One class per term; each returns its value and adds its analytic gradient (d term / d Theta)
// into a PoseGradient when asked. The detection-guided energy of Sec. 4.3 is the same energy with
// the label similarity factor in E_sim.

#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/hand_model.hpp"
#include "handtrack/core/kinematics.hpp"
#include "handtrack/core/pose.hpp"
#include "handtrack/core/surface_fronts.hpp"
#include "handtrack/core/unseen_fingers.hpp"

#include <vector>

namespace handtrack {

// The coverage cap c measured best of 1, 1.5, 2 and 3 (EnergyWeights::coverage_cap): at a true
// pose the model covers the median image Gaussian 1.1-1.5 times and 90 % of them under about 2.
inline constexpr double kMeasuredCoverageCap = 2.0;

// w_s measured on the broadened benchmark (docs/TRACKER.md, "w_s, the weight of E_smo"): from 2 and
// the paper's 1 down through 0.5, 0.25 and 0.1 each step gained on every set of subjects it was
// measured on; 0 (no E_smo) left the fingertips' frame-to-frame jitter 30-70 % above w_s = 1.
inline constexpr double kMeasuredSmoothness = 0.1;
inline constexpr double kPapersSmoothness = 1.0;  // w_s of Sec. 4.1

// w_c while late fusion tracks, measured on the broadened benchmark (docs/TRACKER.md, "w_c while
// tracking"): 0.5 against the paper's 1 on each of four sets of subjects; 0.25 and 2 were worse.
inline constexpr double kMeasuredTrackingCollision = 0.5;

// w_u measured on the broadened benchmark (docs/TRACKER.md, "Unseen fingers curl"): the back view
// 20.6-21.7 -> 17.7-18.3 mm and all views 0.26-0.87 mm better on each of four sets of three
// subjects; 0.03 and 0.05 were worse than 0.01 on a first subset.
inline constexpr double kMeasuredUnseenFingers = 0.01;

struct EnergyWeights {
  // w_c, Sec. 4.1 (1): the (re)start search and its checks, depth-only tracking and the calibration.
  double collision = 1.0;
  // w_c while late fusion tracks (ours): its particles' energies, where the coverage cap and E_free
  // also hold. Fingers that touch in a fist overlap as collision proxies smaller than the skin would
  // not, and at the paper's w_c E_col charges the true pose more than a wrong one there. Kept out of
  // the search: with 0.5 there, 4 of the 17 real SR305 frames fitted as left hands (none with 1);
  // and out of depth-only tracking, which 0.5 makes 0.9 mm worse.
  double tracking_collision = kMeasuredTrackingCollision;
  double limits = 0.2;      // w_l, Sec. 4.1
  // w_s, Sec. 4.1: the paper gives 1, which balances E_smo in our units (metres and radians) but is
  // not a value it reports tuning. kMeasuredSmoothness (0.1, the default) against 1: 1.1-1.7 mm on
  // each of four sets of three subjects, about 2 mm on the paper's seven motions; the raw jitter's
  // median 12-21 % more, its p95 and the lag less (docs/FILTER.md).
  double smoothness = kMeasuredSmoothness;
  // w_h of E_hand: ours (issue 14), the paper tracks one hand. 1.0 weighs an overlap with the other
  // hand as much as the same overlap between two fingers of this hand at the paper's w_c (twice
  // that at tracking_collision).
  double inter_hand = 1.0;
  // w_f of E_free: ours, the paper has no term for model parts over the background. Measured over
  // 0 / 1 / 2 / 3 / 5 / 10 on the broadened benchmark (docs/TRACKER.md, "Free space"): 1 was best
  // over six seeds; 0 is the paper's energy. PoseTracker uses it with late fusion only.
  double free_space = 1.0;
  // w_u of E_unseen: ours (unseen_fingers.hpp), the paper has no prior on fingers it cannot see.
  // PoseTracker uses it while late fusion tracks (it needs the part labels and a previous pose).
  double unseen_fingers = kMeasuredUnseenFingers;
  // c of E_sim's coverage cap: ours, the paper's eq. 6 has none. An image Gaussian q earns at most
  // c D_qq, however many model Gaussians overlap it, so that model parts laid over a surface that
  // other parts already explain (fingers folded onto the back of the hand, where the camera sees
  // none) earn nothing. Both factors, depth and label. kMeasuredCoverageCap (2, the default):
  // 0.75-1.16 mm on each of four sets of three subjects of the broadened benchmark, the back view
  // 1.3-3.3 mm, head-mounted 1.7-2.9 mm (docs/TRACKER.md, "E_sim's coverage cap"); 0: eq. 6.
  // PoseTracker uses it for tracking with late fusion only: the (re)start search and its checks
  // keep eq. 6 (search_weights, tracker.hpp).
  double coverage_cap = kMeasuredCoverageCap;
  // k_max of the surface fronts (surface_fronts.hpp; ours): model Gaussians seen at a slant have
  // the surface the camera sees up to k_max sigma_h in front of them. 1: eq. 7's d_p = z - sigma_h.
  // PoseTracker uses it while late fusion tracks (the fronts come from the previous pose).
  double slant_front = kMeasuredSlantFront;
  // R_i, Sec. 4.3: radius of influence of the label similarity factor.
  double label_radius_mm = 200.0;
  // E_smo mixes units; the paper's w_s = 1 balances it in SI units (metres and radians), so
  // translations enter E_smo in metres.
  double smoothness_translation_per_mm = 1e-3;
};

// Which similarity factor E_sim uses.
enum class SimilarityFactor {
  kDepth,  // Delta(p,q) = max(0, 1 - |d_p - d_q| / (2 sigma_h))                        (eq. 7)
  kLabel,  // Delta_l(p,q) = [l_p = l_q] max(0, 1 - |d_p - d_q| / (2 R_i))            (Sec. 4.3)
  // The detection-guided energy read as "an augmented version of the depth-only energy" (Sec. 1):
  // E_sim = (1 - s) E_sim[Delta] + s E_sim[Delta_l] with the label share s (PoseEnergy's
  // constructor; 0.5 for the guided energy); a weighted mean keeps E_sim on the scale of eq. 2, so
  // w_c, w_l and w_s keep their balance. PoseEnergy sums two SimilarityTerms for it.
  kDepthAndLabel,
};

// E_sim = 1/E(C_I,C_I) * sum_{p in C_p} sum_{q in C_I} Delta(p,q) D_pq                  (eq. 6)
// or, with a coverage cap c > 0 (EnergyWeights::coverage_cap; ours),
//   E_sim = 1/E(C_I,C_I) * sum_{q in C_I} min(S_q, c D_qq),  S_q = sum_{p in C_p} Delta(p,q) D_pq,
// D_qq = pi sigma_q^2 (q's overlap with itself): the pairs of a q over its cap add nothing to the
// gradient either.
// with the projected model Gaussian (Sec. 3.2, scaled orthographic):
//   mu_p = K [I|0] mu_h,  sigma_p = sigma_h f / z,  d_p = z - k_p sigma_h
// k_p = 1 (the paper), or a frame's SurfaceFronts (surface_fronts.hpp; constant in the pose)
// and the 2D overlap D_pq = 2 pi sigma_p^2 sigma_q^2 / S exp(-|mu_p - mu_q|^2 / 2S),
// S = sigma_p^2 + sigma_q^2. Gradient per model Gaussian:
//   dD/dmu_p = -D (mu_p - mu_q) / S
//   dD/dsigma_p = D (2/sigma_p - 2 sigma_p / S + |mu_p - mu_q|^2 sigma_p / S^2)
//   dDelta/dd_p = -sign(d_p - d_q) / (2 sigma_h)    (resp. / (2 R_i))
// chained through the projection to the 3D mean and then to Theta (PosedHand).
//
// The pair sums read DepthInput::mixture (C_I as structure-of-arrays, built once per frame): per
// model Gaussian only the slice of image Gaussians within the depth factor's reach (and, for the
// label factor, of its label), summed branch-free in SIMD with an exp that needs no libm call.
// With a cap, two passes: the first sums S_q and keeps each pair's Delta D_pq and signed D_pq
// (ImageMixture::pair_scratch), the second sums the gradient from them over the open q.
class SimilarityTerm {
 public:
  // coverage_cap: c above (0: eq. 6).
  SimilarityTerm(SimilarityFactor factor, double label_radius_mm, double coverage_cap = 0.0)
      : factor_(factor), label_radius_mm_(label_radius_mm), coverage_cap_(coverage_cap) {}
  double evaluate(const HandModel& model, const PosedHand& hand, const DepthInput& input, PoseGradient* gradient) const;
  // E_sim, adding dE_sim/d centre of each model Gaussian into *dE_dcentres when not null; with
  // `fronts`, d_p = z - k_p sigma_h (k_p = fronts->sigmas), else z - sigma_h.
  double evaluate_centres(const HandModel& model, const PosedHand& hand, const DepthInput& input,
                          CentreGradients* dE_dcentres, const SurfaceFronts* fronts = nullptr) const;

 private:
  SimilarityFactor factor_;
  double label_radius_mm_;
  double coverage_cap_;
};

// E_col = 1/E(C_h,C_h) * sum_{p} sum_{q > p} D_pq over the model's collision pairs      (eq. 8)
// with the 3D overlap D_pq = (2 pi)^(3/2) (s_p^2 s_q^2 / S)^(3/2) exp(-|mu_p - mu_q|^2 / 2S);
// dD/dmu_p = -D (mu_p - mu_q) / S = -dD/dmu_q. E(C_h,C_h) is taken at the rest pose.
class CollisionTerm {
 public:
  double evaluate(const HandModel& model, const PosedHand& hand, PoseGradient* gradient) const;
  // E_col, adding dE_col/d centre of each model Gaussian into *dE_dcentres when not null.
  double evaluate_centres(const HandModel& model, const PosedHand& hand, CentreGradients* dE_dcentres) const;
};

// The other hand, for E_hand: fixed isotropic 3D Gaussians (its posed model) in the camera frame
// of the hand being fitted, mm. A left hand is fitted as the right hand of the image mirrored about
// x = 0 (Tracker), so a pose fitted in one hand's frame enters the other's with x negated when
// exactly one of the two hands is a left hand: assign(..., mirror_x = this_is_left != other_is_left).
// Storage is reused: no allocation after the first assign() of a model of the same size.
class HandObstacle {
 public:
  // The Gaussians of `hand` (posed `model`), x negated when `mirror_x`.
  void assign(const HandModel& model, const PosedHand& hand, bool mirror_x);
  void clear();

  [[nodiscard]] bool empty() const { return x_mm_.empty(); }
  [[nodiscard]] int size() const { return static_cast<int>(x_mm_.size()); }
  [[nodiscard]] Eigen::Vector3d centre(int i) const {
    const auto k = static_cast<size_t>(i);
    return {x_mm_[k], y_mm_[k], z_mm_[k]};
  }
  [[nodiscard]] double sigma_mm(int i) const { return sigma_mm_[static_cast<size_t>(i)]; }
  // A sphere holding every centre, and the largest sigma: lets E_hand skip far-apart hands.
  [[nodiscard]] const Eigen::Vector3d& bound_centre_mm() const { return bound_centre_mm_; }
  [[nodiscard]] double bound_radius_mm() const { return bound_radius_mm_; }
  [[nodiscard]] double max_sigma_mm() const { return max_sigma_mm_; }
  // Structure of arrays, for the vectorised pair sums.
  [[nodiscard]] const double* x_mm() const { return x_mm_.data(); }
  [[nodiscard]] const double* y_mm() const { return y_mm_.data(); }
  [[nodiscard]] const double* z_mm() const { return z_mm_.data(); }
  [[nodiscard]] const double* sigma2_mm2() const { return sigma2_mm2_.data(); }

 private:
  std::vector<double> x_mm_;
  std::vector<double> y_mm_;
  std::vector<double> z_mm_;
  std::vector<double> sigma_mm_;
  std::vector<double> sigma2_mm2_;
  Eigen::Vector3d bound_centre_mm_ = Eigen::Vector3d::Zero();
  double bound_radius_mm_ = 0.0;
  double max_sigma_mm_ = 0.0;
};

// E_hand = 1/E(C_h,C_h) * sum_{p in C_h} sum_{q in other hand} D_pq             (ours, issue 14)
// with E_col's 3D overlap D_pq (eq. 8) and normalisation (E(C_h,C_h) of this hand at rest), over
// every pair of one Gaussian of each hand: hands that touch must not interpenetrate. The other
// hand does not move, so only this hand's centres have a gradient:
//   dE_hand/dmu_p = -1/E(C_h,C_h) * sum_q D_pq (mu_p - mu_q) / S_pq
// Pairs with |mu_p - mu_q|^2 / 2S > 30 count 0 (as in E_col), and a model Gaussian whose reach
// misses the other hand's bounding sphere is skipped whole: hands apart cost ~1 test per Gaussian.
class InterHandCollisionTerm {
 public:
  double evaluate(const HandModel& model, const PosedHand& hand, const HandObstacle& other,
                  PoseGradient* gradient) const;
  // E_hand, adding dE_hand/d centre of each model Gaussian into *dE_dcentres when not null.
  double evaluate_centres(const HandModel& model, const PosedHand& hand, const HandObstacle& other,
                          CentreGradients* dE_dcentres) const;
};

// E_free = 1/|C_h| * sum_p (max(0, r_p - s) / l)^2                                      (ours)
// r_p = D(u_p, v_p) z_p / f: how deep (mm at the Gaussian's depth) the projected centre of model
// Gaussian p lies in free space, where the camera sees through to the background or sees nothing
// (FreeSpaceMap: D in px); slack s = 5 mm for ragged edges, scale l = 10 mm. The centres of a hand's
// Gaussians lie inside its silhouette, so a pose that fits pays nothing; a finger the camera cannot
// see, left stretched out over the background, pays for each of its Gaussians. With e_p = max(0,
// r_p - s) and the projection u = fx x/z + cx, v = fy y/z + cy:
//   dE/dr_p = 2 e_p / (|C_h| l^2)
//   dr_p/dx = z/f dD/du fx/z,  dr_p/dy = z/f dD/dv fy/z,
//   dr_p/dz = D/f - z/f (dD/du fx x + dD/dv fy y) / z^2
// (D bilinear between pixel centres, so its gradient is exact between them).
class FreeSpaceTerm {
 public:
  double evaluate(const PosedHand& hand, const DepthInput& input, PoseGradient* gradient) const;
  // E_free, adding dE_free/d centre of each model Gaussian into *dE_dcentres when not null.
  double evaluate_centres(const PosedHand& hand, const DepthInput& input, CentreGradients* dE_dcentres) const;
};

// E_lim = sum_j (theta_j^l - theta_j)^2 below the limit, (theta_j - theta_j^h)^2 above   (eq. 9)
class JointLimitTerm {
 public:
  double evaluate(const HandModel& model, const PoseParams& params, PoseGradient* gradient) const;
};

// E_smo = sum_j (0.5 (Theta_j^{t-2} + Theta_j^t) - Theta_j^{t-1})^2                    (eq. 10)
// Translations in metres (EnergyWeights::smoothness_translation_per_mm).
class SmoothnessTerm {
 public:
  explicit SmoothnessTerm(double translation_per_mm) : translation_per_mm_(translation_per_mm) {}
  double evaluate(const PoseParams& params, const PoseParams& previous, const PoseParams& before_previous,
                  PoseGradient* gradient) const;

 private:
  double translation_per_mm_;
};

// The value of each term at one pose (for logs, evaluation and tests).
struct EnergyBreakdown {
  double similarity = 0.0;
  double collision = 0.0;
  double limits = 0.0;
  double smoothness = 0.0;
  double inter_hand = 0.0;  // E_hand; 0 without EnergyFrame::other_hand
  double free_space = 0.0;  // E_free; 0 while w_f = 0
  double unseen = 0.0;      // E_unseen; 0 without EnergyFrame::unseen
  double total = 0.0;
};

// Everything the energy needs about the current frame.
struct EnergyFrame {
  const HandModel* model = nullptr;
  const DepthInput* input = nullptr;
  const PoseParams* previous = nullptr;         // Theta^{t-1}; E_smo is off when either is null
  const PoseParams* before_previous = nullptr;  // Theta^{t-2}
  const HandObstacle* other_hand = nullptr;     // E_hand is off when null
  const UnseenFingers* unseen = nullptr;        // E_unseen is off when null
  const SurfaceFronts* fronts = nullptr;        // E_sim's d_p = z - sigma_h when null (eq. 7)
};

class PoseEnergy {
 public:
  // `label_share`: s of SimilarityFactor::kDepthAndLabel (unused by the other factors).
  PoseEnergy(SimilarityFactor factor, const EnergyWeights& weights, double label_share = 0.5);

  // E(Theta) (eq. 2; minus w_f E_free, minus w_u E_unseen when frame.unseen is set, and minus w_h
  // E_hand when frame.other_hand is set); adds dE/dTheta into *gradient (which it zeroes first)
  // when not null. `hand` is scratch space for the posed model.
  double evaluate(const EnergyFrame& frame, const PoseParams& params, PosedHand& hand, PoseGradient* gradient,
                  EnergyBreakdown* breakdown = nullptr) const;
  [[nodiscard]] const EnergyWeights& weights() const { return weights_; }
  [[nodiscard]] SimilarityFactor factor() const { return factor_; }

 private:
  SimilarityFactor factor_;
  EnergyWeights weights_;
  SimilarityTerm similarity_;
  SimilarityTerm label_similarity_;  // kDepthAndLabel only: the label part of E_sim
  double label_share_;
  CollisionTerm collision_;
  InterHandCollisionTerm inter_hand_;
  FreeSpaceTerm free_space_;
  JointLimitTerm limits_;
  SmoothnessTerm smoothness_;
};

}  // namespace handtrack
