// seqlock.hpp (private): the seqlock protocol on PoseRingShm words, the futex calls and the clock.
//
// Seqlock after Boehm 2012 ("Can seqlocks get along with programming language memory models?",
// the variant with fences, sec. 5): the protected data are atomics accessed relaxed, so a reader
// racing with the writer has no data race (no UB, nothing for TSan to report); the sequence
// counter and two fences decide whether the words it copied belong to one version.
//
//   writer (one thread)                      reader (any process)
//   seq.store(odd, relaxed)                  s0 = seq.load(acquire)            (R1)
//   fence(release)                  (W1)     words[k].load(relaxed) ...
//   words[k].store(relaxed) ...              fence(acquire)                    (R2)
//   seq.store(even, release)        (W2)     s1 = seq.load(relaxed)
//                                            accept iff s0 == s1 == expected even value
//
// Why a torn copy is never accepted: if any word the reader loaded was stored by a writer pass
// that began after the version s0, then W1 (release fence, sequenced before that store) and R2
// (acquire fence, sequenced after that load) synchronize, so the odd store before W1 happens
// before the reader's second load: s1 >= that odd value != s0. If no word comes from a later pass,
// R1 reading `even` synchronizes with W2, so every word of that version is visible: the copy is
// exactly that version.
#pragma once

#include <atomic>
#include <cerrno>
#include <climits>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <ctime>

#include "handtrack/common/clock.hpp"
#include "handtrack/common/futex.hpp"

namespace handtrack::ipc::detail {

using handtrack::monotonic_ns;  // common/: the one CLOCK_MONOTONIC clock of every *_ns

inline std::int64_t realtime_us() noexcept {
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000 + ts.tv_nsec / 1000;
}

// now - heartbeat, saturated to +-2^62 so that arithmetic on a garbage heartbeat (a corrupt or
// hostile segment) cannot overflow.
inline std::int64_t heartbeat_age_ns(std::int64_t now_ns, std::int64_t heartbeat_ns) noexcept {
  constexpr std::int64_t kLimit = std::int64_t{1} << 62;
  std::int64_t age = 0;
  if (__builtin_sub_overflow(now_ns, heartbeat_ns, &age)) return heartbeat_ns > now_ns ? -kLimit : kLimit;
  return age < -kLimit ? -kLimit : (age > kLimit ? kLimit : age);
}

// The age after which a writer counts as dead: 2.5 heartbeat periods (kDeadAfterHalfPeriods / 2).
// `period_ns` is at most kMaxHeartbeatPeriodNs (validated), so this cannot overflow.
inline std::int64_t dead_after_ns(std::int64_t period_ns, std::int64_t half_periods) noexcept {
  return half_periods * period_ns / 2;
}

// --- writer side ----------------------------------------------------------------------------

inline void seqlock_begin_write(std::atomic<std::uint64_t>& seq, std::uint64_t odd) noexcept {
  // SYNC: relaxed; ordered before the data stores by the release fence below (W1), which pairs
  // with a reader's acquire fence (R2) after its data loads.
  seq.store(odd, std::memory_order_relaxed);
  std::atomic_thread_fence(std::memory_order_release);
}

inline void seqlock_store_words(std::atomic<std::uint64_t>* dst, const void* src,
                                std::size_t n_words) noexcept {
  const auto* bytes = static_cast<const unsigned char*>(src);
  for (std::size_t k = 0; k < n_words; ++k) {
    std::uint64_t w;
    std::memcpy(&w, bytes + k * sizeof w, sizeof w);
    // SYNC: relaxed; published by seqlock_end_write's release store (W2).
    dst[k].store(w, std::memory_order_relaxed);
  }
}

inline void seqlock_end_write(std::atomic<std::uint64_t>& seq, std::uint64_t even) noexcept {
  // SYNC: release (W2); pairs with the reader's acquire load of seq (R1): a reader that sees
  // `even` sees every data word stored before it.
  seq.store(even, std::memory_order_release);
}

// --- reader side ----------------------------------------------------------------------------

enum class SeqRead { kOk, kNotYet, kGone };

// Copies the version `expected` (an even seq value) of `n_words` words into dst.
// kNotYet: seq < expected (not written yet, or being written); kGone: seq > expected, or the
// writer started a newer version during the copy (the version is lost; dst holds garbage).
inline SeqRead seqlock_read(const std::atomic<std::uint64_t>& seq,
                            const std::atomic<std::uint64_t>* src, void* dst,
                            std::size_t n_words, std::uint64_t expected) noexcept {
  // SYNC: acquire (R1); pairs with the writer's release store of `expected` (W2).
  const std::uint64_t s0 = seq.load(std::memory_order_acquire);
  if (s0 != expected) return s0 < expected ? SeqRead::kNotYet : SeqRead::kGone;
  auto* bytes = static_cast<unsigned char*>(dst);
  for (std::size_t k = 0; k < n_words; ++k) {
    // SYNC: relaxed; validated by the fence and the second seq load below.
    const std::uint64_t w = src[k].load(std::memory_order_relaxed);
    std::memcpy(bytes + k * sizeof w, &w, sizeof w);
  }
  // SYNC: acquire fence (R2); pairs with the writer's release fence (W1) of any pass whose data
  // we may have loaded, making that pass's odd seq store visible to the load below.
  std::atomic_thread_fence(std::memory_order_acquire);
  const std::uint64_t s1 = seq.load(std::memory_order_relaxed);
  return s1 == s0 ? SeqRead::kOk : SeqRead::kGone;
}

// --- futex: common/futex.hpp with FutexScope::kShared (waiter and waker are different processes)

inline void futex_wait(const std::atomic<std::uint32_t>* word, std::uint32_t expected,
                       std::int64_t timeout_ns) noexcept {
  handtrack::futex_wait(word, expected, timeout_ns, FutexScope::kShared);
}

inline void futex_wake_all(std::atomic<std::uint32_t>* word) noexcept {
  handtrack::futex_wake_all(word, FutexScope::kShared);
}

}  // namespace handtrack::ipc::detail
