#include "idle_worker.hpp"

#include <pthread.h>
#include <sched.h>
#include <unistd.h>

namespace handtrack {

namespace {
// The calling thread named `name`, at SCHED_IDLE, allowed on every online CPU (it inherits the
// creating thread's policy and CPU, which in handtrackd may be a real-time stage thread pinned to
// one CPU). Either may fail in a restricted container; the thread then runs as its creator does.
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
}  // namespace

IdleWorker::IdleWorker(const char* name, std::function<void()> job)
    : name_(name), job_(std::move(job)), thread_([this] { run(); }) {}

IdleWorker::~IdleWorker() {
  state_.store(State::kStop, std::memory_order_release);
  state_.notify_all();
  sched_param param{};
  param.sched_priority = 0;
  pthread_setschedparam(thread_.native_handle(), SCHED_OTHER, &param);
  thread_.join();
}

void IdleWorker::submit() {
  state_.store(State::kQueued, std::memory_order_release);
  state_.notify_all();
}

void IdleWorker::cancel() {
  // Not started yet: it never starts (the worker's own exchange then fails).
  State queued = State::kQueued;
  state_.compare_exchange_strong(queued, State::kIdle, std::memory_order_acq_rel);
}

void IdleWorker::wait() const {
  for (State s = state(); s == State::kQueued || s == State::kRunning; s = state()) {
    state_.wait(s, std::memory_order_acquire);
  }
}

void IdleWorker::run() {
  become_idle_class(name_);
  for (;;) {
    State s = state();
    while (s != State::kQueued && s != State::kStop) {
      state_.wait(s, std::memory_order_acquire);
      s = state();
    }
    if (s == State::kStop) return;
    // Cancelled (back to idle) or stopped meanwhile: nothing to do.
    if (!state_.compare_exchange_strong(s, State::kRunning, std::memory_order_acq_rel)) continue;
    job_();
    State running = State::kRunning;
    if (state_.compare_exchange_strong(running, State::kDone, std::memory_order_acq_rel)) state_.notify_all();
  }
}

}  // namespace handtrack
