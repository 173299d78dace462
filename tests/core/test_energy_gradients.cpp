// Finite-difference checks of every energy term's analytic gradient at random poses (STYLE.md:
// "property tests that check analytic Jacobians against numeric ones").
#include "handtrack/core/energy.hpp"
#include "handtrack/core/tracker.hpp"

#include <gtest/gtest.h>

#include <functional>
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

}  // namespace
}  // namespace handtrack
