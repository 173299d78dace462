// The pipeline in-process, with scripted sources: a resolution change mid-stream (buffers rebuilt,
// tracking resumes at the new resolution), frames with no depth in the working volume (no_hand,
// counted), and the newest-frame-wins policy of a live source whose frames come faster than the
// optimizer can take them (drops counted, poses stay fresh, every frame accounted for); two hands
// per frame, the second optimized on the side thread, and checks searched on threads of their own
// (also under ThreadSanitizer: tsan/run.sh).
#include "handtrack/daemon/pipeline.hpp"
#include "source_frames.hpp"
#include "handtrack/ipc/pose_ring_reader.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>

namespace handtrack::daemon {
namespace {

using namespace std::chrono_literals;

int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// Frames from a function, as a recording (lossless with fast) or as a live camera.
class ScriptedSource final : public DepthSource {
 public:
  using Render = std::function<void(uint64_t, RawFrame&)>;
  ScriptedSource(uint64_t frames, bool live, Render render) : frames_(frames), live_(live), render_(std::move(render)) {}
  [[nodiscard]] std::string describe() const override { return "scripted"; }
  bool open(std::string*) override { return true; }
  void close() override {}
  GrabStatus grab(RawFrame& frame, std::chrono::milliseconds) override {
    if (next_ >= frames_) return GrabStatus::kEndOfStream;
    render_(next_, frame);
    frame.frame_number = next_++;
    frame.capture_ns = now_ns();
    return GrabStatus::kFrame;
  }
  [[nodiscard]] CameraIntrinsics camera() const override { return synth::default_camera(); }
  [[nodiscard]] bool is_live() const override { return live_; }

 private:
  uint64_t frames_;
  bool live_;
  Render render_;
  uint64_t next_ = 0;
};

void to_raw(const DepthImage& depth, RawFrame& frame) {
  frame.camera = depth.camera;
  frame.depth_raw.resize(depth.depth_mm.size());
  for (size_t i = 0; i < depth.depth_mm.size(); ++i) {
    const float d = depth.depth_mm[i];
    frame.depth_raw[i] = d > 0.0F ? static_cast<uint16_t>(std::lround(std::min(d, 65535.0F))) : uint16_t{0};
  }
}

struct Ring {
  std::string name = "htd-pipeline-test-" + std::to_string(getpid());
  ipc::PoseRingWriter writer{ipc::PoseRingWriter::Options{.name = name, .capacity = 1024}};
  ~Ring() { ipc::PoseRingWriter::remove(name); }
};

struct RunResult {
  std::vector<ipc::FrameRecord> records;  // every frame published, read through a real ring
  PipelineCounters counters;
};

// Runs a pipeline on `source` until it finishes, reading its poses from the ring as a client does.
RunResult run_to_end(const DaemonConfig& config, std::unique_ptr<DepthSource> source) {
  Ring ring;
  ipc::PoseRingReader reader;
  EXPECT_EQ(reader.open(ring.name), HANDTRACK_OK);
  Pipeline pipeline(config, std::move(source), ring.writer);
  std::string why;
  EXPECT_TRUE(pipeline.start(&why)) << why;
  RunResult out;
  // A pipeline that stops publishing for kStall is stuck. The limit is on a stall, not on the whole
  // run: under ThreadSanitizer on a loaded 2-core machine, the 80 frames of the resolution change
  // took 78 s of wall time, all of them published.
  constexpr auto kStall = 60s;
  auto deadline = std::chrono::steady_clock::now() + kStall;
  ipc::FrameRecord r{};
  while (!pipeline.finished() && std::chrono::steady_clock::now() < deadline) {
    while (reader.wait_next(r, 20ms) == HANDTRACK_OK) {
      out.records.push_back(r);
      deadline = std::chrono::steady_clock::now() + kStall;
    }
  }
  EXPECT_TRUE(pipeline.finished()) << "published nothing for " << kStall.count() << " s";
  while (reader.try_next(r) == HANDTRACK_OK) out.records.push_back(r);
  pipeline.stop();
  pipeline.join();
  out.counters = pipeline.counters();
  return out;
}

// The error of the frame's one hand (a frame without a hand is a miss: infinite).
double fingertip_error_mm(const ipc::FrameRecord& r, const Fingertips& truth) {
  if (r.hand_count != 1) return std::numeric_limits<double>::infinity();
  const ipc::HandRecord& hand = r.hands[0];
  double sum = 0.0;
  for (int f = 0; f < kNumFingers; ++f) {
    const Eigen::Vector3d got(hand.fingertips_mm[f][0], hand.fingertips_mm[f][1], hand.fingertips_mm[f][2]);
    sum += (got - *truth[static_cast<size_t>(f)]).norm();
  }
  return sum / kNumFingers;
}

TEST(Pipeline, ResolutionChangeMidStreamRebuildsBuffersAndKeepsTracking) {
  constexpr uint64_t kFrames = 80;
  synth::SyntheticCamera small(synthetic_source_options("pinch"));
  auto big_options = synthetic_source_options("pinch");
  big_options.camera = synth::default_camera(640, 480);
  synth::SyntheticCamera big(big_options);
  synth::SynthFrame rendered;
  auto source = std::make_unique<ScriptedSource>(kFrames, false, [&](uint64_t i, RawFrame& f) {
    (i < kFrames / 2 ? small : big).render(static_cast<int>(i), rendered);
    to_raw(rendered.depth, f);
  });
  DaemonConfig config;
  config.fast = true;  // lossless: every frame is tracked
  const auto [records, c] = run_to_end(config, std::move(source));
  EXPECT_EQ(c.resolution_changes, 1U);
  EXPECT_EQ(c.frames_published, kFrames);
  ASSERT_EQ(records.size(), kFrames);
  // Tracking at 640x480 after the change: the last 20 frames fit the ground truth.
  double error = 0.0;
  for (uint64_t i = kFrames - 20; i < kFrames; ++i) {
    EXPECT_EQ(records[i].frame, i);
    EXPECT_NE(records[i].hands[0].hand_id, 0U) << "a present hand has an id";
    error += fingertip_error_mm(records[i], big.render(static_cast<int>(i)).fingertips) / 20.0;
  }
  EXPECT_LT(error, 40.0);
}

// Two hands (issue 14): the synthetic two_apart scene through the whole pipeline, every frame
// tracked (fast). `at_grab` (may be empty) runs on the grab thread before each frame is rendered.
RunResult run_two_hands(uint64_t frames, const std::function<void(uint64_t)>& at_grab = {}) {
  DaemonConfig config;
  config.fast = true;
  auto options = synthetic_source_options("two_apart");
  options.frames = static_cast<int>(frames);
  auto camera = std::make_shared<synth::SyntheticCamera>(options);
  return run_to_end(config,
                    std::make_unique<ScriptedSource>(frames, false, [camera, at_grab](uint64_t i, RawFrame& f) {
                      if (at_grab) at_grab(i);
                      to_raw(camera->render(static_cast<int>(i)).depth, f);
                    }));
}

// Both hands are published in each frame, each with its own optimize time, and the two keep their
// ids.
TEST(Pipeline, TwoHandsArePublishedTogetherEachWithItsOwnTimes) {
  constexpr uint64_t kFrames = 60;
  const RunResult run = run_two_hands(kFrames);
  ASSERT_EQ(run.records.size(), kFrames);
  std::array<uint32_t, 2> ids{};
  int both = 0;
  for (const ipc::FrameRecord& r : run.records) {
    if (r.hand_count != 2) continue;
    ++both;
    EXPECT_NE(r.hands[0].hand_id, r.hands[1].hand_id);
    EXPECT_NE(r.hands[0].handedness, r.hands[1].handedness) << "a right and a left hand";
    for (int k = 0; k < 2; ++k) {
      EXPECT_GT(r.hands[k].optimize_ms, 0.0F);
      if (ids[static_cast<size_t>(k)] != 0) {
        EXPECT_EQ(r.hands[k].hand_id, ids[static_cast<size_t>(k)]);
      }
      ids[static_cast<size_t>(k)] = r.hands[k].hand_id;
    }
  }
  EXPECT_GE(both, 58) << "of 60 frames with both hands";
}

// The nice value of each of this process's threads, by name (/proc/self/task/TID/stat: the
// 19th field, counted after the name's closing parenthesis).
std::map<std::string, int> thread_nice_values() {
  std::map<std::string, int> out;
  for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
    std::ifstream comm(task.path() / "comm");
    std::ifstream stat(task.path() / "stat");
    std::string name;
    std::string line;
    if (!std::getline(comm, name) || !std::getline(stat, line)) continue;  // a thread that ended
    std::istringstream fields(line.substr(line.rfind(')') + 2));
    std::string field;
    for (int k = 3; k <= 19 && fields >> field; ++k) {
      if (k == 19) out[name] = std::stoi(field);
    }
  }
  return out;
}

// Where two stage threads share a CPU (each stage's second-hand thread runs on the other stage's
// CPU), the next frame's preprocessing yields to this frame's optimisation: its threads run at a
// higher nice value than the optimize threads (docs/THREADING.md).
TEST(Pipeline, NextFramesPreprocessingYieldsToThisFramesOptimisation) {
  constexpr uint64_t kFrames = 20;
  std::map<std::string, int> nice;
  run_two_hands(kFrames, [&](uint64_t i) {
    if (i == kFrames - 1) nice = thread_nice_values();  // every stage thread has set itself up
  });
  for (const char* name : {"ht-preprocess", "ht-preprocess-2", "ht-optimize", "ht-optimize-2", "ht-grab"}) {
    ASSERT_EQ(nice.count(name), 1U) << name << " not running";
  }
  EXPECT_GT(nice["ht-preprocess"], nice["ht-optimize-2"]) << "they share a CPU";
  EXPECT_GT(nice["ht-preprocess-2"], nice["ht-optimize"]) << "they share a CPU";
  EXPECT_EQ(nice["ht-optimize"], nice["ht-grab"]) << "only preprocessing yields";
}

TEST(Pipeline, FramesWithoutDepthInTheWorkingVolumeAreNoHandAndCounted) {
  constexpr uint64_t kFrames = 30;
  auto source = std::make_unique<ScriptedSource>(kFrames, false, [](uint64_t i, RawFrame& f) {
    f.camera = synth::default_camera();
    // all zero (no measurement), all at the sensor's maximum, all just beyond the far plane
    const uint16_t value = i % 3 == 0 ? 0 : i % 3 == 1 ? 65535 : 601;
    f.depth_raw.assign(static_cast<size_t>(f.camera.width * f.camera.height), value);
  });
  DaemonConfig config;
  config.fast = true;
  const auto [records, c] = run_to_end(config, std::move(source));
  EXPECT_EQ(c.frames_empty, kFrames);
  ASSERT_EQ(records.size(), kFrames);
  for (const auto& r : records) {
    EXPECT_EQ(r.hand_count, 0U) << "no hand seen: a frame with no hands";
    EXPECT_EQ(r.hands[0].hand_id, 0U);
  }
}

TEST(Pipeline, MalformedFramesAreSkippedNotPublished) {
  auto source = std::make_unique<ScriptedSource>(10, false, [](uint64_t i, RawFrame& f) {
    f.camera = synth::default_camera();
    f.depth_raw.assign(static_cast<size_t>(f.camera.width * f.camera.height) - (i % 2), 0);  // odd: one short
  });
  DaemonConfig config;
  config.fast = true;
  const auto [records, c] = run_to_end(config, std::move(source));
  EXPECT_EQ(c.frames_skipped, 5U);
  EXPECT_EQ(records.size(), 5U);
}

TEST(Pipeline, LiveSourceFasterThanTheOptimizerDropsOldestFramesAndStaysFresh) {
  constexpr uint64_t kFrames = 150;
  synth::SyntheticCamera camera(synthetic_source_options("pinch"));
  synth::SynthFrame rendered;
  std::vector<RawFrame> frames(kFrames);
  for (uint64_t i = 0; i < kFrames; ++i) {
    camera.render(static_cast<int>(i), rendered);
    to_raw(rendered.depth, frames[i]);
  }
  // A "camera" at ~1,000 fps (pre-rendered frames, 1 ms apart): faster than tracking with a
  // handedness trial (both hands, 2-10 ms a frame) on any machine, and a stream long enough for
  // many poses after the first frame's (re)start search of both hands (about 50 ms). At 0.1 ms
  // apart the whole stream passed during that first search and 2 or 3 poses were published, too
  // few for the median below.
  auto source = std::make_unique<ScriptedSource>(kFrames, true, [&](uint64_t i, RawFrame& f) {
    std::this_thread::sleep_for(1ms);
    f = frames[i];
  });
  DaemonConfig config;
  config.max_frames = kFrames;
  const auto [records, c] = run_to_end(config, std::move(source));
  EXPECT_EQ(c.frames_captured, kFrames);
  EXPECT_GT(c.frames_dropped, 0U) << "the optimizer kept up with a 10,000 fps source?";
  EXPECT_EQ(c.frames_published + c.frames_dropped + c.frames_skipped, c.frames_captured);
  ASSERT_EQ(records.size(), c.frames_published);
  std::vector<double> age_ms;
  std::vector<double> work_ms;  // preprocess + optimize of each published frame
  for (size_t i = 0; i < records.size(); ++i) {
    if (i > 0) {
      EXPECT_GT(records[i].frame, records[i - 1].frame) << "published out of order";
    }
    age_ms.push_back(static_cast<double>(records[i].publish_ns - records[i].capture_ns) * 1e-6);
    work_ms.push_back(static_cast<double>(records[i].preprocess_ms) + static_cast<double>(records[i].optimize_ms));
  }
  std::sort(age_ms.begin(), age_ms.end());
  std::sort(work_ms.begin(), work_ms.end());
  // Newest wins: a pose is about two frames' work old (the optimizer finishes the frame it holds,
  // then works on the newest), not a queue's worth (raw and input queues hold 4 frames each: a
  // first-in-first-out pipeline would be 8 or more frames' work old). Measured in the pipeline's
  // own work time, so that the bound holds on a slow machine and under ThreadSanitizer alike.
  const double p50 = age_ms[age_ms.size() / 2];
  const double work = work_ms[work_ms.size() / 2];
  std::printf("live overload: %zu published, %llu dropped, age p50 %.1f ms, max %.1f ms, work p50 %.1f ms\n",
              records.size(), static_cast<unsigned long long>(c.frames_dropped), p50, age_ms.back(), work);
  EXPECT_LT(p50, 3.0 * work + 10.0);
}

// Background checks (tracker.background_checks): the searches run on their own threads beside the
// pipeline's, on copies of the frames they check (also under ThreadSanitizer). Every tracked hand
// is rechecked every 5 frames here, so that searches are under way while frames are tracked and
// published, and while the pipeline stops. The searches run at SCHED_IDLE: a camera at 30 fps
// leaves idle CPU for them, but under ThreadSanitizer a frame's work takes about 2 s, the pipeline
// keeps both CPUs busy and a queued search may not start before the stream ends (CI, 2026-11-30:
// 5 frames published, no search finished). So the camera pauses before its last frame, as a real
// one does when nothing moves, until a search has finished (at most 120 s): a search that never
// finishes in idle time still fails.
TEST(Pipeline, BackgroundChecksSearchBesideThePipeline) {
  constexpr uint64_t kFrames = 60;
  const uint64_t searched_before = background_searches_finished();
  auto camera = std::make_shared<synth::SyntheticCamera>(synthetic_source_options("pinch"));
  auto source = std::make_unique<ScriptedSource>(kFrames, true, [camera, searched_before](uint64_t i, RawFrame& f) {
    std::this_thread::sleep_for(33ms);
    if (i + 1 == kFrames) {
      const auto give_up = std::chrono::steady_clock::now() + 120s;
      while (background_searches_finished() == searched_before && std::chrono::steady_clock::now() < give_up) {
        std::this_thread::sleep_for(10ms);
      }
    }
    to_raw(camera->render(static_cast<int>(i)).depth, f);
  });
  DaemonConfig config;
  config.max_frames = kFrames;
  config.tracker.background_checks = true;
  config.tracker.recheck_interval_frames = 5;
  config.tracker.recheck_below_confidence = 1.0;
  const auto [records, c] = run_to_end(config, std::move(source));
  EXPECT_EQ(c.frames_published + c.frames_dropped + c.frames_skipped, c.frames_captured);
  const auto with_hand =
      std::count_if(records.begin(), records.end(), [](const ipc::FrameRecord& r) { return r.hand_count == 1; });
  EXPECT_GE(with_hand, static_cast<std::ptrdiff_t>(records.size()) / 2) << "of " << records.size() << " frames";
  std::printf("%llu background searches finished during %zu published frames\n",
              static_cast<unsigned long long>(background_searches_finished() - searched_before), records.size());
  EXPECT_GT(background_searches_finished(), searched_before) << "no background search finished";
}

}  // namespace
}  // namespace handtrack::daemon
