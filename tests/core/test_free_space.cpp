// FreeSpaceMap (E_free's distances): Euclidean distances to the nearest pixel where the hand can be
// (within three quarters of a pixel of the exact ones where whole cells of 2 x 2 pixels are not
// free: the map is held in such cells), what
// counts as free space, the image's edge, the cap, and the bilinear sample.
#include "handtrack/core/free_space.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace handtrack {
namespace {

constexpr float kHandMm = 400.0F;
// The map's cells are 2 x 2 pixels: its distances are within this of the exact ones where the
// pixels that are not free fill whole cells, away from creases ...
constexpr double kCellTolerancePx = 0.75;
// ... and within a pixel on a crease, where the nearest pixel that is not free changes from one
// region to another and the bilinear sample between cell centres (2 px apart) cuts the ridge.
constexpr double kCreaseTolerancePx = 1.0;

// A 320x240 scene: a wall at 700 mm (free: far behind the hand), a 30x40 px hand at 400 mm.
struct Scene {
  CameraIntrinsics camera;
  std::vector<float> depth;
  std::vector<uint8_t> mask;
  explicit Scene(int width = 320, int height = 240) {
    camera.width = width;
    camera.height = height;
    depth.assign(static_cast<size_t>(width) * static_cast<size_t>(height), 700.0F);
    mask.assign(depth.size(), 0);
  }
  void fill(int u0, int v0, int u1, int v1, float mm, bool hand) {
    for (int v = v0; v < v1; ++v) {
      for (int u = u0; u < u1; ++u) {
        const size_t i = static_cast<size_t>(v) * camera.width + u;
        depth[i] = mm;
        mask[i] = hand ? 1 : 0;
      }
    }
  }
  [[nodiscard]] bool free_at(int u, int v, float margin_mm) const {
    if (u < 0 || v < 0 || u >= camera.width || v >= camera.height) return false;
    const float d = depth[static_cast<size_t>(v) * camera.width + u];
    return d <= 0.0F || d > kHandMm + margin_mm;
  }
  // Brute force: the distance from (u, v) to the nearest pixel that is not free, within `window`
  // pixels, capped.
  [[nodiscard]] double brute_distance(int u, int v, double cap, float margin_mm) const {
    double best = std::numeric_limits<double>::infinity();
    const int window = static_cast<int>(cap) + 2;
    for (int y = v - window; y <= v + window; ++y) {
      for (int x = u - window; x <= u + window; ++x) {
        if (!free_at(x, y, margin_mm)) best = std::min(best, std::hypot(x - u, y - v));
      }
    }
    return std::min(best, cap);
  }
};

TEST(FreeSpaceMap, DistanceIsEuclideanToTheNearestPixelWhereTheHandCanBe) {
  Scene scene;
  scene.fill(100, 100, 130, 140, kHandMm, true);
  scene.fill(150, 100, 160, 110, 300.0F, false);  // an occluder nearer than the hand: not free
  scene.fill(100, 150, 140, 160, 0.0F, false);    // no depth: free
  scene.fill(60, 100, 70, 140, 420.0F, false);    // the forearm, at the hand's depth: not free
  const FreeSpaceConfig config;
  FreeSpaceMap map;
  map.build(scene.camera, scene.depth, scene.mask, config);
  ASSERT_FALSE(map.empty());
  const double cap = config.cap_mm * scene.camera.focal() / kHandMm;
  EXPECT_NEAR(map.cap_px(), cap, 1e-9);
  const auto margin = static_cast<float>(config.margin_mm);
  int checked_inside_cap = 0;
  double error_sum = 0.0;
  // Within the cap of the hand (the map's box); beyond it, the cap.
  const int reach = static_cast<int>(cap);
  for (int v = 100 - reach; v < 140 + reach; v += 3) {
    for (int u = 100 - reach; u < 130 + reach; u += 3) {
      const double expected = scene.brute_distance(u, v, cap, margin);
      ASSERT_NEAR(map.at(u, v), expected, kCellTolerancePx) << "pixel " << u << "," << v;
      if (expected > 0.0 && expected < cap) {
        ++checked_inside_cap;
        error_sum += std::abs(map.at(u, v) - expected);
      }
    }
  }
  EXPECT_LT(error_sum / checked_inside_cap, 0.2) << "mean error (px) between the hand and the cap";
  EXPECT_GT(checked_inside_cap, 500);
  EXPECT_EQ(map.at(115, 120), 0.0) << "the hand";
  EXPECT_EQ(map.at(155, 105), 0.0) << "an occluder";
  EXPECT_EQ(map.at(65, 120), 0.0) << "the forearm";
  EXPECT_NEAR(map.at(120, 155), 16.0, kCellTolerancePx) << "no depth is free: 16 px below the hand";
  EXPECT_EQ(map.at(5, 5), cap) << "outside the map's box";
}

TEST(FreeSpaceMap, ASurfaceJustBehindTheHandIsNotFreeAndTheImageEdgeIsNot) {
  Scene scene;
  scene.fill(0, 0, scene.camera.width, scene.camera.height, 600.0F, false);
  scene.fill(10, 100, 40, 140, kHandMm, true);
  scene.fill(40, 100, 60, 140, kHandMm + 20.0F, false);  // a table 20 mm behind: within the margin
  FreeSpaceMap map;
  map.build(scene.camera, scene.depth, scene.mask);
  EXPECT_EQ(map.at(55, 120), 0.0) << "a table the hand rests on";
  EXPECT_NEAR(map.at(65, 120), 6.0, kCellTolerancePx);
  EXPECT_NEAR(map.at(0, 90), 1.0, kCellTolerancePx) << "the pixel beyond the image's edge is not free";
  EXPECT_NEAR(map.at(5, 90), 6.0, kCellTolerancePx);
  EXPECT_NEAR(map.at(5, 160), 6.0, kCellTolerancePx) << "nor is the rest of the image's edge";
}

// An odd width and height: the cells are marked two pixels at a time, and the last column and row
// share their cells with pixels beyond the image (a bezel in front of the scene, at the edge, is
// not free, and whole cells are marked for it).
TEST(FreeSpaceMap, AnOddImageSizeIsMarkedUpToItsLastColumnAndRow) {
  Scene scene(321, 241);
  scene.fill(320, 0, 321, 241, 300.0F, false);  // the bezel
  scene.fill(0, 240, 321, 241, 300.0F, false);
  scene.fill(270, 190, 300, 226, kHandMm, true);
  scene.fill(302, 166, 306, 186, 300.0F, false);  // an occluder over whole cells
  const FreeSpaceConfig config;
  FreeSpaceMap map;
  map.build(scene.camera, scene.depth, scene.mask, config);
  ASSERT_FALSE(map.empty());
  const auto margin = static_cast<float>(config.margin_mm);
  // The map's box: the cap around the hand, here to the image's edge.
  const int reach = static_cast<int>(map.cap_px());
  double error_sum = 0.0;
  int checked = 0;
  for (int v = 190 - reach; v < 241; ++v) {
    for (int u = 270 - reach; u < 321; ++u) {
      const double expected = scene.brute_distance(u, v, map.cap_px(), margin);
      ASSERT_NEAR(map.at(u, v), expected, kCreaseTolerancePx) << "pixel " << u << "," << v;
      error_sum += std::abs(map.at(u, v) - expected);
      ++checked;
    }
  }
  EXPECT_LT(error_sum / checked, 0.2) << "mean error (px)";
  EXPECT_EQ(map.at(304, 175), 0.0) << "the occluder";
  EXPECT_NEAR(map.at(314, 175), 6.0, kCellTolerancePx) << "beside the bezel";
}

// A cell is not free where either of its two pixels in a row is not: a lone pixel makes its whole
// cell not free, as the first or the second of the cell's columns.
TEST(FreeSpaceMap, ALonePixelMakesItsCellNotFree) {
  for (const int u : {250, 251}) {
    Scene scene;
    scene.fill(200, 100, 230, 140, kHandMm, true);
    scene.fill(u, 120, u + 1, 121, kHandMm, false);
    FreeSpaceMap map;
    map.build(scene.camera, scene.depth, scene.mask);
    // The cell's centre (pixels 250-251, 120-121), where the bilinear sample is the cell's own.
    EXPECT_EQ(map.sample(250.5, 120.5).distance_px, 0.0) << "lone pixel at " << u;
    EXPECT_NEAR(map.at(251, 110), 10.0, kCellTolerancePx) << "lone pixel at " << u;
  }
}

TEST(FreeSpaceMap, SampleIsContinuousWithItsGradient) {
  Scene scene;
  scene.fill(100, 100, 130, 140, kHandMm, true);
  FreeSpaceMap map;
  map.build(scene.camera, scene.depth, scene.mask);
  for (const auto& [u, v] : {std::pair{133.3, 95.6}, std::pair{97.2, 120.9}, std::pair{140.45, 150.1}}) {
    const FreeSpaceMap::Sample s = map.sample(u, v);
    EXPECT_NEAR(s.distance_px, map.sample(u + 1e-9, v - 1e-9).distance_px, 1e-6) << "continuous";
    constexpr double h = 1e-6;
    EXPECT_NEAR(s.d_du, (map.sample(u + h, v).distance_px - map.sample(u - h, v).distance_px) / (2 * h), 1e-6);
    EXPECT_NEAR(s.d_dv, (map.sample(u, v + h).distance_px - map.sample(u, v - h).distance_px) / (2 * h), 1e-6);
    EXPECT_GT(std::hypot(s.d_du, s.d_dv), 0.5) << "outside the hand the distance grows";
    EXPECT_LT(std::hypot(s.d_du, s.d_dv), 1.5) << "about a pixel per pixel";
  }
  // Between cell centres (at half-integer pixels) the sample is bilinear: linear along u.
  const double mid = map.sample(141.2, 150.3).distance_px;
  EXPECT_NEAR(mid, 0.5 * (map.sample(141.0, 150.3).distance_px + map.sample(141.4, 150.3).distance_px), 1e-9);
  const FreeSpaceMap::Sample far = map.sample(1e12, -1e12);
  EXPECT_EQ(far.distance_px, map.cap_px());
  EXPECT_EQ(far.d_du, 0.0);
  const FreeSpaceMap::Sample nan = map.sample(std::nan(""), 3.0);
  EXPECT_EQ(nan.distance_px, map.cap_px());
}

TEST(FreeSpaceMap, EmptyWithoutAHandOrWithMismatchedSizes) {
  Scene scene;
  FreeSpaceMap map;
  map.build(scene.camera, scene.depth, scene.mask);
  EXPECT_TRUE(map.empty());
  scene.fill(100, 100, 130, 140, kHandMm, true);
  std::vector<uint8_t> short_mask(10, 1);
  map.build(scene.camera, scene.depth, short_mask);
  EXPECT_TRUE(map.empty());
  EXPECT_EQ(map.sample(120, 120).distance_px, 0.0) << "an empty map charges nothing";
  FreeSpaceConfig off;
  off.enabled = false;
  map.build(scene.camera, scene.depth, scene.mask, off);
  EXPECT_TRUE(map.empty()) << "disabled (no energy reads it)";
}

}  // namespace
}  // namespace handtrack
