#pragma once
// BackgroundSearch: a check's (re)start search (StartSearch::run) on a worker thread of its own at
// the lowest scheduling priority (IdleWorker), on copies of the check's first frame and of the other
// hand as it was then (TrackerConfig::background_checks). The tracking thread hands a search over
// and takes its result at a later frame; it never waits for one (except wait(), for tests).
//
// Thread roles: reserve(), submit(), take(), cancel() and wait() from the tracking thread (one at a
// time); the search itself on the worker.
#include "idle_worker.hpp"
#include "handtrack/core/start_search.hpp"
#include "handtrack/core/tracker.hpp"

#include <atomic>
#include <optional>

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
  // Starts a search on copies of `input` and `other` (null: no other hand) with `model` (the
  // tracker's, a default adult at its scale: copied without allocating); false, and nothing
  // started, while a search is under way or its result is not taken.
  bool submit(const DepthInput& input, const HandObstacle* other, const HandModel& model);
  // The finished search's best fit, once; nullopt while it runs, when none was submitted, or when
  // it was cancelled.
  std::optional<StartFit> take();
  // Drops the search submitted: one not started never starts, one under way finishes unread.
  void cancel();
  // Blocks until the search under way (if any) has finished.
  void wait();

 private:
  void search();  // the worker's job
  // Finished and unwanted: back to idle (tracking thread).
  void reclaim_dropped();

  std::atomic<bool> stop_{false};  // the destructor: the search stops at its next hypothesis
  bool wanted_ = false;            // tracking thread: the search submitted is to be taken
  // Written by the tracking thread while the worker is idle, read by it while it runs.
  StartSearch search_;
  DepthInput input_;
  HandObstacle other_;
  bool has_other_ = false;
  StartFit result_;  // written while running, read once done
  IdleWorker worker_;  // last: its thread starts once everything it reads is constructed
};

}  // namespace handtrack
