#pragma once
// Pinhole intrinsics of a depth camera, and the image of depth values it delivers.
// Frames: camera frame x right, y down, z forward (mm); pixel (u, v) with u along x, v along y.

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace handtrack {

struct CameraIntrinsics {
  int width = 320;
  int height = 240;
  double fx = 224.502;  // SPEC.md sequence-directory example (Senz3D-like 320x240)
  double fy = 230.494;
  double cx = 160.0;
  double cy = 120.0;
  double depth_scale_mm = 1.0;  // raw depth unit in mm (SR305: 0.125)
  double fps = 60.0;

  // Mean focal length: the f of the paper's scaled orthographic projection (Sec. 3.2).
  [[nodiscard]] double focal() const { return 0.5 * (fx + fy); }

  [[nodiscard]] Eigen::Vector2d project(const Eigen::Vector3d& camera_p_mm) const {
    return {fx * camera_p_mm.x() / camera_p_mm.z() + cx, fy * camera_p_mm.y() / camera_p_mm.z() + cy};
  }
  [[nodiscard]] Eigen::Vector3d unproject(double u, double v, double depth_mm) const {
    return {(u - cx) * depth_mm / fx, (v - cy) * depth_mm / fy, depth_mm};
  }

  // Empty string when the intrinsics are usable, otherwise what is wrong with them.
  [[nodiscard]] std::string problem() const;
};

// A depth image in millimetres, row-major; 0 means "no measurement".
struct DepthImage {
  CameraIntrinsics camera;
  std::vector<float> depth_mm;

  [[nodiscard]] int width() const { return camera.width; }
  [[nodiscard]] int height() const { return camera.height; }
  [[nodiscard]] float at(int u, int v) const { return depth_mm[static_cast<size_t>(v) * camera.width + u]; }
  float& at(int u, int v) { return depth_mm[static_cast<size_t>(v) * camera.width + u]; }

  // Converts raw sensor units (value * depth_scale_mm = mm) into a DepthImage.
  static DepthImage from_raw(const CameraIntrinsics& camera, const std::vector<uint16_t>& raw);
  // Back to raw units (rounded, clamped to 16 bit), e.g. for writing a PNG.
  [[nodiscard]] std::vector<uint16_t> to_raw() const;
};

}  // namespace handtrack
