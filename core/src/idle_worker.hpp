#pragma once
// IdleWorker: a thread of its own at the lowest scheduling priority that runs one job at a time for
// a tracking thread, which hands the job over and takes its result at a later frame without ever
// waiting for it (a check's search: background_search.hpp; a hand's self-calibration:
// self_calibration.hpp).
//
// The thread runs under SCHED_IDLE on every CPU: it gets only time that no other thread of the
// machine wants, so a pipeline thread that wakes preempts it at once, and a job takes as long as
// the idle CPU allows. It starts with the object, so that a tracker's threads are the same from
// its first frame to its last (a daemon's thread count says nothing leaked).
//
// The two threads share no lock: they hand the job over through one atomic state, so a tracking
// thread never waits for a thread that may not run for as long as the machine is busy (a SCHED_IDLE
// thread preempted while holding a lock would hold it that long: priority inversion). The job's
// inputs belong to the tracking thread while the state is idle or done, to the worker while it is
// queued or running.
#include <atomic>
#include <functional>
#include <thread>

namespace handtrack {

class IdleWorker {
 public:
  // kIdle -> kQueued (submit) -> kRunning (the worker) -> kDone -> kIdle (taken, or reclaimed);
  // kQueued -> kIdle (cancel); any -> kStop (the destructor). Each store that hands data over is a
  // release, each load that takes it an acquire.
  enum class State { kIdle, kQueued, kRunning, kDone, kStop };

  // `name`: the thread's (at most 15 characters); `job` runs on it once per submit().
  IdleWorker(const char* name, std::function<void()> job);
  // Waits for a job under way (moved back to the normal class first, so that one starved of idle
  // time reaches its end, or its next stop check, soon).
  ~IdleWorker();
  IdleWorker(const IdleWorker&) = delete;
  IdleWorker& operator=(const IdleWorker&) = delete;

  [[nodiscard]] State state() const { return state_.load(std::memory_order_acquire); }
  // Idle -> queued: the job's inputs are handed over.
  void submit();
  // Done -> idle: its result is taken (or dropped); its inputs are the tracking thread's again.
  void finish() { state_.store(State::kIdle, std::memory_order_release); }
  // Queued -> idle, where the job has not started: it never starts.
  void cancel();
  // Blocks until the job queued or under way (if any) has finished.
  void wait() const;

 private:
  void run();  // the worker thread

  const char* name_;
  std::function<void()> job_;
  std::atomic<State> state_{State::kIdle};
  std::thread thread_;  // last: started once everything it reads is constructed
};

}  // namespace handtrack
