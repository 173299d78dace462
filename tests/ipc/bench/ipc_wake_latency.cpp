// ipc_wake_latency: publish-to-wake latency across processes.
//
//   ipc_wake_latency [--records N] [--interval-us U] [--max-p99-us X] [--realtime 1]
//
// --realtime 1 runs the reader under SCHED_FIFO (what a latency-critical client would do), which
// takes other load on the machine out of the measurement.
// A forked reader process sleeps in wait_next() (futex); the parent publishes N records U us
// apart. For each record the reader takes CLOCK_MONOTONIC right after waking and subtracts the
// record's publish_ns (stamped by the writer just before its FUTEX_WAKE). Prints one JSON line
// {"records":..,"p50_us":..,"p99_us":..,"max_us":..}; exits 1 if a record was lost or
// p99 > X (when given).
#include <handtrack/ipc/pose_ring_reader.hpp>
#include <handtrack/ipc/pose_ring_writer.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

namespace {
std::int64_t now_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}
}  // namespace

int main(int argc, char** argv) {
  int records = 3000;
  int interval_us = 1000;
  double max_p99_us = -1;
  bool realtime = false;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string arg = argv[i];
    if (arg == "--records") records = std::atoi(argv[i + 1]);
    else if (arg == "--interval-us") interval_us = std::atoi(argv[i + 1]);
    else if (arg == "--max-p99-us") max_p99_us = std::atof(argv[i + 1]);
    else if (arg == "--realtime") realtime = std::atoi(argv[i + 1]) != 0;
    else {
      std::fprintf(stderr, "ipc_wake_latency: unknown argument %s\n", arg.c_str());
      return 2;
    }
  }
  using handtrack::ipc::PoseRingWriter;
  const std::string name = "ht_wake_" + std::to_string(::getpid());
  PoseRingWriter::Options options;
  options.name = name;
  options.capacity = 1024;
  PoseRingWriter writer(options);
  int ready_pipe[2], result_pipe[2];
  if (::pipe(ready_pipe) != 0 || ::pipe(result_pipe) != 0) return 1;

  const pid_t child = ::fork();
  if (child == 0) {
    if (realtime) {
      sched_param param{};
      param.sched_priority = 10;
      if (::sched_setscheduler(0, SCHED_FIFO, &param) != 0) std::fprintf(stderr, "no SCHED_FIFO\n");
    }
    handtrack::ipc::PoseRingReader reader;
    if (reader.open(name) != HANDTRACK_OK) ::_exit(3);
    const char ready = 'r';
    if (::write(ready_pipe[1], &ready, 1) != 1) ::_exit(3);
    std::vector<double> latencies_us;
    latencies_us.reserve(static_cast<std::size_t>(records));
    handtrack::ipc::FrameRecord record;
    while (static_cast<int>(latencies_us.size()) < records) {
      if (reader.wait_next(record, std::chrono::seconds(2)) != HANDTRACK_OK) break;
      latencies_us.push_back(static_cast<double>(now_ns() - record.publish_ns) / 1e3);
    }
    std::sort(latencies_us.begin(), latencies_us.end());
    double result[4] = {static_cast<double>(latencies_us.size()), 0, 0, 0};
    if (!latencies_us.empty()) {
      result[1] = latencies_us[latencies_us.size() / 2];
      result[2] = latencies_us[latencies_us.size() * 99 / 100];
      result[3] = latencies_us.back();
    }
    if (::write(result_pipe[1], result, sizeof result) != sizeof result) ::_exit(4);
    ::_exit(0);
  }
  char ready = 0;
  if (::read(ready_pipe[0], &ready, 1) != 1) return 1;

  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  handtrack::ipc::FrameRecord record{};
  for (int i = 0; i < records; ++i) {
    std::this_thread::sleep_for(std::chrono::microseconds(interval_us));  // the reader sleeps
    record.frame = static_cast<std::uint64_t>(i);
    writer.publish(record);
  }
  double result[4] = {};
  const bool got = ::read(result_pipe[0], result, sizeof result) == sizeof result;
  ::waitpid(child, nullptr, 0);
  PoseRingWriter::remove(name);
  if (!got) return 1;
  std::printf("{\"records\":%d,\"p50_us\":%.1f,\"p99_us\":%.1f,\"max_us\":%.1f}\n",
              static_cast<int>(result[0]), result[1], result[2], result[3]);
  if (static_cast<int>(result[0]) != records) return 1;
  if (max_p99_us > 0 && result[2] > max_p99_us) return 1;
  return 0;
}
