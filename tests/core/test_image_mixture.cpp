// ImageMixture's slices (the image Gaussians within a model Gaussian's depth reach, Sec. 3.2): a
// depth slice, found through the depth index, holds exactly the Gaussians a search of all finds.
#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/image_mixture.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <random>
#include <utility>
#include <vector>

namespace handtrack {
namespace {

std::vector<ImageGaussian> gaussians_at(const std::vector<double>& depths_mm) {
  std::vector<ImageGaussian> gaussians;
  for (const double d : depths_mm) {
    ImageGaussian g;
    g.depth_mm = d;
    g.u = d / 10.0;
    gaussians.push_back(g);
  }
  return gaussians;
}

// The slice's Gaussians are those with lo <= d <= hi, and its `first` counts those shallower.
void expect_slice(const ImageMixture& mixture, const std::vector<double>& depths_mm, double lo, double hi) {
  const ImageMixtureSlice slice = mixture.depth_slice(lo, hi);
  const auto shallower = static_cast<std::size_t>(std::count_if(depths_mm.begin(), depths_mm.end(), [&](double d) { return d < lo; }));
  const auto within = static_cast<std::size_t>(
      std::count_if(depths_mm.begin(), depths_mm.end(), [&](double d) { return lo <= d && d <= hi; }));
  ASSERT_EQ(slice.size, within) << "[" << lo << ", " << hi << "] of " << depths_mm.size();
  if (within == 0) return;
  EXPECT_EQ(slice.first, shallower);
  for (std::size_t k = 0; k < slice.size; ++k) {
    EXPECT_GE(slice.depth_mm[k], lo);
    EXPECT_LE(slice.depth_mm[k], hi);
    EXPECT_DOUBLE_EQ(slice.u[k], slice.depth_mm[k] / 10.0) << "the columns stay together";
  }
}

TEST(ImageMixture, ADepthSliceHoldsEveryGaussianWithinItsBounds) {
  std::mt19937 rng(7);
  for (const std::size_t n : {1U, 2U, 3U, 17U, 300U}) {
    // Depths of a hand (300-500 mm), rounded to 5 mm in half the draws so that many are equal.
    for (const bool rounded : {false, true}) {
      std::vector<double> depths;
      std::uniform_real_distribution<double> depth(300.0, 500.0);
      for (std::size_t i = 0; i < n; ++i) depths.push_back(rounded ? 5.0 * std::round(depth(rng) / 5.0) : depth(rng));
      ImageMixture mixture;
      mixture.assign(gaussians_at(depths));
      std::uniform_real_distribution<double> bound(250.0, 550.0);
      std::uniform_real_distribution<double> reach(0.0, 40.0);
      for (int t = 0; t < 500; ++t) {
        const double centre = t % 5 == 0 ? depths[static_cast<std::size_t>(t) % n] : bound(rng);
        const double r = t % 7 == 0 ? 0.0 : reach(rng);
        expect_slice(mixture, depths, centre - r, centre + r);
      }
    }
  }
}

TEST(ImageMixture, ADepthSliceAtTheEdgesAndOfEqualDepths) {
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<double> same(20, 400.0);
  ImageMixture mixture;
  mixture.assign(gaussians_at(same));
  for (const auto& [lo, hi] : std::vector<std::pair<double, double>>{
           {400.0, 400.0}, {399.0, 401.0}, {0.0, 399.9}, {400.1, 1000.0}, {-inf, inf}, {-inf, 400.0}, {400.0, inf}}) {
    expect_slice(mixture, same, lo, hi);
  }
  const std::vector<double> spread{310.0, 320.0, 320.0, 330.0, 490.0};
  mixture.assign(gaussians_at(spread));
  for (const auto& [lo, hi] : std::vector<std::pair<double, double>>{
           {0.0, 309.9}, {310.0, 310.0}, {320.0, 320.0}, {311.0, 489.0}, {490.0, 490.0}, {490.1, inf}, {-inf, inf}}) {
    expect_slice(mixture, spread, lo, hi);
  }
  mixture.assign({});
  EXPECT_EQ(mixture.depth_slice(0.0, 1000.0).size, 0U);
}

}  // namespace
}  // namespace handtrack
