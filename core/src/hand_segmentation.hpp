#pragma once
// Segmentation of the hand in the filtered depth (paper Sec. 4: "the hand is segmented from the
// rest of the body"): near the last pose's palm when there is a hint, otherwise the best connected
// surface in the working volume; the forearm cut at the wrist plane. Private to core
// (DepthInputBuilder); its scratch is reused from frame to frame.
#include "body_eraser.hpp"
#include "surfaces.hpp"

#include "handtrack/core/depth_input.hpp"

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace handtrack {

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
  std::vector<float> own_mm_;  // the filtered depth without the foreign pixels, or a body's wide parts
  BodyEraser body_;
  std::vector<int> stack_;
  PixelBox hand_box_{0, 0, -1, -1};                     // the segmented hand's pixels
  Eigen::Vector3d hand_sum_ = Eigen::Vector3d::Zero();  // sum of their 3D points
  std::vector<double> ray_u_;                           // (u - c_x) / f_x per image column
};

}  // namespace handtrack
