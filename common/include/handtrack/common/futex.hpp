#pragma once
// The two futex calls every blocking wait in handtrack is built on: the pipeline's doorbells
// (threads of one process: FutexScope::kPrivate) and the ring's wake-up word (the daemon and
// its readers are different processes: FutexScope::kShared, no FUTEX_PRIVATE_FLAG).
#include <atomic>
#include <climits>
#include <cstdint>
#include <ctime>

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

namespace handtrack {

enum class FutexScope { kPrivate, kShared };

static_assert(sizeof(std::atomic<uint32_t>) == sizeof(uint32_t) && std::atomic<uint32_t>::is_always_lock_free,
              "the kernel reads the futex word as a plain 32-bit integer");

// Sleeps while *word == expected, at most timeout_ns (returns at once for timeout_ns <= 0).
// The kernel compares *word with `expected` atomically with queueing the waiter, so a wake
// between the caller's load of the word and this call is not lost (the call returns at once).
// Spurious returns happen; callers re-check their condition.
inline void futex_wait(const std::atomic<uint32_t>* word, uint32_t expected, int64_t timeout_ns,
                       FutexScope scope) noexcept {
  if (timeout_ns <= 0) return;
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(timeout_ns / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(timeout_ns % 1'000'000'000);
  ::syscall(SYS_futex, reinterpret_cast<const uint32_t*>(word),
            scope == FutexScope::kPrivate ? FUTEX_WAIT_PRIVATE : FUTEX_WAIT, expected, &ts, nullptr, 0);
}

// Wakes every waiter on `word`.
inline void futex_wake_all(std::atomic<uint32_t>* word, FutexScope scope) noexcept {
  ::syscall(SYS_futex, reinterpret_cast<uint32_t*>(word),
            scope == FutexScope::kPrivate ? FUTEX_WAKE_PRIVATE : FUTEX_WAKE, INT_MAX, nullptr, nullptr, 0);
}

}  // namespace handtrack
