// handtrack-view's picture of a frame: the panels side by side (the model panel: model_panel.cpp).
#include "render.hpp"

#include "hand_colours.hpp"
#include "panel.hpp"

#include "handtrack/core/kinematics.hpp"
#include "handtrack/draw/canvas.hpp"
#include "handtrack/draw/colormap.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

namespace handtrack::view {
namespace {

using draw::Canvas;
using draw::Rgb;

constexpr int kCropPanelHeightPx = 360;
constexpr double kCropMarginFraction = 0.3;  // of the hand's larger bounding-box side, each way
constexpr int kPanelGapPx = 4;
constexpr Rgb kFrameBackground{20, 20, 20};
constexpr Rgb kCaptionText{235, 235, 235};
constexpr double kMaskAlpha = 0.45;
constexpr double kSkeletonFingerAxisMm = 60.0;  // length of the drawn finger-axis estimate

bool in_mask(const DepthInput& in, int u, int v) {
  if (u < 0 || v < 0 || u >= in.camera.width || v >= in.camera.height) return false;
  return in.hand_mask[static_cast<size_t>(v) * static_cast<size_t>(in.camera.width) + static_cast<size_t>(u)] != 0;
}

}  // namespace

std::string format(const char* fmt, double v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

int caption_scale(int panel_width) { return panel_width >= 560 ? 2 : 1; }

void draw_depth(Canvas& c, const ViewMap& view, const DepthImage& depth, std::pair<double, double> range,
                double dim) {
  for (int y = 0; y < view.height; ++y) {
    const int v = view.v_of(y);
    for (int x = 0; x < view.width; ++x) {
      const int u = view.u_of(x);
      if (u < 0 || v < 0 || u >= depth.width() || v >= depth.height()) continue;
      const Rgb g = draw::depth_gray(depth.at(u, v), range.first, range.second);
      c.set_pixel(x, y, dim < 1.0 ? draw::shade(g, dim) : g);
    }
  }
}

void draw_mask_outline(Canvas& c, const ViewMap& view, const DepthInput& in, Rgb colour) {
  for (int y = 0; y < view.height; ++y) {
    for (int x = 0; x < view.width; ++x) {
      if (!in_mask(in, view.u_of(x), view.v_of(y))) continue;
      const bool edge = !in_mask(in, view.u_of(x - 1), view.v_of(y)) || !in_mask(in, view.u_of(x + 1), view.v_of(y)) ||
                        !in_mask(in, view.u_of(x), view.v_of(y - 1)) || !in_mask(in, view.u_of(x), view.v_of(y + 1));
      if (edge) c.set_pixel(x, y, colour);
    }
  }
}

Rgb HandStyle::mask_outline() const { return by_part ? kMaskTint : draw::shade(colour, kLighter); }
Rgb HandStyle::part(int label) const { return by_part ? draw::part_colour(label) : colour; }
Rgb HandStyle::bone() const { return by_part ? draw::colours::kWhite : draw::shade(colour, kLighter); }
Rgb HandStyle::tip(int finger) const { return by_part ? draw::part_colour(part_label(finger, 2)) : colour; }

HandStyle style_of(const FrameView& f, const HandView& h) {
  if (f.hands.size() <= 1) return {};
  return {false, kHandColours[static_cast<size_t>(std::clamp(h.slot, 0, kMaxHands - 1))]};
}

namespace {

// The hands' inputs: each hand's preprocessing (the first's camera is the frame's).
std::vector<const DepthInput*> inputs_of(const FrameView& f) {
  std::vector<const DepthInput*> inputs;
  for (const HandView& h : f.hands) inputs.push_back(h.input);
  return inputs;
}

ViewMap make_view(const DepthImage& depth, const std::vector<const DepthInput*>& inputs, const RenderOptions& options) {
  const int w = depth.width();
  const int h = depth.height();
  ViewMap view;
  int lo_u = w, lo_v = h, hi_u = -1, hi_v = -1;
  if (options.crop) {  // onto every hand's segmented pixels
    for (const DepthInput* input : inputs) {
      for (int v = 0; v < h; ++v) {
        for (int u = 0; u < w; ++u) {
          if (input->hand_mask[static_cast<size_t>(v) * static_cast<size_t>(w) + static_cast<size_t>(u)] == 0) continue;
          lo_u = std::min(lo_u, u);
          hi_u = std::max(hi_u, u);
          lo_v = std::min(lo_v, v);
          hi_v = std::max(hi_v, v);
        }
      }
    }
  }
  if (hi_u < 0) {  // the whole image
    view.height = options.panel_height > 0 ? options.panel_height : h;
    view.s = static_cast<double>(view.height) / h;
    view.width = std::max(1, static_cast<int>(std::lround(w * view.s)));
    return view;
  }
  const double side = std::max(hi_u - lo_u + 1, hi_v - lo_v + 1) * (1.0 + 2.0 * kCropMarginFraction);
  view.u0 = 0.5 * (lo_u + hi_u + 1) - 0.5 * side;
  view.v0 = 0.5 * (lo_v + hi_v + 1) - 0.5 * side;
  view.height = options.panel_height > 0 ? options.panel_height : kCropPanelHeightPx;
  view.width = view.height;
  view.s = view.height / side;
  return view;
}

// Robust display range of the measured depth: the 2nd and 98th percentiles.
std::pair<double, double> depth_range(const std::vector<float>& depth_mm) {
  std::vector<float> valid;
  valid.reserve(depth_mm.size());
  for (float d : depth_mm) {
    if (d > 0.0F && std::isfinite(d)) valid.push_back(d);
  }
  if (valid.empty()) return {0.0, 1.0};
  const auto at = [&valid](double q) {
    auto k = static_cast<size_t>(q * static_cast<double>(valid.size() - 1));
    std::nth_element(valid.begin(), valid.begin() + static_cast<std::ptrdiff_t>(k), valid.end());
    return static_cast<double>(valid[k]);
  };
  const double near = at(0.02);
  const double far = at(0.98);
  return {near, std::max(far, near + 1.0)};
}

Panel depth_panel(const FrameView& f, const ViewMap& view, std::pair<double, double> range) {
  Canvas c(view.width, view.height, draw::colours::kBlack);
  draw_depth(c, view, *f.depth, range);
  for (const HandView& h : f.hands) {
    const DepthInput& in = *h.input;
    const Rgb tint = style_of(f, h).mask();
    for (int y = 0; y < view.height; ++y) {
      for (int x = 0; x < view.width; ++x) {
        if (in_mask(in, view.u_of(x), view.v_of(y))) c.blend_pixel(x, y, tint, kMaskAlpha);
      }
    }
  }
  for (const HandView& h : f.hands) {
    const DepthInput& in = *h.input;
    if (!in.has_hand() || !(in.palm_centre_mm.z() > 1.0)) continue;
    // The preprocessing's palm centre and wrist-to-fingers axis, as a cross and a line.
    const auto palm = in.camera.project(in.palm_centre_mm);
    const auto tip = in.camera.project(in.palm_centre_mm + kSkeletonFingerAxisMm * in.finger_axis);
    const double px = view.x(palm.x()), py = view.y(palm.y());
    c.line(px - 6, py, px + 6, py, draw::colours::kYellow, 2);
    c.line(px, py - 6, px, py + 6, draw::colours::kYellow, 2);
    c.line(px, py, view.x(tip.x()), view.y(tip.y()), draw::colours::kYellow);
  }
  Panel p{std::move(c), {}};
  p.caption = f.name + "\ndepth " + format("%.0f", range.first) + format("-%.0f mm", range.second);
  if (f.hands.size() <= 1) {
    p.caption += format(", hand %.0f px", f.hands.empty() ? 0.0 : f.hands.front().input->hand_pixels);
  } else {
    p.caption += ", hands";
    for (size_t k = 0; k < f.hands.size(); ++k) {
      p.caption += format(k == 0 ? " %.0f" : " + %.0f", f.hands[k].input->hand_pixels);
    }
    p.caption += " px";
  }
  return p;
}

Panel quadtree_panel(const FrameView& f, const ViewMap& view, std::pair<double, double> range) {
  Canvas c(view.width, view.height, draw::colours::kBlack);
  draw_depth(c, view, *f.depth, range, 0.3);
  std::vector<ImageGaussian> gs;  // every hand's
  for (const HandView& h : f.hands) gs.insert(gs.end(), h.input->gaussians.begin(), h.input->gaussians.end());
  const bool labelled = std::any_of(gs.begin(), gs.end(), [](const ImageGaussian& g) { return g.label != 0; });
  double near = 1e9, far = -1e9;
  for (const auto& g : gs) {
    near = std::min(near, g.depth_mm);
    far = std::max(far, g.depth_mm);
  }
  for (const auto& g : gs) {  // the leaf squares, faint
    // The leaf covers image pixels from (u - side/2 + 1/2) on; its left edge lands on panel pixel
    // (first - u0) * s.
    const double first_u = g.u - 0.5 * g.side_px + 0.5;
    const double first_v = g.v - 0.5 * g.side_px + 0.5;
    const int x0 = static_cast<int>(std::lround((first_u - view.u0) * view.s));
    const int y0 = static_cast<int>(std::lround((first_v - view.v0) * view.s));
    const int side = std::max(1, static_cast<int>(std::lround(g.side_px * view.s)));
    c.rect(x0, y0, side, side, Rgb{70, 70, 70});
  }
  for (const auto& g : gs) {
    const Rgb colour = labelled ? draw::part_colour(g.label) : draw::depth_turbo(g.depth_mm, near, far);
    c.circle(view.x(g.u), view.y(g.v), g.sigma_px * view.s, colour);
    c.fill_circle(view.x(g.u), view.y(g.v), std::max(1.0, 0.12 * g.sigma_px * view.s), colour);
  }
  Panel p{std::move(c), {}};
  p.caption = format("quadtree: %.0f Gaussians", static_cast<double>(gs.size()));
  if (!gs.empty()) {
    p.caption += labelled ? "\nby label" : format("\nturbo %.0f", near) + format("-%.0f mm (red=near)", far);
  }
  return p;
}
Panel labels_panel(const FrameView& f, const ViewMap& view, std::pair<double, double> range) {
  Canvas c(view.width, view.height, draw::colours::kBlack);
  draw_depth(c, view, *f.depth, range, 0.35);
  const Gray8Image& labels = *f.labels;
  for (int y = 0; y < view.height; ++y) {
    const int v = view.v_of(y);
    for (int x = 0; x < view.width; ++x) {
      const int u = view.u_of(x);
      if (u < 0 || v < 0 || u >= labels.width || v >= labels.height) continue;
      const int label = labels.pixels[static_cast<size_t>(v) * static_cast<size_t>(labels.width) + static_cast<size_t>(u)];
      if (label != 0) c.set_pixel(x, y, draw::part_colour(label));
    }
  }
  // Legend: the 12 part colours in a row along the bottom edge.
  const int sw = std::max(6, view.width / 40);
  for (int label = 1; label <= kNumPartLabels; ++label) {
    c.fill_rect(4 + (label - 1) * (sw + 2), view.height - sw - 4, sw, sw, draw::part_colour(label));
  }
  return {std::move(c), f.labels_caption};
}

}  // namespace

std::optional<double> fingertip_error_mm(const TrackerOutput& output, const Fingertips& truth) {
  double sum = 0.0;
  int n = 0;
  for (int i = 0; i < kNumFingers; ++i) {
    const auto& t = truth[static_cast<size_t>(i)];
    if (!t) continue;
    sum += (output.fingertips[static_cast<size_t>(i)] - *t).norm();
    ++n;
  }
  if (n == 0) return std::nullopt;
  return sum / n;
}

std::optional<double> nearest_fingertip_error_mm(const TrackerOutput& output, const std::vector<Fingertips>& truth) {
  std::optional<double> best;
  for (const Fingertips& hand : truth) {
    const auto err = fingertip_error_mm(output, hand);
    if (err && (!best || *err < *best)) best = err;
  }
  return best;
}

DepthInput unmirrored(const DepthInput& input) {
  DepthInput out = input;
  const int w = input.camera.width;
  out.camera.cx = static_cast<double>(w - 1) - input.camera.cx;
  const auto flip_rows = [w](auto& pixels) {
    for (size_t row = 0; row + static_cast<size_t>(w) <= pixels.size(); row += static_cast<size_t>(w)) {
      std::reverse(pixels.begin() + static_cast<std::ptrdiff_t>(row),
                   pixels.begin() + static_cast<std::ptrdiff_t>(row) + w);
    }
  };
  flip_rows(out.filtered_mm);
  flip_rows(out.hand_mask);
  flip_rows(out.pixel_labels);
  for (auto& g : out.gaussians) g.u = static_cast<double>(w - 1) - g.u;
  for (Eigen::Vector3d* p : {&out.hand_centroid_mm, &out.palm_centre_mm, &out.finger_axis}) p->x() = -p->x();
  return out;
}

RgbImage render_frame(const FrameView& f, const RenderOptions& options) {
  if (f.depth == nullptr) throw std::invalid_argument("render_frame: the depth image is required");
  for (const HandView& h : f.hands) {
    if (h.input == nullptr || h.output == nullptr || h.model == nullptr) {
      throw std::invalid_argument("render_frame: each hand needs its input, output and model");
    }
  }
  const ViewMap view = make_view(*f.depth, inputs_of(f), options);
  const auto range = depth_range(f.depth->depth_mm);
  std::vector<Panel> panels;
  panels.push_back(depth_panel(f, view, range));
  panels.push_back(quadtree_panel(f, view, range));
  panels.push_back(model_panel(f, view, range));
  if (f.labels != nullptr) panels.push_back(labels_panel(f, view, range));

  const int scale = caption_scale(view.width);
  int caption_px = 0;
  for (auto& p : panels) {
    p.caption = draw::wrap_text(p.caption, view.width - 2, scale);  // within its panel (narrow ones too)
    caption_px = std::max(caption_px, draw::text_height(p.caption, scale));
  }
  caption_px += 8;
  const int n = static_cast<int>(panels.size());
  Canvas out(n * view.width + (n + 1) * kPanelGapPx, caption_px + view.height + kPanelGapPx, kFrameBackground);
  for (int i = 0; i < n; ++i) {
    const int x = kPanelGapPx + i * (view.width + kPanelGapPx);
    out.text(x + 2, 4, panels[static_cast<size_t>(i)].caption, kCaptionText, scale);
    out.blit(panels[static_cast<size_t>(i)].canvas, x, caption_px);
  }
  return out.image();
}

}  // namespace handtrack::view
