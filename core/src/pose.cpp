#include "handtrack/core/pose.hpp"

#include <array>

namespace handtrack {

std::string param_name(int i) {
  static constexpr std::array<const char*, 4> kDof = {"abd", "flex1", "flex2", "flex3"};
  static constexpr std::array<const char*, 3> kAxis = {"x", "y", "z"};
  if (i < 0 || i >= kNumPoseParams) return "?";
  if (i < kRotationParam) return std::string("t") + kAxis[static_cast<size_t>(i)];
  if (i < kFirstAngleParam) return std::string("r") + kAxis[static_cast<size_t>(i - kRotationParam)];
  const int k = i - kFirstAngleParam;
  return std::string(kFingerNames[static_cast<size_t>(k / 4)]) + "_" + kDof[static_cast<size_t>(k % 4)];
}

}  // namespace handtrack
