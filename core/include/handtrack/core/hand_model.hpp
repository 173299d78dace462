#pragma once
// The hand model of Sec. 3.2: a kinematic skeleton with 26 pose parameters and a volumetric
// extent C_h = sum_h w_h G_h(x) of isotropic 3D Gaussians, each attached to a bone and carrying
// one of the 12 part labels (Sec. 4.3). Sec. 6: three scale parameters (hand length, hand width,
// Gaussian sigma) turn the default adult hand into a user-specific one.
//
// Hand frame (origin at the wrist joint, mm): x toward the thumb side, y toward the fingers,
// z = x cross y, out of the palm. Finger f is a chain at base b_f with rest direction d_f and
// palmar normal n_f: rotate by `abd` about n_f, then by flex1 about a_f = d_f x n_f (in the
// abducted frame), bone 1 of length L1 along the rotated d_f, flex2 about the current a_f, bone 2,
// flex3, bone 3. Positive flexion curls toward the palm.

#include "handtrack/core/hand_layout.hpp"
#include "handtrack/core/pose.hpp"

#include <Eigen/Core>

#include <array>
#include <vector>

namespace handtrack {

inline constexpr int kBonesPerFinger = 3;
inline constexpr int kPalmBone = kNumFingers * kBonesPerFinger;  // bones 0..14 are finger bones

struct FingerChain {
  Eigen::Vector3d base;       // hand frame, mm
  Eigen::Vector3d direction;  // unit, rest direction of the chain
  Eigen::Vector3d palmar;     // unit, orthogonal to direction; flexion moves toward it
  std::array<double, kBonesPerFinger> length_mm{};
};

struct ModelGaussian {
  int bone = kPalmBone;          // 3 * finger + segment, or kPalmBone
  double along = 0.0;            // finger bones: position as a fraction of the bone, from its start
  Eigen::Vector3d palm_position = Eigen::Vector3d::Zero();  // palm Gaussians: hand-frame mean, mm
  double sigma_mm = 10.0;        // sigma_h: its 1-sigma sphere is the hand's surface (Sec. 3.2)
  int label = kPalm;             // preassigned part label (Sec. 4.3)
};

// Sec. 6: "a default hand model is scaled using three parameters: hand length, width, and
// variance of Gaussians".
struct HandScale {
  double length = 1.0;
  double width = 1.0;
  double sigma = 1.0;
  friend bool operator==(const HandScale&, const HandScale&) = default;
};

struct JointLimit {
  double lo = 0.0;
  double hi = 0.0;
};

// A pair of model Gaussians whose overlap counts as a collision (E_col).
struct CollisionPair {
  int a = 0;
  int b = 0;
};

class HandModel {
 public:
  // The default adult right hand (43 Gaussians), optionally scaled.
  static HandModel default_adult(const HandScale& scale = {});

  [[nodiscard]] const std::array<FingerChain, kNumFingers>& fingers() const { return fingers_; }
  [[nodiscard]] const std::vector<ModelGaussian>& gaussians() const { return gaussians_; }
  [[nodiscard]] const std::array<JointLimit, kNumJointAngles>& limits() const { return limits_; }
  [[nodiscard]] const std::vector<CollisionPair>& collision_pairs() const { return collision_pairs_; }
  [[nodiscard]] const HandScale& scale() const { return scale_; }
  // E(C_h, C_h) of Sec. 4.1 at the rest pose: normalises E_col (a constant, so that the gradient
  // of E_col is that of its numerator).
  [[nodiscard]] double self_similarity() const { return self_similarity_; }
  // Hand-frame point at the centre of the palm (used for initialisation).
  [[nodiscard]] Eigen::Vector3d palm_centre() const;
  // Half the palm's thickness (its top row's sigma, the last Gaussian) and half its width (from
  // its centre line to the outer edge of its outermost Gaussian), mm: how far the palm centre lies
  // behind the surface seen with the palm or the back, and with an edge, toward the camera.
  [[nodiscard]] double palm_half_thickness_mm() const;
  [[nodiscard]] double palm_half_width_mm() const;
  // Length from the wrist to the middle fingertip, mm.
  [[nodiscard]] double hand_length_mm() const;

 private:
  std::array<FingerChain, kNumFingers> fingers_{};
  std::vector<ModelGaussian> gaussians_;
  std::array<JointLimit, kNumJointAngles> limits_{};
  std::vector<CollisionPair> collision_pairs_;
  HandScale scale_;
  double self_similarity_ = 1.0;
};

// Unnormalised isotropic Gaussians' overlap integral D_pq (paper eq. 4) with unit weights:
//   2D: 2 pi s_p^2 s_q^2 / S * exp(-|mu_p - mu_q|^2 / (2 S)),            S = s_p^2 + s_q^2
//   3D: (2 pi)^(3/2) (s_p^2 s_q^2 / S)^(3/2) * exp(-|mu_p - mu_q|^2 / (2 S))
double overlap_2d(double dist2, double sigma_p, double sigma_q);
double overlap_3d(double dist2, double sigma_p, double sigma_q);

}  // namespace handtrack
