// The accuracy tests of issues 2 and 4: the seven synthetic Dexter-1-like motions (300 frames each,
// 320x240, sensor noise on) of three subjects (testing::kSubjectSeeds) tracked with 2 particles x
// 10 iterations (Sec. 7's configuration), depth-only and with late fusion (Sec. 5, the shipped part
// forest), both on the same rendered frames. Asserts what a user would notice: the mean fingertip
// error, that late fusion is not less accurate than depth-only on any motion (over the subjects),
// NaN-free poses, and that frames without a pose and sequences lost for good are rare. Those two run the paper's energy
// (eq. 2, w_f = 0, the paper's w_c; w_s is ours in all three); the shipped late fusion, with our
// free-space term E_free, E_sim's coverage cap and w_c 0.5 while tracking, runs on the same frames
// against issue "Every view"'s goal for these motions (the mean over 3 seeds).
#include "synthetic_tracking.hpp"

#include "handtrack/eval/scoring.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <string>
#include <vector>

namespace handtrack {
namespace {

using testing::kSequenceFrames;

constexpr double kMaxDepthOnlyMeanMm = 25.0;    // issue 2, "Done when"
constexpr double kMaxLateFusionMeanMm = 15.0;   // issue 4, "Done when"
constexpr double kMaxShippedMeanMm = 10.0;      // issue "Every view", "Done when": over 3 seeds
// Late fusion may be this much worse than depth-only on one motion (its mean over the subjects)
// and still count as "not worse". Why not 0: the particles draw random extrapolation factors, and
// another draw alone moves a motion's mean: depth-only with seeds 1-3 gives pinch 5.12-5.95 mm,
// fingerwave 6.76-9.17 mm, fingercount 12.6-18.8 mm (docs/TRACKER.md, "Late fusion"). 1 mm is above
// the spread of the easy motions and far below the gains late fusion must show on the closed hands
// (flexex1 -9 mm).
constexpr double kNotWorseToleranceMm = 1.0;
// "Lost for good": at the end of a sequence the tracker is not back on the hand: fewer than half
// of the last 60 frames under 30 mm. At most one sequence of the 21 (7 motions x 3 subjects) of
// each energy but the shipped one, which loses none (docs/TRACKER.md, "Tests over three subjects").
constexpr int kTailFrames = 60;
constexpr double kTailBoundMm = 30.0;
constexpr int kMostLostForGood = 1;

bool lost_for_good(const eval::SequenceScore& s) {
  const auto tail_begin = s.per_frame_error_mm.end() - kTailFrames;
  const auto good = std::count_if(tail_begin, s.per_frame_error_mm.end(), [](double e) { return e < kTailBoundMm; });
  return good < kTailFrames / 2;
}

// The hand is always in view: a frame without a pose is a miss. At most 1 % of the frames of each
// energy (the issue "Every view" allows 2 % on its broadened benchmark); measured 3 of 6300, all in
// one sequence of the paper's late fusion (random-s8).
constexpr double kMostWithoutPoseShare = 0.01;

// Every pose finite and nearly every frame posed; returns how many sequences were lost for good,
// naming each.
int expect_sane(const std::vector<eval::SequenceScore>& scores, const char* energy) {
  int lost = 0;
  int frames = 0;
  int without_pose = 0;
  for (const auto& s : scores) {
    EXPECT_EQ(s.nan_poses, 0) << energy << " " << s.name;
    frames += s.frames;
    without_pose += s.without_pose;
    if (s.without_pose > 0) std::printf("%s: %s has %d frames without a pose\n", energy, s.name.c_str(), s.without_pose);
    if (lost_for_good(s)) {
      std::printf("%s: %s is lost for good\n", energy, s.name.c_str());
      ++lost;
    }
  }
  EXPECT_LE(without_pose, kMostWithoutPoseShare * frames) << energy << ": frames without a pose, of " << frames;
  return lost;
}

// The mean error of each motion over the subjects, in kMotionNames' order (`scores` holds the
// subjects one after the other, each the seven motions in that order).
std::vector<double> motion_means(const std::vector<eval::SequenceScore>& scores) {
  std::vector<double> means(synth::kMotionNames.size(), 0.0);
  for (size_t k = 0; k < scores.size(); ++k) means[k % means.size()] += scores[k].mean_error_mm;
  for (double& m : means) m /= static_cast<double>(testing::kSubjectSeeds.size());
  return means;
}

TEST(TrackingAccuracy, SevenSyntheticMotionsDepthOnlyAndLateFusion2Particles10Iterations) {
  const PartForest& forest = testing::shipped_forest();
  std::vector<eval::SequenceScore> depth_only;
  std::vector<eval::SequenceScore> late_fusion;
  std::vector<eval::SequenceScore> shipped;
  TrackerConfig paper_fusion = testing::paper_config(EnergyMode::kLateFusion);
  paper_fusion.weights.free_space = 0.0;  // the paper's energy: eq. 2 with eq. 6's E_sim
  paper_fusion.weights.coverage_cap = 0.0;
  paper_fusion.weights.tracking_collision = paper_fusion.weights.collision;  // and its w_c
  for (const uint64_t seed : testing::kSubjectSeeds) {
    for (const auto motion : synth::kMotionNames) {
      auto camera = testing::motion_camera(motion, seed);
      Tracker depth_tracker(testing::paper_config(EnergyMode::kDepthOnly));
      Tracker fusion_tracker(paper_fusion);
      Tracker shipped_tracker(testing::paper_config(EnergyMode::kLateFusion));
      const std::string name = std::string(motion) + "-s" + std::to_string(seed);
      eval::SequenceScorer depth_scorer{name};
      eval::SequenceScorer fusion_scorer{name};
      eval::SequenceScorer shipped_scorer{name};
      synth::SynthFrame frame;
      for (int i = 0; i < kSequenceFrames; ++i) {
        camera.render(i, frame);
        depth_scorer.add(depth_tracker.track(frame.depth), frame.fingertips);
        fusion_scorer.add(fusion_tracker.track(frame.depth, &forest), frame.fingertips);
        shipped_scorer.add(shipped_tracker.track(frame.depth, &forest), frame.fingertips);
      }
      depth_only.push_back(depth_scorer.finish(0.0));
      late_fusion.push_back(fusion_scorer.finish(0.0));
      shipped.push_back(shipped_scorer.finish(0.0));
    }
  }
  const auto depth_total = eval::overall(depth_only);
  const auto fusion_total = eval::overall(late_fusion);
  const auto shipped_total = eval::overall(shipped);
  std::printf("depth-only:\n%s\nlate fusion:\n%s\nlate fusion with E_free (shipped):\n%s",
              eval::format_table(depth_only, depth_total).c_str(), eval::format_table(late_fusion, fusion_total).c_str(),
              eval::format_table(shipped, shipped_total).c_str());

  EXPECT_LE(depth_total.mean_error_mm, kMaxDepthOnlyMeanMm);
  EXPECT_LE(fusion_total.mean_error_mm, kMaxLateFusionMeanMm);
  EXPECT_LE(shipped_total.mean_error_mm, kMaxShippedMeanMm);
  EXPECT_LE(expect_sane(depth_only, "depth-only"), kMostLostForGood);
  EXPECT_LE(expect_sane(late_fusion, "late fusion"), kMostLostForGood);
  EXPECT_EQ(expect_sane(shipped, "shipped late fusion"), 0);
  const auto depth_means = motion_means(depth_only);
  const auto fusion_means = motion_means(late_fusion);
  for (size_t m = 0; m < synth::kMotionNames.size(); ++m) {
    std::printf("%-12s over the subjects: depth-only %.2f mm, late fusion %.2f mm\n",
                std::string(synth::kMotionNames[m]).c_str(), depth_means[m], fusion_means[m]);
    EXPECT_LE(fusion_means[m], depth_means[m] + kNotWorseToleranceMm)
        << synth::kMotionNames[m] << ": late fusion less accurate than depth-only";
  }
  // Late fusion must be more than one depth-only particle: the detection-guided one has to win.
  EXPECT_GT(fusion_total.guided_wins, 0);
}

}  // namespace
}  // namespace handtrack
