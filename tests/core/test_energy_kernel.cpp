// The optimised E_sim kernel against the plain reference of the same formula (reference_energy.hpp),
// on synthetic frames built into C_I and poses near and off the true pose: the same values to
// 1e-6, and at least 3x faster, both measured in this run (issue 7).
#include "energy_cases.hpp"
#include "reference_energy.hpp"

#include "handtrack/core/energy.hpp"
#include "handtrack/core/kinematics.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <random>
#include <string>
#include <vector>

namespace handtrack {
namespace {

constexpr double kLabelRadiusMm = 200.0;  // EnergyWeights' R_i

class EnergyKernel : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { cases_ = new std::vector<testing::EnergyCase>(testing::synthetic_energy_cases(7, 8)); }
  static void TearDownTestSuite() {
    delete cases_;
    cases_ = nullptr;
  }
  static const std::vector<testing::EnergyCase>& cases() { return *cases_; }
  const HandModel model_ = HandModel::default_adult();

 private:
  static std::vector<testing::EnergyCase>* cases_;
};
std::vector<testing::EnergyCase>* EnergyKernel::cases_ = nullptr;

TEST_F(EnergyKernel, InputsAreRealisticHands) {
  for (const auto& c : cases()) {
    EXPECT_GT(c.input.gaussians.size(), 100U) << "a hand at 320x240 gives a few hundred quadtree leaves";
    EXPECT_EQ(c.input.mixture.size(), c.input.gaussians.size());
    const auto labelled = std::count_if(c.input.gaussians.begin(), c.input.gaussians.end(),
                                        [](const ImageGaussian& g) { return g.label != 0; });
    EXPECT_GT(labelled, static_cast<long>(c.input.gaussians.size() / 2)) << "leaves carry part labels";
  }
}

TEST_F(EnergyKernel, SameEnergyAndGradientAsTheReference) {
  PosedHand hand;
  int compared = 0;
  int capped_evaluations = 0;  // with the cap, those where it closed some image Gaussians
  for (const double cap : {0.0, kMeasuredCoverageCap}) {
    for (const SimilarityFactor factor : {SimilarityFactor::kDepth, SimilarityFactor::kLabel}) {
      const SimilarityTerm term(factor, kLabelRadiusMm, cap);
      for (const auto& c : cases()) {
        for (size_t k = 0; k < c.poses.size(); ++k) {
          hand.update(model_, c.poses[k]);
          PoseGradient expected = PoseGradient::Zero();
          PoseGradient actual = PoseGradient::Zero();
          const double e_ref = reference::similarity(model_, hand, c.input, factor, kLabelRadiusMm, &expected, cap);
          const double e_opt = term.evaluate(model_, hand, c.input, &actual);
          const std::string name = std::string(factor == SimilarityFactor::kDepth ? "depth factor" : "label factor") +
                                   ", cap " + std::to_string(cap) + ", pose " + std::to_string(k);
          if (k == 0) {
            EXPECT_GT(e_ref, 0.1) << name << ": at the true pose the model overlaps the image";
          }
          if (cap > 0.0) {
            const double uncapped = reference::similarity(model_, hand, c.input, factor, kLabelRadiusMm, nullptr);
            EXPECT_LE(e_ref, uncapped * (1.0 + 1e-12)) << name;
            capped_evaluations += e_ref < uncapped * (1.0 - 1e-9) ? 1 : 0;
          }
          EXPECT_NEAR(e_opt, e_ref, 1e-6 * std::abs(e_ref)) << name;
          EXPECT_LE((actual - expected).norm(), 1e-6 * expected.norm()) << name;
          EXPECT_EQ(term.evaluate(model_, hand, c.input, nullptr), e_opt) << "the energy does not depend on the gradient";
          ++compared;
        }
      }
    }
  }
  EXPECT_EQ(compared, 2 * 2 * 7 * 8);
  // Of the 2 x 7 x 8 evaluations with the cap (both factors), more than half (110 when written).
  EXPECT_GT(capped_evaluations, 2 * 7 * 8 / 2) << "the cap must bind in most evaluations for the comparison to test it";
}

// The kinematic chain for all centres at once equals the per-point chain summed.
TEST_F(EnergyKernel, OnePassChainEqualsThePerPointChain) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  PosedHand hand;
  for (const auto& c : cases()) {
    hand.update(model_, c.poses.back());
    CentreGradients per_centre(3, hand.gaussian_count());
    for (auto& x : per_centre.reshaped()) x = n(rng);
    PoseGradient per_point = PoseGradient::Zero();
    for (int i = 0; i < hand.gaussian_count(); ++i) hand.add_point_gradient(i, per_centre.col(i), per_point);
    PoseGradient one_pass = PoseGradient::Zero();
    hand.add_centre_gradients(per_centre, one_pass);
    EXPECT_LE((one_pass - per_point).norm(), 1e-10 * per_point.norm());
  }
}

// E_col (vectorised pair overlaps, fast exp) against the plain sum of eq. 8 over the model's pairs.
TEST_F(EnergyKernel, CollisionEqualsThePlainSumOfOverlaps) {
  const CollisionTerm term;
  PosedHand hand;
  for (const auto& c : cases()) {
    for (const auto& pose : c.poses) {
      hand.update(model_, pose);
      double plain = 0.0;
      for (const auto& pair : model_.collision_pairs()) {
        plain += overlap_3d((hand.centre(pair.a) - hand.centre(pair.b)).squaredNorm(),
                            model_.gaussians()[static_cast<size_t>(pair.a)].sigma_mm,
                            model_.gaussians()[static_cast<size_t>(pair.b)].sigma_mm);
      }
      plain /= model_.self_similarity();
      EXPECT_GT(plain, 0.0);
      EXPECT_NEAR(term.evaluate(model_, hand, nullptr), plain, 1e-9 * plain);
    }
  }
}

// E_hand (vectorised pair sums, fast exp, cut-offs, one-pass chain) against the plain sum over every
// pair of the two hands (libm exp, per-point chain): another hand, at another frame's pose, moved
// into this one (a second right hand, a left hand, a left hand of another size).
TEST_F(EnergyKernel, InterHandEqualsThePlainSumOfOverlaps) {
  const InterHandCollisionTerm term;
  const HandModel small_model = HandModel::default_adult({0.9, 0.9, 0.85});
  PosedHand hand;
  int overlapping = 0;
  int compared = 0;
  for (size_t i = 0; i < cases().size(); ++i) {
    const auto& other_case = cases()[(i + 1) % cases().size()];
    for (int variant = 0; variant < 3; ++variant) {
      const bool mirror = variant > 0;
      const HandModel& other_model = variant == 2 ? small_model : model_;
      PoseParams other_pose = other_case.truth;
      // The other wrist 50 mm to this hand's thumb side (mirrored: x negated after posing).
      other_pose.head<3>() = cases()[i].truth.head<3>() + Eigen::Vector3d(50, 0, 0);
      if (mirror) other_pose[0] = -other_pose[0];
      HandObstacle other;
      other.assign(other_model, PosedHand(other_model, other_pose), mirror);
      for (const auto& pose : cases()[i].poses) {
        hand.update(model_, pose);
        PoseGradient expected = PoseGradient::Zero();
        PoseGradient actual = PoseGradient::Zero();
        const double e_ref = reference::inter_hand(model_, hand, other, &expected);
        const double e_opt = term.evaluate(model_, hand, other, &actual);
        EXPECT_NEAR(e_opt, e_ref, 1e-9 * e_ref + 1e-15) << "case " << i << ", variant " << variant;
        EXPECT_LE((actual - expected).norm(), 1e-9 * expected.norm() + 1e-15)
            << "case " << i << ", variant " << variant;
        EXPECT_EQ(term.evaluate(model_, hand, other, nullptr), e_opt);
        if (e_ref > 1e-3) ++overlapping;
        ++compared;
      }
    }
  }
  EXPECT_GT(overlapping, compared / 2) << "most cases must have the hands overlapping";
}

// Issue 7: the optimised energy-and-gradient kernel stays >= 3x faster than the reference. Both run
// the same evaluations in interleaved rounds; the fastest round of each counts (the machine is
// shared, so the minimum is the least disturbed measurement).
TEST_F(EnergyKernel, AtLeastThreeTimesFasterThanTheReference) {
  PosedHand hand;
  const SimilarityTerm depth_term(SimilarityFactor::kDepth, kLabelRadiusMm);
  const SimilarityTerm label_term(SimilarityFactor::kLabel, kLabelRadiusMm);
  double sink = 0.0;
  const auto run = [&](bool optimised) {
    const auto t0 = std::chrono::steady_clock::now();
    for (const auto& c : cases()) {
      for (const auto& pose : c.poses) {
        hand.update(model_, pose);
        for (const SimilarityTerm* term : {&depth_term, &label_term}) {
          const auto factor = term == &depth_term ? SimilarityFactor::kDepth : SimilarityFactor::kLabel;
          PoseGradient g = PoseGradient::Zero();
          sink += optimised ? term->evaluate(model_, hand, c.input, &g)
                            : reference::similarity(model_, hand, c.input, factor, kLabelRadiusMm, &g);
          sink += g[0];
        }
      }
    }
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  double best_reference = 1e300;
  double best_optimised = 1e300;
  for (int round = 0; round < 9; ++round) {
    best_reference = std::min(best_reference, run(false));
    best_optimised = std::min(best_optimised, run(true));
  }
  const double speedup = best_reference / best_optimised;
  RecordProperty("speedup", std::to_string(speedup));
  std::printf("E_sim energy+gradient: reference %.3f ms, optimised %.3f ms per %zu evaluations: %.1fx\n",
              1e3 * best_reference, 1e3 * best_optimised, 2 * cases().size() * cases().front().poses.size(), speedup);
  EXPECT_TRUE(std::isfinite(sink));
  EXPECT_GE(speedup, 3.0);
}

}  // namespace
}  // namespace handtrack
