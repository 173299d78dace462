// Property tests of the depth input (Sec. 3.1): working volume, segmentation, quadtree leaves.
#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/hand_layout.hpp"
#include "handtrack/core/hands_tracker.hpp"
#include "handtrack/core/hand_model.hpp"
#include "handtrack/core/kinematics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <random>

namespace handtrack {
namespace {

CameraIntrinsics camera(int width, int height) {
  CameraIntrinsics c;
  const double s = width / 320.0;
  c.width = width;
  c.height = height;
  c.fx = 224.502 * s;
  c.fy = 230.494 * s;
  c.cx = width / 2.0;
  c.cy = height / 2.0;
  return c;
}

// A "hand" blob: an elliptic bump at ~depth_mm in front of a body plane at 800 mm (outside the
// working volume), with a forearm strip running to the bottom edge.
DepthImage blob_scene(const CameraIntrinsics& cam, double depth_mm, bool forearm) {
  DepthImage img{cam, std::vector<float>(static_cast<size_t>(cam.width) * cam.height, 800.0F)};
  const double s = cam.width / 320.0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const double du = (u - cam.cx) / (28.0 * s);
      const double dv = (v - cam.cy + 10 * s) / (40.0 * s);
      const double r2 = du * du + dv * dv;
      if (r2 < 1.0) img.at(u, v) = static_cast<float>(depth_mm - 12.0 * (1.0 - r2));
      if (forearm && v > cam.cy + 20 * s && std::abs(u - cam.cx) < 18 * s) {
        img.at(u, v) = static_cast<float>(depth_mm + 0.6 * (v - cam.cy - 20 * s) / s);
      }
    }
  }
  return img;
}

void expect_leaf_properties(const DepthInput& in, const DepthInputConfig& cfg) {
  const int w = in.camera.width;
  const int min_leaf = std::max(1, cfg.quadtree_min_leaf_px * std::max(1, w / 320));
  std::vector<int> owner(in.hand_mask.size(), -1);
  for (size_t k = 0; k < in.gaussians.size(); ++k) {
    const auto& g = in.gaussians[k];
    EXPECT_NEAR(g.sigma_px, g.side_px / std::sqrt(2.0), 1e-12);  // sigma = a / sqrt(2)
    const int x0 = static_cast<int>(std::lround(g.u + 0.5 - 0.5 * g.side_px));
    const int y0 = static_cast<int>(std::lround(g.v + 0.5 - 0.5 * g.side_px));
    float lo = 1e9F;
    float hi = 0.0F;
    double sum = 0.0;
    int n = 0;
    for (int v = y0; v < std::min(y0 + g.side_px, in.camera.height); ++v) {
      for (int u = x0; u < std::min(x0 + g.side_px, w); ++u) {
        const auto i = static_cast<size_t>(v) * w + u;
        EXPECT_EQ(owner[i], -1) << "leaves overlap";
        owner[i] = static_cast<int>(k);
        if (!in.hand_mask[i]) continue;
        lo = std::min(lo, in.filtered_mm[i]);
        hi = std::max(hi, in.filtered_mm[i]);
        sum += in.filtered_mm[i];
        ++n;
      }
    }
    ASSERT_GT(n, 0);
    EXPECT_NEAR(g.depth_mm, sum / n, 1e-3);  // d_q = mean depth of the leaf
    if (g.side_px > min_leaf) {
      EXPECT_LT(hi - lo, cfg.quadtree_threshold_mm);  // epsilon_c
    }
  }
}

TEST(DepthInput, QuadtreeLeavesAreFlatDisjointAndMeanDepthAt320And640) {
  for (const auto& cam : {camera(320, 240), camera(640, 480)}) {
    DepthInputBuilder builder;
    const auto& in = builder.build(blob_scene(cam, 400, false), std::nullopt);
    ASSERT_TRUE(in.has_hand()) << cam.width;
    EXPECT_GT(in.gaussians.size(), 10U);
    expect_leaf_properties(in, builder.config());
  }
}

// E(C_I,C_I) skips pairs that are too far apart to matter: it must equal the plain double sum of
// eq. 3 over all pairs.
TEST(DepthInput, SelfSimilarityEqualsTheFullPairSum) {
  for (const int width : {320, 640}) {
    DepthInputConfig cfg;
    cfg.quadtree_threshold_mm = 2.0;  // many leaves of every size
    DepthInputBuilder builder(cfg);
    const auto& in = builder.build(blob_scene(camera(width, width * 3 / 4), 420, true), std::nullopt);
    ASSERT_GT(in.gaussians.size(), 100U);
    double full = 0.0;
    for (const auto& a : in.gaussians) {
      for (const auto& b : in.gaussians) {
        full += overlap_2d((a.u - b.u) * (a.u - b.u) + (a.v - b.v) * (a.v - b.v), a.sigma_px, b.sigma_px);
      }
    }
    EXPECT_NEAR(in.self_similarity, full, 1e-9 * full) << "width " << width;
  }
}

// An 80 x 80 px square at pixels [120, 200) x [80, 160), 400 mm deep at its left edge and
// `mm_per_px` deeper each pixel to the right, nothing else in view.
DepthImage square_scene(const CameraIntrinsics& cam, double mm_per_px) {
  DepthImage depth{cam, std::vector<float>(static_cast<size_t>(cam.width) * cam.height, 0.0F)};
  for (int v = 80; v < 160; ++v) {
    for (int u = 120; u < 200; ++u) depth.at(u, v) = static_cast<float>(400 + mm_per_px * (u - 120));
  }
  return depth;
}

// A hint that keeps square_scene()'s square whole: centred on it, the wrist plane far below.
HandHint square_hint(const CameraIntrinsics& cam) {
  return {cam.unproject(160, 120, 480), cam.unproject(160, 400, 480), Eigen::Vector3d(0, -1, 0)};
}

TEST(DepthInput, SteepSurfacesSplitFinerThanFlatOnes) {
  const auto cam = camera(320, 240);
  const DepthImage flat = square_scene(cam, 0.0);
  const DepthImage steep = square_scene(cam, 2.0);
  const HandHint hint = square_hint(cam);
  // epsilon_c alone (Sec. 3.1): the leaves that the squares' outline crosses not split once more.
  DepthInputConfig config;
  config.split_partial_leaf_fill = 0.0;
  DepthInputBuilder a(config);
  DepthInputBuilder b(config);
  const auto& in_flat = a.build(flat, hint);
  const auto& in_steep = b.build(steep, hint);
  EXPECT_GE(in_flat.hand_pixels, 80 * 80 - 4);  // the 3x3 median takes the four corners
  EXPECT_GE(in_steep.hand_pixels, 80 * 80 - 4);
  const size_t n_flat = in_flat.gaussians.size();
  const size_t n_steep = in_steep.gaussians.size();
  EXPECT_LT(n_flat, n_steep / 4);
  expect_leaf_properties(b.last(), b.config());
}

// A leaf that the hand's outline crosses is split once more (DepthInputConfig::
// split_partial_leaf_fill), so that no leaf's square hangs far over the outline: a flat square
// whose left and right edges cross the middle of 16 px cells. Kept whole, those cells are half
// full, leaves (min_leaf_fill 0.5) whose Gaussians sit on the outline, half their side beyond it;
// split once, their outer halves are empty and leave, their inner halves are full leaves.
TEST(DepthInput, ALeafTheOutlineCrossesIsSplitOnce) {
  const auto cam = camera(320, 240);
  const DepthImage square = square_scene(cam, 0.0);
  const HandHint hint = square_hint(cam);
  // How far the leaves hang over the square's outline, the most of any, in leaf sides.
  const auto overhang = [&](double split_fill) {
    DepthInputConfig config;
    config.split_partial_leaf_fill = split_fill;
    DepthInputBuilder builder(config);
    const DepthInput& in = builder.build(square, hint);
    EXPECT_GE(in.hand_pixels, 80 * 80 - 4);
    double most = 0.0;
    for (const ImageGaussian& g : in.gaussians) {
      const double u0 = g.u + 0.5 - 0.5 * g.side_px;  // the leaf's pixels: [u0, u0 + side)
      const double v0 = g.v + 0.5 - 0.5 * g.side_px;
      const double over = std::max({120.0 - u0, u0 + g.side_px - 200.0, 80.0 - v0, v0 + g.side_px - 160.0, 0.0});
      most = std::max(most, over / g.side_px);
    }
    return most;
  };
  EXPECT_GE(overhang(0.0), 0.5) << "without the split, half-full leaves hang half over the outline";
  EXPECT_LE(overhang(DepthInputConfig{}.split_partial_leaf_fill), 0.0) << "split once, none does";
}

TEST(DepthInput, NothingInsideTheWorkingVolumeMeansNoHand) {
  const auto cam = camera(320, 240);
  DepthInputBuilder builder;
  DepthImage zeros{cam, std::vector<float>(static_cast<size_t>(cam.width) * cam.height, 0.0F)};
  EXPECT_FALSE(builder.build(zeros, std::nullopt).has_hand());
  DepthImage far{cam, std::vector<float>(static_cast<size_t>(cam.width) * cam.height, 900.0F)};
  EXPECT_FALSE(builder.build(far, std::nullopt).has_hand());
  DepthImage max_range{cam, std::vector<float>(static_cast<size_t>(cam.width) * cam.height, 65535.0F)};
  EXPECT_FALSE(builder.build(max_range, std::nullopt).has_hand());
  DepthImage nan{cam, std::vector<float>(static_cast<size_t>(cam.width) * cam.height, std::nanf(""))};
  EXPECT_FALSE(builder.build(nan, std::nullopt).has_hand());
}

TEST(DepthInput, ASurfaceReachingIntoTheVolumeIsNotAHand) {
  // A shoulder-like slanted surface from 540 mm at the left edge to 900 mm: its part inside the
  // working volume is hand-sized but its outline runs along the far plane.
  const auto cam = camera(320, 240);
  DepthImage img{cam, std::vector<float>(static_cast<size_t>(cam.width) * cam.height, 0.0F)};
  for (int v = 40; v < 200; ++v) {
    for (int u = 0; u < 160; ++u) img.at(u, v) = static_cast<float>(540.0 + 2.5 * u);
  }
  DepthInputBuilder builder;
  EXPECT_FALSE(builder.build(img, std::nullopt).has_hand());
  // The same blob in front of a body well behind the far plane is taken.
  DepthInputBuilder fresh;
  EXPECT_TRUE(fresh.build(blob_scene(cam, 560, false), std::nullopt).has_hand());
}

// A desk across the whole image rising away toward the top (a plane: 400 mm at the bottom edge,
// 460 mm in the middle, 540 mm at the top), a hand-sized bump resting on it (up to 25 mm in front
// of it, its outline on the desk: the depth is continuous from one to the other) and a forearm
// strip lying on it down to the bottom edge. `in_front_mm` gets each pixel's height above the desk.
DepthImage desk_scene(const CameraIntrinsics& cam, std::vector<float>& in_front_mm) {
  DepthImage img{cam, std::vector<float>(static_cast<size_t>(cam.width) * cam.height, 0.0F)};
  in_front_mm.assign(img.depth_mm.size(), 0.0F);
  const double s = cam.width / 320.0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const double desk = 460.0 / (1.0 + 0.29 * (v - cam.cy) / cam.fy);
      const double du = (u - cam.cx) / (34.0 * s);
      const double dv = (v - cam.cy + 10 * s) / (48.0 * s);
      const double r2 = du * du + dv * dv;
      double height = 0.0;
      if (r2 < 1.0) height = 25.0 * (1.0 - r2);
      if (v > cam.cy + 20 * s && std::abs(u - cam.cx) < 18 * s) height = std::max(height, 15.0);
      img.at(u, v) = static_cast<float>(desk - height);
      in_front_mm[static_cast<size_t>(v) * cam.width + u] = static_cast<float>(height);
    }
  }
  return img;
}

TEST(DepthInput, AHandOnADeskIsFoundWithoutTheDesk) {
  const auto cam = camera(320, 240);
  std::vector<float> height;
  const DepthImage img = desk_scene(cam, height);
  // Hand and desk are one connected surface: without the plane, the "hand" is no hand or takes in
  // the desk around it.
  DepthInputConfig without;
  without.support_plane.enabled = false;
  DepthInputBuilder plain(without);
  const auto& merged = plain.build(img, std::nullopt);
  int bump = 0;  // pixels of the bump and the forearm clear of the desk's band
  int desk_taken = 0;
  for (size_t i = 0; i < height.size(); ++i) {
    bump += height[i] > 10.0F ? 1 : 0;
    desk_taken += merged.hand_mask[i] && height[i] < 1.0F ? 1 : 0;
  }
  EXPECT_TRUE(!merged.has_hand() || desk_taken > bump / 10) << desk_taken << " desk pixels in the hand";

  DepthInputBuilder builder;
  const auto& in = builder.build(img, std::nullopt);
  ASSERT_TRUE(in.has_hand());
  int kept = 0;
  int desk_in_hand = 0;  // within SupportPlaneConfig::band_mm of the desk
  for (size_t i = 0; i < height.size(); ++i) {
    if (!in.hand_mask[i]) continue;
    desk_in_hand += height[i] <= 8.0F ? 1 : 0;
    kept += height[i] > 10.0F ? 1 : 0;
  }
  EXPECT_EQ(desk_in_hand, 0);
  // The hand's pixels clear of the band (the forearm below the wrist is cut, as without a desk).
  int hand_clear = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const auto i = static_cast<size_t>(v) * cam.width + u;
      hand_clear += height[i] > 10.0F && v < cam.cy + 20 ? 1 : 0;
    }
  }
  EXPECT_GT(kept, 0.9 * hand_clear);
  // The camera sees the desk beside the hand: free space for E_free, 30 px left of the bump.
  EXPECT_GT(in.free_space.at(static_cast<int>(cam.cx) - 64, static_cast<int>(cam.cy) - 10), 10.0);
}

TEST(DepthInput, AFlatHandIsNotADesk) {
  // A flat plate of 190 cm^2 (more than an open adult hand) facing the camera at 400 mm, with a
  // forearm to the bottom edge, in front of a body outside the working volume: not removed.
  const auto cam = camera(320, 240);
  DepthImage img{cam, std::vector<float>(static_cast<size_t>(cam.width) * cam.height, 800.0F)};
  const double half_u = 0.5 * 110.0 * cam.fx / 400.0;  // 110 x 170 mm
  const double half_v = 0.5 * 170.0 * cam.fy / 400.0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const bool plate = std::abs(u - cam.cx) < half_u && std::abs(v - cam.cy) < half_v;
      const bool forearm = v >= cam.cy && std::abs(u - cam.cx) < 0.5 * half_u;
      if (plate || forearm) img.at(u, v) = 400.0F;
    }
  }
  DepthInputConfig without;
  without.support_plane.enabled = false;
  DepthInputBuilder plain(without);
  DepthInputBuilder builder;
  const int expected = plain.build(img, std::nullopt).hand_pixels;
  ASSERT_GT(expected, 0);
  EXPECT_EQ(builder.build(img, std::nullopt).hand_pixels, expected);
}

// The depth where the ray through pixel (u, v) first meets the sphere of `radius` mm about `centre`
// (camera frame), or 0 where it misses.
double sphere_depth(const CameraIntrinsics& cam, double u, double v, const Eigen::Vector3d& centre, double radius) {
  const Eigen::Vector3d ray((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);  // p = z ray
  const double b = ray.dot(centre);
  const double disc = b * b - ray.squaredNorm() * (centre.squaredNorm() - radius * radius);
  return disc < 0.0 ? 0.0 : (b - std::sqrt(disc)) / ray.squaredNorm();
}

// A user close to the camera (body_eraser.hpp): the torso, rounded (a sphere of radius 200 mm
// centred at (torso_x_mm, 0, 540 mm): its front 340 mm away), seen where it is less than
// 60 mm deeper than its front; the hand, an elliptic bump (about 55 x 80 mm) at 450 mm right of the
// image centre, with its forearm down to the bottom edge; beyond both, 800 mm. With `arm`, a band
// joins the torso to the hand, its depth running from one to the other: torso, arm and hand are one
// surface. Marks each pixel as torso (1) or hand (2; its forearm not) in `part`.
// hand_alone() is the same scene without the torso (and the arm): what the hand is without them.
DepthImage body_scene(const CameraIntrinsics& cam, double torso_x_mm, bool arm, std::vector<uint8_t>& part) {
  const auto n = static_cast<size_t>(cam.width) * cam.height;
  DepthImage img{cam, std::vector<float>(n, 800.0F)};
  part.assign(n, 0);
  const double s = cam.width / 320.0;
  const double hand_u = cam.cx + 60 * s;
  const double hand_v = cam.cy - 10 * s;
  constexpr double kRadius = 200.0;
  const Eigen::Vector3d centre(torso_x_mm, 0.0, 540.0);
  const double front = centre.z() - kRadius;
  // Where the ray through pixel (u, v) meets the sphere (the nearer root), if less than 60 mm
  // deeper than its front; else 0.
  const auto torso_depth = [&](double u, double v) {
    const double z = sphere_depth(cam, u, v, centre, kRadius);
    return z < front + 60.0 ? z : 0.0;
  };
  // Where the torso ends on the arm's middle row: the arm leaves it there.
  int join = 0;
  while (join + 1 < cam.width && torso_depth(join + 1, hand_v) > 0.0) ++join;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const auto i = static_cast<size_t>(v) * cam.width + u;
      const double du = (u - hand_u) / (28.0 * s);
      const double dv = (v - hand_v) / (40.0 * s);
      const double r2 = du * du + dv * dv;
      if (const double z = torso_depth(u, v); z > 0.0) {
        img.depth_mm[i] = static_cast<float>(z);
        part[i] = 1;
      } else if (r2 < 1.0) {
        img.depth_mm[i] = static_cast<float>(450.0 - 12.0 * (1.0 - r2));
        part[i] = 2;
      } else if (v > hand_v + 30 * s && std::abs(u - hand_u) < 18 * s) {
        img.depth_mm[i] = 460.0F;  // forearm
      } else if (arm && u > join && u < hand_u && std::abs(v - hand_v) < 15 * s) {
        const double t = (u - join) / (hand_u - 28.0 * s - join);
        img.depth_mm[i] = static_cast<float>((1 - t) * torso_depth(join, hand_v) + t * 450.0);
      }
    }
  }
  return img;
}

DepthImage hand_alone(const CameraIntrinsics& cam) {
  std::vector<uint8_t> part;
  DepthImage img = body_scene(cam, -220.0, false, part);
  for (size_t i = 0; i < part.size(); ++i) {
    if (part[i] == 1) img.depth_mm[i] = 800.0F;
  }
  return img;
}

// What of the torso (part 1) and of the hand (part 2) a mask holds.
std::pair<int, double> torso_pixels_and_hand_share(const std::vector<uint8_t>& mask, const std::vector<uint8_t>& part) {
  int torso = 0;
  int hand = 0;
  int hand_in_mask = 0;
  for (size_t i = 0; i < part.size(); ++i) {
    torso += mask[i] != 0 && part[i] == 1 ? 1 : 0;
    hand += part[i] == 2 ? 1 : 0;
    hand_in_mask += mask[i] != 0 && part[i] == 2 ? 1 : 0;
  }
  return {torso, static_cast<double>(hand_in_mask) / std::max(1, hand)};
}

TEST(DepthInput, ABodyNearerThanTheHandIsNotTakenForIt) {
  // The torso's front is 340 mm away, the hand 440-450: the nearest sizeable surface is the body.
  // The hand is segmented as it is without the body.
  for (const int width : {320, 640}) {
    SCOPED_TRACE(width);
    const auto cam = camera(width, width * 3 / 4);
    std::vector<uint8_t> part;
    const DepthImage img = body_scene(cam, -220.0, false, part);
    DepthInputBuilder alone;
    const std::vector<uint8_t> expected = alone.build(hand_alone(cam), std::nullopt).hand_mask;
    DepthInputBuilder builder;
    const auto& in = builder.build(img, std::nullopt);
    ASSERT_TRUE(in.has_hand());
    EXPECT_EQ(torso_pixels_and_hand_share(in.hand_mask, part).first, 0);
    EXPECT_TRUE(in.hand_mask == expected);
  }
}

TEST(DepthInput, AnArmJoinedToABodyIsFollowedToItsHand) {
  // Torso (front at 340 mm, all of it in the image), arm and hand one surface: the hand is the part
  // that reaches out of it (without the body eraser, the end of the surface nearer the camera).
  const auto cam = camera(320, 240);
  std::vector<uint8_t> part;
  const DepthImage img = body_scene(cam, -130.0, true, part);
  DepthInputBuilder builder;
  const auto& in = builder.build(img, std::nullopt);
  ASSERT_TRUE(in.has_hand());
  const auto [torso, hand_share] = torso_pixels_and_hand_share(in.hand_mask, part);
  EXPECT_LT(torso, in.hand_pixels / 50);  // at most a sliver where the arm leaves the torso
  EXPECT_GT(hand_share, 0.5);             // the wrist cut takes the hand's lower end, as without the torso
  const Eigen::Vector3d hand_centre = cam.unproject(cam.cx + 60, cam.cy - 10, 445.0);
  EXPECT_LT((in.palm_centre_mm - hand_centre).norm(), 40.0) << in.palm_centre_mm.transpose();
}

TEST(DepthInput, AHeadBehindATrackedHandIsNotInItsMask) {
  // Tracking (a hint from the last pose): a head (a sphere of radius 80 mm, its front 100 mm behind
  // the hand) shows above and beside the hand's fingers, within a hand length of the palm centre
  // but nowhere within half of one, and apart from the hand in depth: not the hand.
  const auto cam = camera(320, 240);
  std::vector<uint8_t> part;
  DepthImage img = hand_alone(cam);
  body_scene(cam, -220.0, false, part);  // marks the hand's pixels (2)
  const Eigen::Vector3d head(70.0, -110.0, 630.0);
  int head_pixels = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const auto i = static_cast<size_t>(v) * cam.width + u;
      const double z = sphere_depth(cam, u, v, head, 80.0);
      if (z <= 0.0 || z >= img.depth_mm[i]) continue;  // a miss, or the hand is in front
      img.depth_mm[i] = static_cast<float>(z);
      part[i] = 1;
      ++head_pixels;
    }
  }
  ASSERT_GT(head_pixels, 1000);
  const Eigen::Vector3d palm = cam.unproject(cam.cx + 60, cam.cy - 10, 455.0);
  const HandHint hint{palm, palm + Eigen::Vector3d(0.0, 50.0, 0.0), Eigen::Vector3d(0.0, -1.0, 0.0)};
  DepthInputBuilder alone;
  const std::vector<uint8_t> expected = alone.build(hand_alone(cam), hint).hand_mask;
  DepthInputBuilder builder;
  const auto& in = builder.build(img, hint);
  ASSERT_TRUE(in.has_hand());
  EXPECT_EQ(torso_pixels_and_hand_share(in.hand_mask, part).first, 0);  // no head pixel
  EXPECT_TRUE(in.hand_mask == expected);
}

TEST(HandsInputs, ANewHandIsNotABody) {
  // With room for one or two hands and none tracked, a free slot's new surface is the hand, not the
  // nearer torso: its centroid and pixels are the hand's without the torso.
  const auto cam = camera(320, 240);
  std::vector<uint8_t> part;
  const DepthImage img = body_scene(cam, -220.0, false, part);
  for (const int max_hands : {1, 2}) {
    SCOPED_TRACE(max_hands);
    HandsRequest request;
    request.max_hands = max_hands;
    HandsInputs alone;
    alone.build(hand_alone(cam), request);
    HandsInputs inputs;
    inputs.build(img, request);
    ASSERT_TRUE(alone.has(0) && alone.candidate(0));
    ASSERT_TRUE(inputs.has(0) && inputs.candidate(0));
    EXPECT_LT((*inputs.candidate(0) - *alone.candidate(0)).norm(), 1e-9);
    const auto& mask = inputs.slot(0).get(Handedness::kRight)->hand_mask;
    EXPECT_EQ(torso_pixels_and_hand_share(mask, part).first, 0);
    EXPECT_TRUE(mask == alone.slot(0).get(Handedness::kRight)->hand_mask);
  }
}

// HandsInputs that borrow one FrameSplitter (handtrackd's pool of frames): a frame's inputs are
// what HandsInputs of its own give, and stay so when another frame is shared out with the same
// splitter (nothing of a built frame lives in the splitter).
TEST(HandsInputs, ThoseBorrowingOneSplitterKeepTheirOwnFrame) {
  const auto cam = camera(320, 240);
  std::vector<uint8_t> part;
  const DepthImage with_body = body_scene(cam, -220.0, false, part);
  const DepthImage blob = blob_scene(cam, 450, false);
  HandsRequest request;
  request.max_hands = 2;
  HandsInputs own;
  own.build(with_body, request);
  ASSERT_TRUE(own.has(0));
  const DepthInput& expected = *own.slot(0).get(Handedness::kRight);
  FrameSplitter splitter;
  HandsInputs first(DepthInputConfig{}, splitter);
  HandsInputs second(DepthInputConfig{}, splitter);
  first.build(with_body, request);
  second.build(blob, request);  // the next frame, another scene
  ASSERT_TRUE(first.has(0));
  const DepthInput& kept = *first.slot(0).get(Handedness::kRight);
  EXPECT_TRUE(kept.hand_mask == expected.hand_mask);
  EXPECT_TRUE(kept.filtered_mm == expected.filtered_mm);
  ASSERT_EQ(kept.gaussians.size(), expected.gaussians.size());
  for (size_t i = 0; i < kept.gaussians.size(); ++i) {
    EXPECT_EQ(kept.gaussians[i].depth_mm, expected.gaussians[i].depth_mm) << "leaf " << i;
  }
  EXPECT_LT((*first.candidate(0) - *own.candidate(0)).norm(), 1e-9);
  ASSERT_TRUE(second.has(0));
  EXPECT_FALSE(second.slot(0).get(Handedness::kRight)->filtered_mm == kept.filtered_mm) << "the scenes differ";
}

TEST(DepthInput, AShareOfTheFrameSegmentedAfreshIsItsLargestSurface) {
  // Touching hands are split pixel by pixel, which can leave a slot a sliver of the other hand
  // nearer the camera than its own (two_clap, docs/TRACKER.md "Two hands"). Segmented afresh (a
  // check: no hint), a slot's share of the frame is its largest sizeable surface; the whole frame,
  // as one hand alone sees it, its nearest.
  const auto cam = camera(320, 240);
  DepthImage img = blob_scene(cam, 450, false);
  for (int v = 20; v < 50; ++v) {
    for (int u = 20; u < 50; ++u) img.at(u, v) = 350.0F;  // a sliver, 30 x 30 px, nearer
  }
  std::vector<uint8_t> foreign(img.depth_mm.size(), 0);
  for (int v = 190; v < 230; ++v) {
    for (int u = 250; u < 300; ++u) {
      img.at(u, v) = 420.0F;  // the other slot's hand
      foreign[static_cast<size_t>(v) * cam.width + u] = 1;
    }
  }
  DepthInputBuilder whole;
  const DepthInput& alone = whole.build(img, std::nullopt);
  ASSERT_TRUE(alone.has_hand());
  EXPECT_NEAR(alone.hand_centroid_mm.z(), 350.0, 5.0) << "the whole frame: its nearest surface";
  DepthInputBuilder slot;
  const DepthInput& share = slot.build(img, std::nullopt, nullptr, &foreign);
  ASSERT_TRUE(share.has_hand());
  EXPECT_NEAR(share.hand_centroid_mm.z(), 444.0, 10.0) << "a share of the frame: its largest surface";
}

TEST(DepthInput, MedianFilterRemovesFlyingPixels) {
  const auto cam = camera(320, 240);
  DepthImage img = blob_scene(cam, 400, false);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> u(0, cam.width - 1);
  std::uniform_int_distribution<int> v(0, cam.height - 1);
  for (int k = 0; k < 300; ++k) img.at(u(rng), v(rng)) = 250.0F;  // isolated pixels in the volume
  DepthInputBuilder builder;
  const auto& in = builder.build(img, std::nullopt);
  ASSERT_TRUE(in.has_hand());
  for (const auto& g : in.gaussians) EXPECT_GT(g.depth_mm, 370.0);
}


// The 3x3 filter is exact: every pixel equals the median of its clamped 3x3 window (non-finite
// samples count as 0), on noise with NaNs and infinities, at both resolutions.
TEST(DepthInput, MedianFilterIsTheExactWindowMedian) {
  for (const int width : {320, 641}) {
    CameraIntrinsics cam = camera(width, width * 3 / 4);
    DepthImage img{cam, std::vector<float>(static_cast<size_t>(cam.width) * cam.height)};
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> depth(100.0F, 700.0F);
    std::uniform_int_distribution<int> special(0, 49);
    for (float& d : img.depth_mm) {
      const int s = special(rng);
      d = s == 0 ? NAN : s == 1 ? INFINITY : s == 2 ? 0.0F : depth(rng);
    }
    DepthInputConfig cfg;
    cfg.near_mm = 0.0;
    cfg.far_mm = 1e9;
    DepthInputBuilder builder(cfg);
    const auto& in = builder.build(img, std::nullopt);
    int mismatches = 0;
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        std::vector<float> window;
        for (int dv = -1; dv <= 1; ++dv) {
          for (int du = -1; du <= 1; ++du) {
            const float d = img.at(std::clamp(u + du, 0, cam.width - 1), std::clamp(v + dv, 0, cam.height - 1));
            window.push_back(std::isfinite(d) ? d : 0.0F);
          }
        }
        std::sort(window.begin(), window.end());
        mismatches += in.filtered_mm[static_cast<size_t>(v) * cam.width + u] != window[4] ? 1 : 0;
      }
    }
    EXPECT_EQ(mismatches, 0) << "width " << width;
  }
}
TEST(DepthInput, ForearmIsCutAtTheWrist) {
  const auto cam = camera(320, 240);
  const DepthImage img = blob_scene(cam, 400, true);
  DepthInputBuilder builder;
  // The tracker's hint: wrist just below the blob, fingers up the image.
  const Eigen::Vector3d wrist = cam.unproject(cam.cx, cam.cy + 32, 400);
  const HandHint hint{cam.unproject(cam.cx, cam.cy - 10, 400), wrist, Eigen::Vector3d(0, -1, 0)};
  const auto& in = builder.build(img, hint);
  ASSERT_TRUE(in.has_hand());
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      if (!in.hand_mask[static_cast<size_t>(v) * cam.width + u]) continue;
      const Eigen::Vector3d p = cam.unproject(u, v, in.filtered_mm[static_cast<size_t>(v) * cam.width + u]);
      EXPECT_GT((p - wrist).dot(hint.finger_axis), -11.0);
    }
  }
  // Without a hint the blob's far end from the image border is taken as the hand.
  DepthInputBuilder fresh;
  const auto& first = fresh.build(img, std::nullopt);
  ASSERT_TRUE(first.has_hand());
  EXPECT_LT(first.finger_axis.y(), -0.8);  // fingers point up the image, away from the arm
}

TEST(DepthInput, RegionsLabelledBackgroundLeaveTheHand) {
  // The blob with its forearm, labelled palm except a disc of 20 px radius (about 39 cm^2 at 400 mm,
  // as a held ball would be labelled) and a speck of 3 px radius (under 1 cm^2, as the forest
  // mislabels real depth): with part labels the disc leaves the hand and C_I, the speck stays
  // (DepthInputConfig::drop_background_min_area_mm2); with drop_background off both stay.
  const auto cam = camera(320, 240);
  const DepthImage img = blob_scene(cam, 400, true);
  std::vector<uint8_t> labels(img.depth_mm.size(), kPalm);
  const auto in_disc = [&](int u, int v) { return std::hypot(u - cam.cx, v - (cam.cy - 10)) < 20.0; };
  const auto in_speck = [&](int u, int v) { return std::hypot(u - (cam.cx + 12), v - (cam.cy - 38)) < 3.0; };
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      if (in_disc(u, v) || in_speck(u, v)) labels[static_cast<size_t>(v) * cam.width + u] = kBackground;
    }
  }
  const FixedLabels labeller(&labels);
  const auto pixels_in_hand = [&](const DepthInput& in, const auto& inside) {
    int n = 0;
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) n += inside(u, v) && in.hand_mask[static_cast<size_t>(v) * cam.width + u];
    }
    return n;
  };
  const auto leaf_area = [](const DepthInput& in) {  // px covered by C_I's leaves
    int area = 0;
    for (const auto& g : in.gaussians) area += g.side_px * g.side_px;
    return area;
  };
  DepthInputBuilder plain;
  const DepthInput kept = plain.build(img, std::nullopt);
  ASSERT_TRUE(kept.has_hand());
  const int disc = pixels_in_hand(kept, in_disc);
  const int speck = pixels_in_hand(kept, in_speck);
  EXPECT_GT(disc, 1000);
  EXPECT_GT(speck, 20);

  DepthInputBuilder dropping;
  const auto& dropped = dropping.build(img, std::nullopt, &labeller);
  ASSERT_TRUE(dropped.has_hand());
  EXPECT_EQ(pixels_in_hand(dropped, in_disc), 0);
  EXPECT_EQ(pixels_in_hand(dropped, in_speck), speck);
  EXPECT_EQ(dropped.hand_pixels, kept.hand_pixels - disc);
  EXPECT_LT(leaf_area(dropped), leaf_area(kept) - disc / 2) << "C_I leaves the disc out";
  for (const uint8_t m : dropped.hand_mask) ASSERT_LE(m, 1);

  DepthInputConfig keep_config;
  keep_config.drop_background = false;
  DepthInputBuilder keeping(keep_config);
  const auto& labelled = keeping.build(img, std::nullopt, &labeller);
  EXPECT_EQ(pixels_in_hand(labelled, in_disc), disc);
  EXPECT_EQ(leaf_area(labelled), leaf_area(kept));
}

TEST(DepthInput, GroundTruthLabelsFollowTheLeftHandsMirroredFrame) {
  // A left hand is fitted in the mirrored frame (Tracker), so ground-truth labels given in the
  // camera's frame must reach its input mirrored: the blob labelled thumb left of the image centre
  // and little finger right of it. The right hand's input keeps the labels where they are; in the
  // left hand's, pixel (u, v) carries the label of (width - 1 - u, v). (Until 2026-11-27 the left
  // input got them unmirrored, and handtrack-eval --oracle-labels fitted left hands to labels of
  // the wrong side.)
  const auto cam = camera(320, 240);
  const DepthImage img = blob_scene(cam, 400, false);
  std::vector<uint8_t> labels(img.depth_mm.size());
  for (size_t i = 0; i < labels.size(); ++i) {
    labels[i] = static_cast<int>(i % static_cast<size_t>(cam.width)) < cam.width / 2 ? kThumbDistal : kLittleDistal;
  }
  const FixedLabels labeller(&labels);
  InputRequest both;
  both.left = true;
  TrackerInputs inputs;
  inputs.build(img, both, &labeller);
  for (const Handedness hand : {Handedness::kRight, Handedness::kLeft}) {
    const DepthInput* in = inputs.get(hand);
    ASSERT_NE(in, nullptr);
    ASSERT_TRUE(in->has_hand());
    EXPECT_EQ(in->mirrored, hand == Handedness::kLeft);
    int checked = 0;
    int wrong = 0;
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        const auto i = static_cast<size_t>(v) * cam.width + u;
        if (in->hand_mask[i] == 0) continue;
        const int u_camera = hand == Handedness::kLeft ? cam.width - 1 - u : u;
        wrong += in->pixel_labels[i] != labels[static_cast<size_t>(v) * cam.width + u_camera];
        ++checked;
      }
    }
    EXPECT_GT(checked, 1000);
    EXPECT_EQ(wrong, 0) << (hand == Handedness::kLeft ? "left" : "right") << " hand's input";
  }
}

TEST(Projection, UnprojectInvertsProjectAndSigmaScalesWithInverseDepth) {
  const auto cam = camera(640, 480);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> x(-100, 100);
  std::uniform_real_distribution<double> z(150, 600);
  for (int k = 0; k < 100; ++k) {
    const Eigen::Vector3d p(x(rng), x(rng), z(rng));
    const auto uv = cam.project(p);
    EXPECT_LT((cam.unproject(uv.x(), uv.y(), p.z()) - p).norm(), 1e-9);
  }
  // Scaled orthographic (Sec. 3.2): a sphere of radius sigma at depth z spans ~sigma f / z pixels.
  const Eigen::Vector3d c(0, 0, 400);
  const double sigma = 10.0;
  const double span = cam.project(c + Eigen::Vector3d(sigma, 0, 0)).x() - cam.project(c).x();
  EXPECT_NEAR(span, sigma * cam.fx / c.z(), 1e-9);
}

}  // namespace
}  // namespace handtrack

// Raw sensor units to mm, in place (the daemon's preprocess stage): the scale applied, 0 kept as
// "no depth", the working-volume count right at both limits, and no reallocation once sized.
TEST(DepthImageFromRaw, ScalesInPlaceAndCountsTheWorkingVolume) {
  handtrack::CameraIntrinsics cam;
  cam.width = 4;
  cam.height = 1;
  cam.depth_scale_mm = 0.125;  // SR305
  handtrack::DepthImage image;
  const std::vector<uint16_t> raw = {0, 1200, 4800, 4808};  // 0, 150, 600, 601 mm
  EXPECT_EQ(image.assign_raw(cam, raw, 150.0F, 600.0F), 2U);
  EXPECT_EQ(image.depth_mm, (std::vector<float>{0.0F, 150.0F, 600.0F, 601.0F}));
  const float* buffer = image.depth_mm.data();
  EXPECT_EQ(image.assign_raw(cam, {0, 0, 0, 0}, 150.0F, 600.0F), 0U);
  EXPECT_EQ(image.depth_mm.data(), buffer) << "reallocated";
  EXPECT_EQ(handtrack::DepthImage::from_raw(cam, raw).depth_mm[2], 600.0F);
}
