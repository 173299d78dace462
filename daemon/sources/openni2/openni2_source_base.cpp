// The shared helpers of openni2_source_base.hpp.
#include "openni2_source_base.hpp"

#include <algorithm>
#include <cmath>

namespace handtrack::daemon::openni2 {

std::string extended_error() {
  const char* e = openni::OpenNI::getExtendedError();
  std::string s = e ? e : "";
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return {};
  s = s.substr(first, s.find_last_not_of(" \t\r\n") - first + 1);
  std::replace(s.begin(), s.end(), '\n', ' ');
  return s;
}

std::string with_detail(std::string what) {
  const std::string detail = extended_error();
  if (!detail.empty()) what += " (" + detail + ")";
  return what;
}

double depth_unit_mm(openni::PixelFormat format) {
  switch (format) {
    case openni::PIXEL_FORMAT_DEPTH_1_MM:
      return 1.0;
    case openni::PIXEL_FORMAT_DEPTH_100_UM:
      return 0.1;
    default:
      return 0.0;
  }
}

bool intrinsics_from_stream(openni::VideoStream& stream, CameraIntrinsics* camera, std::string* why) {
  const openni::VideoMode mode = stream.getVideoMode();
  const double unit_mm = depth_unit_mm(mode.getPixelFormat());
  if (unit_mm == 0.0) {
    *why = "the depth stream delivers pixel format " + std::to_string(static_cast<int>(mode.getPixelFormat())) +
           ", not depth in 1 mm or 100 um";
    return false;
  }
  const double hfov = stream.getHorizontalFieldOfView();
  const double vfov = stream.getVerticalFieldOfView();
  if (!(hfov > 0.0 && hfov < M_PI) || !(vfov > 0.0 && vfov < M_PI)) {
    *why = "the depth stream reports no usable field of view (h " + std::to_string(hfov) + ", v " +
           std::to_string(vfov) + " rad)";
    return false;
  }
  CameraIntrinsics c;
  c.width = mode.getResolutionX();
  c.height = mode.getResolutionY();
  c.fx = 0.5 * c.width / std::tan(0.5 * hfov);
  c.fy = 0.5 * c.height / std::tan(0.5 * vfov);
  c.cx = 0.5 * c.width;
  c.cy = 0.5 * c.height;
  c.depth_scale_mm = unit_mm;
  c.fps = mode.getFps() > 0 ? mode.getFps() : 30.0;
  if (const std::string problem = c.problem(); !problem.empty()) {
    *why = "intrinsics from the device are unusable: " + problem;
    return false;
  }
  *camera = c;
  return true;
}

}  // namespace handtrack::daemon::openni2
