#pragma once
// Which side of a flat hand faces the camera, read from how the depth curves across the palm (ours,
// not in the paper).
//
// A right hand's palm and a left hand's back are mirror images through the hand's plane: the same to
// a model of spheres, which tells them apart only by the few places where it is not symmetric about
// that plane (the thumb sits in front of the palm, the fingers flex toward it). On our own renders
// that was enough, because they are drawn from the hand the model was made from; on depth from
// another hand the two fits explain it alike (a renderer's hand whose back is convex: 0.91 against
// 0.90; docs/TRACKER.md, "A hollow palm and a convex back"). A real hand is not symmetric about its
// plane across the metacarpals: the back is convex (the transverse metacarpal arch) and the palm
// hollow between its thenar and hypothenar pads. So, in the palm region of a fit (between the wrist
// and the knuckles, within the index and little knuckles), the depth is fitted, in the hand's frame,
// by
//
//   h(x, y) = a + b x + c x^2 + e y,
//
// x across the palm (-1 and 1 at the index and little knuckles), y along it, h toward the camera
// along the palm normal (mm). c is how far the palm region's sides stand toward the camera from its
// middle: > 0 hollow (a palm faces the camera), < 0 bulging (the back). The linear terms take up a
// fit turned a little off the surface. Every real SR305 palm measured +0.7 to +10 mm, the renderer's
// convex backs -6 to -8, its flat hands -1.5 to +2.
#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/tracker.hpp"

#include <optional>

namespace handtrack {

// How a frame's handedness evidence (Tracker::weigh) counts c for a pair of mirror twins: c /
// kFullHollowMm, within [-1, 1], times kHollowEvidence toward the fit that shows the camera the side
// c says. 5 mm: above the 1-2 mm a flat render reads, about the middle of the real palms' +0.7 to
// +10 mm, below a convex back's 6-8; 0.15: handedness_margin, so that a clear hollow or arch alone
// decides. Neither was tuned (docs/TRACKER.md, "A hollow palm and a convex back").
inline constexpr double kFullHollowMm = 5.0;
inline constexpr double kHollowEvidence = 0.15;

// c above, from the hand pixels of `input` and the fit `fit` in input's camera frame; nullopt where
// the palm region is too little seen to tell (fewer than kMinPalmHollowPixels pixels, or under
// kMinPalmHollowNear of its pixels within kPalmHollowReachMm of the palm's plane: fingers folded
// over the palm, a hand edge-on).
std::optional<double> palm_hollow_mm(const DepthInput& input, const TrackerOutput& fit);

}  // namespace handtrack
