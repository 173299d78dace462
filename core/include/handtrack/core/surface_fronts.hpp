#pragma once
// Where the surface the camera sees lies in front of a model Gaussian seen at a slant (ours, not in
// the paper).
//
// E_sim's depth factor (eq. 7) compares the depth d_q of an image Gaussian with d_p = z - sigma_h,
// the front of model Gaussian p taken as a sphere of radius sigma_h. But the hand is not a set of
// separate spheres: the palm is a slab and each finger bone a capsule, and seen at a slant the
// surface along the ray through a Gaussian's centre lies further in front of it than sigma_h:
//
//   palm (a slab of half thickness sigma_h, normal n):         sigma_h / |n . r|
//   finger bone (a capsule of radius sigma_h along the bone a): sigma_h / sqrt(1 - (a . r)^2)
//
// with r the unit ray to the centre. At a grazing angle the spheres' fronts then lie behind the
// surface the camera sees, and a fit that puts them on it tips the hand toward the camera and
// slides it nearer: seen from behind, along fingers that point away from the camera (the head-
// mounted view), the truth's palm Gaussians were 6-16 mm behind the visible surface and the fits
// 10-13 mm nearer at the knuckles, tipped 8-12 deg (docs/TRACKER.md, "The head-mounted view taken
// apart", "Surfaces seen at a slant"). So
//
//   d_p = z - k_p sigma_h,   k_p = min(1 / cos, k_max)
//
// where cos is |n . r| for the palm's Gaussians and sqrt(1 - (a . r)^2) for a finger bone's. A bone
// counts only where it points away from the camera (a . r > 0): then the ray from its centre
// toward the camera runs back along the finger toward the palm, which is there; pointing toward
// the camera it runs out through the fingertip (with every bone: 0.7 mm worse in the palm view,
// the flexed fingers of pinch and tigergrasp). k_max keeps a surface seen edge-on from moving the
// front without bound (a palm edge-on is seen at its edge, one sigma_h in front).
//
// The k_p hold for a frame: taken from the previous pose, as E_unseen's weights are
// (unseen_fingers.hpp), so d_p stays z minus a constant and eq. 7's gradient is unchanged. Late
// fusion, while tracking (a previous pose); the (re)start search and its checks keep eq. 7.

#include "handtrack/core/hand_model.hpp"
#include "handtrack/core/kinematics.hpp"

#include <array>

namespace handtrack {

// k_max measured on the broadened benchmark: 1.5 against 2 and 3 (docs/TRACKER.md, "Surfaces seen
// at a slant"); 1 is eq. 7.
inline constexpr double kMeasuredSlantFront = 1.5;

// k_p of each model Gaussian, in the model's order (1 where the Gaussian is seen square on).
struct SurfaceFronts {
  std::array<double, kMaxModelGaussians> sigmas{};
};

// k_p of `model` posed at the previous frame's pose (`previous`), capped at `max_ratio` (>= 1).
SurfaceFronts surface_fronts(const HandModel& model, const PosedHand& previous, double max_ratio);

}  // namespace handtrack
