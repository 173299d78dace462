#include "background_search.hpp"
#include "idle_thread.hpp"

namespace handtrack {

namespace {
// background_searches_finished()
std::atomic<uint64_t> finished_searches{0};
}  // namespace

uint64_t background_searches_finished() { return finished_searches.load(std::memory_order_relaxed); }

BackgroundSearch::BackgroundSearch(const TrackerConfig& config)
    : search_(config), thread_([this] { run(); }) {
  // Room for the other hand: a model's Gaussians (submit() copies one of the same size). The search
  // thread reads other_ only once a search is queued.
  other_.assign(search_.model(), PosedHand(search_.model(), PoseParams::Zero()), false);
}

BackgroundSearch::~BackgroundSearch() {
  stop_.store(true, std::memory_order_relaxed);
  state_.store(State::kStop, std::memory_order_release);
  state_.notify_all();
  join_from_idle_class(thread_);  // the search stops at its next hypothesis
}

void BackgroundSearch::reclaim_dropped() {
  if (!wanted_ && state_.load(std::memory_order_acquire) == State::kDone) {
    state_.store(State::kIdle, std::memory_order_release);
  }
}

void BackgroundSearch::reserve(int width, int height) {
  reclaim_dropped();
  if (state_.load(std::memory_order_acquire) == State::kIdle) reserve_input(input_, width, height);
}

bool BackgroundSearch::submit(const DepthInput& input, const HandObstacle* other, const HandModel& model) {
  reclaim_dropped();
  if (state_.load(std::memory_order_acquire) != State::kIdle) return false;
  input_ = input;  // into the room reserve() made: no allocation
  has_other_ = other != nullptr;
  if (has_other_) other_ = *other;
  search_.set_model(model);  // a self-calibrated scale (tracker.cpp)
  wanted_ = true;
  state_.store(State::kQueued, std::memory_order_release);
  state_.notify_all();
  return true;
}

std::optional<StartFit> BackgroundSearch::take() {
  if (!wanted_ || state_.load(std::memory_order_acquire) != State::kDone) {
    reclaim_dropped();
    return std::nullopt;
  }
  StartFit fit = result_;
  wanted_ = false;
  state_.store(State::kIdle, std::memory_order_release);
  return fit;
}

void BackgroundSearch::cancel() {
  wanted_ = false;
  // Not started yet: it never starts (the search thread's own exchange then fails).
  State queued = State::kQueued;
  state_.compare_exchange_strong(queued, State::kIdle, std::memory_order_acq_rel);
  reclaim_dropped();
}

void BackgroundSearch::wait() {
  for (State s = state_.load(std::memory_order_acquire); s == State::kQueued || s == State::kRunning;
       s = state_.load(std::memory_order_acquire)) {
    state_.wait(s, std::memory_order_acquire);
  }
}

void BackgroundSearch::run() {
  become_idle_class("ht-search");
  for (;;) {
    State s = state_.load(std::memory_order_acquire);
    while (s != State::kQueued && s != State::kStop) {
      state_.wait(s, std::memory_order_acquire);
      s = state_.load(std::memory_order_acquire);
    }
    if (s == State::kStop) return;
    // Cancelled (back to idle) or stopped meanwhile: nothing to search.
    if (!state_.compare_exchange_strong(s, State::kRunning, std::memory_order_acq_rel)) continue;
    // input_, other_ and the model stay as submit() left them until the state is idle again.
    search_.set_other_hand(has_other_ ? &other_ : nullptr);
    result_ = search_.run(input_, SearchPurpose::kCheck, &stop_);
    search_.take_iterations();  // the tracking thread counts its own iterations only
    finished_searches.fetch_add(1, std::memory_order_relaxed);
    State running = State::kRunning;
    if (state_.compare_exchange_strong(running, State::kDone, std::memory_order_acq_rel)) state_.notify_all();
  }
}

}  // namespace handtrack
