#include "background_search.hpp"

#include <pthread.h>
#include <sched.h>
#include <unistd.h>

namespace handtrack {

namespace {
// background_searches_finished()
std::atomic<uint64_t> finished_searches{0};

// The calling thread at SCHED_IDLE, allowed on every online CPU (it inherits the creating
// thread's policy and CPU, which in handtrackd may be a real-time stage thread pinned to one CPU).
// Either may fail in a restricted container; the search then runs as its creator does.
void become_idle_class() {
  pthread_setname_np(pthread_self(), "ht-search");
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

uint64_t background_searches_finished() { return finished_searches.load(std::memory_order_relaxed); }

BackgroundSearch::BackgroundSearch(const TrackerConfig& config)
    : search_(config), scale_(config.scale), thread_([this] { run(); }) {
  // Room for the other hand: a model's Gaussians (submit() copies one of the same size).
  const std::lock_guard lock(mutex_);
  other_.assign(search_.model(), PosedHand(search_.model(), PoseParams::Zero()), false);
}

BackgroundSearch::~BackgroundSearch() {
  {
    const std::lock_guard lock(mutex_);
    stop_.store(true, std::memory_order_relaxed);
  }
  changed_.notify_all();
  // Back to the normal class, so that a search starved of idle time still reaches its next
  // hypothesis soon and stops.
  sched_param param{};
  param.sched_priority = 0;
  pthread_setschedparam(thread_.native_handle(), SCHED_OTHER, &param);
  thread_.join();
}

void BackgroundSearch::reserve(int width, int height) {
  const std::lock_guard lock(mutex_);
  if (state_ == State::kIdle) reserve_input(input_, width, height);
}

bool BackgroundSearch::submit(const DepthInput& input, const HandObstacle* other, const HandScale& scale) {
  {
    const std::lock_guard lock(mutex_);
    if (state_ != State::kIdle) return false;
    input_ = input;  // into the room reserve() made: no allocation
    has_other_ = other != nullptr;
    if (has_other_) other_ = *other;
    scale_ = scale;
    state_ = State::kQueued;
  }
  changed_.notify_all();
  return true;
}

bool BackgroundSearch::busy() const {
  const std::lock_guard lock(mutex_);
  return state_ != State::kIdle;
}

std::optional<StartFit> BackgroundSearch::take() {
  const std::lock_guard lock(mutex_);
  if (state_ != State::kDone) return std::nullopt;
  state_ = State::kIdle;
  return result_;
}

void BackgroundSearch::cancel() {
  const std::lock_guard lock(mutex_);
  if (state_ == State::kRunning) {
    dropped_ = true;
  } else {
    state_ = State::kIdle;
  }
}

void BackgroundSearch::wait() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [this] { return state_ == State::kIdle || state_ == State::kDone; });
}

void BackgroundSearch::run() {
  become_idle_class();
  std::unique_lock lock(mutex_);
  for (;;) {
    changed_.wait(lock, [this] { return state_ == State::kQueued || stop_.load(std::memory_order_relaxed); });
    if (stop_.load(std::memory_order_relaxed)) return;
    state_ = State::kRunning;
    lock.unlock();
    // input_, other_ and scale_ stay as submit() left them until the state is idle again.
    search_.set_scale(scale_);
    search_.set_other_hand(has_other_ ? &other_ : nullptr);
    const StartFit fit = search_.run(input_, &stop_);
    search_.take_iterations();  // the tracking thread counts its own iterations only
    lock.lock();
    result_ = fit;
    state_ = dropped_ ? State::kIdle : State::kDone;
    dropped_ = false;
    finished_searches.fetch_add(1, std::memory_order_relaxed);
    changed_.notify_all();
  }
}

}  // namespace handtrack
