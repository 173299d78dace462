#include "thread_setup.hpp"

#include "logging.hpp"

#include <pthread.h>
#include <sched.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace handtrack::daemon {

namespace {
// Normal scheduling: the preprocessing threads' nice value this much above the other stages'
// (CFS gives a thread of nice +5 a third of the weight of one of nice 0, and a waking nice-0
// thread preempts it sooner). SCHED_FIFO: one priority below them, which makes the order strict.
constexpr int kPreprocessNice = 5;
}  // namespace

void setup_pipeline_thread(const char* name, int cpu, const PipelineConfig& config, StageRank rank) {
  pthread_setname_np(pthread_self(), name);
  if (cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    if (const int e = pthread_setaffinity_np(pthread_self(), sizeof set, &set); e != 0) {
      log().warn("{}: cannot pin to CPU {}: {}; running unpinned", name, cpu, std::strerror(e));
    }
  }
  const bool yields = rank == StageRank::kPreprocess;
  if (config.realtime_priority <= 0 && yields) {
    // Per thread on Linux (the thread id, not the process), above the nice the daemon runs at;
    // raising one's own nice needs no privilege. getpriority() may return -1 as a value: errno
    // tells.
    const auto self = static_cast<id_t>(gettid());
    errno = 0;
    const int nice = getpriority(PRIO_PROCESS, self) + kPreprocessNice;
    if (errno != 0 || setpriority(PRIO_PROCESS, self, nice) != 0) {
      log().warn("{}: cannot lower its priority: {}", name, std::strerror(errno));
    }
  }
  if (config.realtime_priority > 0) {
    sched_param p{};
    p.sched_priority = yields ? std::max(1, config.realtime_priority - 1) : config.realtime_priority;
    if (const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p); e != 0) {
      log().warn("{}: cannot use SCHED_FIFO priority {}: {}; normal scheduling", name, p.sched_priority,
                 std::strerror(e));
    }
  }
}

}  // namespace handtrack::daemon
