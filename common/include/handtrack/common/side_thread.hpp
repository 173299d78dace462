#pragma once
// SideThread: one persistent thread that runs one job at a time for its owner, so that two pieces
// of one frame's work (the two hands' optimisations, issue 14) run on two cores at once without
// creating a thread per frame (which allocates, and costs ~50 us). The owner posts a job, does its
// own share, then waits for the job; both sides sleep on futexes, never spin.
//
//   SideThread side([] { name the thread, pin it });
//   side.post(job);        // job() starts on the side thread
//   ...                    // the owner's own work
//   side.wait();           // job() has returned; its writes are visible here
//
// Thread roles: post() and wait() from the owning thread only, alternately; the job runs on the
// side thread. The destructor stops and joins the thread (after a posted job returns).
#include "handtrack/common/futex.hpp"

#include <atomic>
#include <cstdint>
#include <functional>
#include <thread>
#include <utility>

namespace handtrack {

class SideThread {
 public:
  // `setup` runs first on the new thread (its name, CPU, scheduling class).
  explicit SideThread(std::function<void()> setup = {}) : thread_([this, setup = std::move(setup)] {
    if (setup) setup();
    loop();
  }) {}
  ~SideThread() {
    stop_.store(true, std::memory_order_relaxed);
    // SYNC: release, pairs with loop()'s acquire load of posted_: the thread sees stop_.
    posted_.fetch_add(1, std::memory_order_release);
    futex_wake_all(&posted_, FutexScope::kPrivate);
    thread_.join();
  }
  SideThread(const SideThread&) = delete;
  SideThread& operator=(const SideThread&) = delete;

  // Starts `job` on the side thread. `job` must stay valid until wait() returns.
  void post(const std::function<void()>& job) {
    job_ = &job;
    // SYNC: release, pairs with loop()'s acquire load: the thread sees job_ and everything the
    // owner wrote before posting.
    posted_.fetch_add(1, std::memory_order_release);
    futex_wake_all(&posted_, FutexScope::kPrivate);
  }
  // Until the posted job has returned.
  void wait() {
    // SYNC: acquire, pairs with loop()'s release increment of done_: the job's writes are
    // visible after this returns.
    for (uint32_t d = done_.load(std::memory_order_acquire); d != posted_.load(std::memory_order_relaxed);
         d = done_.load(std::memory_order_acquire)) {
      futex_wait(&done_, d, kWaitSliceNs, FutexScope::kPrivate);
    }
  }

 private:
  // A wait re-checks at least this often (a futex wake is never lost: the kernel compares the
  // word; this only bounds a wait if one were).
  static constexpr int64_t kWaitSliceNs = 50'000'000;

  void loop() {
    uint32_t seen = 0;
    for (;;) {
      uint32_t p = posted_.load(std::memory_order_acquire);
      while (p == seen) {
        futex_wait(&posted_, p, kWaitSliceNs, FutexScope::kPrivate);
        p = posted_.load(std::memory_order_acquire);
      }
      if (stop_.load(std::memory_order_relaxed)) return;
      seen = p;
      (*job_)();
      // SYNC: release, pairs with wait()'s acquire load.
      done_.store(seen, std::memory_order_release);
      futex_wake_all(&done_, FutexScope::kPrivate);
    }
  }

  const std::function<void()>* job_ = nullptr;
  alignas(64) std::atomic<uint32_t> posted_{0};
  alignas(64) std::atomic<uint32_t> done_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;  // last: starts after every other member is initialised
};

// One frame's work split by hand slot: `slots` has bit s set for each slot s (0 and 1) that has
// work. With a side thread and both slots, slot 1 runs as `side_job` on the side thread while this
// thread does `run(0)`; otherwise `run(s)` does every slot here, in order. Returns when all is done.
// (`side_job` is a prepared std::function, so posting it allocates nothing.)
template <typename Run>
void run_slots(uint32_t slots, SideThread* side, const std::function<void()>& side_job, Run&& run) {
  const bool parallel = side != nullptr && slots == 3U;
  if (parallel) side->post(side_job);
  for (int s = 0; s < 2; ++s) {
    if ((slots & (1U << static_cast<unsigned>(s))) != 0 && !(parallel && s == 1)) run(s);
  }
  if (parallel) side->wait();
}

}  // namespace handtrack
