// The pipeline of pipeline.hpp. Reading guide: Frame (one pool entry and everything a stage
// writes into it), the four stage loops (grab_loop, preprocess_loop, optimize_loop, publish_loop),
// and the step functions they share with the single-threaded loop (single_loop).
#include "handtrack/daemon/pipeline.hpp"

#include "handtrack/core/part_forest.hpp"

#include "clock.hpp"
#include "logging.hpp"

#include <boost/lockfree/spsc_queue.hpp>
#include <fmt/format.h>

#include <linux/futex.h>
#include <pthread.h>
#include <sched.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

namespace handtrack::daemon {

namespace {

constexpr auto kGrabTimeout = std::chrono::milliseconds(100);  // a grab() returns at least this often
constexpr int64_t kIdleWaitNs = 50'000'000;                    // queue waits re-check stop this often
constexpr int64_t kReopenIntervalNs = 1'000'000'000;           // live device: open() retries
constexpr int64_t kLogIntervalNs = 1'000'000'000;              // rate limit of repeated warnings
constexpr size_t kLatencySamples = 4096;                       // per statistics interval
constexpr size_t kRecordBuffers = 32;                          // --record: frames in flight to the disk

// A futex-backed wake-up for a queue's consumer: lock-free queues have no blocking pop, and a
// consumer must neither spin nor sleep a fixed time. The producer pushes, then ring()s; the
// consumer takes a ticket, tries to pop, and waits on the ticket only if the queue was empty.
// SYNC: ring()'s release increment pairs with ticket()'s acquire load; the kernel compares the
// word under its own lock, so a ring() between ticket() and wait() makes wait() return at once.
class Doorbell {
 public:
  [[nodiscard]] uint32_t ticket() const { return word_.load(std::memory_order_acquire); }
  void wait(uint32_t ticket, int64_t timeout_ns) {
    timespec ts{static_cast<time_t>(timeout_ns / 1'000'000'000), static_cast<long>(timeout_ns % 1'000'000'000)};
    syscall(SYS_futex, word(), FUTEX_WAIT_PRIVATE, ticket, &ts, nullptr, 0);
  }
  void ring() {
    word_.fetch_add(1, std::memory_order_release);
    syscall(SYS_futex, word(), FUTEX_WAKE_PRIVATE, INT_MAX, nullptr, nullptr, 0);
  }

 private:
  uint32_t* word() { return reinterpret_cast<uint32_t*>(&word_); }
  static_assert(sizeof(std::atomic<uint32_t>) == sizeof(uint32_t) && std::atomic<uint32_t>::is_always_lock_free);
  alignas(64) std::atomic<uint32_t> word_{0};
};

struct Frame {
  RawFrame raw;
  DepthImage depth;                    // mm
  DepthInputBuilder builder;           // per frame: frame t+1 is preprocessed while t is optimized
  uint64_t builder_generation = 0;
  const DepthInput* input = nullptr;   // null: no depth in the working volume, or malformed
  bool empty = false;                  // nothing in the working volume: published as no_hand
  bool malformed = false;              // buffer does not match its intrinsics: skipped
  bool resolution_changed = false;     // first frame of a new resolution: the tracker restarts
  TrackerOutput output;
  HandScale scale;
  uint64_t seq = 0;                    // daemon frame number (PoseRecord::frame)
  int64_t capture_ns = 0;
  int64_t grab_end_ns = 0;
  int64_t preprocess_start_ns = 0;
  int64_t preprocess_end_ns = 0;
  int64_t optimize_start_ns = 0;
  int64_t optimize_end_ns = 0;
};

struct RecordBuffer {
  Gray16Image image;
  CameraIntrinsics camera;
  uint64_t frame = 0;
};

// What a stage is doing, for the watchdog: 0 = waiting for input (legitimately idle), otherwise
// when it started on its current item. SYNC: relaxed; the control thread only needs a recent value.
struct alignas(64) StageActivity {
  std::atomic<int64_t> busy_since_ns{0};
  std::atomic<uint64_t> frame{0};
};

using FrameQueue = boost::lockfree::spsc_queue<Frame*>;
using RecordQueue = boost::lockfree::spsc_queue<RecordBuffer*>;

// Rate-limited warning state (one thread each).
struct Throttle {
  int64_t last_ns = 0;
  uint64_t suppressed = 0;
  bool allow(int64_t now) {
    if (now - last_ns < kLogIntervalNs) {
      ++suppressed;
      return false;
    }
    last_ns = now;
    return true;
  }
};

uint64_t env_u64(const char* name) {
  const char* text = std::getenv(name);
  if (text == nullptr || *text == '\0') return 0;
  return std::strtoull(text, nullptr, 10);
}

}  // namespace

struct Pipeline::Impl {
  Impl(const DaemonConfig& c, std::unique_ptr<DepthSource> s, ipc::PoseRingWriter& r)
      : config(c), source(std::move(s)), ring(r), lossless(c.fast && !source->is_live()) {}

  DaemonConfig config;
  std::unique_ptr<DepthSource> source;
  ipc::PoseRingWriter& ring;
  const bool lossless;  // recordings with --fast: back-pressure, never drop
  bool source_open = false;

  std::vector<std::unique_ptr<Frame>> pool;
  std::optional<FrameQueue> raw_q, input_q, result_q, free_from_pre, free_from_opt, free_from_pub;
  Doorbell grab_bell, pre_bell, opt_bell, pub_bell, rec_bell;
  std::array<StageActivity, kNumStages> activity{};
  std::vector<std::thread> threads;

  std::atomic<bool> stop_flag{false};
  std::atomic<bool> grab_done{false};
  std::atomic<bool> failed_flag{false};
  std::atomic<uint64_t> captured{0};
  std::atomic<uint64_t> completed{0};  // published + dropped + skipped: finished() compares with captured
  std::atomic<uint64_t> published{0}, dropped{0}, skipped{0}, empty_frames{0}, source_errors{0},
      resolution_changes{0}, records_dropped{0}, frames_recorded{0};
  std::atomic<int64_t> first_capture_ns{0}, last_publish_ns{0};
  std::atomic<int32_t> tracking_state{HANDTRACK_STATE_NO_HAND};
  std::atomic<uint32_t> device_state{static_cast<uint32_t>(ipc::DeviceState::kStarting)};

  // The hint for segmentation: from the last optimized pose (optimize writes, preprocess reads).
  std::mutex hint_mutex;
  std::optional<HandHint> hint;

  // SIGHUP: a new tracker configuration; stages pick it up between frames.
  std::mutex reload_mutex;
  TrackerConfig reloaded;
  std::atomic<uint64_t> generation{0};

  // Optimize stage state.
  std::optional<PoseTracker> tracker;
  std::optional<PartForest> forest;  // labels the hand's pixels for the detection-guided particle
  uint64_t tracker_generation = 0;
  uint64_t optimized = 0;
  uint64_t stall_after = 0;  // test hook: HANDTRACKD_TEST_STALL_OPTIMIZER_AFTER

  // Preprocess stage state.
  DepthInputConfig input_config;
  uint64_t input_generation = 0;
  int stream_width = 0;
  int stream_height = 0;

  // Publish stage state (statistics of the current interval).
  std::vector<float> latencies_ms;
  double sum_grab_ms = 0, sum_preprocess_ms = 0, sum_optimize_ms = 0, sum_publish_ms = 0;
  uint64_t interval_frames = 0;
  int64_t interval_start_ns = 0;
  int32_t logged_state = -1;
  uint64_t state_changes = 0;
  int64_t state_logged_ns = 0;
  ipc::PoseRecord record{};
  mutable std::mutex stats_mutex;
  ipc::RingStats last_stats{};

  // Grab stage state.
  uint64_t next_seq = 0;
  Throttle error_log, drop_log;
  std::string last_open_problem;
  int64_t next_open_ns = 0;

  // --record
  std::optional<RecordQueue> rec_q, rec_free;
  std::vector<std::unique_ptr<RecordBuffer>> rec_pool;
  std::optional<SequenceWriter> writer;

  // ---- helpers ---------------------------------------------------------------------------------
  bool stopping() const { return stop_flag.load(std::memory_order_acquire); }
  void busy(Stage s, uint64_t frame) {
    auto& a = activity[static_cast<size_t>(s)];
    a.frame.store(frame, std::memory_order_relaxed);
    a.busy_since_ns.store(monotonic_ns(), std::memory_order_relaxed);
  }
  void idle(Stage s) { activity[static_cast<size_t>(s)].busy_since_ns.store(0, std::memory_order_relaxed); }
  void set_device_state(ipc::DeviceState s) {
    device_state.store(static_cast<uint32_t>(s), std::memory_order_relaxed);
    ring.set_device_state(s);
  }
  void complete(uint64_t n = 1) { completed.fetch_add(n, std::memory_order_acq_rel); }
  void wake_all() {
    for (auto* b : {&grab_bell, &pre_bell, &opt_bell, &pub_bell, &rec_bell}) b->ring();
  }

  void setup_thread(const char* name, int cpu) {
    pthread_setname_np(pthread_self(), name);
    if (cpu >= 0) {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(cpu, &set);
      if (const int e = pthread_setaffinity_np(pthread_self(), sizeof set, &set); e != 0) {
        log().warn("{}: cannot pin to CPU {}: {}; running unpinned", name, cpu, std::strerror(e));
      }
    }
    if (config.pipeline.realtime_priority > 0) {
      sched_param p{};
      p.sched_priority = config.pipeline.realtime_priority;
      if (const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p); e != 0) {
        log().warn("{}: cannot use SCHED_FIFO priority {}: {}; normal scheduling", name,
                   config.pipeline.realtime_priority, std::strerror(e));
      }
    }
  }

  template <typename Body>
  void run_stage(const char* name, Body body) {
    try {
      body();
    } catch (const std::exception& e) {
      log().error("{} thread failed: {}", name, e.what());
      failed_flag = true;
      stop_flag = true;
      wake_all();
    }
  }

  Frame* acquire_free() {
    Frame* f = nullptr;
    for (auto* q : {&*free_from_pub, &*free_from_opt, &*free_from_pre}) {
      if (q->pop(f)) return f;
    }
    return nullptr;
  }

  // ---- grab ------------------------------------------------------------------------------------
  enum class GrabStep { kFrame, kNothing, kDone };

  // Opens a live source when needed and grabs one frame into `f`.
  GrabStep grab_step(Frame& f) {
    if (config.max_frames > 0 && next_seq >= static_cast<uint64_t>(config.max_frames)) return GrabStep::kDone;
    if (!source_open) {
      const int64_t now = monotonic_ns();
      if (now < next_open_ns) {
        grab_bell.wait(grab_bell.ticket(), std::min<int64_t>(next_open_ns - now, kIdleWaitNs));
        return GrabStep::kNothing;
      }
      busy(Stage::kGrab, next_seq);
      std::string why;
      const bool opened = source->open(&why);
      idle(Stage::kGrab);
      if (!opened) {
        next_open_ns = monotonic_ns() + kReopenIntervalNs;
        set_device_state(ipc::DeviceState::kWaitingForDevice);
        if (why != last_open_problem) log().info("waiting for {}: {}", source->describe(), why);
        last_open_problem = why;
        return GrabStep::kNothing;
      }
      last_open_problem.clear();
      source_open = true;
      const auto cam = source->camera();
      log().info("{} opened: {}x{} at {} fps", source->describe(), cam.width, cam.height, cam.fps);
      set_device_state(ipc::DeviceState::kStreaming);
    }
    busy(Stage::kGrab, next_seq);
    const GrabStatus status = source->grab(f.raw, kGrabTimeout);
    const int64_t now = monotonic_ns();
    idle(Stage::kGrab);
    switch (status) {
      case GrabStatus::kFrame:
        f.seq = next_seq++;
        f.capture_ns = f.raw.capture_ns != 0 ? f.raw.capture_ns : now;
        f.grab_end_ns = now;
        if (captured.fetch_add(1, std::memory_order_acq_rel) == 0) first_capture_ns.store(f.capture_ns);
        if (rec_q) record_frame(f);
        return GrabStep::kFrame;
      case GrabStatus::kTimeout:
        return GrabStep::kNothing;
      case GrabStatus::kEndOfStream:
        log().info("{}: end of stream after {} frames", source->describe(), next_seq);
        return GrabStep::kDone;
      case GrabStatus::kDisconnected:
        log().warn("{}: device lost{}{}; waiting for it to come back", source->describe(),
                   source->last_error().empty() ? "" : ": ", source->last_error());
        source->close();
        source_open = false;
        next_open_ns = now + kReopenIntervalNs / 2;
        set_device_state(ipc::DeviceState::kWaitingForDevice);
        return GrabStep::kNothing;
      case GrabStatus::kError: {
        const auto errors = source_errors.fetch_add(1, std::memory_order_relaxed) + 1;
        if (error_log.allow(now)) {
          log().warn("{}: bad frame skipped ({} so far): {}", source->describe(), errors, source->last_error());
        }
        return GrabStep::kNothing;
      }
    }
    return GrabStep::kNothing;
  }

  void record_frame(const Frame& f) {
    RecordBuffer* b = nullptr;
    if (!rec_free->pop(b)) {
      records_dropped.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    b->camera = f.raw.camera;
    b->frame = f.seq;
    b->image.width = f.raw.camera.width;
    b->image.height = f.raw.camera.height;
    b->image.channels = 1;
    b->image.pixels.assign(f.raw.depth_raw.begin(), f.raw.depth_raw.end());
    rec_q->push(b);
    rec_bell.ring();
  }

  void grab_loop() {
    setup_thread("ht-grab", config.pipeline.cpu[0]);
    Frame* f = nullptr;
    while (!stopping()) {
      if (f == nullptr) {
        const uint32_t ticket = grab_bell.ticket();
        f = acquire_free();
        if (f == nullptr) {
          grab_bell.wait(ticket, kIdleWaitNs);
          continue;
        }
      }
      const GrabStep step = grab_step(*f);
      if (step == GrabStep::kDone) break;
      if (step == GrabStep::kNothing) continue;
      // Hand the frame to preprocess. Lossless: wait for room. Otherwise a full queue means
      // preprocess itself is stuck (it always drains to the newest): drop this frame.
      for (;;) {
        const uint32_t ticket = grab_bell.ticket();
        if (raw_q->push(f)) {
          f = nullptr;
          pre_bell.ring();
          break;
        }
        if (!lossless) {
          count_drop(1);
          break;
        }
        if (stopping()) break;
        grab_bell.wait(ticket, kIdleWaitNs);
      }
    }
    grab_done.store(true, std::memory_order_release);
    wake_all();
  }

  void count_drop(uint64_t n) {
    dropped.fetch_add(n, std::memory_order_relaxed);
    complete(n);
  }

  // ---- preprocess ------------------------------------------------------------------------------
  void preprocess_step(Frame& f) {
    f.preprocess_start_ns = monotonic_ns();
    busy(Stage::kPreprocess, f.seq);
    if (const auto g = generation.load(std::memory_order_acquire); g != input_generation) {
      std::lock_guard lock(reload_mutex);
      input_config = reloaded.input;
      input_generation = g;
    }
    if (f.builder_generation != input_generation) {
      f.builder = DepthInputBuilder(input_config);
      f.builder_generation = input_generation;
    }
    f.input = nullptr;
    f.empty = false;
    f.malformed = false;
    f.resolution_changed = false;
    const CameraIntrinsics& cam = f.raw.camera;
    const auto n = static_cast<size_t>(std::max(cam.width, 0)) * static_cast<size_t>(std::max(cam.height, 0));
    if (n == 0 || f.raw.depth_raw.size() != n || !(cam.depth_scale_mm > 0.0)) {
      f.malformed = true;
    } else {
      if (cam.width != stream_width || cam.height != stream_height) {
        if (stream_width != 0) {
          resolution_changes.fetch_add(1, std::memory_order_relaxed);
          log().info("resolution changed from {}x{} to {}x{} at frame {}: frame buffers rebuilt, tracking restarts",
                     stream_width, stream_height, cam.width, cam.height, f.seq);
          f.resolution_changed = true;
        }
        stream_width = cam.width;
        stream_height = cam.height;
      }
      // Raw units to mm; count pixels inside the working volume (Sec. 4: 150..600 mm).
      f.depth.camera = cam;
      f.depth.depth_mm.resize(n);  // no reallocation once a resolution has been seen
      const auto scale = static_cast<float>(cam.depth_scale_mm);
      const auto near = static_cast<float>(input_config.near_mm);
      const auto far = static_cast<float>(input_config.far_mm);
      size_t in_volume = 0;
      for (size_t i = 0; i < n; ++i) {
        const float d = static_cast<float>(f.raw.depth_raw[i]) * scale;
        f.depth.depth_mm[i] = d;
        in_volume += (d >= near && d <= far) ? 1 : 0;
      }
      if (in_volume == 0) {
        f.empty = true;
      } else {
        std::optional<HandHint> h;
        {
          std::lock_guard lock(hint_mutex);
          h = hint;
        }
        f.input = &f.builder.build(f.depth, h, forest ? &*forest : nullptr);
      }
    }
    f.preprocess_end_ns = monotonic_ns();
    idle(Stage::kPreprocess);
  }

  void drop_to_grab(FrameQueue& free_q, Frame* f) {
    free_q.push(f);  // capacity = pool size: never full
    count_drop(1);
    grab_bell.ring();
  }

  void preprocess_loop() {
    setup_thread("ht-preprocess", config.pipeline.cpu[1]);
    Frame* pending = nullptr;  // preprocessed, waiting for room in input_q
    while (!stopping()) {
      const uint32_t ticket = pre_bell.ticket();
      bool worked = false;
      if (pending == nullptr || !lossless) {
        Frame* next = nullptr;
        Frame* f = nullptr;
        while (raw_q->pop(f)) {  // newest wins (lossless: one at a time)
          if (next != nullptr) drop_to_grab(*free_from_pre, next);
          next = f;
          if (lossless) break;
        }
        if (next != nullptr) {
          grab_bell.ring();  // room in raw_q
          if (pending != nullptr) drop_to_grab(*free_from_pre, pending);
          preprocess_step(*next);
          pending = next;
          worked = true;
        }
      }
      if (pending != nullptr && input_q->push(pending)) {
        pending = nullptr;
        opt_bell.ring();
        worked = true;
      }
      if (!worked) pre_bell.wait(ticket, kIdleWaitNs);
    }
  }

  // ---- optimize --------------------------------------------------------------------------------
  void optimize_step(Frame& f) {
    f.optimize_start_ns = monotonic_ns();
    busy(Stage::kOptimize, f.seq);
    if (const auto g = generation.load(std::memory_order_acquire); g != tracker_generation) {
      TrackerConfig c;
      {
        std::lock_guard lock(reload_mutex);
        c = reloaded;
      }
      tracker.emplace(c);  // SIGHUP only: allocates
      tracker_generation = g;
      log().info("tracker parameters reloaded ({} particles x {} iterations); tracking restarts", c.particles,
                 c.optimizer.iterations);
    }
    if (f.resolution_changed) tracker->reset();
    if (f.input != nullptr) {
      f.output = tracker->optimise(*f.input);
    } else {
      tracker->reset();
      f.output = TrackerOutput{};
    }
    f.scale = tracker->config().scale;
    // Hint for the next frames' segmentation (none after a loss: the next frame starts afresh).
    const std::optional<HandHint> h = tracker->hint();
    {
      std::lock_guard lock(hint_mutex);
      hint = h;
    }
    f.optimize_end_ns = monotonic_ns();
    ++optimized;
    if (stall_after != 0 && optimized >= stall_after) {
      // Test hook: the optimizer hangs (busy on this frame) until the daemon stops.
      log().warn("test hook: optimizer stalls after {} frames (HANDTRACKD_TEST_STALL_OPTIMIZER_AFTER)", optimized);
      while (!stopping()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    idle(Stage::kOptimize);
  }

  void optimize_loop() {
    setup_thread("ht-optimize", config.pipeline.cpu[2]);
    while (!stopping()) {
      const uint32_t ticket = opt_bell.ticket();
      Frame* next = nullptr;
      Frame* f = nullptr;
      while (input_q->pop(f)) {  // newest wins (lossless: in order)
        if (next != nullptr) drop_to_grab(*free_from_opt, next);
        next = f;
        if (lossless) break;
      }
      if (next == nullptr) {
        opt_bell.wait(ticket, kIdleWaitNs);
        continue;
      }
      pre_bell.ring();  // room in input_q
      optimize_step(*next);
      if (stopping()) break;
      result_q->push(next);  // capacity = pool size: never full
      pub_bell.ring();
    }
  }

  // ---- publish ---------------------------------------------------------------------------------
  void publish_step(Frame& f) {
    busy(Stage::kPublish, f.seq);
    if (f.malformed) {
      skipped.fetch_add(1, std::memory_order_relaxed);
      idle(Stage::kPublish);
      return;
    }
    if (f.empty) empty_frames.fetch_add(1, std::memory_order_relaxed);
    const TrackerOutput& o = f.output;
    ipc::PoseRecord& p = record;
    p = ipc::PoseRecord{};
    p.frame = f.seq;
    p.capture_ns = f.capture_ns;
    p.grab_ms = ms_between(f.capture_ns, f.grab_end_ns);
    p.preprocess_ms = ms_between(f.preprocess_start_ns, f.preprocess_end_ns);
    p.optimize_ms = ms_between(f.optimize_start_ns, f.optimize_end_ns);
    p.state = static_cast<int32_t>(o.state);
    p.confidence = static_cast<float>(o.confidence);
    p.energy = static_cast<float>(o.energy);
    for (int i = 0; i < kNumPoseParams; ++i) p.params[i] = o.params[i];
    for (int j = 0; j < kNumJoints; ++j) {
      for (int k = 0; k < 3; ++k) p.joints_mm[j][k] = static_cast<float>(o.joints[static_cast<size_t>(j)][k]);
    }
    for (int t = 0; t < kNumFingers; ++t) {
      for (int k = 0; k < 3; ++k) p.fingertips_mm[t][k] = static_cast<float>(o.fingertips[static_cast<size_t>(t)][k]);
    }
    for (int k = 0; k < 3; ++k) {
      p.palm_center_mm[k] = static_cast<float>(o.palm_centre[k]);
      p.palm_normal[k] = static_cast<float>(o.palm_normal[k]);
    }
    p.pinch_distance_mm = static_cast<float>(o.pinch_distance_mm);
    p.pinch_strength = static_cast<float>(o.pinch_strength);
    p.hand_scale[0] = static_cast<float>(f.scale.length);
    p.hand_scale[1] = static_cast<float>(f.scale.width);
    p.hand_scale[2] = static_cast<float>(f.scale.sigma);
    // publish_ms: from the end of optimization to the record going out (hand-over + filling).
    p.publish_ms = ms_between(f.optimize_end_ns, monotonic_ns());
    ring.publish(p);
    const int64_t end_ns = monotonic_ns();
    published.fetch_add(1, std::memory_order_relaxed);
    last_publish_ns.store(end_ns, std::memory_order_relaxed);
    tracking_state.store(p.state, std::memory_order_relaxed);

    sum_grab_ms += p.grab_ms;
    sum_preprocess_ms += p.preprocess_ms;
    sum_optimize_ms += p.optimize_ms;
    sum_publish_ms += ms_between(f.optimize_end_ns, end_ns);
    ++interval_frames;
    if (latencies_ms.size() < latencies_ms.capacity()) latencies_ms.push_back(ms_between(f.capture_ns, end_ns));

    // State changes at info, at most once a second.
    if (p.state != logged_state) {
      ++state_changes;
      if (end_ns - state_logged_ns >= kLogIntervalNs) {
        log().info("hand: {}{}", to_string(o.state),
                   state_changes > 1 ? fmt::format(" ({} state changes since the last message)", state_changes) : "");
        logged_state = p.state;
        state_changes = 0;
        state_logged_ns = end_ns;
      }
    }
    idle(Stage::kPublish);
  }

  static float percentile(std::vector<float>& v, double q) {
    if (v.empty()) return 0.0F;
    const auto k = static_cast<size_t>(std::min<double>(static_cast<double>(v.size() - 1), q * static_cast<double>(v.size())));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return v[k];
  }

  void maybe_stats(int64_t now) {
    if (interval_start_ns == 0) interval_start_ns = now;
    const int64_t elapsed = now - interval_start_ns;
    if (elapsed < static_cast<int64_t>(config.pipeline.stats_interval_ms) * 1'000'000) return;
    ipc::RingStats s{};
    const double n = static_cast<double>(std::max<uint64_t>(interval_frames, 1));
    s.fps = static_cast<float>(static_cast<double>(interval_frames) * 1e9 / static_cast<double>(elapsed));
    s.grab_ms = static_cast<float>(sum_grab_ms / n);
    s.preprocess_ms = static_cast<float>(sum_preprocess_ms / n);
    s.optimize_ms = static_cast<float>(sum_optimize_ms / n);
    s.publish_ms = static_cast<float>(sum_publish_ms / n);
    s.latency_p50_ms = percentile(latencies_ms, 0.5);
    s.latency_p99_ms = percentile(latencies_ms, 0.99);
    s.frames_captured = captured.load(std::memory_order_relaxed);
    s.frames_dropped = dropped.load(std::memory_order_relaxed);
    s.frames_skipped = skipped.load(std::memory_order_relaxed);
    s.source_errors = source_errors.load(std::memory_order_relaxed);
    ring.set_stats(s);
    {
      std::lock_guard lock(stats_mutex);
      last_stats = s;
    }
    log().debug(
        "{:.1f} fps; grab {:.1f} ms, preprocess {:.1f} ms, optimize {:.1f} ms, publish {:.2f} ms; latency p50 {:.1f} "
        "ms, p99 {:.1f} ms; {} captured, {} dropped, {} skipped, {} empty, {} source errors",
        s.fps, s.grab_ms, s.preprocess_ms, s.optimize_ms, s.publish_ms, s.latency_p50_ms, s.latency_p99_ms,
        s.frames_captured, s.frames_dropped, s.frames_skipped, empty_frames.load(std::memory_order_relaxed),
        s.source_errors);
    latencies_ms.clear();
    sum_grab_ms = sum_preprocess_ms = sum_optimize_ms = sum_publish_ms = 0;
    interval_frames = 0;
    interval_start_ns = now;
  }

  void publish_loop() {
    setup_thread("ht-publish", config.pipeline.cpu[3]);
    while (!stopping()) {
      const uint32_t ticket = pub_bell.ticket();
      Frame* f = nullptr;
      if (result_q->pop(f)) {
        publish_step(*f);
        free_from_pub->push(f);
        complete();
        grab_bell.ring();
      } else {
        pub_bell.wait(ticket, kIdleWaitNs);
      }
      maybe_stats(monotonic_ns());
    }
  }

  // ---- one thread ------------------------------------------------------------------------------
  void single_loop() {
    setup_thread("ht-single", config.pipeline.cpu[0]);
    Frame& f = *pool.front();
    while (!stopping()) {
      const GrabStep step = grab_step(f);
      if (step == GrabStep::kDone) break;
      if (step == GrabStep::kFrame) {
        preprocess_step(f);
        optimize_step(f);
        publish_step(f);
        complete();
      }
      maybe_stats(monotonic_ns());
    }
    grab_done.store(true, std::memory_order_release);
  }

  // ---- --record --------------------------------------------------------------------------------
  void record_loop() {
    pthread_setname_np(pthread_self(), "ht-record");
    bool size_warned = false;
    Throttle write_log;
    for (;;) {
      const uint32_t ticket = rec_bell.ticket();
      RecordBuffer* b = nullptr;
      if (!rec_q->pop(b)) {
        if (stopping() || grab_done.load(std::memory_order_acquire)) break;  // drained
        rec_bell.wait(ticket, kIdleWaitNs);
        continue;
      }
      try {
        if (!writer) {
          writer.emplace(config.record_dir, b->camera);
          record_camera = b->camera;
          log().info("recording raw depth to {} ({}x{})", config.record_dir, b->camera.width, b->camera.height);
        }
        if (b->camera.width != record_camera.width || b->camera.height != record_camera.height) {
          if (!size_warned) log().warn("--record: frames of a new resolution are not recorded (one camera.json per directory)");
          size_warned = true;
          records_dropped.fetch_add(1, std::memory_order_relaxed);
        } else {
          writer->write_depth_raw(static_cast<int>(b->frame), b->image);
          frames_recorded.fetch_add(1, std::memory_order_relaxed);
        }
      } catch (const std::exception& e) {
        records_dropped.fetch_add(1, std::memory_order_relaxed);
        if (write_log.allow(monotonic_ns())) log().error("--record: {}", e.what());
      }
      rec_free->push(b);
    }
    if (writer) {
      try {
        writer->flush();
      } catch (const std::exception& e) {
        log().error("--record: {}", e.what());
      }
    }
  }
  CameraIntrinsics record_camera;  // of the recording's camera.json
};

Pipeline::Pipeline(const DaemonConfig& config, std::unique_ptr<DepthSource> source, ipc::PoseRingWriter& ring)
    : impl_(std::make_unique<Impl>(config, std::move(source), ring)) {}

Pipeline::~Pipeline() {
  stop();
  join();
}

bool Pipeline::start(std::string* why) {
  Impl& m = *impl_;
  if (!m.source->is_live()) {
    if (!m.source->open(why)) return false;
    m.source_open = true;
    const auto cam = m.source->camera();
    log().info("{}: {}x{} at {} fps{}", m.source->describe(), cam.width, cam.height, cam.fps,
               m.config.fast ? ", as fast as possible" : "");
    m.set_device_state(ipc::DeviceState::kStreaming);
  } else {
    m.set_device_state(ipc::DeviceState::kWaitingForDevice);
  }
  if (!m.config.forest_model.empty()) {
    try {
      m.forest.emplace(PartForest::load(m.config.forest_model));
    } catch (const std::exception& e) {
      *why = e.what();
      return false;
    }
    m.config.tracker.mode = EnergyMode::kLateFusion;
    log().info("part forest {}: late fusion", m.config.forest_model);
  }
  m.input_config = m.config.tracker.input;
  m.reloaded = m.config.tracker;
  m.tracker.emplace(m.config.tracker);
  m.stall_after = env_u64("HANDTRACKD_TEST_STALL_OPTIMIZER_AFTER");

  // The pool: one frame per place a frame can be (grab 1, raw queue, preprocess 2, input queue,
  // optimize 1, publish 1) plus the result queue's worth, unless configured.
  const int q = m.config.pipeline.queue_capacity;
  const auto pool_size = static_cast<size_t>(m.config.single_thread ? 1
                                             : m.config.pipeline.pool_frames > 0 ? m.config.pipeline.pool_frames
                                                                                 : 2 * q + 6);
  m.pool.reserve(pool_size);
  for (size_t i = 0; i < pool_size; ++i) {
    auto f = std::make_unique<Frame>();
    f->builder = DepthInputBuilder(m.input_config);
    // Pre-size for the source's resolution so the first frames do not allocate either.
    const auto cam = m.source_open ? m.source->camera() : CameraIntrinsics{};
    const auto n = static_cast<size_t>(cam.width) * static_cast<size_t>(cam.height);
    f->raw.depth_raw.reserve(n);
    f->depth.depth_mm.reserve(n);
    m.pool.push_back(std::move(f));
  }
  m.latencies_ms.reserve(kLatencySamples);
  m.raw_q.emplace(static_cast<size_t>(q));
  m.input_q.emplace(static_cast<size_t>(q));
  m.result_q.emplace(pool_size);
  m.free_from_pre.emplace(pool_size);
  m.free_from_opt.emplace(pool_size);
  m.free_from_pub.emplace(pool_size);
  for (auto& f : m.pool) m.free_from_pub->push(f.get());

  if (!m.config.record_dir.empty()) {
    m.rec_q.emplace(kRecordBuffers);
    m.rec_free.emplace(kRecordBuffers);
    for (size_t i = 0; i < kRecordBuffers; ++i) {
      m.rec_pool.push_back(std::make_unique<RecordBuffer>());
      m.rec_free->push(m.rec_pool.back().get());
    }
    // The recording's camera.json is that of its first frame.
    m.threads.emplace_back([&m] { m.run_stage("record", [&m] { m.record_loop(); }); });
  }

  if (m.config.single_thread) {
    m.threads.emplace_back([&m] { m.run_stage("pipeline", [&m] { m.single_loop(); }); });
  } else {
    m.threads.emplace_back([&m] { m.run_stage("grab", [&m] { m.grab_loop(); }); });
    m.threads.emplace_back([&m] { m.run_stage("preprocess", [&m] { m.preprocess_loop(); }); });
    m.threads.emplace_back([&m] { m.run_stage("optimize", [&m] { m.optimize_loop(); }); });
    m.threads.emplace_back([&m] { m.run_stage("publish", [&m] { m.publish_loop(); }); });
  }
  return true;
}

void Pipeline::stop() {
  impl_->stop_flag.store(true, std::memory_order_release);
  impl_->wake_all();
}

void Pipeline::join() {
  for (auto& t : impl_->threads) {
    if (t.joinable()) t.join();
  }
  impl_->threads.clear();
  if (impl_->source_open) {
    impl_->source->close();
    impl_->source_open = false;
  }
}

bool Pipeline::finished() const {
  const Impl& m = *impl_;
  if (m.failed_flag.load()) return true;
  if (!m.grab_done.load(std::memory_order_acquire)) return false;
  return m.completed.load(std::memory_order_acquire) >= m.captured.load(std::memory_order_acquire);
}

bool Pipeline::failed() const { return impl_->failed_flag.load(); }

Health Pipeline::health() const {
  const int64_t now = monotonic_ns();
  const int64_t limit = static_cast<int64_t>(impl_->config.pipeline.stall_timeout_ms) * 1'000'000;
  for (const auto& a : impl_->activity) {
    const int64_t since = a.busy_since_ns.load(std::memory_order_relaxed);
    if (since != 0 && now - since > limit) return Health::kStalled;
  }
  return Health::kProgressing;
}

std::string Pipeline::stall_description() const {
  const int64_t now = monotonic_ns();
  std::string out;
  for (int s = 0; s < kNumStages; ++s) {
    const auto& a = impl_->activity[static_cast<size_t>(s)];
    const int64_t since = a.busy_since_ns.load(std::memory_order_relaxed);
    if (since == 0) continue;
    const double seconds = static_cast<double>(now - since) * 1e-9;
    if (seconds * 1000.0 < impl_->config.pipeline.stall_timeout_ms) continue;
    if (!out.empty()) out += ", ";
    out += fmt::format("{} busy on frame {} for {:.1f} s", to_string(static_cast<Stage>(s)),
                       a.frame.load(std::memory_order_relaxed), seconds);
  }
  return out;
}

PipelineCounters Pipeline::counters() const {
  const Impl& m = *impl_;
  PipelineCounters c;
  c.frames_captured = m.captured.load();
  c.frames_published = m.published.load();
  c.frames_dropped = m.dropped.load();
  c.frames_skipped = m.skipped.load();
  c.frames_empty = m.empty_frames.load();
  c.source_errors = m.source_errors.load();
  c.resolution_changes = m.resolution_changes.load();
  c.records_dropped = m.records_dropped.load();
  c.frames_recorded = m.frames_recorded.load();
  {
    std::lock_guard lock(m.stats_mutex);
    c.last_stats = m.last_stats;
  }
  c.first_capture_ns = m.first_capture_ns.load();
  c.last_publish_ns = m.last_publish_ns.load();
  c.tracking_state = m.tracking_state.load();
  c.device_state = static_cast<ipc::DeviceState>(m.device_state.load());
  return c;
}

void Pipeline::reload(const TrackerConfig& tracker) {
  {
    std::lock_guard lock(impl_->reload_mutex);
    impl_->reloaded = tracker;
    // The forest is loaded once at start; a reload keeps the energy mode it chose.
    impl_->reloaded.mode = impl_->config.tracker.mode;
  }
  impl_->generation.fetch_add(1, std::memory_order_acq_rel);
}

const DepthSource& Pipeline::source() const { return *impl_->source; }

}  // namespace handtrack::daemon
