// The client library's pose filter (handtrack_filter_*, a One Euro filter; docs/FILTER.md) on
// known signals: its step response is the first-order low-pass of the paper's equations, it
// removes noise from a still hand and follows a moving one with a bounded lag, and it starts
// afresh where the pose sequence breaks (new epoch, gap, time going back, no hand); several hands
// are smoothed each on its own, followed by hand_id.
#include <handtrack/client.h>
#include <handtrack/client.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace {

constexpr double kFps = 60.0;
constexpr int64_t kFrameNs = static_cast<int64_t>(1e9 / kFps);

// A tracked hand whose every point is (x, y, z).
handtrack_hand hand_at(float x, float y = 0.0F, float z = 400.0F, uint32_t hand_id = 1) {
  handtrack_hand p{};
  p.hand_id = hand_id;
  p.state = HANDTRACK_STATE_TRACKING;
  for (auto& j : p.joints_mm) {
    j[0] = x;
    j[1] = y;
    j[2] = z;
  }
  for (auto& t : p.fingertips_mm) {
    t[0] = x;
    t[1] = y;
    t[2] = z;
  }
  p.palm_center_mm[0] = x;
  p.palm_center_mm[1] = y;
  p.palm_center_mm[2] = z;
  p.palm_normal[2] = -1.0F;
  return p;
}

// Frame `i` with one tracked hand (id 1) whose every point is (x, y, z).
handtrack_frame pose_at(int i, float x, float y = 0.0F, float z = 400.0F, uint64_t epoch = 1) {
  handtrack_frame f{};
  f.epoch = epoch;
  f.capture_ns = 1'000'000'000 + i * kFrameNs;
  f.hand_count = 1;
  f.hands[0] = hand_at(x, y, z);
  return f;
}

handtrack_filter_params params(double min_cutoff, double beta) {
  handtrack_filter_params p = handtrack::PoseFilter::defaults();
  p.min_cutoff_hz = min_cutoff;
  p.beta = beta;
  return p;
}

TEST(PoseFilter, StepResponseIsTheFirstOrderLowPass) {
  // beta = 0: a fixed cutoff f_c, x^_n = x^_{n-1} + a (x_n - x^_{n-1}), a = 1 / (1 + tau / dt),
  // tau = 1 / (2 pi f_c); after a step of 100 mm, n frames later 100 (1 - (1 - a)^n).
  handtrack::PoseFilter filter(params(2.0, 0.0));
  ASSERT_TRUE(filter.ok());
  handtrack_frame p = pose_at(0, 0.0F);
  filter.apply(p);
  EXPECT_FLOAT_EQ(p.hands[0].fingertips_mm[1][0], 0.0F) << "the first pose passes through";
  const double dt = 1.0 / kFps;
  const double a = 1.0 / (1.0 + (1.0 / (2.0 * std::numbers::pi * 2.0)) / dt);
  for (int n = 1; n <= 30; ++n) {
    p = pose_at(n, 100.0F);
    filter.apply(p);
    EXPECT_NEAR(p.hands[0].fingertips_mm[1][0], 100.0 * (1.0 - std::pow(1.0 - a, n)), 1e-3) << "frame " << n;
    EXPECT_NEAR(p.hands[0].joints_mm[20][0], p.hands[0].fingertips_mm[1][0], 1e-4);
    EXPECT_FLOAT_EQ(p.hands[0].fingertips_mm[1][2], 400.0F) << "a still coordinate stays";
  }
}

TEST(PoseFilter, DefaultsCutTheJitterOfAStillHandInHalf) {
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0.0F, 2.0F);
  handtrack::PoseFilter filter;
  double raw2 = 0.0;
  double smooth2 = 0.0;
  float last_raw = 0.0F;
  float last_smooth = 0.0F;
  for (int i = 0; i < 600; ++i) {
    handtrack_frame p = pose_at(i, 50.0F + noise(rng));
    const float raw = p.hands[0].fingertips_mm[0][0];
    filter.apply(p);
    const float smooth = p.hands[0].fingertips_mm[0][0];
    if (i > 60) {  // past the start
      raw2 += (raw - last_raw) * (raw - last_raw);
      smooth2 += (smooth - last_smooth) * (smooth - last_smooth);
    }
    last_raw = raw;
    last_smooth = smooth;
  }
  EXPECT_LT(std::sqrt(smooth2), 0.5 * std::sqrt(raw2)) << "frame-to-frame change, raw vs smoothed";
}

TEST(PoseFilter, AFastHandIsFollowedWithinAFrame) {
  // 500 mm/s (a quick reach) at 60 fps: 8.3 mm a frame. With the defaults the smoothed point
  // trails the true one by at most about a frame's travel once the speed estimate settled.
  handtrack::PoseFilter filter;
  const double speed = 500.0;
  for (int i = 0; i <= 60; ++i) {
    const float x = static_cast<float>(speed * i / kFps);
    handtrack_frame p = pose_at(i, x);
    filter.apply(p);
    if (i >= 20) {
      EXPECT_LT(x - p.hands[0].fingertips_mm[2][0], speed / kFps * 1.05) << "frame " << i;
    }
  }
}

TEST(PoseFilter, StartsAfreshWhereTheSequenceBreaks) {
  handtrack::PoseFilter filter(params(0.5, 0.0));  // heavy smoothing: a non-reset would show
  int i = 0;
  for (; i < 10; ++i) {
    handtrack_frame p = pose_at(i, 0.0F);
    filter.apply(p);
  }
  auto passes_through = [&](handtrack_frame p) {
    const float x = p.hands[0].fingertips_mm[0][0];
    filter.apply(p);
    return p.hands[0].fingertips_mm[0][0] == x;
  };
  handtrack_frame moved = pose_at(i++, 100.0F);
  EXPECT_FALSE(passes_through(moved)) << "the same sequence is smoothed";

  EXPECT_TRUE(passes_through(pose_at(i++, 200.0F, 0.0F, 400.0F, 2))) << "a new epoch (daemon restart)";
  i += 30;  // 0.5 s > max_gap_s 0.25 s
  EXPECT_TRUE(passes_through(pose_at(i++, 300.0F, 0.0F, 400.0F, 2))) << "a gap";
  EXPECT_TRUE(passes_through(pose_at(i - 5, 400.0F, 0.0F, 400.0F, 2))) << "time going backwards";
  handtrack_frame recovering = pose_at(i++, 500.0F, 0.0F, 400.0F, 2);
  recovering.hands[0].state = HANDTRACK_STATE_RECOVERING;
  EXPECT_TRUE(passes_through(recovering)) << "not tracking";
  EXPECT_TRUE(passes_through(pose_at(i++, 600.0F, 0.0F, 400.0F, 2))) << "the first tracked pose after it";
  EXPECT_FALSE(passes_through(pose_at(i++, 650.0F, 0.0F, 400.0F, 2)));
  handtrack_frame none = pose_at(i++, 0.0F, 0.0F, 400.0F, 2);
  none.hand_count = 0;
  filter.apply(none);
  EXPECT_TRUE(passes_through(pose_at(i++, 600.0F, 0.0F, 400.0F, 2))) << "a frame without the hand ends its history";
  EXPECT_FALSE(passes_through(pose_at(i++, 700.0F, 0.0F, 400.0F, 2)));
  filter.reset();
  EXPECT_TRUE(passes_through(pose_at(i++, 800.0F, 0.0F, 400.0F, 2))) << "an explicit reset";
}

TEST(PoseFilter, ThePalmNormalStaysAUnitVector) {
  handtrack::PoseFilter filter;
  for (int i = 0; i < 30; ++i) {
    handtrack_frame p = pose_at(i, 0.0F);
    float* normal = p.hands[0].palm_normal;
    const double angle = 0.1 * i;
    normal[0] = static_cast<float>(std::sin(angle));
    normal[1] = 0.0F;
    normal[2] = static_cast<float>(-std::cos(angle));
    filter.apply(p);
    const double n = std::hypot(normal[0], normal[1], normal[2]);
    EXPECT_NEAR(n, 1.0, 1e-5);
  }
}

// Two hands in one stream: each is smoothed with its own history, found by hand_id wherever it is
// in hands[]; a new id starts afresh while the other hand keeps its history.
TEST(PoseFilter, EachHandIsSmoothedOnItsOwnByItsId) {
  handtrack::PoseFilter filter(params(0.5, 0.0));  // heavy smoothing: a shared history would show
  auto two_hands = [](int i, float x_a, float x_b, uint32_t id_b = 2, bool swapped = false) {
    handtrack_frame f = pose_at(i, 0.0F);
    f.hand_count = 2;
    f.hands[swapped ? 1 : 0] = hand_at(x_a, 0.0F, 400.0F, 1);
    f.hands[swapped ? 0 : 1] = hand_at(x_b, 0.0F, 400.0F, id_b);
    return f;
  };
  int i = 0;
  for (; i < 10; ++i) {
    handtrack_frame f = two_hands(i, 0.0F, 300.0F);
    filter.apply(f);
    EXPECT_FLOAT_EQ(f.hands[0].fingertips_mm[0][0], 0.0F) << "hand 1 is still: its own history";
    EXPECT_FLOAT_EQ(f.hands[1].fingertips_mm[0][0], 300.0F) << "hand 2 is still: its own history";
  }
  handtrack_frame swapped = two_hands(i++, 0.0F, 300.0F, 2, true);
  filter.apply(swapped);
  EXPECT_FLOAT_EQ(swapped.hands[1].fingertips_mm[0][0], 0.0F) << "hand 1, now second, keeps its history";
  EXPECT_FLOAT_EQ(swapped.hands[0].fingertips_mm[0][0], 300.0F) << "hand 2, now first, keeps its history";

  handtrack_frame step = two_hands(i++, 100.0F, 400.0F, 3);  // hand 2 left, hand 3 came
  filter.apply(step);
  EXPECT_GT(step.hands[0].fingertips_mm[0][0], 0.0F);
  EXPECT_LT(step.hands[0].fingertips_mm[0][0], 50.0F) << "hand 1's step is smoothed";
  EXPECT_FLOAT_EQ(step.hands[1].fingertips_mm[0][0], 400.0F) << "a new hand starts afresh";
}

TEST(PoseFilter, InvalidParametersAreRefused) {
  handtrack_filter* f = nullptr;
  for (const auto& bad : {params(0.0, 0.01), params(-1.0, 0.01), params(1.0, -0.1), params(NAN, 0.01),
                          params(1.0, INFINITY)}) {
    EXPECT_EQ(handtrack_filter_new(&bad, &f), HANDTRACK_ERR_INVALID_ARGUMENT);
    EXPECT_EQ(f, nullptr);
  }
  handtrack_filter_params gap = handtrack::PoseFilter::defaults();
  gap.max_gap_s = 0.0;
  EXPECT_EQ(handtrack_filter_new(&gap, &f), HANDTRACK_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(handtrack_filter_new(nullptr, nullptr), HANDTRACK_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(handtrack_filter_apply(nullptr, nullptr), HANDTRACK_ERR_INVALID_ARGUMENT);
  ASSERT_EQ(handtrack_filter_new(nullptr, &f), HANDTRACK_OK);
  handtrack_filter_free(f);
  EXPECT_FALSE(handtrack::PoseFilter(params(0.0, 0.0)).ok());
}

}  // namespace
