#pragma once
// The pose fitting energy of Sec. 4.1, maximised over the pose Theta:
//
//   E(Theta) = E_sim - w_c E_col - w_l E_lim - w_s E_smo                    (paper eq. 2)
//
// One class per term; each returns its value and adds its analytic gradient (d term / d Theta)
// into a PoseGradient when asked. The detection-guided energy of Sec. 4.3 is the same energy with
// the label similarity factor in E_sim.

#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/hand_model.hpp"
#include "handtrack/core/kinematics.hpp"
#include "handtrack/core/pose.hpp"

#include <vector>

namespace handtrack {

struct EnergyWeights {
  double collision = 1.0;   // w_c, Sec. 4.1
  double limits = 0.2;      // w_l, Sec. 4.1
  double smoothness = 1.0;  // w_s, Sec. 4.1
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
// with the projected model Gaussian (Sec. 3.2, scaled orthographic):
//   mu_p = K [I|0] mu_h,  sigma_p = sigma_h f / z,  d_p = z - sigma_h
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
class SimilarityTerm {
 public:
  SimilarityTerm(SimilarityFactor factor, double label_radius_mm) : factor_(factor), label_radius_mm_(label_radius_mm) {}
  double evaluate(const HandModel& model, const PosedHand& hand, const DepthInput& input, PoseGradient* gradient) const;
  // E_sim, adding dE_sim/d centre of each model Gaussian into *dE_dcentres when not null.
  double evaluate_centres(const HandModel& model, const PosedHand& hand, const DepthInput& input,
                          CentreGradients* dE_dcentres) const;

 private:
  SimilarityFactor factor_;
  double label_radius_mm_;
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
  double total = 0.0;
};

// Everything the energy needs about the current frame.
struct EnergyFrame {
  const HandModel* model = nullptr;
  const DepthInput* input = nullptr;
  const PoseParams* previous = nullptr;         // Theta^{t-1}; E_smo is off when either is null
  const PoseParams* before_previous = nullptr;  // Theta^{t-2}
};

class PoseEnergy {
 public:
  // `label_share`: s of SimilarityFactor::kDepthAndLabel (unused by the other factors).
  PoseEnergy(SimilarityFactor factor, const EnergyWeights& weights, double label_share = 0.5);

  // E(Theta) (eq. 2); adds dE/dTheta into *gradient (which it zeroes first) when not null.
  // `hand` is scratch space for the posed model.
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
  JointLimitTerm limits_;
  SmoothnessTerm smoothness_;
};

}  // namespace handtrack
