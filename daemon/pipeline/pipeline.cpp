// The pipeline of pipeline.hpp: wires the stages (grab_stage, preprocess_stage, optimize_stage,
// publish_stage, recorder) with the frame pool, the queues between them and one thread each.
// The stages do the work; this file decides only which frame goes where, and when a thread sleeps.
// docs/ARCHITECTURE.md has the picture; docs/THREADING.md the words used for thread roles.
#include "handtrack/daemon/pipeline.hpp"

#include "doorbell.hpp"
#include "frame.hpp"
#include "grab_stage.hpp"
#include "interval_stats.hpp"
#include "optimize_stage.hpp"
#include "pipeline_tally.hpp"
#include "preprocess_stage.hpp"
#include "publish_stage.hpp"
#include "recorder.hpp"
#include "stage_links.hpp"
#include "stage_watch.hpp"
#include "thread_setup.hpp"

#include "handtrack/common/clock.hpp"
#include "logging.hpp"

#include <fmt/format.h>
#include <pthread.h>

#include <atomic>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

namespace handtrack::daemon {

struct Pipeline::Impl {
  Impl(const DaemonConfig& c, std::unique_ptr<DepthSource> s, ipc::PoseRingWriter& r)
      : config(c), source(std::move(s)), ring(r), lossless(c.fast && !source->is_live()),
        stats(c.pipeline.stats_interval_ms, tally, r) {}

  DaemonConfig config;
  std::unique_ptr<DepthSource> source;
  ipc::PoseRingWriter& ring;
  const bool lossless;  // recordings with --fast: back-pressure, never drop

  PipelineTally tally;
  StageWatch watch;
  std::optional<TrackerReload> reload;  // made at start(), with the energy mode the forest decides
  RequestMailbox request;
  IntervalStats stats;
  std::optional<PartForest> forest;  // labels the hand's pixels for the detection-guided particle
  std::unique_ptr<Recorder> recorder;
  std::optional<GrabStage> grab;
  std::optional<PreprocessStage> preprocess;
  std::optional<OptimizeStage> optimize;
  std::optional<PublishStage> publish;

  // Frames circulate: grab -> raw_q -> preprocess -> input_q -> optimize -> result_q -> publish,
  // and back to grab through one free queue per stage that returns frames (SPSC: one producer).
  std::vector<std::unique_ptr<Frame>> pool;
  std::optional<FrameQueue> raw_q, input_q, result_q, free_from_pre, free_from_opt, free_from_pub;
  Doorbell grab_bell, pre_bell, opt_bell, pub_bell;
  std::vector<std::thread> threads;

  // SYNC: stop_flag and grab_done are release-stored and acquire-loaded: a thread that sees
  // either also sees what the storing thread did before (its last frame counted, for grab_done).
  std::atomic<bool> stop_flag{false};
  std::atomic<bool> grab_done{false};
  // SYNC: relaxed; it only selects finished()'s answer and the exit code, read after stop_flag.
  std::atomic<bool> failed_flag{false};

  // SYNC: acquire, pairs with the release stores in stop() and run_stage().
  bool stopping() const { return stop_flag.load(std::memory_order_acquire); }
  void wake_all() {
    for (auto* b : {&grab_bell, &pre_bell, &opt_bell, &pub_bell}) b->ring();
    if (recorder) recorder->wake();
  }

  // Runs a stage's loop; an exception fails the pipeline (finished(), failed()) instead of the
  // process.
  template <typename Body>
  void run_stage(const char* name, Body body) {
    try {
      body();
    } catch (const std::exception& e) {
      log().error("{} thread failed: {}", name, e.what());
      failed_flag.store(true, std::memory_order_relaxed);
      stop_flag.store(true, std::memory_order_release);  // SYNC: release, pairs with stopping()
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

  // A frame that will not be published goes back to grab.
  void drop_to_grab(FrameQueue& free_q, Frame* f) {
    free_q.push(f);  // capacity = pool size: never full
    tally.count_drop(1);
    grab_bell.ring();
  }

  // Takes the frame to work on next from `q`: in order when lossless, otherwise the newest (the
  // older ones are dropped into `free_q`). Null when `q` is empty.
  Frame* take_newest(FrameQueue& q, FrameQueue& free_q) {
    Frame* next = nullptr;
    Frame* f = nullptr;
    while (q.pop(f)) {
      if (next != nullptr) drop_to_grab(free_q, next);
      next = f;
      if (lossless) break;
    }
    return next;
  }

  void grab_loop() {
    setup_pipeline_thread("ht-grab", config.pipeline.cpu[0], config.pipeline);
    Frame* f = nullptr;
    while (!stopping()) {
      if (f == nullptr) {
        const uint32_t ticket = grab_bell.ticket();
        f = acquire_free();
        if (f == nullptr) {
          grab_bell.wait(ticket, Doorbell::kIdleWaitNs);
          continue;
        }
      }
      const GrabStage::Step step = grab->step(*f);
      if (step == GrabStage::Step::kDone) break;
      if (step == GrabStage::Step::kNothing) continue;
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
          tally.count_drop(1);
          break;
        }
        if (stopping()) break;
        grab_bell.wait(ticket, Doorbell::kIdleWaitNs);
      }
    }
    // SYNC: release, pairs with the acquire loads in finished() and the recorder's done(): every
    // capture this thread counted happened before.
    grab_done.store(true, std::memory_order_release);
    wake_all();
  }

  void preprocess_loop() {
    setup_pipeline_thread("ht-preprocess", config.pipeline.cpu[1], config.pipeline, StageRank::kPreprocess);
    Frame* pending = nullptr;  // preprocessed, waiting for room in input_q
    while (!stopping()) {
      const uint32_t ticket = pre_bell.ticket();
      bool worked = false;
      if (pending == nullptr || !lossless) {
        if (Frame* next = take_newest(*raw_q, *free_from_pre); next != nullptr) {
          grab_bell.ring();  // room in raw_q
          if (pending != nullptr) drop_to_grab(*free_from_pre, pending);
          preprocess->step(*next);
          pending = next;
          worked = true;
        }
      }
      if (pending != nullptr && input_q->push(pending)) {
        pending = nullptr;
        opt_bell.ring();
        worked = true;
      }
      if (!worked) pre_bell.wait(ticket, Doorbell::kIdleWaitNs);
    }
  }

  void optimize_loop() {
    setup_pipeline_thread("ht-optimize", config.pipeline.cpu[2], config.pipeline);
    while (!stopping()) {
      const uint32_t ticket = opt_bell.ticket();
      Frame* next = take_newest(*input_q, *free_from_opt);
      if (next == nullptr) {
        opt_bell.wait(ticket, Doorbell::kIdleWaitNs);
        continue;
      }
      pre_bell.ring();  // room in input_q
      optimize->step(*next);
      if (stopping()) break;
      result_q->push(next);  // capacity = pool size: never full
      pub_bell.ring();
    }
  }

  void publish_loop() {
    setup_pipeline_thread("ht-publish", config.pipeline.cpu[3], config.pipeline);
    while (!stopping()) {
      const uint32_t ticket = pub_bell.ticket();
      Frame* f = nullptr;
      if (result_q->pop(f)) {
        publish->step(*f);
        free_from_pub->push(f);
        tally.complete();
        grab_bell.ring();
      } else {
        pub_bell.wait(ticket, Doorbell::kIdleWaitNs);
      }
      stats.maybe_publish(monotonic_ns());
    }
  }

  // --single-thread: every stage in turn on one frame (the baseline the overlap is measured by).
  void single_loop() {
    setup_pipeline_thread("ht-single", config.pipeline.cpu[0], config.pipeline);
    Frame& f = *pool.front();
    while (!stopping()) {
      const GrabStage::Step step = grab->step(f);
      if (step == GrabStage::Step::kDone) break;
      if (step == GrabStage::Step::kFrame) {
        preprocess->step(f);
        optimize->step(f);
        publish->step(f);
        tally.complete();
      }
      stats.maybe_publish(monotonic_ns());
    }
    // SYNC: release, pairs with the acquire loads in finished() and the recorder's done(): every
    // capture this thread counted happened before.
    grab_done.store(true, std::memory_order_release);
  }

  // The pool: one frame per place a frame can be (grab 1, raw queue, preprocess 2, input queue,
  // optimize 1, publish 1) plus the result queue's worth, unless configured. Buffers are
  // pre-sized for the source's resolution so that the first frames do not allocate either.
  void allocate_pool() {
    const int q = config.pipeline.queue_capacity;
    const auto pool_size = static_cast<size_t>(config.single_thread          ? 1
                                               : config.pipeline.pool_frames > 0 ? config.pipeline.pool_frames
                                                                                 : 2 * q + 6);
    const auto cam = source->is_live() ? CameraIntrinsics{} : source->camera();
    const auto n = static_cast<size_t>(cam.width) * static_cast<size_t>(cam.height);
    pool.reserve(pool_size);
    for (size_t i = 0; i < pool_size; ++i) {
      auto f = std::make_unique<Frame>();
      f->inputs = preprocess->make_inputs();
      f->raw.depth_raw.reserve(n);
      f->depth.depth_mm.reserve(n);
      pool.push_back(std::move(f));
    }
    raw_q.emplace(static_cast<size_t>(q));
    input_q.emplace(static_cast<size_t>(q));
    result_q.emplace(pool_size);
    free_from_pre.emplace(pool_size);
    free_from_opt.emplace(pool_size);
    free_from_pub.emplace(pool_size);
    for (auto& f : pool) free_from_pub->push(f.get());
  }
};

Pipeline::Pipeline(const DaemonConfig& config, std::unique_ptr<DepthSource> source, ipc::PoseRingWriter& ring)
    : impl_(std::make_unique<Impl>(config, std::move(source), ring)) {}

Pipeline::~Pipeline() {
  stop();
  join();
}

bool Pipeline::start(std::string* why) {
  Impl& m = *impl_;
  if (!m.config.record_dir.empty()) m.recorder = std::make_unique<Recorder>(m.config.record_dir, m.tally);
  std::optional<std::filesystem::path> forest_path;
  if (m.config.tracker.mode == EnergyMode::kLateFusion) {
    // A forest named in the configuration must load; without one, the shipped forest, and where
    // even that is missing (a partial install), depth-only with a warning rather than no tracking.
    forest_path = m.config.forest_model.empty() ? shipped_forest_path()
                                                : std::optional<std::filesystem::path>(m.config.forest_model);
    if (forest_path) {
      try {
        m.forest.emplace(PartForest::load(*forest_path));
      } catch (const std::exception& e) {
        *why = e.what();
        return false;
      }
    } else {
      m.config.tracker.mode = EnergyMode::kDepthOnly;
      log().warn("no part forest found (tracker.forest_model is empty, $HANDTRACK_FOREST unset, none shipped): "
                 "depth-only");
    }
  }
  const std::optional<CameraRoll> roll = camera_roll_from_degrees(m.config.camera_roll_deg);
  if (!roll) {
    *why = fmt::format("camera.roll = {}: allowed: {}", m.config.camera_roll_deg, kCameraRollValues);
    return false;
  }
  // The source starts after the forest is loaded: a recording plays in real time from its start.
  m.grab.emplace(m.config, *m.source, m.ring, m.tally, m.watch, m.grab_bell, m.recorder.get());
  if (!m.grab->start(why)) return false;
  if (m.forest) log().info("part forest {}: late fusion", forest_path->string());
  m.reload.emplace(m.config.tracker);
  const PartForest* forest = m.forest ? &*m.forest : nullptr;
  // Each stage's side thread (the second hand) shares the other stage's CPU.
  m.preprocess.emplace(m.config.tracker, *roll, *m.reload, m.request, forest, m.tally, m.watch, !m.config.single_thread,
                       [&m] {
                         setup_pipeline_thread("ht-preprocess-2", m.config.pipeline.cpu[2], m.config.pipeline,
                                               StageRank::kPreprocess);
                       });
  m.optimize.emplace(m.config.tracker, *roll, *m.reload, m.request, m.watch, !m.config.single_thread,
                     [&m] { setup_pipeline_thread("ht-optimize-2", m.config.pipeline.cpu[1], m.config.pipeline); });
  m.publish.emplace(m.ring, m.tally, m.watch, m.stats);
  m.allocate_pool();

  if (m.recorder) {
    m.threads.emplace_back([&m] {
      pthread_setname_np(pthread_self(), "ht-record");
      m.run_stage("record", [&m] {
        // SYNC: acquire, pairs with the grab thread's release store: the last offer() is queued.
        m.recorder->run([&m] { return m.stopping() || m.grab_done.load(std::memory_order_acquire); });
      });
    });
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
  impl_->stop_flag.store(true, std::memory_order_release);  // SYNC: release, pairs with stopping()
  impl_->wake_all();
}

void Pipeline::join() {
  for (auto& t : impl_->threads) {
    if (t.joinable()) t.join();
  }
  impl_->threads.clear();
  if (impl_->grab) impl_->grab->close();
}

bool Pipeline::finished() const {
  const Impl& m = *impl_;
  if (m.failed_flag.load(std::memory_order_relaxed)) return true;
  // SYNC: acquire loads, pairing with grab_done's release store and the acq_rel increments of
  // `captured` and `completed` (pipeline_tally.hpp): `captured` read here is final.
  if (!m.grab_done.load(std::memory_order_acquire)) return false;
  return m.tally.completed.load(std::memory_order_acquire) >= m.tally.captured.load(std::memory_order_acquire);
}

bool Pipeline::failed() const { return impl_->failed_flag.load(std::memory_order_relaxed); }

Health Pipeline::health() const {
  const int64_t limit_ns = static_cast<int64_t>(impl_->config.pipeline.stall_timeout_ms) * 1'000'000;
  return impl_->watch.stalled(monotonic_ns(), limit_ns) ? Health::kStalled : Health::kProgressing;
}

std::string Pipeline::stall_description() const {
  const int64_t limit_ns = static_cast<int64_t>(impl_->config.pipeline.stall_timeout_ms) * 1'000'000;
  return impl_->watch.describe_stalls(monotonic_ns(), limit_ns);
}

PipelineCounters Pipeline::counters() const {
  PipelineCounters c = impl_->tally.snapshot();
  c.last_stats = impl_->stats.last();
  return c;
}

void Pipeline::reload(const TrackerConfig& tracker) {
  TrackerConfig c = tracker;
  // The forest is loaded once at start; a reload keeps the energy mode it chose.
  c.mode = impl_->config.tracker.mode;
  if (impl_->reload) impl_->reload->post(c);
}

const DepthSource& Pipeline::source() const { return *impl_->source; }

}  // namespace handtrack::daemon
