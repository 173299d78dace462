#pragma once
// Doorbell: a futex-backed wake-up for a lock-free queue's consumer. Lock-free queues have no
// blocking pop, and a consumer must neither spin nor sleep a fixed time. The producer pushes,
// then ring()s; the consumer takes a ticket, tries to pop, and waits on the ticket only if the
// queue was empty.
//
// Thread roles: thread-safe; any number of threads ring(), any number wait().
#include "handtrack/common/futex.hpp"

#include <atomic>
#include <cstdint>

namespace handtrack::daemon {

class Doorbell {
 public:
  // How long a waiting pipeline thread sleeps at most before it re-checks whether to stop (a
  // stop rings every doorbell, so this only bounds a missed or absent ring).
  static constexpr int64_t kIdleWaitNs = 50'000'000;

  // SYNC: acquire, pairs with ring()'s release increment: whatever the producer wrote before
  // ringing (the queue push) is visible to a consumer whose ticket shows the ring.
  [[nodiscard]] uint32_t ticket() const { return word_.load(std::memory_order_acquire); }
  // Sleeps until the word differs from `ticket` or `timeout_ns` passed. The kernel compares the
  // word under its own lock, so a ring() between ticket() and wait() makes wait() return at once.
  void wait(uint32_t ticket, int64_t timeout_ns) { futex_wait(&word_, ticket, timeout_ns, FutexScope::kPrivate); }
  void ring() {
    // SYNC: release, pairs with ticket()'s acquire load (see there).
    word_.fetch_add(1, std::memory_order_release);
    futex_wake_all(&word_, FutexScope::kPrivate);
  }

 private:
  alignas(64) std::atomic<uint32_t> word_{0};
};

}  // namespace handtrack::daemon
