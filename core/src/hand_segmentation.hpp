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
  // A connected part of the selected pixels is the hand's only when it comes within this many hand
  // lengths of the palm centre (a finger apart from the palm in depth does within about 0.3-0.4).
  static constexpr double kNearPalmInLengths = 0.5;
  // Takes out of `mask` (1 = selected; `kept` pixels, hand_box_ and hand_sum_ theirs) the sizeable
  // connected parts that do not come within kNearPalmInLengths of `centre`; returns how many
  // pixels remain.
  int keep_near_palm(const DepthInputConfig& config, const CameraIntrinsics& cam, const std::vector<float>& depth,
                     const Eigen::Vector3d& centre, std::vector<uint8_t>& mask, int kept);

  std::vector<int> component_;
  std::vector<Surface> blobs_;
  std::vector<float> own_mm_;  // the filtered depth without the foreign pixels, or a body's wide parts
  BodyEraser body_;
  std::vector<int> stack_;
  std::vector<int> part_;  // keep_near_palm(): one part's pixels
  PixelBox hand_box_{0, 0, -1, -1};                     // the segmented hand's pixels
  Eigen::Vector3d hand_sum_ = Eigen::Vector3d::Zero();  // sum of their 3D points
  std::vector<double> ray_u_;                           // (u - c_x) / f_x per image column
  // Unprojection by ray (as segment() sets ray_u_): p = (r_u d, r_v d, d), r_v = (v - c_y) / f_y.
  static double ray_v_of(const CameraIntrinsics& cam, int v) { return (v - cam.cy) / cam.fy; }
  [[nodiscard]] Eigen::Vector3d ray_point(int u, double r_v, float depth) const {
    return {ray_u_[static_cast<size_t>(u)] * depth, r_v * depth, depth};
  }
};

}  // namespace handtrack
