// (c) of handtrack-view: the fitted models over the depth, one hand or several.
#include "panel.hpp"

#include "handtrack/core/kinematics.hpp"
#include "handtrack/draw/colormap.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace handtrack::view {
namespace {

using draw::Canvas;
using draw::Rgb;

constexpr double kModelAlpha = 0.6;
constexpr Rgb kTruthCross{0, 230, 255};  // annotated fingertips
constexpr double kLabelBoxAlpha = 0.6;   // the dark box under a hand's label

// "#id side". Strings here are appended piecewise: GCC 12 warns falsely (-Wrestrict) on
// "literal" + std::string.
std::string hand_name(const TrackerOutput& out) {
  std::string name = "#";
  name += std::to_string(out.hand_id);
  name += ' ';
  name += to_string(out.handedness);
  return name;
}

// A model Gaussian as drawn: where, how large, in what colour; depth-sorted across the hands so
// that the nearer hand covers the farther one where they overlap.
struct DrawnGaussian {
  bool visible = false;  // in front of the camera
  double z_mm = 0.0;
  double x = 0.0;
  double y = 0.0;
  double radius = 0.0;
  Rgb colour{};
};

// Scaled orthographic projection of Sec. 3.2: centre projected, sigma_p = sigma_h f / z.
void add_model_gaussians(const FrameView& f, const HandView& h, const CameraIntrinsics& cam, const ViewMap& view,
                         std::vector<DrawnGaussian>& out) {
  const PosedHand hand(*h.model, h.output->params);
  const auto& model_gaussians = h.model->gaussians();
  const HandStyle style = style_of(f, h);
  for (int i = 0; i < hand.gaussian_count(); ++i) {
    Eigen::Vector3d p = hand.centre(i);
    if (h.mirrored_model) p.x() = -p.x();
    if (!(p.z() > 1.0)) {
      out.push_back({false, p.z()});  // sorted with the others, as ever, but not drawn
      continue;
    }
    const auto& mg = model_gaussians[static_cast<size_t>(i)];
    const auto uv = cam.project(p);
    out.push_back({true, p.z(), view.x(uv.x()), view.y(uv.y()), mg.sigma_mm * cam.focal() / p.z() * view.s,
                   style.part(mg.label)});
  }
}

// Skeleton (wrist to each fingertip through its joints) and fingertip discs of one hand.
void draw_skeleton(Canvas& c, const HandStyle& style, const TrackerOutput& out, const CameraIntrinsics& cam,
                   const ViewMap& view, int thick) {
  const auto to_panel = [&](const Eigen::Vector3d& p) {
    const auto uv = cam.project(p);
    return Eigen::Vector2d(view.x(uv.x()), view.y(uv.y()));
  };
  const Eigen::Vector2d wrist = to_panel(out.joints[kWristJoint]);
  for (int finger = 0; finger < kNumFingers; ++finger) {
    Eigen::Vector2d prev = wrist;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d q = to_panel(out.joints[static_cast<size_t>(joint_index(finger, k))]);
      c.line(prev.x(), prev.y(), q.x(), q.y(), style.bone(), thick);
      prev = q;
    }
  }
  for (const auto& j : out.joints) {
    const Eigen::Vector2d q = to_panel(j);
    c.fill_circle(q.x(), q.y(), thick, style.bone());
  }
  for (int finger = 0; finger < kNumFingers; ++finger) {
    const Eigen::Vector2d q = to_panel(out.fingertips[static_cast<size_t>(finger)]);
    c.fill_circle(q.x(), q.y(), 2.0 * thick, style.tip(finger));
    c.circle(q.x(), q.y(), 2.0 * thick, draw::colours::kBlack);
  }
}

// A label's box on the panel, px.
struct LabelBox {
  int x = 0;
  int y = 0;
  int w = 0;
  int h = 0;
  [[nodiscard]] bool overlaps(const LabelBox& o) const {
    return x < o.x + o.w && o.x < x + w && y < o.y + o.h && o.y < y + h;
  }
};

// "#id side conf": a hand's label by the hand, above its joints (below them when there is no room
// above), on a dark box so it reads over the depth. Where the hands overlap in the image their
// labels would too: a label meeting one already drawn (`taken`) goes above that one, or below it
// at the top edge.
void draw_hand_label(Canvas& c, const HandStyle& style, const TrackerOutput& out, const CameraIntrinsics& cam,
                     const ViewMap& view, int scale, std::vector<LabelBox>& taken) {
  double lo_x = 1e9, hi_x = -1e9, lo_y = 1e9, hi_y = -1e9;
  for (const auto& j : out.joints) {
    if (!(j.z() > 1.0)) continue;
    const auto uv = cam.project(j);
    lo_x = std::min(lo_x, view.x(uv.x()));
    hi_x = std::max(hi_x, view.x(uv.x()));
    lo_y = std::min(lo_y, view.y(uv.y()));
    hi_y = std::max(hi_y, view.y(uv.y()));
  }
  if (hi_x < lo_x) return;
  const std::string text = hand_name(out) + format(" %.2f", out.confidence);
  const int w = draw::text_width(text, scale);
  const int h = draw::text_height(text, scale);
  constexpr int kPad = 2;  // px around the text
  const int x = std::clamp(static_cast<int>(std::lround(0.5 * (lo_x + hi_x))) - w / 2, kPad,
                           std::max(kPad, view.width - w - kPad));
  int y = static_cast<int>(std::lround(lo_y)) - h - 3 * kPad;
  if (y < kPad) y = std::min(static_cast<int>(std::lround(hi_y)) + 3 * kPad, view.height - h - kPad);
  LabelBox box{x - kPad, y - kPad, w + 2 * kPad, h + 2 * kPad};
  for (const LabelBox& other : taken) {  // few: one per hand drawn before
    if (!box.overlaps(other)) continue;
    box.y = other.y - box.h - kPad;
    if (box.y < 0) box.y = other.y + other.h + kPad;
  }
  taken.push_back(box);
  c.fill_rect(box.x, box.y, box.w, box.h, draw::colours::kBlack, kLabelBoxAlpha);
  c.text(box.x + kPad, box.y + kPad, text, style.colour, scale);
}

}  // namespace

Panel model_panel(const FrameView& f, const ViewMap& view, std::pair<double, double> range) {
  Canvas c(view.width, view.height, draw::colours::kBlack);
  draw_depth(c, view, *f.depth, range, 0.55);
  // The camera as the hands' inputs carry it (a left hand's unmirrored(): the frame's up to rounding,
  // which one hand's picture has always been drawn with).
  const CameraIntrinsics& cam = f.hands.empty() ? f.depth->camera : f.hands.front().input->camera;
  for (const HandView& h : f.hands) draw_mask_outline(c, view, *h.input, style_of(f, h).mask_outline());
  std::vector<DrawnGaussian> gaussians;
  for (const HandView& h : f.hands) {
    if (posed(*h.output)) add_model_gaussians(f, h, cam, view, gaussians);
  }
  // std::sort, as this panel always sorted one hand's Gaussians: the same order of equally deep ones.
  std::sort(gaussians.begin(), gaussians.end(),
                   [](const DrawnGaussian& a, const DrawnGaussian& b) { return a.z_mm > b.z_mm; });
  for (const DrawnGaussian& g : gaussians) {
    if (!g.visible) continue;
    c.fill_circle(g.x, g.y, g.radius, g.colour, kModelAlpha);
    c.circle(g.x, g.y, g.radius, draw::shade(g.colour, 0.5));
  }
  const int thick = view.width >= 560 ? 3 : 2;
  for (const HandView& h : f.hands) {
    if (posed(*h.output)) draw_skeleton(c, style_of(f, h), *h.output, cam, view, thick);
  }
  for (const Fingertips& hand_tips : f.truth_tips) {  // annotated fingertips: cyan crosses
    for (const auto& tip : hand_tips) {
      if (!tip || !(tip->z() > 1.0)) continue;
      const auto uv = cam.project(*tip);
      const double x = view.x(uv.x()), y = view.y(uv.y());
      c.line(x - 5, y - 5, x + 5, y + 5, kTruthCross, 2);
      c.line(x - 5, y + 5, x + 5, y - 5, kTruthCross, 2);
    }
  }
  Panel p{std::move(c), {}};
  const bool annotated = !f.truth_tips.empty();
  if (f.hands.size() <= 1) {  // as handtrack-view drew one hand before there were two
    const TrackerOutput none;
    const TrackerOutput& out = f.hands.empty() ? none : *f.hands.front().output;
    p.caption = std::string("model: ") + to_string(out.state);
    if (posed(out)) {
      p.caption += std::string(", ") + to_string(out.handedness) + " hand" + format("  conf %.2f", out.confidence) +
                   format("  E %.3g", out.energy);
    }
    if (annotated) {
      if (const auto err = nearest_fingertip_error_mm(out, f.truth_tips); err && posed(out)) {
        p.caption += format("\ntip error %.1f mm (x = truth)", *err);
      }
    }
    return p;
  }
  std::vector<LabelBox> labels;
  for (const HandView& h : f.hands) {
    if (posed(*h.output)) {
      draw_hand_label(p.canvas, style_of(f, h), *h.output, cam, view, caption_scale(view.width), labels);
    }
  }
  p.caption = format("model: %.0f hands", static_cast<double>(f.hands.size())) + (annotated ? ", x = truth" : "");
  for (const HandView& h : f.hands) {
    const TrackerOutput& out = *h.output;
    p.caption += '\n';
    p.caption += hand_name(out);
    p.caption += ' ';
    p.caption += to_string(out.state);
    p.caption += format(", conf %.2f", out.confidence);
    if (const auto err = nearest_fingertip_error_mm(out, f.truth_tips); err && posed(out)) {
      p.caption += format(", tip %.1f mm", *err);
    }
  }
  return p;
}
}  // namespace handtrack::view
