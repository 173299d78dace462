#pragma once
// The connected surfaces of the working volume (paper Sec. 4 segments the hand as one): what
// segmentation, the body eraser and the two-hand splitter share. Private to core.
#include "handtrack/core/depth_input.hpp"

#include <algorithm>
#include <vector>

namespace handtrack {

// Room for this many surfaces from the start in per-surface storage (noise makes dozens of
// one-pixel surfaces, a hand and its forearm one or a few): a pipeline's frames each have their
// own, and each would otherwise grow it frame by frame as it meets more surfaces.
inline constexpr size_t kReservedSurfaces = 1024;

// Inclusive pixel bounding box; empty while u1 < u0.
struct PixelBox {
  int u0, v0, u1, v1;
  void add(int u, int v) {
    u0 = std::min(u0, u);
    v0 = std::min(v0, v);
    u1 = std::max(u1, u);
    v1 = std::max(v1, v);
  }
};

// The 4-connected flood fill of the segmentation's region steps (label_surfaces, a held object's
// regions, a tracked hand's far parts, the body eraser's outline parts). Floods the cells of `box`
// in a grid `w` cells wide from the cells on `stack`, each marked by the caller: a 4-neighbour j of
// a flooded cell i joins when `enter(j, i)` holds (enter marks it, so no cell joins twice), and
// `visit(i)` sees each flooded cell once. `stack` is scratch: empty afterwards.
template <typename Enter, typename Visit>
void flood4(const PixelBox& box, int w, std::vector<int>& stack, const Enter& enter, const Visit& visit) {
  const auto step = static_cast<size_t>(w);
  while (!stack.empty()) {
    const auto i = static_cast<size_t>(stack.back());
    stack.pop_back();
    visit(i);
    const int u = static_cast<int>(i % step);
    const int v = static_cast<int>(i / step);
    if (u > box.u0 && enter(i - 1, i)) stack.push_back(static_cast<int>(i - 1));
    if (u < box.u1 && enter(i + 1, i)) stack.push_back(static_cast<int>(i + 1));
    if (v > box.v0 && enter(i - step, i)) stack.push_back(static_cast<int>(i - step));
    if (v < box.v1 && enter(i + step, i)) stack.push_back(static_cast<int>(i + step));
  }
}

// A connected surface of the working volume: 4-neighbours whose depths differ less than
// DepthInputConfig::continuity_mm.
struct Surface {
  int pixels = 0;
  double depth_sum = 0.0;  // mm, over its pixels
  [[nodiscard]] double mean_depth() const { return depth_sum / pixels; }
};

// The area in mm^2 that `pixels` pixels cover at `depth_mm` (each pixel z/f_x by z/f_y).
inline double surface_area_mm2(const CameraIntrinsics& camera, int pixels, double depth_mm) {
  return pixels * depth_mm * depth_mm / (camera.fx * camera.fy);
}

// Labels the connected surfaces of `d` (0 = outside the working volume): component[i] = index into
// `surfaces`, -1 for no depth. `stack` is scratch. Storage is reused.
void label_surfaces(const DepthInputConfig& config, const std::vector<float>& d, int w, int h, std::vector<int>& component,
                    std::vector<int>& stack, std::vector<Surface>& surfaces);

// A surface whose outline runs along the far plane of the working volume for more than this share
// is a larger surface (a shoulder, a desk) reaching into the volume, not a hand in front of one.
// Measured: synthetic hands with their forearms 0-0.10 (at the benchmark's distances), the
// shoulder of the .oni recording 0.16-0.24; a real hand straddling the far plane (SR305
// 231615/100: 0.25) is missed until it comes nearer, which is what a working volume means.
inline constexpr double kMaxFarPlaneCut = 0.15;

// ... unless it comes this much nearer than the far plane: then it is a hand held in front, whose
// forearm reaches back through the far plane. The farther the hand, the larger that share of its
// small outline: hands 80 mm farther than the benchmark's (handtrack-synth --depth-offset 80) cut
// more than 0.15 (up to 0.30) in 249 frames of five sequences, and came 116-222 mm nearer than
// the far plane; the shoulder of the .oni recording comes 55-63 mm nearer, the slanted shoulder
// of the suite's test 60 (docs/TRACKER.md, "Hands nearer and farther").
inline constexpr double kMinHandReachMm = 100.0;

// Where surface `blob` meets the far plane: the share of its outline where the depth (before the
// working volume: `unclamped_mm`) goes on just beyond the far plane, and its nearest depth.
struct FarPlaneCut {
  double share = 0.0;
  float nearest_mm = 0.0F;
};
FarPlaneCut far_plane_cut(const DepthInputConfig& config, const std::vector<float>& unclamped_mm,
                          const std::vector<int>& component, int blob, int w, int h);

// Whether a surface so cut is a larger surface reaching into the working volume through its far
// plane: more than kMaxFarPlaneCut of its outline, and no pixel kMinHandReachMm nearer than it.
inline bool reaches_in_through_far_plane(const DepthInputConfig& config, const FarPlaneCut& cut) {
  return cut.share > kMaxFarPlaneCut && cut.nearest_mm > config.far_mm - kMinHandReachMm;
}

}  // namespace handtrack
