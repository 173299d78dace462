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

class HandSegmenter {
 public:
  // Reads out.camera, out.filtered_mm and the median-filtered depth before the working volume
  // (`unclamped_mm`, to see surfaces that go on beyond the far plane); writes out.hand_mask,
  // hand_pixels, hand_centroid_mm, palm_centre_mm and finger_axis.
  void segment(const DepthInputConfig& config, const std::vector<float>& unclamped_mm,
               const std::optional<HandHint>& hint, DepthInput& out);
  // The segmented hand's pixels, for the quadtree.
  [[nodiscard]] const PixelBox& hand_box() const { return hand_box_; }

 private:
  // Share of a connected surface's outline where it goes on just beyond the far plane.
  [[nodiscard]] double far_plane_cut_fraction(const DepthInputConfig& config, const std::vector<float>& unclamped_mm,
                                              const DepthInput& out, int blob) const;

  std::vector<int> component_;
  std::vector<int> stack_;
  PixelBox hand_box_{0, 0, -1, -1};                     // the segmented hand's pixels
  Eigen::Vector3d hand_sum_ = Eigen::Vector3d::Zero();  // sum of their 3D points
  std::vector<double> ray_u_;                           // (u - c_x) / f_x per image column
};

}  // namespace handtrack
