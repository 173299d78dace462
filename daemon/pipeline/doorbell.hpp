#pragma once
// Doorbell: a futex-backed wake-up for a lock-free queue's consumer. Lock-free queues have no
// blocking pop, and a consumer must neither spin nor sleep a fixed time. The producer pushes,
// then ring()s; the consumer takes a ticket, tries to pop, and waits on the ticket only if the
// queue was empty.
//
// Thread roles: thread-safe; any number of threads ring(), any number wait().
#include <atomic>
#include <climits>
#include <cstdint>
#include <ctime>

#include <linux/futex.h>
#include <sys/syscall.h>
#include <unistd.h>

namespace handtrack::daemon {

class Doorbell {
 public:
  // SYNC: acquire, pairs with ring()'s release increment: whatever the producer wrote before
  // ringing (the queue push) is visible to a consumer whose ticket shows the ring.
  [[nodiscard]] uint32_t ticket() const { return word_.load(std::memory_order_acquire); }
  // Sleeps until the word differs from `ticket` or `timeout_ns` passed. The kernel compares the
  // word under its own lock, so a ring() between ticket() and wait() makes wait() return at once.
  void wait(uint32_t ticket, int64_t timeout_ns) {
    timespec ts{static_cast<time_t>(timeout_ns / 1'000'000'000), static_cast<long>(timeout_ns % 1'000'000'000)};
    syscall(SYS_futex, word(), FUTEX_WAIT_PRIVATE, ticket, &ts, nullptr, 0);
  }
  void ring() {
    // SYNC: release, pairs with ticket()'s acquire load (see there).
    word_.fetch_add(1, std::memory_order_release);
    syscall(SYS_futex, word(), FUTEX_WAKE_PRIVATE, INT_MAX, nullptr, nullptr, 0);
  }

 private:
  uint32_t* word() { return reinterpret_cast<uint32_t*>(&word_); }
  static_assert(sizeof(std::atomic<uint32_t>) == sizeof(uint32_t) && std::atomic<uint32_t>::is_always_lock_free);
  alignas(64) std::atomic<uint32_t> word_{0};
};

}  // namespace handtrack::daemon
