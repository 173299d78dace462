// Finite-difference checks of every energy term's analytic gradient at random poses (STYLE.md:
// "property tests that check analytic Jacobians against numeric ones").
#include "handtrack/core/energy.hpp"
#include "handtrack/core/tracker.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>

namespace handtrack {
namespace {

// A random pose near the frontal hand at ~400 mm, angles inside and outside the limits.
PoseParams random_pose(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  PoseParams p;
  p << 10 * u(rng), 20 * u(rng), 400 + 30 * u(rng), 0.6 * u(rng), 0.6 * u(rng), 0.6 * u(rng), 0, 0, 0, 0, 0, 0, 0,
      0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0;
  for (int j = kFirstAngleParam; j < kNumPoseParams; ++j) p[j] = 0.4 + 0.9 * u(rng);
  return p;
}

// Image Gaussians scattered where the model projects, with depths near the model's surface.
DepthInput synthetic_input(const HandModel& model, const PoseParams& pose, std::mt19937_64& rng) {
  DepthInput in;
  in.camera = CameraIntrinsics{};
  const PosedHand hand(model, pose);
  std::normal_distribution<double> jitter(0.0, 4.0);
  std::uniform_int_distribution<int> side(1, 4);
  for (int p = 0; p < hand.gaussian_count(); ++p) {
    const auto uv = in.camera.project(hand.centre(p));
    for (int k = 0; k < 3; ++k) {
      ImageGaussian g;
      g.side_px = 1 << side(rng);
      g.sigma_px = g.side_px / std::sqrt(2.0);
      g.u = uv.x() + jitter(rng);
      g.v = uv.y() + jitter(rng);
      g.depth_mm = hand.centre(p).z() - model.gaussians()[static_cast<size_t>(p)].sigma_mm + 2.0 * jitter(rng);
      g.label = model.gaussians()[static_cast<size_t>(p)].label;
      in.gaussians.push_back(g);
    }
  }
  in.self_similarity = image_self_similarity(in.gaussians);
  in.mixture.assign(in.gaussians);
  return in;
}

// The depth a camera sees of the model at `pose` in front of a wall 200 mm behind it (free space
// for E_free): each Gaussian a disc of radius sigma_p at depth z - sigma_h, the nearest in front;
// the discs are the hand's mask. Sets input.free_space.
void add_silhouette(const HandModel& model, const PoseParams& pose, DepthInput& input) {
  const auto& cam = input.camera;
  const PosedHand hand(model, pose);
  std::vector<float> depth(static_cast<size_t>(cam.width * cam.height), 0.0F);
  std::vector<uint8_t> mask(depth.size(), 0);
  double farthest = 0.0;
  for (int p = 0; p < hand.gaussian_count(); ++p) {
    const Eigen::Vector3d& c = hand.centre(p);
    const double sigma = model.gaussians()[static_cast<size_t>(p)].sigma_mm;
    const auto uv = cam.project(c);
    const double r = sigma * cam.focal() / c.z();
    farthest = std::max(farthest, c.z());
    const int v_end = std::min(cam.height - 1, static_cast<int>(uv.y() + r));
    const int u_end = std::min(cam.width - 1, static_cast<int>(uv.x() + r));
    for (int v = std::max(0, static_cast<int>(uv.y() - r)); v <= v_end; ++v) {
      for (int u = std::max(0, static_cast<int>(uv.x() - r)); u <= u_end; ++u) {
        if (std::hypot(u - uv.x(), v - uv.y()) > r) continue;
        const size_t i = static_cast<size_t>(v) * cam.width + u;
        const auto d = static_cast<float>(c.z() - sigma);
        if (mask[i] == 0 || d < depth[i]) depth[i] = d;
        mask[i] = 1;
      }
    }
  }
  for (size_t i = 0; i < depth.size(); ++i) {
    if (mask[i] == 0) depth[i] = static_cast<float>(farthest + 200.0);
  }
  input.free_space.build(cam, depth, mask);
}

// The other hand for E_hand: the same model at `other` (its own angles and rotation), moved so that
// its wrist is `offset_mm` from this hand's. Mirrored, it is a left hand (the right-hand model at
// x-negated translation, then every centre's x negated): the two hands' thumbs then face each other.
HandObstacle obstacle_near(const HandModel& model, const PoseParams& pose, PoseParams other,
                           const Eigen::Vector3d& offset_mm, bool mirror_x) {
  other.head<3>() = pose.head<3>() + offset_mm;
  if (mirror_x) other[0] = -other[0];
  HandObstacle obstacle;
  obstacle.assign(model, PosedHand(model, other), mirror_x);
  return obstacle;
}

// Central differences, one parameter at a time; compares with the analytic gradient.
void expect_gradient_matches(const std::function<double(const PoseParams&, PoseGradient*)>& f, const PoseParams& x,
                             const char* what) {
  PoseGradient analytic = PoseGradient::Zero();
  f(x, &analytic);
  const double scale = std::max(1e-12, analytic.cwiseAbs().maxCoeff());
  for (int j = 0; j < kNumPoseParams; ++j) {
    const double h = param_kind(j) == ParamKind::kTranslation ? 1e-4 : 1e-6;
    PoseParams a = x;
    PoseParams b = x;
    a[j] += h;
    b[j] -= h;
    const double numeric = (f(a, nullptr) - f(b, nullptr)) / (2 * h);
    // Relative to the largest component: E_sim's depth factor has a kink at d_p = d_q that a
    // difference step may straddle, so allow a small absolute slack as well.
    EXPECT_NEAR(analytic[j], numeric, 2e-4 * scale + 1e-3 * std::abs(numeric))
        << what << ": d/d" << param_name(j);
  }
}

class EnergyGradient : public ::testing::TestWithParam<int> {};

TEST_P(EnergyGradient, EveryTermMatchesFiniteDifferences) {
  std::mt19937_64 rng(1000 + GetParam());
  const HandModel model = HandModel::default_adult({1.05, 0.95, 1.1});
  const PoseParams pose = random_pose(rng);
  PoseParams data_pose = pose;
  data_pose.head<3>() += Eigen::Vector3d(3, -4, 5);  // the data sits a little off the pose
  const DepthInput input = synthetic_input(model, data_pose, rng);
  const PoseParams prev = random_pose(rng);
  const PoseParams prev2 = random_pose(rng);
  PosedHand hand;

  const SimilarityTerm depth_sim(SimilarityFactor::kDepth, 200.0);
  expect_gradient_matches(
      [&](const PoseParams& p, PoseGradient* g) {
        hand.update(model, p);
        return depth_sim.evaluate(model, hand, input, g);
      },
      pose, "E_sim (depth)");
  const SimilarityTerm label_sim(SimilarityFactor::kLabel, 200.0);
  expect_gradient_matches(
      [&](const PoseParams& p, PoseGradient* g) {
        hand.update(model, p);
        return label_sim.evaluate(model, hand, input, g);
      },
      pose, "E_sim (label)");
  // With the coverage cap: a kink where an image Gaussian reaches its cap, which a difference step
  // straddles about as rarely as the depth factor's.
  const SimilarityTerm capped_sim(SimilarityFactor::kDepth, 200.0, kMeasuredCoverageCap);
  expect_gradient_matches(
      [&](const PoseParams& p, PoseGradient* g) {
        hand.update(model, p);
        return capped_sim.evaluate(model, hand, input, g);
      },
      pose, "E_sim (depth, capped)");
  const CollisionTerm col;
  expect_gradient_matches(
      [&](const PoseParams& p, PoseGradient* g) {
        hand.update(model, p);
        return col.evaluate(model, hand, g);
      },
      pose, "E_col");
  const JointLimitTerm lim;
  expect_gradient_matches([&](const PoseParams& p, PoseGradient* g) { return lim.evaluate(model, p, g); }, pose,
                          "E_lim");
  const SmoothnessTerm smo(1e-3);
  expect_gradient_matches([&](const PoseParams& p, PoseGradient* g) { return smo.evaluate(p, prev, prev2, g); },
                          pose, "E_smo");
  const PoseEnergy total(SimilarityFactor::kDepth, EnergyWeights{});
  const EnergyFrame frame{&model, &input, &prev, &prev2};
  expect_gradient_matches([&](const PoseParams& p, PoseGradient* g) { return total.evaluate(frame, p, hand, g); },
                          pose, "E (eq. 2)");

  // E_free against the silhouette of a pose 12-15 mm away with other finger angles: some of the
  // model's Gaussians over the wall behind.
  DepthInput seen = input;
  PoseParams seen_pose = random_pose(rng);
  seen_pose.head<3>() = pose.head<3>() + Eigen::Vector3d(12, -9, 6);
  add_silhouette(model, seen_pose, seen);
  const FreeSpaceTerm free_space;
  hand.update(model, pose);
  EXPECT_GT(free_space.evaluate(hand, seen, nullptr), 1e-3) << "parts of the model must be over free space";
  expect_gradient_matches(
      [&](const PoseParams& p, PoseGradient* g) {
        hand.update(model, p);
        return free_space.evaluate(hand, seen, g);
      },
      pose, "E_free");
  EnergyWeights with_free;
  with_free.free_space = 2.0;
  const PoseEnergy total_free(SimilarityFactor::kDepth, with_free);
  const EnergyFrame seen_frame{&model, &seen, &prev, &prev2};
  expect_gradient_matches(
      [&](const PoseParams& p, PoseGradient* g) { return total_free.evaluate(seen_frame, p, hand, g); }, pose,
      "E with E_free");

  // E_unseen, alone and in E, with both weights on every finger they act on.
  UnseenFingers unseen;
  unseen.weight = {0.0, 0.3, 0.6, 0.9, 1.0};
  unseen.held = {0.0, 0.4, 0.1, 0.2, 0.38};
  EXPECT_GT(unseen_finger_energy(unseen, pose, nullptr), 1e-3);
  expect_gradient_matches([&](const PoseParams& p, PoseGradient* g) { return unseen_finger_energy(unseen, p, g); },
                          pose, "E_unseen");
  EnergyWeights with_unseen;
  with_unseen.unseen_fingers = 0.5;
  const PoseEnergy total_unseen(SimilarityFactor::kDepth, with_unseen);
  EnergyFrame unseen_frame = frame;
  unseen_frame.unseen = &unseen;
  expect_gradient_matches(
      [&](const PoseParams& p, PoseGradient* g) { return total_unseen.evaluate(unseen_frame, p, hand, g); }, pose,
      "E with E_unseen");

  // E_sim with the surface fronts of the previous pose (surface_fronts.hpp), capped as late fusion
  // tracks: d_p moves with k_p, which holds for the frame, so the gradient keeps eq. 7's form.
  hand.update(model, prev);
  const SurfaceFronts fronts = surface_fronts(model, hand, 3.0);
  EnergyFrame fronts_frame = frame;
  fronts_frame.fronts = &fronts;
  hand.update(model, pose);
  EXPECT_NE(capped_sim.evaluate_centres(model, hand, input, nullptr, &fronts),
            capped_sim.evaluate_centres(model, hand, input, nullptr))
      << "the fronts must move some model Gaussian for a real check";
  expect_gradient_matches(
      [&](const PoseParams& p, PoseGradient* g) { return total.evaluate(fronts_frame, p, hand, g); }, pose,
      "E with surface fronts");

  // E_hand against another hand overlapping this one: beside it (a second right hand), and a left
  // hand (mirrored) reaching into it from the thumb side; its pose is one more random pose.
  const InterHandCollisionTerm inter;
  for (const bool mirror : {false, true}) {
    const Eigen::Vector3d offset_mm = mirror ? Eigen::Vector3d(55, 10, 10) : Eigen::Vector3d(45, -10, 15);
    const HandObstacle other = obstacle_near(model, pose, random_pose(rng), offset_mm, mirror);
    const char* what = mirror ? "E_hand (mirrored obstacle)" : "E_hand";
    hand.update(model, pose);
    EXPECT_GT(inter.evaluate(model, hand, other, nullptr), 1e-3) << what << ": the hands must overlap for a real check";
    expect_gradient_matches(
        [&](const PoseParams& p, PoseGradient* g) {
          hand.update(model, p);
          return inter.evaluate(model, hand, other, g);
        },
        pose, what);
    EnergyFrame two_hands = frame;
    two_hands.other_hand = &other;
    expect_gradient_matches(
        [&](const PoseParams& p, PoseGradient* g) { return total.evaluate(two_hands, p, hand, g); }, pose,
        mirror ? "E with E_hand (mirrored obstacle)" : "E with E_hand");
  }
}

INSTANTIATE_TEST_SUITE_P(RandomPoses, EnergyGradient, ::testing::Range(0, 8));

TEST(EnergyTerms, SimilarityPeaksWhenModelSitsOnItsOwnImage) {
  std::mt19937_64 rng(7);
  const HandModel model = HandModel::default_adult();
  PoseParams pose = PoseParams::Zero();
  pose.head<3>() << 0, 40, 400;
  const DepthInput input = synthetic_input(model, pose, rng);
  PosedHand hand;
  const SimilarityTerm sim(SimilarityFactor::kDepth, 200.0);
  hand.update(model, pose);
  const double at_truth = sim.evaluate(model, hand, input, nullptr);
  for (const Eigen::Vector3d& shift : {Eigen::Vector3d(15, 0, 0), Eigen::Vector3d(0, 15, 0), Eigen::Vector3d(0, 0, 30)}) {
    PoseParams moved = pose;
    moved.head<3>() += shift;
    hand.update(model, moved);
    EXPECT_LT(sim.evaluate(model, hand, input, nullptr), at_truth) << "shift " << shift.transpose();
  }
}

// k_p (surface_fronts.hpp): 1 for a hand seen square on; a palm tipped 60 deg from the view has
// its surface 1 / cos 60 = 2 sigma_h in front, capped at k_max; a finger bone pointing away from
// the camera likewise, one pointing toward it stays at 1.
TEST(EnergyTerms, SurfaceFrontsMoveForwardWhereTheHandIsSeenAtASlant) {
  const HandModel model = HandModel::default_adult();
  const auto fronts_at = [&](double tip_rad, PosedHand& hand) {
    PoseParams pose = PoseParams::Zero();
    pose.head<3>() << 0, 0, 400;
    pose[3] = tip_rad;  // about the camera's x axis: the fingers toward (+) or away from (-) it
    hand.update(model, pose);
    return surface_fronts(model, hand, kMeasuredSlantFront);
  };
  const auto& gaussians = model.gaussians();
  PosedHand hand;
  // Square on: the rays through the Gaussians are at most ~25 deg off the camera's axis (the
  // fingertips, 180 mm above it at 400 mm), so a part lying across the view is seen at most that
  // slanted: 1 / cos 25 deg = 1.10.
  const SurfaceFronts square = fronts_at(0.0, hand);
  for (int i = 0; i < hand.gaussian_count(); ++i) {
    EXPECT_LT(square.sigmas[static_cast<size_t>(i)], 1.11) << "Gaussian " << i;
    EXPECT_GE(square.sigmas[static_cast<size_t>(i)], 1.0) << "Gaussian " << i;
  }
  for (const double tip_rad : {-std::numbers::pi / 3, std::numbers::pi / 3}) {
    const SurfaceFronts tipped = fronts_at(tip_rad, hand);
    const bool away = hand.fingertip(kMiddle).z() > hand.joints()[joint_index(kMiddle, 0)].z();
    EXPECT_EQ(away, tip_rad < 0.0);
    for (int i = 0; i < hand.gaussian_count(); ++i) {
      const auto& g = gaussians[static_cast<size_t>(i)];
      const double k = tipped.sigmas[static_cast<size_t>(i)];
      if (g.bone == kPalmBone) {
        EXPECT_DOUBLE_EQ(k, kMeasuredSlantFront) << "palm Gaussian " << i << " at " << tip_rad << " rad";
      } else if (g.bone / kBonesPerFinger == kMiddle) {
        if (away) {
          EXPECT_DOUBLE_EQ(k, kMeasuredSlantFront) << "middle finger Gaussian " << i << ", pointing away";
        } else {
          EXPECT_EQ(k, 1.0) << "middle finger Gaussian " << i << ", pointing toward the camera";
        }
      }
    }
  }
}

// u_f (unseen_fingers.hpp): 1 for a finger the labels do not see on a hand whose palm faces the
// camera with the fingers across the view, 0 for a finger in full view, for the thumb, for a hand
// seen edge-on or pointing at the camera, and without labels; E_unseen is 0 at the curled pose.
// h_f: n_z a_z on every finger but the thumb, seen or not, for a hand seen from behind with its
// fingers pointing away; 0 otherwise.
TEST(EnergyTerms, UnseenFingersAreTheFingersTheLabelsMissOnAHandFacingTheCamera) {
  DepthInput input;
  const auto label = [&](int part, int pixels) { input.pixel_labels.insert(input.pixel_labels.end(), pixels, part); };
  label(kPalm, 700);
  label(part_label(kThumb, 1), 100);
  label(part_label(kIndex, 0), 100);
  label(part_label(kMiddle, 2), 80);
  label(part_label(kLittle, 1), 20);  // 2 % of the labelled pixels: half seen
  label(kBackground, 500);            // not counted
  // u_f and h_f for a previous pose turned by `rotation` (no segmented hand: no reach beyond the
  // knuckles, which FistsFromBehind in test_views.cpp tests on rendered frames).
  const HandModel model = HandModel::default_adult();
  const auto fingers = [&](const Eigen::Vector3d& rotation) {
    PoseParams pose = PoseParams::Zero();
    pose.segment<3>(kRotationParam) = rotation;
    return unseen_fingers(input, PosedHand(model, pose));
  };
  const auto weights = [&](const Eigen::Vector3d& rotation) { return fingers(rotation).weight; };
  const auto held = [&](const Eigen::Vector3d& rotation) { return fingers(rotation).held; };
  const auto facing = weights(Eigen::Vector3d::Zero());  // palm toward the camera, fingers up
  EXPECT_EQ(facing[kThumb], 0.0);
  EXPECT_EQ(facing[kIndex], 0.0);
  EXPECT_EQ(facing[kMiddle], 0.0);
  EXPECT_NEAR(facing[kRing], 1.0, 1e-12);
  EXPECT_NEAR(facing[kLittle], 0.5, 1e-12);
  const auto back = weights(Eigen::Vector3d(0, std::numbers::pi, 0));  // the back toward it
  EXPECT_NEAR(back[kRing], 1.0, 1e-9);
  const auto edge_on = weights(Eigen::Vector3d(0, std::numbers::pi / 2, 0));  // the thumb side toward it
  EXPECT_NEAR(edge_on[kRing], 0.0, 1e-9);
  const auto pointing = weights(Eigen::Vector3d(std::numbers::pi / 2, 0, 0));  // fingers along the view
  EXPECT_NEAR(pointing[kRing], 0.0, 1e-9);

  // The head-mounted view: turned 115 deg about the camera's x axis, the back of the hand toward the
  // camera (n_z = cos 65 deg) and the fingers pointing away from it (a_z = sin 65 deg).
  const double tipped = -(std::numbers::pi / 2 + 25.0 * std::numbers::pi / 180.0);
  const auto from_behind = held(Eigen::Vector3d(tipped, 0, 0));
  const double expected = std::cos(65.0 * std::numbers::pi / 180.0) * std::sin(65.0 * std::numbers::pi / 180.0);
  EXPECT_EQ(from_behind[kThumb], 0.0);
  for (const int f : {kIndex, kMiddle, kRing, kLittle}) EXPECT_NEAR(from_behind[f], expected, 1e-9) << f;
  EXPECT_NEAR(held(Eigen::Vector3d::Zero())[kRing], 0.0, 1e-9);                         // palm toward
  EXPECT_NEAR(held(Eigen::Vector3d(0, std::numbers::pi, 0))[kRing], 0.0, 1e-9);         // back, fingers up
  EXPECT_NEAR(held(Eigen::Vector3d(-tipped, 0, 0))[kRing], 0.0, 1e-9);                  // fingers toward it
  input.pixel_labels.clear();
  EXPECT_EQ(weights(Eigen::Vector3d::Zero())[kRing], 0.0);
  EXPECT_EQ(held(Eigen::Vector3d(tipped, 0, 0))[kRing], 0.0);

  UnseenFingers unseen;
  unseen.weight[kRing] = 1.0;
  PoseParams curled = PoseParams::Zero();
  for (int d = 1; d <= 3; ++d) curled[angle_param(kRing, d)] = kCurledFlexion[static_cast<size_t>(d - 1)];
  EXPECT_EQ(unseen_finger_energy(unseen, curled, nullptr), 0.0);
  EXPECT_NEAR(unseen_finger_energy(unseen, PoseParams::Zero(), nullptr), 1.3 * 1.3 + 1.6 * 1.6 + 0.9 * 0.9, 1e-12);
  UnseenFingers behind;
  behind.held[kRing] = 0.5;
  PoseParams half = PoseParams::Zero();
  for (int d = 1; d <= 3; ++d) half[angle_param(kRing, d)] = kHalfCurlFlexion[static_cast<size_t>(d - 1)];
  EXPECT_EQ(unseen_finger_energy(behind, half, nullptr), 0.0);
  EXPECT_NEAR(unseen_finger_energy(behind, PoseParams::Zero(), nullptr), 0.5 * 3 * 0.6 * 0.6, 1e-12);
}

TEST(EnergyTerms, JointLimitIsZeroInsideAndQuadraticOutside) {
  const HandModel model = HandModel::default_adult();
  const JointLimitTerm lim;
  PoseParams p = PoseParams::Zero();
  EXPECT_EQ(lim.evaluate(model, p, nullptr), 0.0);
  p[angle_param(kIndex, 2)] = model.limits()[4 * kIndex + 2].hi + 0.5;
  EXPECT_NEAR(lim.evaluate(model, p, nullptr), 0.25, 1e-12);
}

TEST(EnergyTerms, CollisionGrowsWhenFingersCross) {
  const HandModel model = HandModel::default_adult();
  const CollisionTerm col;
  PosedHand hand;
  PoseParams open = PoseParams::Zero();
  open.head<3>() << 0, 0, 400;
  PoseParams crossed = open;
  crossed[angle_param(kIndex, 0)] = 0.35;   // positive abduction: toward the little finger
  crossed[angle_param(kMiddle, 0)] = -0.35;  // middle toward the index finger
  hand.update(model, open);
  const double e_open = col.evaluate(model, hand, nullptr);
  hand.update(model, crossed);
  EXPECT_GT(col.evaluate(model, hand, nullptr), 1.5 * e_open);
}

// A left hand (mirrored obstacle) facing this right hand across x, thumbs toward each other, moved
// in from far away: E_hand is exactly 0 while they are apart, then positive and growing as the
// other hand sinks into this one.
TEST(EnergyTerms, InterHandIsZeroApartAndGrowsAsHandsInterpenetrate) {
  const HandModel model = HandModel::default_adult();
  const InterHandCollisionTerm inter;
  PoseParams pose = PoseParams::Zero();
  pose.head<3>() << 0, 0, 400;
  const PosedHand hand(model, pose);
  double previous = -1.0;
  for (const double gap_mm :
       {600.0, 400.0, 300.0, 250.0, 200.0, 160.0, 120.0, 100.0, 90.0, 80.0, 70.0, 60.0, 50.0, 40.0}) {
    const HandObstacle other = obstacle_near(model, pose, pose, Eigen::Vector3d(gap_mm, 0, 0), true);
    PoseGradient g = PoseGradient::Zero();
    const double e = inter.evaluate(model, hand, other, &g);
    if (gap_mm >= 300.0) {
      // Beyond every pair's cut-off (exp(-30)): nothing at all, not even the gradient.
      EXPECT_EQ(e, 0.0) << "wrists " << gap_mm << " mm apart";
      EXPECT_EQ(g.cwiseAbs().maxCoeff(), 0.0) << "wrists " << gap_mm << " mm apart";
    } else {
      EXPECT_GT(e, previous) << "wrists " << gap_mm << " mm apart";
      if (gap_mm >= 250.0) {
        EXPECT_LT(e, 1e-9) << "wrists " << gap_mm << " mm apart: the hands are ~100 mm apart";
      }
      // E_hand grows as this hand moves toward the other (+x); -w_h E_hand in E pushes it away.
      if (gap_mm <= 100.0) {
        EXPECT_GT(g[0], 0.0) << "wrists " << gap_mm << " mm apart";
      }
    }
    previous = e;
  }
  // At 40 mm the hands' surfaces (1-sigma spheres) interpenetrate by ~28 mm: E_hand ~0.57, well
  // above E_col of this whole open hand (~0.02) and of a fist's true pose (up to 0.06,
  // docs/TRACKER.md), so the optimizer feels it. (At 200 mm the surfaces are ~8 mm apart and
  // E_hand ~8e-4; at 100 mm they are 8 mm deep and E_hand ~0.06.)
  EXPECT_GT(previous, 0.3);
}

// Without another hand PoseEnergy is eq. 2 to the bit; a far hand or w_h = 0 changes nothing
// either, so single-hand tracking is untouched.
TEST(EnergyTerms, NoOtherHandLeavesTheEnergyBitIdentical) {
  std::mt19937_64 rng(31);
  const HandModel model = HandModel::default_adult({1.05, 0.95, 1.1});
  for (int k = 0; k < 4; ++k) {
    const PoseParams pose = random_pose(rng);
    const DepthInput input = synthetic_input(model, pose, rng);
    const PoseParams prev = random_pose(rng);
    const PoseParams prev2 = random_pose(rng);
    const EnergyWeights weights;
    const PoseEnergy energy(SimilarityFactor::kDepth, weights);
    PosedHand hand;
    const EnergyFrame one_hand{&model, &input, &prev, &prev2};
    PoseGradient g_one;
    EnergyBreakdown parts;
    const double e_one = energy.evaluate(one_hand, pose, hand, &g_one, &parts);
    EXPECT_EQ(parts.inter_hand, 0.0);
    // Eq. 2 from the terms, in PoseEnergy's order.
    hand.update(model, pose);
    const SimilarityTerm similarity(SimilarityFactor::kDepth, weights.label_radius_mm, weights.coverage_cap);
    const double sim = similarity.evaluate(model, hand, input, nullptr);
    const double col = CollisionTerm().evaluate(model, hand, nullptr);
    const double lim = JointLimitTerm().evaluate(model, pose, nullptr);
    const double smo = SmoothnessTerm(weights.smoothness_translation_per_mm).evaluate(pose, prev, prev2, nullptr);
    EXPECT_EQ(e_one, sim - weights.collision * col - weights.limits * lim - weights.smoothness * smo);

    PoseParams far_pose = pose;
    far_pose[0] += 600.0;
    HandObstacle far;
    far.assign(model, PosedHand(model, far_pose), false);
    EnergyFrame with_far = one_hand;
    with_far.other_hand = &far;
    PoseGradient g_far;
    EXPECT_EQ(energy.evaluate(with_far, pose, hand, &g_far), e_one);
    EXPECT_EQ(g_far, g_one);

    const HandObstacle near = obstacle_near(model, pose, pose, Eigen::Vector3d(50, 0, 0), true);
    EnergyFrame with_near = one_hand;
    with_near.other_hand = &near;
    EnergyWeights no_inter = weights;
    no_inter.inter_hand = 0.0;
    PoseGradient g_off;
    EXPECT_EQ(PoseEnergy(SimilarityFactor::kDepth, no_inter).evaluate(with_near, pose, hand, &g_off), e_one);
    EXPECT_EQ(g_off, g_one);
    // ... while with w_h on, the near hand lowers the energy by exactly w_h E_hand.
    EnergyBreakdown parts_near;
    const double e_near = energy.evaluate(with_near, pose, hand, nullptr, &parts_near);
    EXPECT_GT(parts_near.inter_hand, 0.0);
    EXPECT_NEAR(e_near, e_one - weights.inter_hand * parts_near.inter_hand, 1e-12);
  }
}

// assign() reuses the obstacle's storage: no allocation per frame once it has seen one hand.
TEST(EnergyTerms, ObstacleAssignReusesStorage) {
  const HandModel model = HandModel::default_adult();
  PoseParams pose = PoseParams::Zero();
  pose.head<3>() << 0, 0, 400;
  HandObstacle other;
  other.assign(model, PosedHand(model, pose), false);
  const double* storage = other.x_mm();
  pose[0] = 30.0;
  other.assign(model, PosedHand(model, pose), true);
  EXPECT_EQ(other.x_mm(), storage);
  EXPECT_EQ(other.size(), static_cast<int>(model.gaussians().size()));
  EXPECT_DOUBLE_EQ(other.centre(0).x(), -PosedHand(model, pose).centre(0).x());
}

}  // namespace
}  // namespace handtrack
