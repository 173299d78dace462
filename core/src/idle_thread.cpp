#include "idle_thread.hpp"

#include <pthread.h>
#include <sched.h>
#include <unistd.h>

namespace handtrack {

void become_idle_class(const char* name) {
  pthread_setname_np(pthread_self(), name);
  sched_param param{};
  param.sched_priority = 0;
  pthread_setschedparam(pthread_self(), SCHED_IDLE, &param);
  cpu_set_t cpus;
  CPU_ZERO(&cpus);
  const long online = sysconf(_SC_NPROCESSORS_ONLN);
  for (long c = 0; c < online && c < CPU_SETSIZE; ++c) CPU_SET(static_cast<int>(c), &cpus);
  pthread_setaffinity_np(pthread_self(), sizeof(cpus), &cpus);
}

void join_from_idle_class(std::thread& thread) {
  sched_param param{};
  param.sched_priority = 0;
  pthread_setschedparam(thread.native_handle(), SCHED_OTHER, &param);
  thread.join();
}

}  // namespace handtrack
