// libFuzzer + ASan/UBSan: the part-forest loader (core/src/part_forest.cpp PartForest::from_bytes)
// on arbitrary bytes. A file's last 8 bytes are its FNV-1a 64 checksum, which a mutation almost
// never keeps right; so when the first input byte is odd the target appends the right checksum
// to the rest, and the loader's checks behind the checksum are fuzzed too. A bad model must throw
// one std::runtime_error; never crash, or allocate what the header merely claims.
#include "handtrack/core/part_forest.hpp"

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace {

// FNV-1a 64 (part_forest.hpp: the file's checksum).
uint64_t fnv1a64(const uint8_t* data, size_t size) {
  uint64_t hash = 0xcbf29ce484222325ULL;
  for (size_t i = 0; i < size; ++i) hash = (hash ^ data[i]) * 0x100000001b3ULL;
  return hash;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  std::vector<uint8_t> bytes(data + 1, data + size);
  if ((data[0] & 1) != 0) {
    const uint64_t checksum = fnv1a64(bytes.data(), bytes.size());
    for (int i = 0; i < 8; ++i) bytes.push_back(static_cast<uint8_t>(checksum >> (8 * i)));
  }
  try {
    (void)handtrack::PartForest::from_bytes(bytes, "fuzz.htf");
  } catch (const std::runtime_error&) {
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
