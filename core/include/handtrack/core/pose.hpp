#pragma once
// The 26 skeletal pose parameters of Sec. 3.2 ("3 translational DOFs, 3 global rotations, and 20
// joint angles"):
//   [0..2]  t: wrist position in the camera frame, mm
//   [3..5]  r: global rotation as an exponential-map vector, camera_R_hand = exp([r]x) * R0, where
//           R0 = diag(1,-1,-1) makes r = 0 the frontal pose (palm facing the camera, fingers up)
//   [6..25] per finger thumb..little: [abduction, flex1, flex2, flex3] in radians
//           (MCP abduction and flexion, PIP, DIP; thumb: CMC abduction and flexion, MCP, IP).

#include "handtrack/core/hand_layout.hpp"

#include <Eigen/Core>

#include <string>

namespace handtrack {

using PoseParams = Eigen::Matrix<double, kNumPoseParams, 1>;
using PoseGradient = Eigen::Matrix<double, kNumPoseParams, 1>;

inline constexpr int kTranslationParam = 0;
inline constexpr int kRotationParam = 3;
inline constexpr int kFirstAngleParam = 6;
constexpr int angle_param(int finger, int dof) { return kFirstAngleParam + 4 * finger + dof; }

enum class ParamKind { kTranslation, kRotation, kAngle };
constexpr ParamKind param_kind(int i) {
  return i < kRotationParam ? ParamKind::kTranslation : i < kFirstAngleParam ? ParamKind::kRotation : ParamKind::kAngle;
}

// "tx", "ry", "index_flex2", ...
std::string param_name(int i);

}  // namespace handtrack
