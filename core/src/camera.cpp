#include "handtrack/core/camera.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace handtrack {

namespace {
// A recording played at its own rate waits 1/fps between frames: below 1 fps a "camera" is a
// slide show (and 1e-6 fps waits for days); above 1000 no depth camera exists.
constexpr double kMinFps = 1.0;
constexpr double kMaxFps = 1000.0;
}  // namespace

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
  } else if (!(std::isfinite(fps) && fps >= kMinFps && fps <= kMaxFps)) {
    why << "fps must be in [" << kMinFps << ", " << kMaxFps << "], got " << fps;
  }
  return why.str();
}

DepthImage DepthImage::from_raw(const CameraIntrinsics& camera, const std::vector<uint16_t>& raw) {
  DepthImage image;
  image.assign_raw(camera, raw, 0.0F, 0.0F);
  return image;
}

size_t DepthImage::assign_raw(const CameraIntrinsics& c, const std::vector<uint16_t>& raw, float near_mm, float far_mm) {
  camera = c;
  depth_mm.resize(raw.size());
  const auto scale = static_cast<float>(c.depth_scale_mm);
  size_t in_volume = 0;
  for (size_t i = 0; i < raw.size(); ++i) {
    const float d = static_cast<float>(raw[i]) * scale;
    depth_mm[i] = d;
    in_volume += (d >= near_mm && d <= far_mm) ? 1 : 0;
  }
  return in_volume;
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
