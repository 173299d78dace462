#include "support_plane.hpp"

#include <Eigen/Eigenvalues>

#include <cmath>
#include <cstdint>

namespace handtrack {

namespace {

using Eigen::Vector3d;

// Sample grid: every kGridStep-th pixel of every kGridStep-th row at 320 px image width.
constexpr int kGridStep = 4;
// RANSAC hypotheses, at most. With a desk filling more than half the working volume's samples, 3
// samples from it come up with probability >= 1/8 each, and 48 hypotheses miss it with < 2e-3.
constexpr int kHypotheses = 48;
// A plane with this share of the working volume's area is the one: the search stops there.
constexpr double kClearMajority = 0.6;
// Three samples closer together than this (mm, the sides of their triangle) give a plane too
// uncertain to score.
constexpr double kMinSpanMm = 20.0;

// xorshift64: a fixed sequence, so that a frame always gives the same plane.
struct Xorshift {
  uint64_t state = 0x9E3779B97F4A7C15ULL;
  size_t below(size_t n) {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return static_cast<size_t>(state % n);
  }
};

// The area of the samples within `tolerance` of the plane n . x = offset: branch-free, vectorised.
double inlier_area(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>& z,
                   const std::vector<double>& area, const Vector3d& n, double offset, double tolerance) {
  const double* const px = x.data();
  const double* const py = y.data();
  const double* const pz = z.data();
  const double* const pa = area.data();
  const double nx = n.x();
  const double ny = n.y();
  const double nz = n.z();
  double sum = 0.0;
#pragma omp simd reduction(+ : sum)
  for (size_t i = 0; i < x.size(); ++i) {
    const double distance = std::abs(nx * px[i] + ny * py[i] + nz * pz[i] - offset);
    sum += distance < tolerance ? pa[i] : 0.0;
  }
  return sum;
}

}  // namespace

bool SupportPlane::find(const SupportPlaneConfig& config, const CameraIntrinsics& camera,
                        const std::vector<float>& depth_mm) {
  if (!config.enabled) return false;
  const int w = camera.width;
  const int h = camera.height;
  const int step = std::max(1, kGridStep * w / 320);
  const double pixel_area = static_cast<double>(step) * step / (camera.fx * camera.fy);  // x z^2
  x_.clear();
  y_.clear();
  z_.clear();
  area_.clear();
  double total = 0.0;
  for (int v = step / 2; v < h; v += step) {
    for (int u = step / 2; u < w; u += step) {
      const float z = depth_mm[static_cast<size_t>(v) * w + u];
      if (z <= 0.0F) continue;
      const Vector3d p = camera.unproject(u, v, z);
      x_.push_back(p.x());
      y_.push_back(p.y());
      z_.push_back(p.z());
      area_.push_back(pixel_area * z * z);
      total += area_.back();
    }
  }
  if (total < config.min_area_mm2) return false;

  // RANSAC: the plane through 3 samples with the most area within half the band.
  const double tolerance = 0.5 * config.band_mm;
  const size_t n = x_.size();
  const auto sample = [&](size_t i) { return Vector3d(x_[i], y_[i], z_[i]); };
  Xorshift rng;
  Vector3d best_normal = Vector3d::UnitZ();
  double best_offset = 0.0;
  double best_area = 0.0;
  for (int k = 0; k < kHypotheses && best_area < kClearMajority * total; ++k) {
    const Vector3d a = sample(rng.below(n));
    const Vector3d b = sample(rng.below(n));
    const Vector3d c = sample(rng.below(n));
    if ((b - a).norm() < kMinSpanMm || (c - a).norm() < kMinSpanMm || (c - b).norm() < kMinSpanMm) continue;
    const Vector3d cross = (b - a).cross(c - a);
    const double norm = cross.norm();
    if (norm < kMinSpanMm * kMinSpanMm) continue;  // nearly collinear
    const Vector3d normal = cross / norm;
    const double offset = normal.dot(a);
    const double area = inlier_area(x_, y_, z_, area_, normal, offset, tolerance);
    if (area > best_area) {
      best_area = area;
      best_normal = normal;
      best_offset = offset;
    }
  }
  if (best_area < config.min_area_mm2) return false;

  // Least squares on the inliers: through their (area-weighted) mean, normal of least variance.
  const auto inlier = [&](size_t i) { return std::abs(best_normal.dot(sample(i)) - best_offset) < tolerance; };
  Vector3d mean = Vector3d::Zero();
  double weight = 0.0;
  for (size_t i = 0; i < n; ++i) {
    if (!inlier(i)) continue;
    mean += area_[i] * sample(i);
    weight += area_[i];
  }
  mean /= weight;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    if (!inlier(i)) continue;
    const Vector3d q = sample(i) - mean;
    cov += area_[i] * q * q.transpose();
  }
  normal_ = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
  if (normal_.dot(mean) > 0.0) normal_ = -normal_;  // toward the camera (at the origin)
  offset_ = normal_.dot(mean);
  band_mm_ = config.band_mm;
  column_slope_.resize(static_cast<size_t>(w));
  for (int u = 0; u < w; ++u) column_slope_[static_cast<size_t>(u)] = normal_.x() * (u - camera.cx) / camera.fx;
  return true;
}

// A pixel's point is z (r_u, r_v, 1) with r_u = (u - c_x) / f_x, r_v = (v - c_y) / f_y, so its
// height above the plane is z (n_x r_u + n_y r_v + n_z) - offset: per row one multiply-add a pixel.
void SupportPlane::erase(const CameraIntrinsics& camera, std::vector<float>& depth_mm) const {
  const int w = camera.width;
  const int h = camera.height;
  const double* const column = column_slope_.data();
  for (int v = 0; v < h; ++v) {
    const double row = normal_.y() * (v - camera.cy) / camera.fy + normal_.z();
    float* const depth = depth_mm.data() + static_cast<size_t>(v) * w;
    for (int u = 0; u < w; ++u) {
      const bool on_or_beyond = depth[u] * (row + column[u]) - offset_ < band_mm_;
      depth[u] = on_or_beyond ? 0.0F : depth[u];
    }
  }
}

}  // namespace handtrack
