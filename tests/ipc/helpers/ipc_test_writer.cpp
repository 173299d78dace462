// ipc_test_writer: a writer process for the multi-process tests.
//
//   ipc_test_writer --name N [--capacity C] [--period-ms P] [--rate-hz R (0: full speed)]
//                   [--count K] [--die-mid-publish-at I] [--stop-mid-publish-at I]
//                   [--timestamps FILE] [--no-stop] [--realtime]
//
// Publishes make_test_record(frame) records, heartbeats every period, prints "ready EPOCH" on
// stdout once the segment exists, and on SIGTERM (or after K records) marks the segment stopped
// (unless --no-stop) and writes every publish completion time (CLOCK_MONOTONIC ns, one a line) to
// FILE. --die-mid-publish-at I: SIGKILL itself between the two sequence stores of record I;
// --stop-mid-publish-at I: SIGSTOP itself there (the test then SIGKILLs it).
#include <handtrack/ipc/pose_ring_writer.hpp>

#include "../test_pattern.hpp"

#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include <sched.h>
#include <unistd.h>

namespace {

volatile std::sig_atomic_t g_stop = 0;
std::uint64_t g_die_at = UINT64_MAX;
std::uint64_t g_pause_at = UINT64_MAX;

void on_term(int) { g_stop = 1; }

void mid_publish_hook(std::uint64_t index) {
  if (index == g_die_at) ::kill(::getpid(), SIGKILL);
  if (index == g_pause_at) ::kill(::getpid(), SIGSTOP);
}

std::int64_t now_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

void sleep_until(std::int64_t t_ns) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t_ns / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(t_ns % 1'000'000'000);
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR && !g_stop) {
  }
}

}  // namespace

int main(int argc, char** argv) {
  using handtrack::ipc::PoseRingWriter;
  PoseRingWriter::Options options;
  double rate_hz = 0;
  std::uint64_t count = 0;
  std::string timestamps_path;
  bool stop_at_end = true;
  bool realtime = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "ipc_test_writer: %s needs a value\n", arg.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (arg == "--name") options.name = value();
    else if (arg == "--capacity") options.capacity = static_cast<std::uint32_t>(std::stoul(value()));
    else if (arg == "--period-ms") options.heartbeat_period = std::chrono::milliseconds(std::stol(value()));
    else if (arg == "--rate-hz") rate_hz = std::stod(value());
    else if (arg == "--count") count = std::stoull(value());
    else if (arg == "--die-mid-publish-at") g_die_at = std::stoull(value());
    else if (arg == "--stop-mid-publish-at") g_pause_at = std::stoull(value());
    else if (arg == "--timestamps") timestamps_path = value();
    else if (arg == "--no-stop") stop_at_end = false;
    else if (arg == "--realtime") realtime = true;
    else {
      std::fprintf(stderr, "ipc_test_writer: unknown argument %s\n", arg.c_str());
      return 2;
    }
  }
  if (g_die_at != UINT64_MAX || g_pause_at != UINT64_MAX) {
    options.test_hook_mid_publish = mid_publish_hook;
  }
  std::signal(SIGTERM, on_term);
  std::signal(SIGINT, on_term);
  if (realtime) {
    // Timing tests: keep other jobs on the machine out of the measured publish intervals, so
    // only what the readers could do to the writer remains. Best effort (needs CAP_SYS_NICE).
    sched_param param{};
    param.sched_priority = 10;
    if (::sched_setscheduler(0, SCHED_FIFO, &param) != 0) std::fprintf(stderr, "no SCHED_FIFO\n");
  }

  try {
    PoseRingWriter writer(options);
    writer.set_device_state(handtrack::ipc::DeviceState::kStreaming);
    std::printf("ready %llu\n", static_cast<unsigned long long>(writer.epoch()));
    std::fflush(stdout);

    std::vector<std::int64_t> stamps;
    if (!timestamps_path.empty()) stamps.reserve(1 << 20);
    const std::int64_t period_ns = writer.heartbeat_period().count();
    const std::int64_t interval_ns = rate_hz > 0 ? static_cast<std::int64_t>(1e9 / rate_hz) : 0;
    std::int64_t next_publish = now_ns();
    std::int64_t next_heartbeat = next_publish + period_ns;
    std::uint64_t frame = 0;
    while (!g_stop && (count == 0 || frame < count)) {
      if (interval_ns > 0) {
        const std::int64_t wake = std::min(next_publish, next_heartbeat);
        sleep_until(wake);
        const std::int64_t t = now_ns();
        if (t >= next_heartbeat) {
          writer.heartbeat();
          next_heartbeat = t + period_ns;
        }
        if (t < next_publish) continue;
        next_publish += interval_ns;
        if (next_publish < t) next_publish = t + interval_ns;  // do not burst after a stall
      }
      writer.publish(handtrack::ipc::test::make_test_record(frame++));
      if (!timestamps_path.empty() && stamps.size() < stamps.capacity()) stamps.push_back(now_ns());
    }
    if (stop_at_end) writer.mark_stopped();
    if (!timestamps_path.empty()) {
      FILE* f = std::fopen(timestamps_path.c_str(), "w");
      if (f == nullptr) return 1;
      for (std::int64_t t : stamps) std::fprintf(f, "%lld\n", static_cast<long long>(t));
      std::fclose(f);
    }
    if (!stop_at_end) {
      // Leave the segment as a killed writer would (no "stopped" state): skip the destructor.
      std::fflush(nullptr);
      std::_Exit(0);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "ipc_test_writer: %s\n", e.what());
    return 1;
  }
  return 0;
}
