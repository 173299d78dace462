// libFuzzer target: arbitrary bytes as a shared-memory segment.
// 1. shm::validate_segment on the bytes (in ordinary, 64-byte aligned memory) must not read out of
//    bounds (ASan) or hit undefined behaviour (UBSan), and if it accepts, every slot the reader
//    could index lies inside the bytes.
// 2. The same bytes as a real shm object, opened by the real client path (PoseRingReader: open,
//    latest, try_next, wait_next(0), writer_status): no crash, no UB, only status values, and a
//    frame it returns never claims more hands than it holds.
#include <handtrack/ipc/pose_ring_reader.hpp>
#include <handtrack/ipc/pose_ring_shm.hpp>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <string>

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

namespace shm = handtrack::ipc::shm;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > (1U << 20)) return -1;
  {
    // Exactly `size` bytes, 64-byte aligned, so ASan flags any read past them.
    const std::size_t alloc = (size + 63) / 64 * 64;
    void* raw = std::aligned_alloc(64, alloc == 0 ? 64 : alloc);
    std::memcpy(raw, data, size);
    std::string detail;
    const auto status = shm::validate_segment(size == 0 ? raw : raw, size, &detail);
    if (status == HANDTRACK_OK) {
      const auto* h = static_cast<const shm::Header*>(raw);
      if (shm::segment_size(h->capacity) > size) std::abort();  // accepted but does not fit
    } else if (detail.empty()) {
      std::abort();  // every refusal says why
    }
    std::free(raw);
  }
  {
    static const std::string name = "ht_fuzz_" + std::to_string(::getpid());
    const int fd = ::shm_open(("/" + name).c_str(), O_RDWR | O_CREAT | O_TRUNC, 0600);
    if (fd < 0) return 0;
    if (size > 0 && ::write(fd, data, size) != static_cast<ssize_t>(size)) std::abort();
    ::close(fd);
    handtrack::ipc::PoseRingReader reader;
    if (reader.open(name) == HANDTRACK_OK) {
      handtrack::ipc::FrameRecord record;
      const auto check = [&](handtrack::ipc::Status st) {
        if (st == HANDTRACK_OK && record.hand_count > handtrack::ipc::kMaxHands) std::abort();
      };
      check(reader.latest(record));
      check(reader.try_next(record));
      check(reader.wait_next(record, std::chrono::nanoseconds(0)));
      handtrack::ipc::WriterStatus status;
      (void)reader.writer_status(status);
    } else if (reader.error_detail().empty()) {
      std::abort();
    }
    ::shm_unlink(("/" + name).c_str());
  }
  return 0;
}
