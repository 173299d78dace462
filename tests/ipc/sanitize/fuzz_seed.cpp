// Writes a valid segment image (header + 2 slots, one record) as the fuzzer's seed.
#include <handtrack/ipc/pose_ring_shm.hpp>

#include <cstdio>
#include <new>
#include <vector>

namespace shm = handtrack::ipc::shm;

int main(int argc, char** argv) {
  if (argc != 2) return 2;
  constexpr std::uint32_t kCapacity = 2;
  std::vector<std::uint64_t> words(shm::segment_size(kCapacity) / 8, 0);
  auto* h = new (words.data()) shm::Header();
  h->abi_version = HANDTRACK_ABI_VERSION;
  h->endian_marker = shm::kEndianMarker;
  h->header_size = sizeof(shm::Header);
  h->record_size = sizeof(handtrack::ipc::FrameRecord);
  h->slot_size = sizeof(shm::Slot);
  h->capacity = kCapacity;
  h->total_size = shm::segment_size(kCapacity);
  h->epoch = 1;
  h->heartbeat_period_ns = 100'000'000;
  h->head.store(1);
  h->device_state.store(3);
  auto* slots = reinterpret_cast<shm::Slot*>(words.data() + sizeof(shm::Header) / 8);
  new (&slots[0]) shm::Slot();
  slots[0].seq.store(2);
  h->magic.store(shm::kMagic);
  FILE* f = std::fopen(argv[1], "wb");
  if (f == nullptr) return 1;
  std::fwrite(words.data(), 8, words.size(), f);
  return std::fclose(f) == 0 ? 0 : 1;
}
