#include "handtrack/core/camera_roll.hpp"

#include "handtrack/core/pose.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace handtrack {

namespace {

bool sideways(CameraRoll roll) { return roll == CameraRoll::k90 || roll == CameraRoll::k270; }

}  // namespace

// The upright pixel (u', v') of the camera's (u, v) (W x H, p_upright = R_z(-phi) p_camera):
//   90: (v, W-1-u)   180: (W-1-u, H-1-v)   270: (H-1-v, u)
// and the principal point with it (at 90 and 270 the focal lengths swap with the axes).
CameraIntrinsics upright_camera(const CameraIntrinsics& camera, CameraRoll roll) {
  CameraIntrinsics upright = camera;
  const double last_u = camera.width - 1.0;
  const double last_v = camera.height - 1.0;
  if (sideways(roll)) {
    std::swap(upright.width, upright.height);
    std::swap(upright.fx, upright.fy);
  }
  switch (roll) {
    case CameraRoll::k0: break;
    case CameraRoll::k90: upright.cx = camera.cy; upright.cy = last_u - camera.cx; break;
    case CameraRoll::k180: upright.cx = last_u - camera.cx; upright.cy = last_v - camera.cy; break;
    case CameraRoll::k270: upright.cx = last_v - camera.cy; upright.cy = camera.cx; break;
  }
  return upright;
}

template <typename T>
void turn_upright(const std::vector<T>& pixels, const CameraIntrinsics& camera, CameraRoll roll,
                  std::vector<T>* upright) {
  const auto w = static_cast<size_t>(camera.width);
  const auto h = static_cast<size_t>(camera.height);
  if (camera.width <= 0 || camera.height <= 0 || pixels.size() != w * h) {
    upright->clear();
    return;
  }
  upright->resize(w * h);
  T* out = upright->data();
  switch (roll) {
    case CameraRoll::k0: std::copy(pixels.begin(), pixels.end(), out); return;
    case CameraRoll::k180: std::reverse_copy(pixels.begin(), pixels.end(), out); return;
    default: break;
  }
  // 90 and 270: the upright image (h wide, w high) is the camera's transposed with one axis
  // reversed; in tiles, so that the reads down the camera's columns stay in cache.
  constexpr size_t kTile = 32;
  for (size_t v0 = 0; v0 < w; v0 += kTile) {
    for (size_t u0 = 0; u0 < h; u0 += kTile) {
      for (size_t v = v0; v < std::min(v0 + kTile, w); ++v) {
        for (size_t u = u0; u < std::min(u0 + kTile, h); ++u) {
          // 90: from (W-1-v', u'); 270: from (v', H-1-u').
          const size_t from = roll == CameraRoll::k90 ? u * w + (w - 1 - v) : (h - 1 - u) * w + v;
          out[v * h + u] = pixels[from];
        }
      }
    }
  }
}

template void turn_upright(const std::vector<float>&, const CameraIntrinsics&, CameraRoll, std::vector<float>*);
template void turn_upright(const std::vector<uint8_t>&, const CameraIntrinsics&, CameraRoll, std::vector<uint8_t>*);

void turn_upright(const DepthImage& image, CameraRoll roll, DepthImage* upright) {
  turn_upright(image.depth_mm, image.camera, roll, &upright->depth_mm);
  upright->camera = upright_camera(image.camera, roll);
  upright->mirrored = image.mirrored;
}

const DepthImage& upright_frame(const DepthImage& image, CameraRoll roll, DepthImage* scratch) {
  if (roll == CameraRoll::k0) return image;
  turn_upright(image, roll, scratch);
  return *scratch;
}

Eigen::Vector3d turn_to_camera(CameraRoll roll, const Eigen::Vector3d& p) {
  switch (roll) {
    case CameraRoll::k0: return p;
    case CameraRoll::k90: return {-p.y(), p.x(), p.z()};
    case CameraRoll::k180: return {-p.x(), -p.y(), p.z()};
    case CameraRoll::k270: return {p.y(), -p.x(), p.z()};
  }
  return p;
}

Eigen::Vector3d turn_to_upright(CameraRoll roll, const Eigen::Vector3d& p) {
  return turn_to_camera(inverse(roll), p);
}

void turn_to_camera(CameraRoll roll, TrackerOutput* output) {
  if (roll == CameraRoll::k0) return;
  for (auto& j : output->joints) j = turn_to_camera(roll, j);
  for (auto& t : output->fingertips) t = turn_to_camera(roll, t);
  output->palm_centre = turn_to_camera(roll, output->palm_centre);
  output->palm_normal = turn_to_camera(roll, output->palm_normal);
  // The parameters: R_z(phi) for a right hand, R_z(-phi) in a left hand's mirrored image.
  const CameraRoll params_roll = output->handedness == Handedness::kLeft
                                     ? inverse(roll)
                                     : roll;
  PoseParams& params = output->params;
  const Eigen::Vector3d wrist = params.segment<3>(kTranslationParam);
  params.segment<3>(kTranslationParam) = turn_to_camera(params_roll, wrist);
  const Eigen::Vector3d r = params.segment<3>(kRotationParam);
  const Eigen::Matrix3d exp_r =
      r.norm() > 0.0 ? Eigen::AngleAxisd(r.norm(), r.normalized()).toRotationMatrix() : Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(degrees(params_roll) * M_PI / 180.0, Eigen::Vector3d::UnitZ())
                                   .toRotationMatrix();
  const Eigen::AngleAxisd turned(turn * exp_r);
  params.segment<3>(kRotationParam) = turned.angle() * turned.axis();
}

void turn_to_camera(CameraRoll roll, HandsOutput* output) {
  for (int i = 0; i < output->count; ++i) turn_to_camera(roll, &output->hands[static_cast<size_t>(i)]);
}

}  // namespace handtrack
