#pragma once
// Segmentation of the hand in the filtered depth (paper Sec. 4: "the hand is segmented from the
// rest of the body"): near the last pose's palm when there is a hint, otherwise the best connected
// surface in the working volume; the forearm cut at the wrist plane. Private to core
// (DepthInputBuilder); its scratch is reused from frame to frame.
#include "handtrack/core/depth_input.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <optional>
#include <vector>

namespace handtrack {

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
// Measured: synthetic hands with their forearms 0-0.10, the shoulder of the .oni recording
// 0.18-0.24; a real hand straddling the far plane (SR305 231615/100: 0.25) is missed until it
// comes nearer, which is what a working volume means.
inline constexpr double kMaxFarPlaneCut = 0.15;

// Share of surface `blob`'s outline where the depth (before the working volume: `unclamped_mm`)
// goes on just beyond the far plane.
double far_plane_cut_fraction(const DepthInputConfig& config, const std::vector<float>& unclamped_mm,
                              const std::vector<int>& component, int blob, int w, int h);

class HandSegmenter {
 public:
  // Reads out.camera, out.filtered_mm and the median-filtered depth before the working volume
  // (`unclamped_mm`, to see surfaces that go on beyond the far plane); writes out.hand_mask,
  // hand_pixels, hand_centroid_mm, palm_centre_mm and finger_axis.
  // Pixels set in `foreign` (may be null) are never the hand (DepthInputBuilder::build).
  void segment(const DepthInputConfig& config, const std::vector<float>& unclamped_mm,
               const std::optional<HandHint>& hint, DepthInput& out, const std::vector<uint8_t>* foreign = nullptr);
  // The segmented hand's pixels, for the quadtree.
  [[nodiscard]] const PixelBox& hand_box() const { return hand_box_; }

 private:
  std::vector<int> component_;
  std::vector<Surface> blobs_;
  std::vector<float> own_mm_;  // the filtered depth without the foreign pixels (surfaces)
  std::vector<int> stack_;
  PixelBox hand_box_{0, 0, -1, -1};                     // the segmented hand's pixels
  Eigen::Vector3d hand_sum_ = Eigen::Vector3d::Zero();  // sum of their 3D points
  std::vector<double> ray_u_;                           // (u - c_x) / f_x per image column
};

}  // namespace handtrack
