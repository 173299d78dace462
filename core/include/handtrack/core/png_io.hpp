#pragma once
// PNG files through libpng's simplified API (no setjmp in our code). Loading throws
// std::runtime_error whose message names the file and what is wrong with it.

#include <cstdint>
#include <filesystem>
#include <vector>

namespace handtrack {

template <typename T>
struct Image {
  int width = 0;
  int height = 0;
  int channels = 1;
  std::vector<T> pixels;  // row-major, channels interleaved
};
using Gray16Image = Image<uint16_t>;
using Gray8Image = Image<uint8_t>;
using RgbImage = Image<uint8_t>;  // channels == 3

// The largest side a PNG may claim before it is refused: camera.json's limit (camera.cpp).
inline constexpr int kMaxPngSide = 8192;

// The size a PNG must have (0 x 0: any size up to kMaxPngSide). Checked against the header before
// a pixel is decoded or a byte allocated for it: a 177-byte file claiming 60000 x 60000 pixels is
// refused at once, not after allocating gigabytes.
struct PngSize {
  int width = 0;
  int height = 0;
};

// Reads a 16-bit grayscale PNG exactly as stored (no gamma). An 8-bit file is refused: depth
// frames are 16-bit (SPEC.md "Sequence directory"), and reading 0-255 as mm would be silent garbage.
Gray16Image read_png_gray16(const std::filesystem::path& path, PngSize expected = {});
// Reads an 8-bit grayscale PNG (e.g. part labels).
Gray8Image read_png_gray8(const std::filesystem::path& path, PngSize expected = {});

void write_png_gray16(const std::filesystem::path& path, const Gray16Image& image);
void write_png_gray8(const std::filesystem::path& path, const Gray8Image& image);
void write_png_rgb(const std::filesystem::path& path, const RgbImage& image);

}  // namespace handtrack
