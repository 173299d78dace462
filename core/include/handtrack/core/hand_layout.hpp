#pragma once
// The names shared by everything that speaks about a hand: fingers, the 21 joints of SPEC.md
// (wrist, then per finger thumb..little: MCP/CMC, PIP, DIP, TIP) and the 12 part labels of the
// paper (Sec. 4.3, Fig. 1) used by the synthetic label images, the forest and the model.

#include <array>
#include <string_view>

namespace handtrack {

inline constexpr int kNumFingers = 5;           // thumb, index, middle, ring, little
inline constexpr int kNumJoints = 21;           // wrist + 4 per finger
inline constexpr int kNumPoseParams = 26;       // Sec. 3.2: 3 translation, 3 global rotation, 20 angles
inline constexpr int kNumJointAngles = 20;
inline constexpr int kNumPartLabels = 12;       // Sec. 4.3: "We use 12 part labels for the hand"

enum Finger : int { kThumb = 0, kIndex = 1, kMiddle = 2, kRing = 3, kLittle = 4 };
inline constexpr std::array<std::string_view, kNumFingers> kFingerNames = {"thumb", "index", "middle", "ring",
                                                                           "little"};

// Joint index in the 21-joint layout. k: 0 = MCP (CMC for the thumb), 1 = PIP (thumb MCP),
// 2 = DIP (thumb IP), 3 = TIP.
inline constexpr int kWristJoint = 0;
constexpr int joint_index(int finger, int k) { return 1 + 4 * finger + k; }
constexpr int fingertip_joint(int finger) { return joint_index(finger, 3); }

// Column stem of each joint in joints.csv ("wrist", "thumb_cmc", ..., "little_tip").
std::string_view joint_name(int joint);

// Part labels (label images: 0 = background, 1..12 = parts). The palm is one part, the thumb has
// three (metacarpal, proximal, distal), each other finger two (proximal phalanx; middle+distal).
enum PartLabel : int {
  kBackground = 0,
  kPalm = 1,
  kThumbMetacarpal = 2,
  kThumbProximal = 3,
  kThumbDistal = 4,
  kIndexProximal = 5,
  kIndexDistal = 6,
  kMiddleProximal = 7,
  kMiddleDistal = 8,
  kRingProximal = 9,
  kRingDistal = 10,
  kLittleProximal = 11,
  kLittleDistal = 12,
};
// Label of the phalanx `bone` (0 = proximal, 1 = middle, 2 = distal) of a non-thumb finger, or of the
// thumb's bone (0 = metacarpal, 1 = proximal, 2 = distal).
constexpr int part_label(int finger, int bone) {
  if (finger == kThumb) return kThumbMetacarpal + bone;
  return kIndexProximal + 2 * (finger - 1) + (bone == 0 ? 0 : 1);
}
// The finger a part label belongs to (Finger), or -1 for the palm and the background.
constexpr int part_finger(int label) {
  if (label < kThumbMetacarpal) return -1;
  if (label <= kThumbDistal) return kThumb;
  return kIndex + (label - kIndexProximal) / 2;
}

}  // namespace handtrack
