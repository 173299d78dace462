#pragma once
// Forged PNG files for tests of hostile input: a valid file whose header claims another size.
#include "handtrack/core/png_io.hpp"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace handtrack::test {

// CRC-32 of PNG chunks (ISO 3309, as zlib's crc32), to forge a header that libpng accepts.
inline uint32_t png_crc(const std::string& bytes) {
  uint32_t c = 0xFFFFFFFFU;
  for (const unsigned char b : bytes) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320U & (0U - (c & 1U)));
  }
  return c ^ 0xFFFFFFFFU;
}

// A valid 16-bit PNG whose IHDR now claims width x height (the pixel data stays 4x4).
inline void write_png_claiming(const std::filesystem::path& file, uint32_t width, uint32_t height) {
  write_png_gray16(file, Gray16Image{4, 4, 1, std::vector<uint16_t>(16, 500)});
  std::ifstream in(file, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  in.close();
  // Signature (8), IHDR length (4), "IHDR" at 12, width at 16, height at 20, CRC of "IHDR"+13 at 29.
  const auto put32 = [&](size_t at, uint32_t v) {
    for (int k = 0; k < 4; ++k) bytes[at + static_cast<size_t>(k)] = static_cast<char>((v >> (24 - 8 * k)) & 0xFFU);
  };
  put32(16, width);
  put32(20, height);
  put32(29, png_crc(bytes.substr(12, 17)));
  std::ofstream(file, std::ios::binary) << bytes;
}

}  // namespace handtrack::test
