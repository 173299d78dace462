#pragma once
// A desk, a table or a wall the hand rests on or touches (ours; the paper's scenes keep the hand
// clear of everything else, Sec. 4 segments it "from the rest of the body"). Where the hand touches
// a surface, the depth is continuous from one to the other, so segmentation (connected surfaces
// whose neighbouring depths differ < continuity_mm) sees one surface: a desk with a hand on it.
// A hand is at most ~200 cm^2 of surface; a surface of the working volume that is planar over more
// than SupportPlaneConfig::min_area_mm2 is not a hand, and its pixels are taken out of the
// working volume before segmentation. Private to core (DepthInputBuilder); scratch is reused.
//
// The plane is found by RANSAC (Fischler and Bolles 1981) on a grid of the working volume's
// points: planes through 3 sample points, scored by the area (sum of z^2 / (f_x f_y) per sample)
// of the samples within half the band; the best is refitted by least squares to its inliers (the
// normal is the covariance's eigenvector of least variance). A fixed seed makes it deterministic.
#include "handtrack/core/depth_input.hpp"

#include <Eigen/Core>

#include <vector>

namespace handtrack {

class SupportPlane {
 public:
  // Looks for a plane covering at least config.min_area_mm2 among the pixels of `depth_mm`
  // (working volume: 0 outside it); true when there is one. Frames whose working volume holds less
  // than min_area_mm2 of surface cost one pass over a grid of 1/16 of the pixels.
  bool find(const SupportPlaneConfig& config, const CameraIntrinsics& camera, const std::vector<float>& depth_mm);
  // Zeroes the pixels of `depth_mm` within config.band_mm of the plane found last, or beyond it
  // (an image of the camera find() was given).
  void erase(const CameraIntrinsics& camera, std::vector<float>& depth_mm) const;

 private:
  // The grid's points (mm) and the area each stands for (mm^2), as columns for the vectorised score.
  std::vector<double> x_;
  std::vector<double> y_;
  std::vector<double> z_;
  std::vector<double> area_;
  Eigen::Vector3d normal_ = Eigen::Vector3d::UnitZ();  // unit, toward the camera
  double offset_ = 0.0;                                // normal_ . x = offset_ on the plane
  double band_mm_ = 0.0;
  std::vector<double> column_slope_;  // n_x (u - c_x) / f_x per image column
};

}  // namespace handtrack
