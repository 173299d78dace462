#pragma once
// BackgroundSearch: a check's (re)start search (StartSearch::run) on a thread of its own, at the
// lowest scheduling priority, on copies of the check's first frame and of the other hand as it was
// then (TrackerConfig::background_checks). The tracking thread hands a search over and takes its
// result at a later frame; it never waits for one (except wait(), for tests).
//
// The thread runs under SCHED_IDLE on every CPU: it gets only time that no other thread of the
// machine wants, so a pipeline thread that wakes preempts it at once, and a search takes as long
// as the idle CPU allows. It starts with the object, so that a tracker's threads are the same from
// its first frame to its last (a daemon's thread count says nothing leaked).
//
// Thread roles: submit(), busy(), take(), cancel() and wait() from the tracking thread (one at a
// time); the search itself on the search thread.
#include "handtrack/core/start_search.hpp"
#include "handtrack/core/tracker.hpp"

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <thread>

namespace handtrack {

class BackgroundSearch {
 public:
  explicit BackgroundSearch(const TrackerConfig& config);
  ~BackgroundSearch();  // drops a search under way (it stops at its next hypothesis)
  BackgroundSearch(const BackgroundSearch&) = delete;
  BackgroundSearch& operator=(const BackgroundSearch&) = delete;

  // Room for copies of inputs of a width x height image, so that submit() allocates nothing (as
  // the daemon's steady state requires); none made while a search reads the copy.
  void reserve(int width, int height);
  // Starts a search on copies of `input` and `other` (null: no other hand) with the hand model at
  // `scale`; false, and nothing started, while a search is under way or its result is not taken.
  bool submit(const DepthInput& input, const HandObstacle* other, const HandScale& scale);
  // A search submitted and its result not yet taken (or dropped).
  [[nodiscard]] bool busy() const;
  // The finished search's best fit, once; nullopt while it runs, or when none was submitted.
  std::optional<StartFit> take();
  // Drops the search under way: its result will not be taken.
  void cancel();
  // Blocks until the search under way (if any) has finished.
  void wait();

 private:
  enum class State { kIdle, kQueued, kRunning, kDone };
  void run();  // the search thread

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  State state_ = State::kIdle;
  bool dropped_ = false;  // cancel() while running: the result goes, the state back to idle
  std::atomic<bool> stop_{false};  // the destructor: the search stops at its next hypothesis
  // Written by submit() while idle, read by the search thread while queued or running.
  StartSearch search_;
  DepthInput input_;
  HandObstacle other_;
  bool has_other_ = false;
  HandScale scale_;
  StartFit result_;  // kDone
  std::thread thread_;  // last: started once everything it reads is constructed
};

}  // namespace handtrack
