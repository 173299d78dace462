#include "handtrack/core/camera.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace handtrack {

std::string CameraIntrinsics::problem() const {
  std::ostringstream why;
  if (width < 8 || height < 8 || width > 8192 || height > 8192) {
    why << "width and height must be in [8, 8192], got " << width << "x" << height;
  } else if (!(std::isfinite(fx) && fx > 1.0 && std::isfinite(fy) && fy > 1.0)) {
    why << "fx and fy must be finite and > 1 pixel, got " << fx << ", " << fy;
  } else if (!(std::isfinite(cx) && std::isfinite(cy) && cx >= 0 && cy >= 0 && cx <= width && cy <= height)) {
    why << "cx, cy must lie inside the image, got " << cx << ", " << cy;
  } else if (!(std::isfinite(depth_scale_mm) && depth_scale_mm > 0.0 && depth_scale_mm <= 100.0)) {
    why << "depth_scale_mm must be in (0, 100], got " << depth_scale_mm;
  } else if (!(std::isfinite(fps) && fps > 0.0 && fps <= 1000.0)) {
    why << "fps must be in (0, 1000], got " << fps;
  }
  return why.str();
}

DepthImage DepthImage::from_raw(const CameraIntrinsics& camera, const std::vector<uint16_t>& raw) {
  DepthImage image{camera, std::vector<float>(raw.size())};
  const auto scale = static_cast<float>(camera.depth_scale_mm);
  for (size_t i = 0; i < raw.size(); ++i) image.depth_mm[i] = static_cast<float>(raw[i]) * scale;
  return image;
}

std::vector<uint16_t> DepthImage::to_raw() const {
  std::vector<uint16_t> raw(depth_mm.size());
  const double inv = 1.0 / camera.depth_scale_mm;
  for (size_t i = 0; i < raw.size(); ++i) {
    const double v = std::round(static_cast<double>(depth_mm[i]) * inv);
    raw[i] = static_cast<uint16_t>(std::isfinite(v) ? std::clamp(v, 0.0, 65535.0) : 0.0);
  }
  return raw;
}

}  // namespace handtrack
