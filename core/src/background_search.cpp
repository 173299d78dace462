#include "background_search.hpp"

namespace handtrack {

namespace {
// background_searches_finished()
std::atomic<uint64_t> finished_searches{0};
}  // namespace

uint64_t background_searches_finished() { return finished_searches.load(std::memory_order_relaxed); }

BackgroundSearch::BackgroundSearch(const TrackerConfig& config)
    : search_(config), worker_("ht-search", [this] { search(); }) {
  // Room for the other hand: a model's Gaussians (submit() copies one of the same size). The search
  // thread reads other_ only once a search is queued.
  other_.assign(search_.model(), PosedHand(search_.model(), PoseParams::Zero()), false);
}

BackgroundSearch::~BackgroundSearch() {
  stop_.store(true, std::memory_order_relaxed);  // then worker_ waits for the search to stop
}

void BackgroundSearch::reclaim_dropped() {
  if (!wanted_ && worker_.state() == IdleWorker::State::kDone) worker_.finish();
}

void BackgroundSearch::reserve(int width, int height) {
  reclaim_dropped();
  if (worker_.state() == IdleWorker::State::kIdle) reserve_input(input_, width, height);
}

bool BackgroundSearch::submit(const DepthInput& input, const HandObstacle* other, const HandModel& model) {
  reclaim_dropped();
  if (worker_.state() != IdleWorker::State::kIdle) return false;
  input_ = input;  // into the room reserve() made: no allocation
  has_other_ = other != nullptr;
  if (has_other_) other_ = *other;
  search_.set_model(model);  // a self-calibrated scale (tracker.cpp)
  wanted_ = true;
  worker_.submit();
  return true;
}

std::optional<StartFit> BackgroundSearch::take() {
  if (!wanted_ || worker_.state() != IdleWorker::State::kDone) {
    reclaim_dropped();
    return std::nullopt;
  }
  StartFit fit = result_;
  wanted_ = false;
  worker_.finish();
  return fit;
}

void BackgroundSearch::cancel() {
  wanted_ = false;
  worker_.cancel();
  reclaim_dropped();
}

void BackgroundSearch::wait() { worker_.wait(); }

void BackgroundSearch::search() {
  // input_, other_ and the model stay as submit() left them until the worker is idle again.
  search_.set_other_hand(has_other_ ? &other_ : nullptr);
  result_ = search_.run(input_, SearchPurpose::kCheck, &stop_);
  search_.take_iterations();  // the tracking thread counts its own iterations only
  finished_searches.fetch_add(1, std::memory_order_relaxed);
}

}  // namespace handtrack
