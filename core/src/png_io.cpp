#include "handtrack/core/png_io.hpp"

#include "file_error.hpp"

#include <png.h>

#include <cstring>
#include <stdexcept>
#include <string>

namespace handtrack {
namespace {

struct PngImage {
  png_image image{};
  PngImage() {
    std::memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
  }
  ~PngImage() { png_image_free(&image); }
  PngImage(const PngImage&) = delete;
  PngImage& operator=(const PngImage&) = delete;
};

std::string size_text(png_uint_32 width, png_uint_32 height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// Opens `path`, checks it is grayscale without alpha and of the expected size (header only:
// nothing is decoded or allocated for the pixels yet).
void begin_gray_read(const std::filesystem::path& path, PngSize expected, PngImage& png) {
  if (!std::filesystem::exists(path)) throw_file_error(path, "no such file");
  if (png_image_begin_read_from_file(&png.image, path.c_str()) == 0) {
    throw_file_error(path, std::string("not a readable PNG (") + png.image.message + ")");
  }
  if ((png.image.format & PNG_FORMAT_FLAG_COLOR) != 0 || (png.image.format & PNG_FORMAT_FLAG_ALPHA) != 0) {
    throw_file_error(path, "expected a single-channel grayscale PNG");
  }
  const png_uint_32 w = png.image.width;
  const png_uint_32 h = png.image.height;
  if (expected.width > 0 && (w != static_cast<png_uint_32>(expected.width) ||
                             h != static_cast<png_uint_32>(expected.height))) {
    throw_file_error(path, "is " + size_text(w, h) + " but camera.json says " +
                     size_text(static_cast<png_uint_32>(expected.width), static_cast<png_uint_32>(expected.height)));
  }
  if (w == 0 || h == 0 || w > static_cast<png_uint_32>(kMaxPngSide) || h > static_cast<png_uint_32>(kMaxPngSide)) {
    throw_file_error(path, "claims " + size_text(w, h) + " pixels; at most " + std::to_string(kMaxPngSide) + " a side");
  }
}

void write(const std::filesystem::path& path, int width, int height, png_uint_32 format, const void* pixels,
           size_t size_bytes, size_t bytes_per_pixel) {
  if (width <= 0 || height <= 0 || size_bytes != static_cast<size_t>(width) * height * bytes_per_pixel) {
    throw_file_error(path, "image buffer does not match its size");
  }
  PngImage png;
  png.image.width = static_cast<png_uint_32>(width);
  png.image.height = static_cast<png_uint_32>(height);
  png.image.format = format;
  if (png_image_write_to_file(&png.image, path.c_str(), 0, pixels, 0, nullptr) == 0) {
    throw_file_error(path, std::string("cannot write PNG (") + png.image.message + ")");
  }
}

}  // namespace

Gray16Image read_png_gray16(const std::filesystem::path& path, PngSize expected) {
  PngImage png;
  begin_gray_read(path, expected, png);
  if ((png.image.format & PNG_FORMAT_FLAG_LINEAR) == 0) {
    throw_file_error(path, "8-bit PNG: depth frames must be 16-bit grayscale (raw sensor units, SPEC.md)");
  }
  Gray16Image out{static_cast<int>(png.image.width), static_cast<int>(png.image.height), 1, {}};
  out.pixels.resize(static_cast<size_t>(png.image.width) * png.image.height);
  // A 16-bit file is read as PNG_FORMAT_LINEAR_Y: libpng treats 16-bit data as linear and hands
  // the stored values back unchanged (checked against the raw file in tests).
  png.image.format = PNG_FORMAT_LINEAR_Y;
  if (png_image_finish_read(&png.image, nullptr, out.pixels.data(), 0, nullptr) == 0) {
    throw_file_error(path, std::string("corrupt PNG data (") + png.image.message + ")");
  }
  return out;
}

Gray8Image read_png_gray8(const std::filesystem::path& path, PngSize expected) {
  PngImage png;
  begin_gray_read(path, expected, png);
  if ((png.image.format & PNG_FORMAT_FLAG_LINEAR) != 0) throw_file_error(path, "expected an 8-bit PNG, found 16-bit");
  Gray8Image out{static_cast<int>(png.image.width), static_cast<int>(png.image.height), 1, {}};
  out.pixels.resize(static_cast<size_t>(png.image.width) * png.image.height);
  png.image.format = PNG_FORMAT_GRAY;
  if (png_image_finish_read(&png.image, nullptr, out.pixels.data(), 0, nullptr) == 0) {
    throw_file_error(path, std::string("corrupt PNG data (") + png.image.message + ")");
  }
  return out;
}

void write_png_gray16(const std::filesystem::path& path, const Gray16Image& image) {
  write(path, image.width, image.height, PNG_FORMAT_LINEAR_Y, image.pixels.data(),
        image.pixels.size() * sizeof(uint16_t), sizeof(uint16_t));
}

void write_png_gray8(const std::filesystem::path& path, const Gray8Image& image) {
  write(path, image.width, image.height, PNG_FORMAT_GRAY, image.pixels.data(), image.pixels.size(), 1);
}

void write_png_rgb(const std::filesystem::path& path, const RgbImage& image) {
  write(path, image.width, image.height, PNG_FORMAT_RGB, image.pixels.data(), image.pixels.size(), 3);
}

}  // namespace handtrack
