#pragma once
// An RGB canvas over handtrack::RgbImage for the offline tools' pictures (handtrack-view, the
// evaluator's error plot). Coordinates are pixels, x right, y down, with pixel (x, y) centred on
// the point (x, y): a shape at (10.0, 4.0) is centred on pixel (10, 4) and a line's end points are
// rounded to the nearest pixel. Everything outside the canvas is clipped silently; non-finite
// coordinates draw nothing: drawing never fails.

#include "handtrack/core/png_io.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace handtrack::draw {

struct Rgb {
  uint8_t r = 0;
  uint8_t g = 0;
  uint8_t b = 0;
  friend bool operator==(const Rgb&, const Rgb&) = default;
};

// (1 - alpha) * under + alpha * over, per channel, alpha clamped to [0, 1].
Rgb mix(Rgb under, Rgb over, double alpha);
// The colour scaled toward black (factor < 1) or white (factor > 1).
Rgb shade(Rgb colour, double factor);

namespace colours {
inline constexpr Rgb kBlack{0, 0, 0};
inline constexpr Rgb kWhite{255, 255, 255};
inline constexpr Rgb kGray{128, 128, 128};
inline constexpr Rgb kDarkGray{48, 48, 48};
inline constexpr Rgb kLightGray{200, 200, 200};
inline constexpr Rgb kRed{230, 40, 40};
inline constexpr Rgb kGreen{40, 200, 70};
inline constexpr Rgb kBlue{50, 100, 240};
inline constexpr Rgb kYellow{250, 220, 40};
}  // namespace colours

class Canvas {
 public:
  Canvas() = default;
  Canvas(int width, int height, Rgb background = colours::kBlack);
  // Draws on an existing image; throws std::invalid_argument unless it has 3 channels and
  // width * height * 3 pixels.
  explicit Canvas(RgbImage image);

  [[nodiscard]] int width() const { return image_.width; }
  [[nodiscard]] int height() const { return image_.height; }
  [[nodiscard]] bool contains(int x, int y) const { return x >= 0 && y >= 0 && x < width() && y < height(); }
  // The pixel's colour; black outside the canvas.
  [[nodiscard]] Rgb pixel(int x, int y) const;
  [[nodiscard]] const RgbImage& image() const { return image_; }

  void fill(Rgb colour);
  void set_pixel(int x, int y, Rgb colour);
  void blend_pixel(int x, int y, Rgb colour, double alpha);

  // A line from (x0, y0) to (x1, y1) inclusive (Bresenham on the rounded end points); thickness > 1
  // stamps a disc of that diameter along it.
  void line(double x0, double y0, double x1, double y1, Rgb colour, int thickness = 1);
  // Every pixel whose centre lies within `radius` of (cx, cy) (at least the centre pixel).
  void fill_circle(double cx, double cy, double radius, Rgb colour, double alpha = 1.0);
  // The ring of pixels whose centres lie within [radius - thickness, radius] of (cx, cy); a radius
  // below one pixel draws the centre pixel.
  void circle(double cx, double cy, double radius, Rgb colour, int thickness = 1);
  // Axis-aligned rectangle covering pixels x..x+w-1, y..y+h-1.
  void fill_rect(int x, int y, int w, int h, Rgb colour, double alpha = 1.0);
  void rect(int x, int y, int w, int h, Rgb colour, int thickness = 1);
  // Copies `source` with its top-left corner at (x, y).
  void blit(const Canvas& source, int x, int y);

  // Text in the built-in 5x7 font (printable ASCII; other bytes draw as '?'), each font pixel a
  // scale x scale block, top-left corner of the first glyph at (x, y). '\n' starts a new line.
  // Returns the width in pixels of the widest line drawn.
  int text(int x, int y, std::string_view text, Rgb colour, int scale = 1);

  void write_png(const std::filesystem::path& path) const { write_png_rgb(path, image_); }

 private:
  RgbImage image_;
};

// The built-in font's metrics: a glyph is 5x7 font pixels in a 6x9 cell (one column and two rows of
// spacing), all multiplied by `scale`.
inline constexpr int kGlyphWidth = 5;
inline constexpr int kGlyphHeight = 7;
inline constexpr int kGlyphAdvance = 6;
inline constexpr int kLineAdvance = 9;
// Size in pixels of `text` drawn at `scale` (widest line; lines * kLineAdvance * scale, minus the
// spacing below the last line).
int text_width(std::string_view text, int scale = 1);
int text_height(std::string_view text, int scale = 1);
// `text` with its lines broken so that none is wider than `max_width` pixels at `scale`: at the
// last space that fits (the space dropped), or mid-word where a word alone is too wide.
std::string wrap_text(std::string_view text, int max_width, int scale = 1);

}  // namespace handtrack::draw
