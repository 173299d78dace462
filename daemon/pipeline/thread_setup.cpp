#include "thread_setup.hpp"

#include "logging.hpp"

#include <pthread.h>
#include <sched.h>

#include <cstring>

namespace handtrack::daemon {

void setup_pipeline_thread(const char* name, int cpu, const PipelineConfig& config) {
  pthread_setname_np(pthread_self(), name);
  if (cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    if (const int e = pthread_setaffinity_np(pthread_self(), sizeof set, &set); e != 0) {
      log().warn("{}: cannot pin to CPU {}: {}; running unpinned", name, cpu, std::strerror(e));
    }
  }
  if (config.realtime_priority > 0) {
    sched_param p{};
    p.sched_priority = config.realtime_priority;
    if (const int e = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p); e != 0) {
      log().warn("{}: cannot use SCHED_FIFO priority {}: {}; normal scheduling", name, config.realtime_priority,
                 std::strerror(e));
    }
  }
}

}  // namespace handtrack::daemon
