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

// Reads a grayscale PNG as 16-bit values exactly as stored (8-bit files are widened, no gamma).
Gray16Image read_png_gray16(const std::filesystem::path& path);
// Reads an 8-bit grayscale PNG (e.g. part labels).
Gray8Image read_png_gray8(const std::filesystem::path& path);

void write_png_gray16(const std::filesystem::path& path, const Gray16Image& image);
void write_png_gray8(const std::filesystem::path& path, const Gray8Image& image);
void write_png_rgb(const std::filesystem::path& path, const RgbImage& image);

}  // namespace handtrack
