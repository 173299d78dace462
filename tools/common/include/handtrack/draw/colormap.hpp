#pragma once
// Colour maps for depth images and part labels.

#include "handtrack/draw/canvas.hpp"

namespace handtrack::draw {

// Depth as gray, near = bright: near_mm -> white, far_mm -> dark gray (60), beyond clamped;
// depth <= 0 (no measurement) or non-finite -> black.
Rgb depth_gray(double depth_mm, double near_mm, double far_mm);
// t in [0, 1] along a turbo-like rainbow (dark blue, blue, cyan, green, yellow, orange, dark red);
// clamped outside.
Rgb turbo(double t);
// Depth through turbo(), near = red end; no measurement -> black.
Rgb depth_turbo(double depth_mm, double near_mm, double far_mm);
// Part label 0..12 (hand_layout.hpp: 0 = background, 1 = palm, 2..4 thumb, then two per finger),
// 13 distinct colours; a finger's proximal and distal parts share a hue (distal lighter). Labels
// outside 0..12 are magenta.
Rgb part_colour(int label);
// The i-th colour of a palette for plot lines (cycles after 8).
Rgb series_colour(int i);

}  // namespace handtrack::draw
