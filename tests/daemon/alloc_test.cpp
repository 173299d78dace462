// No heap allocation in the steady state (issue 5, STYLE "allocation only in the constructor"):
// this binary replaces the global operator new with a counting one, runs the whole pipeline
// in-process (all four stage threads, the ring, statistics several times a second) on frames of
// the synthetic camera, lets it warm up, and then requires the count not to move over 150 frames.
//
// The frames are rendered before the run and replayed (back and forth, so the motion stays
// smooth): SyntheticCamera::render allocates in its motion keyframes (synth/), which is the
// virtual camera's cost, not the pipeline's.
#include "handtrack/daemon/pipeline.hpp"
#include "source_frames.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <new>
#include <thread>

namespace {

std::atomic<uint64_t> g_allocations{0};

void* counted_alloc(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (size == 0) size = 1;
  if (void* p = std::malloc(size)) return p;
  throw std::bad_alloc();
}

void* counted_aligned_alloc(std::size_t size, std::align_val_t align) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  const auto a = static_cast<std::size_t>(align);
  if (void* p = std::aligned_alloc(a, (std::max<std::size_t>(size, 1) + a - 1) / a * a)) return p;
  throw std::bad_alloc();
}

}  // namespace

void* operator new(std::size_t size) { return counted_alloc(size); }
void* operator new[](std::size_t size) { return counted_alloc(size); }
void* operator new(std::size_t size, std::align_val_t align) { return counted_aligned_alloc(size, align); }
void* operator new[](std::size_t size, std::align_val_t align) { return counted_aligned_alloc(size, align); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

namespace handtrack::daemon {
namespace {

using namespace std::chrono_literals;

// Replays pre-rendered raw frames: a source that itself never allocates.
class ReplaySource final : public DepthSource {
 public:
  ReplaySource(const std::string& motion, int frames) {
    synth::SyntheticCamera camera(synthetic_source_options(motion));
    for (int i = 0; i < frames; ++i) {
      const auto depth = camera.render(i).depth;
      RawFrame raw;
      raw.camera = depth.camera;
      for (const float d : depth.depth_mm) raw.depth_raw.push_back(static_cast<uint16_t>(d > 0.0F ? d + 0.5F : 0.0F));
      frames_.push_back(std::move(raw));
    }
  }
  [[nodiscard]] std::string describe() const override { return "replay"; }
  bool open(std::string*) override { return true; }
  void close() override {}
  GrabStatus grab(RawFrame& frame, std::chrono::milliseconds) override {
    const auto n = frames_.size();
    const auto period = 2 * n - 2;
    const auto k = next_ % period;
    const RawFrame& from = frames_[k < n ? k : period - k];
    frame.camera = from.camera;
    frame.depth_raw.assign(from.depth_raw.begin(), from.depth_raw.end());
    frame.frame_number = next_++;
    timespec ts{};
    clock_gettime(CLOCK_MONOTONIC, &ts);
    frame.capture_ns = static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
    return GrabStatus::kFrame;
  }
  [[nodiscard]] CameraIntrinsics camera() const override { return frames_.front().camera; }
  [[nodiscard]] bool is_live() const override { return false; }

 private:
  std::vector<RawFrame> frames_;
  uint64_t next_ = 0;
};

uint64_t wait_for_published(const Pipeline& pipeline, uint64_t n) {
  const auto deadline = std::chrono::steady_clock::now() + 60s;
  while (pipeline.counters().frames_published < n && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(5ms);
  }
  return pipeline.counters().frames_published;
}

// `motion`: one of the synthetic camera's, one hand or two (both hands preprocessed and optimized
// on two threads).
void expect_no_steady_state_allocation(bool single_thread, const std::string& motion = "pinch") {
  DaemonConfig config;
  config.fast = true;
  config.single_thread = single_thread;
  config.pipeline.stats_interval_ms = 200;  // several statistics rounds inside the window
  // A hand's self-calibration allocates, once per hand that comes into view, as a (re)start does;
  // under a pipeline running flat out its idle-priority search may never run: after it, nothing
  // allocates (SteadyState.ACalibratedHandDoesNotAllocate).
  config.tracker.self_calibrate = false;
  const std::string name = "htd-alloc-test-" + std::to_string(getpid());
  ipc::PoseRingWriter ring(ipc::PoseRingWriter::Options{.name = name, .capacity = 64});
  {
    Pipeline pipeline(config, std::make_unique<ReplaySource>(motion, 60), ring);
    std::string why;
    ASSERT_TRUE(pipeline.start(&why)) << why;
    ASSERT_GE(wait_for_published(pipeline, 40), 40U);  // warm-up: every pool frame has been used
    const uint64_t before = g_allocations.load();
    const uint64_t from = pipeline.counters().frames_published;
    const uint64_t to = wait_for_published(pipeline, from + 150);
    const uint64_t after = g_allocations.load();
    pipeline.stop();
    pipeline.join();
    ASSERT_GE(to, from + 150);
    const auto c = pipeline.counters();
    EXPECT_EQ(after - before, 0U) << "heap allocations over " << (to - from) << " steady-state frames ("
                                  << c.frames_published << " published)";
  }
  ipc::PoseRingWriter::remove(name);
}

// A Tracker that checks its fit every third frame, in the background (TrackerConfig::
// background_checks), on `n` rendered frames of the pinch.
TrackerConfig checked_every_third_frame(bool self_calibrate) {
  TrackerConfig config;
  config.self_calibrate = self_calibrate;
  config.background_checks = true;
  config.check_interval_frames = 3;
  config.recheck_interval_frames = 3;
  config.recheck_below_confidence = 1.0;  // every recheck is due
  return config;
}

std::vector<DepthImage> pinch_frames(int n) {
  synth::SyntheticCamera camera(synthetic_source_options("pinch"));
  std::vector<DepthImage> frames;
  for (int i = 0; i < n; ++i) frames.push_back(camera.render(i).depth);
  return frames;
}

// Tracks frames [from, to), each check and calibration waited for; the hand is found in each.
void track_waiting(Tracker& tracker, const std::vector<DepthImage>& frames, int from, int to) {
  for (int i = from; i < to; ++i) {
    ASSERT_NE(tracker.track(frames[static_cast<size_t>(i)]).state, TrackingState::kNoHand) << "frame " << i;
    tracker.wait_for_checks();
  }
}

// Background checks copy their frame and search it on a thread of their own: neither allocates once
// the tracker has (re)started. The pipelines above meet a check only when one happens to fall in
// their window, and its search only when a core is idle; here a check starts every third frame and
// each is waited for.
TEST(SteadyState, BackgroundChecksDoNotAllocate) {
  Tracker tracker(checked_every_third_frame(false));  // self-calibration: the next test
  const auto frames = pinch_frames(40);
  track_waiting(tracker, frames, 0, 10);  // the (re)start, its handedness trial and the first checks
  const uint64_t searched = background_searches_finished();
  const uint64_t before = g_allocations.load();
  track_waiting(tracker, frames, 10, 40);
  const uint64_t after = g_allocations.load();
  EXPECT_GE(background_searches_finished() - searched, 5U);
  EXPECT_EQ(after - before, 0U) << "heap allocations over 30 frames with background checks";
}

// Self-calibration (TrackerConfig::self_calibrate) gathers its frames and searches the scale once
// per hand that comes into view; after it, with the checks' background searches given the
// calibrated model, nothing allocates.
TEST(SteadyState, ACalibratedHandDoesNotAllocate) {
  Tracker tracker(checked_every_third_frame(true));
  constexpr int kFrames = 240;
  const auto frames = pinch_frames(kFrames);
  const uint64_t calibrated = self_calibrations_taken();
  int i = 0;
  for (; i < kFrames && self_calibrations_taken() == calibrated; ++i) track_waiting(tracker, frames, i, i + 1);
  ASSERT_GT(self_calibrations_taken(), calibrated) << "the hand was never calibrated";
  ASSERT_NE(tracker.config().scale, HandScale{}) << "calibrated to the default scale: nothing changed";
  ASSERT_LE(i + 30, kFrames) << "calibrated at frame " << i;
  const uint64_t searched = background_searches_finished();
  const uint64_t before = g_allocations.load();
  track_waiting(tracker, frames, i, i + 30);
  const uint64_t after = g_allocations.load();
  EXPECT_GE(background_searches_finished() - searched, 5U);
  EXPECT_EQ(after - before, 0U) << "heap allocations over 30 frames after the calibration";
}

TEST(SteadyState, PipelinedDaemonDoesNotAllocate) { expect_no_steady_state_allocation(false); }
TEST(SteadyState, SingleThreadedDaemonDoesNotAllocate) { expect_no_steady_state_allocation(true); }
TEST(SteadyState, PipelinedDaemonWithTwoHandsDoesNotAllocate) { expect_no_steady_state_allocation(false, "two_apart"); }

}  // namespace
}  // namespace handtrack::daemon
