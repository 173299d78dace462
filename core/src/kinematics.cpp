#include "handtrack/core/kinematics.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>

namespace handtrack {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

Matrix3d skew(const Vector3d& v) {
  Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

}  // namespace

Matrix3d frontal_rotation() { return Eigen::Vector3d(1, -1, -1).asDiagonal(); }

Matrix3d rotation_exp(const Vector3d& r) {
  const double theta = r.norm();
  if (theta < 1e-12) return Matrix3d::Identity() + skew(r);
  return Eigen::AngleAxisd(theta, r / theta).toRotationMatrix();
}

Matrix3d hand_rotation(const PoseParams& params) {
  return rotation_exp(params.segment<3>(kRotationParam)) * frontal_rotation();
}

Matrix3d right_jacobian(const Vector3d& r) {
  // J_r(r) = I - (1 - cos t)/t^2 [r]x + (t - sin t)/t^3 [r]x^2, with its Taylor series near t = 0.
  const double t2 = r.squaredNorm();
  const Matrix3d k = skew(r);
  double a = 0.5 - t2 / 24.0;
  double b = 1.0 / 6.0 - t2 / 120.0;
  if (t2 > 1e-8) {
    const double t = std::sqrt(t2);
    a = (1.0 - std::cos(t)) / t2;
    b = (t - std::sin(t)) / (t2 * t);
  }
  return Matrix3d::Identity() - a * k + b * k * k;
}

Vector3d rotation_log(const Matrix3d& rotation) {
  const Eigen::AngleAxisd aa(rotation);
  return aa.angle() * aa.axis();
}

PosedHand::PosedHand(const HandModel& model, const PoseParams& params) { update(model, params); }

void PosedHand::update(const HandModel& model, const PoseParams& params) {
  const Vector3d r = params.segment<3>(kRotationParam);
  camera_t_hand_ = params.segment<3>(kTranslationParam);
  exp_r_ = rotation_exp(r);
  right_jacobian_ = right_jacobian(r);
  const Matrix3d r0 = frontal_rotation();
  camera_R_hand_ = exp_r_ * r0;

  // Per finger: hand-frame bone frames, joint positions and the twists of its four DOFs.
  std::array<std::array<Vector3d, 4>, kNumFingers> hand_joints{};
  std::array<std::array<Vector3d, kBonesPerFinger>, kNumFingers> bone_dirs{};
  joints_[kWristJoint] = camera_t_hand_;
  for (int f = 0; f < kNumFingers; ++f) {
    const auto& chain = model.fingers()[static_cast<size_t>(f)];
    const Vector3d flex_axis = chain.direction.cross(chain.palmar);
    const auto angle = [&](int dof) { return params[angle_param(f, dof)]; };
    Matrix3d frame = Eigen::AngleAxisd(angle(0), chain.palmar).toRotationMatrix();
    auto& tw = twists_[static_cast<size_t>(f)];
    auto& hj = hand_joints[static_cast<size_t>(f)];
    hj[0] = chain.base;
    tw[0] = {chain.palmar, chain.base};
    for (int b = 0; b < kBonesPerFinger; ++b) {
      const Vector3d axis = frame * flex_axis;
      tw[static_cast<size_t>(b + 1)] = {axis, hj[static_cast<size_t>(b)]};
      frame = Eigen::AngleAxisd(angle(b + 1), axis).toRotationMatrix() * frame;
      bone_dirs[static_cast<size_t>(f)][static_cast<size_t>(b)] = frame * chain.direction;
      hj[static_cast<size_t>(b + 1)] =
          hj[static_cast<size_t>(b)] + chain.length_mm[static_cast<size_t>(b)] * bone_dirs[static_cast<size_t>(f)][static_cast<size_t>(b)];
    }
    for (auto& t : tw) t = {camera_R_hand_ * t.axis, to_camera(t.pivot)};
    for (int k = 0; k < 4; ++k) joints_[joint_index(f, k)] = to_camera(hj[static_cast<size_t>(k)]);
  }

  const auto& gaussians = model.gaussians();
  if (gaussians.size() > static_cast<size_t>(kMaxModelGaussians)) {
    throw std::invalid_argument("hand model: more Gaussians than kMaxModelGaussians");
  }
  centres_.resize(gaussians.size());
  frontal_points_.resize(gaussians.size());
  bones_.resize(gaussians.size());
  for (size_t i = 0; i < gaussians.size(); ++i) {
    const auto& g = gaussians[i];
    Vector3d q = g.palm_position;
    if (g.bone != kPalmBone) {
      const auto f = static_cast<size_t>(g.bone / kBonesPerFinger);
      const auto b = static_cast<size_t>(g.bone % kBonesPerFinger);
      q = hand_joints[f][b] + g.along * (hand_joints[f][b + 1] - hand_joints[f][b]);
    }
    bones_[i] = g.bone;
    frontal_points_[i] = r0 * q;
    centres_[i] = to_camera(q);
  }
}

void PosedHand::add_point_gradient(int gaussian, const Vector3d& dE_dp, PoseGradient& gradient) const {
  const auto i = static_cast<size_t>(gaussian);
  const Vector3d& p = centres_[i];
  gradient.segment<3>(kTranslationParam) += dE_dp;
  // dE/dr = J_r^T (R0 q x exp(r)^T dE/dp), from dp/dr = -exp(r) [R0 q]x J_r.
  gradient.segment<3>(kRotationParam) +=
      right_jacobian_.transpose() * frontal_points_[i].cross(exp_r_.transpose() * dE_dp);
  const int bone = bones_[i];
  if (bone == kPalmBone) return;
  const int f = bone / kBonesPerFinger;
  const int dofs = bone % kBonesPerFinger + 2;  // abd and flex1 move bone 0; flex2 bone 1; flex3 bone 2
  const auto& tw = twists_[static_cast<size_t>(f)];
  for (int d = 0; d < dofs; ++d) {
    const auto& t = tw[static_cast<size_t>(d)];
    gradient[angle_param(f, d)] += t.axis.cross(p - t.pivot).dot(dE_dp);
  }
}

void PosedHand::add_centre_gradients(const CentreGradients& dE_dcentres, PoseGradient& gradient) const {
  // Force and torque about the wrist t per bone (the palm is bone kPalmBone), see the header.
  std::array<Vector3d, kPalmBone + 1> force;
  std::array<Vector3d, kPalmBone + 1> torque;
  force.fill(Vector3d::Zero());
  torque.fill(Vector3d::Zero());
  for (size_t i = 0; i < centres_.size(); ++i) {
    const Vector3d g = dE_dcentres.col(static_cast<Eigen::Index>(i));
    const auto b = static_cast<size_t>(bones_[i]);
    force[b] += g;
    torque[b] += (centres_[i] - camera_t_hand_).cross(g);
  }
  Vector3d total_force = Vector3d::Zero();
  Vector3d total_torque = Vector3d::Zero();
  for (size_t b = 0; b <= kPalmBone; ++b) {
    total_force += force[b];
    total_torque += torque[b];
  }
  gradient.segment<3>(kTranslationParam) += total_force;
  gradient.segment<3>(kRotationParam) += right_jacobian_.transpose() * (exp_r_.transpose() * total_torque);
  for (int f = 0; f < kNumFingers; ++f) {
    // Joint d moves bones >= max(0, d - 1) of its finger: sum the bones from the tip down.
    Vector3d moved_force = Vector3d::Zero();
    Vector3d moved_torque = Vector3d::Zero();
    const auto& tw = twists_[static_cast<size_t>(f)];
    for (int b = kBonesPerFinger - 1; b >= 0; --b) {
      const auto bone = static_cast<size_t>(f * kBonesPerFinger + b);
      moved_force += force[bone];
      moved_torque += torque[bone];
      for (int d = b == 0 ? 0 : b + 1; d <= b + 1; ++d) {
        const auto& t = tw[static_cast<size_t>(d)];
        gradient[angle_param(f, d)] += t.axis.dot(moved_torque - (t.pivot - camera_t_hand_).cross(moved_force));
      }
    }
  }
}

}  // namespace handtrack
