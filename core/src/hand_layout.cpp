#include "handtrack/core/hand_layout.hpp"

namespace handtrack {

std::string_view joint_name(int joint) {
  static constexpr std::array<std::string_view, kNumJoints> kNames = {
      "wrist",      "thumb_cmc", "thumb_mcp", "thumb_ip",   "thumb_tip", "index_mcp",  "index_pip",
      "index_dip",  "index_tip", "middle_mcp", "middle_pip", "middle_dip", "middle_tip", "ring_mcp",
      "ring_pip",   "ring_dip",  "ring_tip",  "little_mcp", "little_pip", "little_dip", "little_tip"};
  return (joint >= 0 && joint < kNumJoints) ? kNames[static_cast<size_t>(joint)] : std::string_view("?");
}

}  // namespace handtrack
