#pragma once
// The colour of each hand where handtrack-view draws several (issue 14): the hand of HandsTracker
// slot i is drawn in kHandColours[i] (its model, its fingertips, its caption, its segmented
// pixels), so a hand keeps its colour from frame to frame while its slot tracks it. One hand alone
// is drawn as it always was (the model by part colour, the mask green). Header-only so that
// tests/tools/test_view_cli.cpp can look for these exact colours in a picture.

#include "handtrack/core/hands_tracker.hpp"
#include "handtrack/draw/canvas.hpp"

#include <array>

namespace handtrack::view {

// Chosen apart from the other colours of the panels: the mask green, the palm-marker yellow, the
// ground-truth cyan, the white skeleton, the gray depth.
inline constexpr std::array<draw::Rgb, kMaxHands> kHandColours{{
    {255, 120, 30},  // slot 0: orange
    {150, 90, 255},  // slot 1: violet
}};

}  // namespace handtrack::view
