#include "handtrack/draw/canvas.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <stdexcept>
#include <utility>

namespace handtrack::draw {
namespace {

uint8_t channel(double v) { return static_cast<uint8_t>(std::clamp(std::lround(v), 0L, 255L)); }

}  // namespace

Rgb mix(Rgb under, Rgb over, double alpha) {
  const double a = std::clamp(alpha, 0.0, 1.0);
  return {channel((1.0 - a) * under.r + a * over.r), channel((1.0 - a) * under.g + a * over.g),
          channel((1.0 - a) * under.b + a * over.b)};
}

Rgb shade(Rgb colour, double factor) {
  if (factor <= 1.0) return {channel(colour.r * factor), channel(colour.g * factor), channel(colour.b * factor)};
  return mix(colour, colours::kWhite, factor - 1.0);
}

Canvas::Canvas(int width, int height, Rgb background) {
  if (width < 0 || height < 0) throw std::invalid_argument("Canvas: negative size");
  image_.width = width;
  image_.height = height;
  image_.channels = 3;
  image_.pixels.resize(static_cast<size_t>(width) * static_cast<size_t>(height) * 3);
  fill(background);
}

Canvas::Canvas(RgbImage image) : image_(std::move(image)) {
  if (image_.channels != 3 || image_.width < 0 || image_.height < 0 ||
      image_.pixels.size() != static_cast<size_t>(image_.width) * static_cast<size_t>(image_.height) * 3) {
    throw std::invalid_argument("Canvas: image is not width x height x 3");
  }
}

Rgb Canvas::pixel(int x, int y) const {
  if (!contains(x, y)) return colours::kBlack;
  const size_t i = (static_cast<size_t>(y) * static_cast<size_t>(width()) + static_cast<size_t>(x)) * 3;
  return {image_.pixels[i], image_.pixels[i + 1], image_.pixels[i + 2]};
}

void Canvas::fill(Rgb colour) {
  for (size_t i = 0; i + 2 < image_.pixels.size(); i += 3) {
    image_.pixels[i] = colour.r;
    image_.pixels[i + 1] = colour.g;
    image_.pixels[i + 2] = colour.b;
  }
}

void Canvas::set_pixel(int x, int y, Rgb colour) {
  if (!contains(x, y)) return;
  const size_t i = (static_cast<size_t>(y) * static_cast<size_t>(width()) + static_cast<size_t>(x)) * 3;
  image_.pixels[i] = colour.r;
  image_.pixels[i + 1] = colour.g;
  image_.pixels[i + 2] = colour.b;
}

void Canvas::blend_pixel(int x, int y, Rgb colour, double alpha) {
  if (!contains(x, y)) return;
  if (alpha >= 1.0) {
    set_pixel(x, y, colour);
    return;
  }
  set_pixel(x, y, mix(pixel(x, y), colour, alpha));
}

void Canvas::line(double x0, double y0, double x1, double y1, Rgb colour, int thickness) {
  if (!std::isfinite(x0) || !std::isfinite(y0) || !std::isfinite(x1) || !std::isfinite(y1)) return;
  // Keep the integer arithmetic in range: clip absurd end points to a generous box first.
  const double limit = 4.0 * (std::max(width(), height()) + 16);
  const auto clamp = [limit](double v) { return std::clamp(v, -limit, limit); };
  long x = std::lround(clamp(x0));
  long y = std::lround(clamp(y0));
  const long xe = std::lround(clamp(x1));
  const long ye = std::lround(clamp(y1));
  const long dx = std::labs(xe - x);
  const long dy = -std::labs(ye - y);
  const long sx = x < xe ? 1 : -1;
  const long sy = y < ye ? 1 : -1;
  long err = dx + dy;
  const double stamp = 0.5 * thickness;
  for (;;) {
    if (thickness <= 1) {
      set_pixel(static_cast<int>(x), static_cast<int>(y), colour);
    } else {
      fill_circle(static_cast<double>(x), static_cast<double>(y), stamp, colour);
    }
    if (x == xe && y == ye) break;
    const long e2 = 2 * err;
    if (e2 >= dy) {
      err += dy;
      x += sx;
    }
    if (e2 <= dx) {
      err += dx;
      y += sy;
    }
  }
}

void Canvas::fill_circle(double cx, double cy, double radius, Rgb colour, double alpha) {
  if (!std::isfinite(cx) || !std::isfinite(cy) || !std::isfinite(radius)) return;
  const double r = std::max(radius, 0.5);
  const double r2 = r * r;
  const int x_lo = std::max(0, static_cast<int>(std::floor(cx - r)));
  const int x_hi = std::min(width() - 1, static_cast<int>(std::ceil(cx + r)));
  const int y_lo = std::max(0, static_cast<int>(std::floor(cy - r)));
  const int y_hi = std::min(height() - 1, static_cast<int>(std::ceil(cy + r)));
  for (int y = y_lo; y <= y_hi; ++y) {
    for (int x = x_lo; x <= x_hi; ++x) {
      const double ddx = x - cx;
      const double ddy = y - cy;
      if (ddx * ddx + ddy * ddy <= r2) blend_pixel(x, y, colour, alpha);
    }
  }
}

void Canvas::circle(double cx, double cy, double radius, Rgb colour, int thickness) {
  if (!std::isfinite(cx) || !std::isfinite(cy) || !std::isfinite(radius)) return;
  if (radius < 1.0) {
    set_pixel(static_cast<int>(std::lround(cx)), static_cast<int>(std::lround(cy)), colour);
    return;
  }
  // A ring [radius - thickness, radius] widened by half a pixel each side so that a thin ring is
  // closed (no gaps on the diagonals).
  const double outer = radius + 0.5;
  const double inner = std::max(0.0, radius - thickness + 0.5);
  const int x_lo = std::max(0, static_cast<int>(std::floor(cx - outer)));
  const int x_hi = std::min(width() - 1, static_cast<int>(std::ceil(cx + outer)));
  const int y_lo = std::max(0, static_cast<int>(std::floor(cy - outer)));
  const int y_hi = std::min(height() - 1, static_cast<int>(std::ceil(cy + outer)));
  for (int y = y_lo; y <= y_hi; ++y) {
    for (int x = x_lo; x <= x_hi; ++x) {
      const double d = std::hypot(x - cx, y - cy);
      if (d >= inner && d <= outer) set_pixel(x, y, colour);
    }
  }
}

void Canvas::fill_rect(int x, int y, int w, int h, Rgb colour, double alpha) {
  const int x_lo = std::max(0, x);
  const int y_lo = std::max(0, y);
  const int x_hi = std::min(width(), x + std::max(0, w));
  const int y_hi = std::min(height(), y + std::max(0, h));
  for (int yy = y_lo; yy < y_hi; ++yy) {
    for (int xx = x_lo; xx < x_hi; ++xx) blend_pixel(xx, yy, colour, alpha);
  }
}

void Canvas::rect(int x, int y, int w, int h, Rgb colour, int thickness) {
  if (w <= 0 || h <= 0) return;
  const int t = std::max(1, thickness);
  fill_rect(x, y, w, std::min(t, h), colour);
  fill_rect(x, y + h - std::min(t, h), w, std::min(t, h), colour);
  fill_rect(x, y, std::min(t, w), h, colour);
  fill_rect(x + w - std::min(t, w), y, std::min(t, w), h, colour);
}

void Canvas::blit(const Canvas& source, int x, int y) {
  for (int sy = 0; sy < source.height(); ++sy) {
    const int ty = y + sy;
    if (ty < 0 || ty >= height()) continue;
    for (int sx = 0; sx < source.width(); ++sx) set_pixel(x + sx, ty, source.pixel(sx, sy));
  }
}

}  // namespace handtrack::draw
