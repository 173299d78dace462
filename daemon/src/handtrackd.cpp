// handtrackd's program: grab depth, track the hand, publish poses into shared memory
// (docs/DAEMON.md). main() is daemon/src/main.cpp; tests build it with more sources.
//
// The main thread is the control thread: it owns the ring and the pipeline, waits for signals
// (SIGTERM/SIGINT stop, SIGHUP reloads), feeds the watchdog only while the pipeline makes
// progress, and keeps the ring's heartbeat and systemd's STATUS= fresh.
#include "handtrackd.hpp"

#include "handtrack/daemon/config.hpp"
#include "handtrack/daemon/pipeline.hpp"
#include "handtrack/ipc/pose_ring_writer.hpp"
#include "logging.hpp"
#include "notify.hpp"

#include "handtrack/common/cli.hpp"
#include <fmt/format.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <thread>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace handtrack;
using namespace handtrack::daemon;

namespace {

int exit_with_error(const std::string& message) { return report_error("handtrackd", message, 1); }

const char* device_state_name(ipc::DeviceState state) {
  switch (state) {
    case ipc::DeviceState::kStopped: return "stopped";
    case ipc::DeviceState::kStarting: return "starting";
    case ipc::DeviceState::kWaitingForDevice: return "waiting_for_device";
    case ipc::DeviceState::kStreaming: return "streaming";
    case ipc::DeviceState::kError: return "error";
  }
  return "unknown";
}

std::string status_line(const Pipeline& pipeline, const DaemonConfig& config) {
  const auto c = pipeline.counters();
  const char* device = device_state_name(c.device_state);
  if (c.device_state == ipc::DeviceState::kWaitingForDevice) {
    return fmt::format("{}: {}", device, pipeline.source().describe());
  }
  return fmt::format("{}, {}, {:.1f} fps, latency p50 {:.1f} ms p99 {:.1f} ms, {} frames, {} dropped, {} empty, "
                     "{} source errors",
                     device, to_string(static_cast<TrackingState>(c.tracking_state)), c.last_stats.fps, c.last_stats.latency_p50_ms,
                     c.last_stats.latency_p99_ms, c.frames_captured, c.frames_dropped, c.frames_empty,
                     c.source_errors) +
         (config.record_dir.empty() ? "" : fmt::format(", {} recorded", c.frames_recorded));
}

// The record directory must be creatable and writable before the daemon claims to be ready.
std::string record_dir_problem(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return dir + ": cannot create the record directory: " + ec.message();
  const fs::path probe = fs::path(dir) / ".handtrackd-write-test";
  {
    std::ofstream out(probe);
    if (!out) return dir + ": the record directory is not writable";
  }
  fs::remove(probe, ec);
  return {};
}

// Pipeline::start() loads the part forest (13 MB: about half a second, more on a busy machine)
// before the source starts, while the ring already exists: a client that opens it meanwhile would
// call a writer silent for 2.5 heartbeat periods dead (docs/IPC.md). So a helper thread keeps the
// heartbeat going until start() returns; the main loop takes over from there.
bool start_beating(Pipeline& pipeline, ipc::PoseRingWriter& ring, std::string* why) {
  std::atomic<bool> started{false};
  std::thread beat([&] {
    // SYNC: relaxed: the flag only ends the loop, it guards no data (join() orders the rest).
    while (!started.load(std::memory_order_relaxed)) {
      ring.heartbeat();  // any thread may beat (PoseRingWriter's thread roles)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));  // twice per 100 ms period
    }
  });
  const bool ok = pipeline.start(why);
  started.store(true, std::memory_order_relaxed);
  beat.join();
  return ok;
}

}  // namespace

int handtrack::daemon::run_handtrackd(int argc, char** argv, const SourceFactory& source_factory) {
  CLI::App app{"handtrackd: tracks a hand in depth frames and publishes poses into shared memory "
               "(Sridhar et al., CVPR 2015). See docs/DAEMON.md."};
  std::string config_file = kDefaultConfigFile;
  std::string source, shm_name, record_dir, log_level;
  int particles = 0, iterations = 0;
  int64_t frames = 0;
  bool print_config = false, fast = false, loop = false, single_thread = false;
  auto* config_opt = app.add_option("--config", config_file, "TOML configuration file")->capture_default_str();
  auto* source_opt = app.add_option("--source", source,
                                    "openni2 | openni2:URI | oni:FILE.oni | seq:DIR | synthetic[:MOTION] "
                                    "(default: daemon.source of the config, openni2)");
  auto* shm_opt = app.add_option("--shm-name", shm_name, "shared-memory object name (default: handtrack)");
  auto* fast_opt = app.add_flag("--fast", fast, "recordings and synthetic: as fast as possible, every frame tracked");
  auto* loop_opt = app.add_flag("--loop", loop, "recordings: play again at the end (default: exit at the end)");
  auto* record_opt = app.add_option("--record", record_dir, "write the raw depth to DIR as a sequence directory");
  auto* particles_opt = app.add_option("--particles", particles, "pose particles per frame (tracker.particles)");
  auto* iterations_opt =
      app.add_option("--iterations", iterations, "optimizer iterations (tracker.optimizer.iterations)");
  auto* frames_opt = app.add_option("--frames", frames, "stop after N frames (0: never)")->check(CLI::NonNegativeNumber);
  auto* level_opt = app.add_option("--log-level", log_level, "trace | debug | info | warn | error | off");
  auto* single_opt = app.add_flag("--single-thread", single_thread, "run every stage on one thread (baseline for the overlap)");
  app.add_flag("--print-config", print_config, "print the effective configuration as TOML and exit");
  if (const auto exit_code = parse_command_line(app, argc, argv, "handtrackd", 1)) return *exit_code;

  // Command-line values over the file's; also applied again on every SIGHUP reload.
  const std::function<void(DaemonConfig&)> apply_cli = [&](DaemonConfig& c) {
    if (source_opt->count() > 0) c.source = source;
    if (shm_opt->count() > 0) c.shm_name = shm_name;
    if (fast_opt->count() > 0) c.fast = true;
    if (loop_opt->count() > 0) c.loop = true;
    if (record_opt->count() > 0) c.record_dir = record_dir;
    if (particles_opt->count() > 0) c.tracker.particles = particles;
    if (iterations_opt->count() > 0) c.tracker.optimizer.iterations = iterations;
    if (frames_opt->count() > 0) c.max_frames = frames;
    if (single_opt->count() > 0) c.single_thread = true;
    c.source_options.loop = c.loop;
    c.source_options.as_fast_as_possible = c.fast;
  };
  const bool explicit_config = config_opt->count() > 0;
  const auto load = [&]() {
    DaemonConfig c = load_config(config_file, explicit_config);
    apply_cli(c);
    if (level_opt->count() > 0 && !parse_log_level(log_level, &c.log_level)) {
      throw ConfigError("--log-level " + log_level + ": allowed: trace, debug, info, warn, error, off");
    }
    validate(c, "command line");
    return c;
  };
  DaemonConfig config;
  try {
    config = load();
  } catch (const ConfigError& e) {
    return exit_with_error(e.what());
  }
  if (print_config) {
    std::fputs(describe_config(config).c_str(), stdout);
    return 0;
  }

  setup_logging(config.log_level);
  std::unique_ptr<DepthSource> source_ptr;
  try {
    source_ptr = source_factory(config.source, config.source_options);
  } catch (const std::exception& e) {
    return exit_with_error(e.what());
  }
  if (!config.record_dir.empty()) {
    if (const auto problem = record_dir_problem(config.record_dir); !problem.empty()) return exit_with_error(problem);
  }

  // Signals go to this thread only (sigtimedwait below): block them before any thread starts.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGHUP);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  std::signal(SIGPIPE, SIG_IGN);

  SystemdNotifier notifier;
  if (notifier.watchdog_interval().count() > 0) {
    // A stall must be noticed before systemd's watchdog fires: within half its interval.
    const auto half_ms = static_cast<int>(notifier.watchdog_interval().count() / 2000);
    config.pipeline.stall_timeout_ms = std::max(100, std::min(config.pipeline.stall_timeout_ms, half_ms));
  }

  std::optional<ipc::PoseRingWriter> ring;
  try {
    ring.emplace(ipc::PoseRingWriter::Options{.name = config.shm_name,
                                              .capacity = static_cast<uint32_t>(config.ring_capacity)});
  } catch (const std::exception& e) {
    return exit_with_error(e.what());
  }
  if (!ring->removed_foreign_owner().empty()) {
    log().warn("removed /{} of {}: an object of another user under our name is never written to or trusted",
               config.shm_name, ring->removed_foreign_owner());
  }
  if (ring->replaced_epoch()) log().info("replaced a stale ring /{} (epoch {})", config.shm_name, *ring->replaced_epoch());
  ring->set_device_state(ipc::DeviceState::kStarting);

  Pipeline pipeline(config, std::move(source_ptr), *ring);
  std::string why;
  if (!start_beating(pipeline, *ring, &why)) {
    ring.reset();
    ipc::PoseRingWriter::remove(config.shm_name);
    return exit_with_error(why);
  }
  log().info("handtrackd {} on {}: publishing to /{} (epoch {}), {} particles x {} iterations{}",
             HANDTRACK_VERSION, pipeline.source().describe(), config.shm_name, ring->epoch(), config.tracker.particles,
             config.tracker.optimizer.iterations, config.single_thread ? ", single thread" : "");
  notifier.ready(status_line(pipeline, config));

  using Clock = std::chrono::steady_clock;
  const auto started = Clock::now();
  const auto watchdog_every = notifier.watchdog_interval() / 2;
  auto last_ping = Clock::now();
  auto last_status = Clock::now();
  bool stalled = false;
  int exit_code = 0;
  const timespec tick{0, 50'000'000};  // heartbeat_period is 100 ms: beat twice per period
  for (;;) {
    siginfo_t info{};
    const int sig = sigtimedwait(&signals, &info, &tick);
    if (sig == SIGTERM || sig == SIGINT) {
      log().info("{}: stopping", sig == SIGTERM ? "SIGTERM" : "SIGINT");
      break;
    }
    if (sig == SIGHUP) {
      try {
        DaemonConfig fresh = load();
        const auto fixed = changed_but_not_live(config, fresh);
        if (!fixed.empty()) {
          std::string list;
          for (const auto& f : fixed) list += (list.empty() ? "" : ", ") + f;
          log().warn("SIGHUP: {} changed but only take effect after a restart", list);
        }
        set_log_level(fresh.log_level);
        config.log_level = fresh.log_level;
        config.tracker = fresh.tracker;
        pipeline.reload(fresh.tracker);
        log().info("SIGHUP: configuration reloaded from {}", explicit_config || fs::exists(config_file)
                                                                  ? config_file
                                                                  : std::string("the built-in defaults"));
      } catch (const ConfigError& e) {
        log().error("SIGHUP: reload refused, keeping the running configuration: {}", e.what());
      }
    }
    const auto now = Clock::now();
    if (pipeline.health() == Health::kProgressing) {
      if (stalled) log().info("pipeline progressing again; watchdog pings resume");
      stalled = false;
      ring->heartbeat();
      if (watchdog_every.count() > 0 && now - last_ping >= watchdog_every) {
        notifier.watchdog();
        last_ping = now;
      }
    } else if (!stalled) {
      stalled = true;
      log().error("pipeline stalled ({}): heartbeat and watchdog pings stop", pipeline.stall_description());
      notifier.status("stalled: " + pipeline.stall_description());
    }
    if (!stalled && now - last_status >= std::chrono::milliseconds(config.pipeline.stats_interval_ms)) {
      notifier.status(status_line(pipeline, config));
      last_status = now;
    }
    if (pipeline.finished()) {
      if (pipeline.failed()) exit_code = 1;
      break;
    }
  }

  notifier.stopping();
  pipeline.stop();
  pipeline.join();
  ring->mark_stopped();
  const auto c = pipeline.counters();
  const double span_s = c.last_publish_ns > c.first_capture_ns
                            ? static_cast<double>(c.last_publish_ns - c.first_capture_ns) * 1e-9
                            : std::chrono::duration<double>(Clock::now() - started).count();
  log().info(
      "stopped: {} frames captured, {} published in {:.2f} s ({:.1f} fps), {} dropped, {} skipped, {} empty, {} "
      "source errors, {} resolution changes{}",
      c.frames_captured, c.frames_published, span_s,
      span_s > 0 ? static_cast<double>(c.frames_published > 0 ? c.frames_published - 1 : 0) / span_s : 0.0,
      c.frames_dropped, c.frames_skipped, c.frames_empty, c.source_errors, c.resolution_changes,
      config.record_dir.empty()
          ? std::string()
          : fmt::format(", {} recorded to {} ({} not recorded)", c.frames_recorded, config.record_dir,
                        c.records_dropped));
  return exit_code;
}
