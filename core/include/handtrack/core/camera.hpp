#pragma once
// Pinhole intrinsics of a depth camera, and the image of depth values it delivers.
// Frames: camera frame x right, y down, z forward (mm); pixel (u, v) with u along x, v along y.

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace handtrack {

// The SPEC.md sequence-directory example camera (a Senz3D-like depth camera, 320x240 at 60 fps,
// principal point at the image centre): the one home of the default intrinsics. CameraIntrinsics{}
// is this camera; the synthetic camera renders with it (scaled to other sizes); the part forest's
// offsets are trained at its focal lengths.
struct SpecCamera {
  static constexpr int kWidth = 320;
  static constexpr int kHeight = 240;
  static constexpr double kFx = 224.502;
  static constexpr double kFy = 230.494;
  static constexpr double kFps = 60.0;
};

// The RealSense SR305 at 640x480 (the real frames of ../shared/data/real-sr305): depth in 1/8 mm.
struct Sr305Camera {
  static constexpr int kWidth = 640;
  static constexpr int kHeight = 480;
  static constexpr double kFx = 476.007;
  static constexpr double kFy = 476.007;
  static constexpr double kCx = 313.683;
  static constexpr double kCy = 242.755;
  static constexpr double kDepthScaleMm = 0.125;
};

struct CameraIntrinsics {
  int width = SpecCamera::kWidth;
  int height = SpecCamera::kHeight;
  double fx = SpecCamera::kFx;
  double fy = SpecCamera::kFy;
  double cx = 0.5 * SpecCamera::kWidth;
  double cy = 0.5 * SpecCamera::kHeight;
  double depth_scale_mm = 1.0;  // raw depth unit in mm (SR305: 0.125)
  double fps = SpecCamera::kFps;

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
  // The scene's mirror image about x = 0, as the camera would take it (Tracker: a left hand is
  // tracked as the right hand of this image). Anything else given per pixel of the camera's own
  // frame (ground-truth labels, FixedLabels) must be mirrored to go with it.
  bool mirrored = false;

  [[nodiscard]] int width() const { return camera.width; }
  [[nodiscard]] int height() const { return camera.height; }
  [[nodiscard]] float at(int u, int v) const { return depth_mm[static_cast<size_t>(v) * camera.width + u]; }
  float& at(int u, int v) { return depth_mm[static_cast<size_t>(v) * camera.width + u]; }

  // Converts raw sensor units (value * depth_scale_mm = mm) into a DepthImage.
  static DepthImage from_raw(const CameraIntrinsics& camera, const std::vector<uint16_t>& raw);
  // The same in place (no allocation once depth_mm has the size): returns how many pixels lie in
  // [near_mm, far_mm], the working volume of Sec. 4 (0: nothing there to track).
  size_t assign_raw(const CameraIntrinsics& camera, const std::vector<uint16_t>& raw, float near_mm, float far_mm);
  // Back to raw units (rounded, clamped to 16 bit), e.g. for writing a PNG.
  [[nodiscard]] std::vector<uint16_t> to_raw() const;
};

}  // namespace handtrack
