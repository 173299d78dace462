#pragma once
// What render.cpp's panels share (private to handtrack-view): the image-to-panel map, the hands'
// colours, the depth backdrop. The model panel, the largest, is model_panel.cpp.

#include "render.hpp"

#include "handtrack/draw/canvas.hpp"

#include <cmath>
#include <string>
#include <utility>

namespace handtrack::view {

inline constexpr draw::Rgb kMaskTint{40, 220, 90};  // one hand's segmented pixels

// printf of one number, for captions.
std::string format(const char* fmt, double v);

// Maps image pixels (centres at integers) onto a panel: the region starting at (u0, v0) scaled by s.
struct ViewMap {
  double u0 = 0.0;
  double v0 = 0.0;
  double s = 1.0;
  int width = 0;
  int height = 0;
  [[nodiscard]] double x(double u) const { return (u - u0 + 0.5) * s - 0.5; }
  [[nodiscard]] double y(double v) const { return (v - v0 + 0.5) * s - 0.5; }
  [[nodiscard]] int u_of(int x_px) const { return static_cast<int>(std::floor((x_px + 0.5) / s + u0)); }
  [[nodiscard]] int v_of(int y_px) const { return static_cast<int>(std::floor((y_px + 0.5) / s + v0)); }
};

struct Panel {
  draw::Canvas canvas;
  std::string caption;
};

// Caption text scale of a panel this wide.
int caption_scale(int panel_width);

// The depth image in gray (near = bright) through the view; `dim` < 1 darkens it.
void draw_depth(draw::Canvas& c, const ViewMap& view, const DepthImage& depth, std::pair<double, double> range,
                double dim = 1.0);
// The outline of a segmented hand: panel pixels inside the mask with a neighbour outside, so the
// fitted model can be judged against the hand it was fitted to.
void draw_mask_outline(draw::Canvas& c, const ViewMap& view, const DepthInput& in, draw::Rgb colour);

// How a hand is coloured: one hand alone as handtrack-view always drew it (the mask green, the
// model by parts); each of several in its slot's colour (hand_colours.hpp).
struct HandStyle {
  bool by_part = true;
  draw::Rgb colour{};
  [[nodiscard]] draw::Rgb mask() const { return by_part ? kMaskTint : colour; }
  [[nodiscard]] draw::Rgb mask_outline() const;
  [[nodiscard]] draw::Rgb part(int label) const;
  [[nodiscard]] draw::Rgb bone() const;
  [[nodiscard]] draw::Rgb tip(int finger) const;
  static constexpr double kLighter = 1.5;  // draw::shade() toward white: bones and outlines
};
HandStyle style_of(const FrameView& f, const HandView& h);

// Whether the output has a pose to draw.
inline bool posed(const TrackerOutput& out) {
  return out.state != TrackingState::kNoHand && out.params.allFinite();
}

// (c): the hands' model Gaussians, skeletons and fingertips over the depth and the outlines of
// their segmented pixels, the annotated fingertips as crosses.
Panel model_panel(const FrameView& f, const ViewMap& view, std::pair<double, double> range);

}  // namespace handtrack::view
