#pragma once
// The median filter of the depth image "to remove flying pixels" (paper Sec. 4): the exact 3x3
// median from sorted column triples (vectorised), any other radius by sorting each window.
// Private to core (DepthInputBuilder); its scratch is reused from frame to frame.
#include "handtrack/core/camera.hpp"

#include <vector>

namespace handtrack {

class MedianFilter {
 public:
  // The median of each (2 radius + 1)^2 window of depth.depth_mm (borders repeat the edge pixel,
  // non-finite samples count as 0); valid until the next call.
  const std::vector<float>& apply(const DepthImage& depth, int radius);
  // The last apply()'s result.
  [[nodiscard]] const std::vector<float>& last() const { return out_; }

 private:
  void median_3x3(const DepthImage& depth);
  void median_any(const DepthImage& depth, int radius);

  std::vector<float> out_;
  std::vector<float> window_;         // median_any's window
  std::vector<float> clean_;          // median_3x3's input, non-finite samples as 0
  std::vector<float> lo_, mid_, hi_;  // median_3x3's sorted column triples
};

}  // namespace handtrack
