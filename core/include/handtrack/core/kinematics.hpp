#pragma once
// Forward kinematics of the hand model for one pose, and the chain rule from a model point back
// to the 26 pose parameters.
//
// A hand-frame point q is at camera_p = t + camera_R_hand q with camera_R_hand = exp([r]x) R0.
// Derivatives (all analytic):
//   dp/dt      = I
//   dp/dr      = -exp([r]x) [R0 q]x J_r(r)   (J_r: right Jacobian of SO(3))
//   dp/dtheta_j = w_j x (p - c_j)            (twist of revolute joint j: world axis w_j through c_j)
// Summed over many points (PosedHand::add_centre_gradients) the chain needs only each bone's total
// force F = sum_i g_i and torque tau = sum_i (p_i - t) x g_i, with g_i = dE/dp_i:
//   dE/dt = F,  dE/dr = J_r(r)^T exp([r]x)^T tau,  dE/dtheta_j = w_j . (tau_j - (c_j - t) x F_j)
// where F_j, tau_j sum over the points that joint j moves (a x R^T b = R^T (R a x b), R R0 q = p - t).

#include "handtrack/core/hand_model.hpp"
#include "handtrack/core/pose.hpp"

#include <Eigen/Core>

#include <array>
#include <vector>

namespace handtrack {

// R0 = diag(1, -1, -1): the frontal pose (palm to camera, fingers up) at r = 0.
Eigen::Matrix3d frontal_rotation();
// exp([r]x) (Rodrigues) and the right Jacobian J_r(r) of SO(3).
Eigen::Matrix3d rotation_exp(const Eigen::Vector3d& r);
Eigen::Matrix3d right_jacobian(const Eigen::Vector3d& r);
// log of a rotation matrix: the r with exp([r]x) = R, |r| <= pi.
Eigen::Vector3d rotation_log(const Eigen::Matrix3d& rotation);
// camera_R_hand = exp([r]x) R0 of a pose, without posing the hand (PosedHand allocates).
Eigen::Matrix3d hand_rotation(const PoseParams& params);

// dE/d centre (camera frame) of every model Gaussian, one column each. A fixed capacity keeps it
// on the stack: no allocation per energy evaluation.
inline constexpr int kMaxModelGaussians = 64;
using CentreGradients = Eigen::Matrix<double, 3, Eigen::Dynamic, Eigen::ColMajor, 3, kMaxModelGaussians>;

class PosedHand {
 public:
  PosedHand() = default;
  PosedHand(const HandModel& model, const PoseParams& params);

  // Recomputes everything for a new pose, reusing storage (no allocation after the first call).
  void update(const HandModel& model, const PoseParams& params);

  [[nodiscard]] const Eigen::Vector3d& centre(int gaussian) const { return centres_[static_cast<size_t>(gaussian)]; }
  [[nodiscard]] int gaussian_count() const { return static_cast<int>(centres_.size()); }
  // The 21 joints of SPEC.md in the camera frame, mm.
  [[nodiscard]] const std::array<Eigen::Vector3d, kNumJoints>& joints() const { return joints_; }
  [[nodiscard]] Eigen::Vector3d fingertip(int finger) const { return joints_[fingertip_joint(finger)]; }
  [[nodiscard]] const Eigen::Matrix3d& camera_R_hand() const { return camera_R_hand_; }
  [[nodiscard]] const Eigen::Vector3d& camera_t_hand() const { return camera_t_hand_; }
  // Hand-frame point to camera frame.
  [[nodiscard]] Eigen::Vector3d to_camera(const Eigen::Vector3d& hand_p) const {
    return camera_t_hand_ + camera_R_hand_ * hand_p;
  }

  // gradient += (d centre(gaussian) / d params)^T * dE_dp: the chain rule for one model point.
  void add_point_gradient(int gaussian, const Eigen::Vector3d& dE_dp, PoseGradient& gradient) const;
  // The same for all model Gaussians at once (column i = dE/d centre(i), gaussian_count() columns),
  // in one pass through the kinematic chain: what the energy terms use.
  void add_centre_gradients(const CentreGradients& dE_dcentres, PoseGradient& gradient) const;

 private:
  struct Twist {
    Eigen::Vector3d axis;   // world axis w_j
    Eigen::Vector3d pivot;  // world point c_j on the axis
  };
  std::vector<Eigen::Vector3d> centres_;
  std::vector<Eigen::Vector3d> frontal_points_;  // R0 q for the rotation derivative
  std::vector<int> bones_;
  std::array<std::array<Twist, 4>, kNumFingers> twists_{};  // per finger: abd, flex1, flex2, flex3
  std::array<Eigen::Vector3d, kNumJoints> joints_{};
  Eigen::Matrix3d camera_R_hand_ = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d exp_r_ = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d right_jacobian_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d camera_t_hand_ = Eigen::Vector3d::Zero();
};

}  // namespace handtrack
