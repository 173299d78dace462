#pragma once
// Unseen fingers curl (ours, not in the paper): a prior on the flexion of a finger the part labels
// do not see.
//
// With the back of the hand toward the camera, a finger curled into the palm is behind the hand:
// the camera sees none of it, E_sim (Sec. 4.1) is indifferent to where it is, E_smo carries on its
// last motion, and E_free only charges what lies over the background. So curled fingers were
// fitted stretched out behind the back of the hand (fists seen from the back: 25-34 mm,
// docs/TRACKER.md). A finger lying across the view, on a hand whose flat side faces the camera, is
// seen unless it is curled behind the hand; so where the labels find none of a finger on such a
// hand, it is curled:
//
//   E_unseen = sum_f u_f sum_{d = 1..3} (theta_{f,d} - theta^curl_d)^2        (f: index..little)
//   u_f = g (1 - min(1, s_f / s_0)),   g = n_z^2 (1 - |a_z|)
//
// s_f: the share of the labelled hand pixels the forest gives finger f's parts; s_0 = 4 % (in an
// open hand seen palm-on, index to little hold 6-12 % each); n, a: the palm normal and the finger
// axis (camera frame) of the previous pose, so g is 1 for a hand whose flat side faces the camera
// with the fingers across the view, and 0 for a hand seen edge-on (the fingers stand behind one
// another) or pointing along the view (an outstretched finger can hide behind the hand). Squared in
// n_z: with |n_z| the side view lost 0.7-1.4 mm on each of three sets of subjects (fingers behind
// one another on a hand turned only part of the way), with n_z^2 -0.4 to +0.9 mm (docs/TRACKER.md,
// "Unseen fingers curl"). theta^curl is a relaxed fist. The weights hold for a frame (they do not
// depend on the pose being fitted), so E_unseen is a plain quadratic in Theta with an exact
// gradient. The thumb is left out (its curl is not a fist's; not measured with it). Late fusion
// only (labels), only while tracking (a previous pose), and not beside another hand (it can hide
// an outstretched finger too).
//
// Seen from behind along the fingers (a head-mounted camera over a hand reaching forward: the back
// of the hand toward the camera, the fingers pointing away from it) the fingers are behind the
// knuckles whatever their flexion, and the labels cannot say how far they are curled. There
// E_sim pays a finger for curling toward the visible back of the hand, and fingers that were
// extended were fitted curled into a fist (docs/TRACKER.md, "The head-mounted view taken apart").
// So there every finger is also held at a half curl, whatever the labels see:
//
//   E_unseen += sum_f h_f sum_{d = 1..3} (theta_{f,d} - theta^half)^2,   h_f = max(0, n_z) max(0, a_z)
//
// (n_z > 0: the back of the hand toward the camera; a_z > 0: the fingers pointing away from it;
// at the head-mounted view's 65 deg, h_f = 0.38; 0 with the palm toward the camera or the fingers
// across the view). theta^half = 0.6 rad and the weight were chosen on ten head-mounted sequences
// of seeds 1-2 and measured on the whole benchmark of seeds 1-9 (docs/TRACKER.md, "Fingers seen
// from behind hold a half curl").
//
// Unless the hand is a fist: from behind, fingers held at the half curl that are really curled
// into the palm put their tips 60-77 mm off (head-mounted flexex1, fitted at 45-75 deg of curl
// where the truth closes to 125-140). What tells them apart is the depth beyond the
// knuckles: an extended or half-curled finger seen from behind goes on past its knuckle, a finger
// curled into the palm does not. So per finger, from the previous pose posed:
//
//   r_f = the farthest a segmented hand pixel reaches beyond the finger's knuckle (MCP) along its
//         direction in the palm plane (the proximal bone with the flexion taken out), within
//         kReachBandMm across it;
//   c_f = clamp((kOpenReachMm - r_f) / (kOpenReachMm - kCurledReachMm), 0, 1),   c = mean_f c_f,
//   k_f = c_f c,   h_f -> h_f (1 - k_f),   u_f += h_f k_f   (toward the relaxed fist).
//
// The product with the mean: one curled finger beside extended ones (a pinch's index, which curls
// to 80 deg, not to a fist) is not pulled as far as the fingers of a fist; a fist's are, together.
// Set on the 42 head-mounted sequences of seeds 1-3 (29.22 -> 27.17 mm; c_f alone 27.34, with
// the pinch 20.6 -> 27.0 mm), then measured on seeds 4-6 and 7-9 (docs/TRACKER.md, "Fists seen
// from behind"). A flying pixel on the hand's outline, between the hand and what lies behind it,
// counts as reach; a fit whose knuckles are off reads the reach of whatever lies on its lines.
// Guards against both were tried and did worse on the sets they were not chosen on.

#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/hand_layout.hpp"
#include "handtrack/core/kinematics.hpp"
#include "handtrack/core/pose.hpp"

#include <array>

namespace handtrack {

// The flexion (flex1..flex3, radians) of a relaxed fist, inside every finger's joint limits.
inline constexpr std::array<double, 3> kCurledFlexion = {1.3, 1.6, 0.9};
// s_0: a finger whose parts hold this share of the labelled hand pixels counts as fully seen.
inline constexpr double kSeenFingerShare = 0.04;
// theta^half: the flexion (flex1..flex3, radians) at which fingers seen from behind along their
// length are held.
inline constexpr std::array<double, 3> kHalfCurlFlexion = {0.6, 0.6, 0.6};

// A finger whose reach beyond its knuckle (r_f above) is kCurledReachMm or less is curled as in a
// fist (c_f = 1); kOpenReachMm or more, it is not (c_f = 0). The reach is measured over the hand
// pixels within kReachBandMm across the finger's line.
inline constexpr double kCurledReachMm = 10.0;
inline constexpr double kOpenReachMm = 35.0;
inline constexpr double kReachBandMm = 10.0;

// u_f and h_f of one frame (0 for the thumb).
struct UnseenFingers {
  std::array<double, kNumFingers> weight{};  // u_f, toward the relaxed fist
  std::array<double, kNumFingers> held{};    // h_f, toward the half curl
};

// u_f from the frame's part labels and the previous pose, h_f from the previous pose's rotation,
// each moved toward the fist by the segmented hand's reach beyond the previous pose's knuckles
// (`previous`: that pose posed); all 0 without labels, and no reach without a segmented hand
// (hand_mask not the image's size).
UnseenFingers unseen_fingers(const DepthInput& input, const PosedHand& previous);

// E_unseen at `params`; adds dE_unseen/dTheta into *gradient when not null.
double unseen_finger_energy(const UnseenFingers& unseen, const PoseParams& params, PoseGradient* gradient);

}  // namespace handtrack
