#include "handtrack/draw/colormap.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace handtrack::draw {
namespace {

// Depth to [0, 1] with near = 0; NaN for no measurement.
double depth_fraction(double depth_mm, double near_mm, double far_mm) {
  if (!(depth_mm > 0.0) || !std::isfinite(depth_mm)) return std::nan("");
  const double span = far_mm - near_mm;
  if (!(std::abs(span) > 1e-9)) return 0.0;
  return std::clamp((depth_mm - near_mm) / span, 0.0, 1.0);
}

struct Stop {
  double t;
  Rgb colour;
};
// Control points of a rainbow in the spirit of Google's "Turbo": perceptually smoother than jet,
// dark at both ends. Chosen by eye for this project.
constexpr std::array<Stop, 10> kTurboStops = {{
    {0.00, {48, 18, 59}},
    {0.13, {67, 98, 222}},
    {0.25, {40, 160, 250}},
    {0.38, {25, 220, 190}},
    {0.50, {100, 250, 90}},
    {0.62, {190, 240, 50}},
    {0.72, {245, 195, 40}},
    {0.82, {250, 130, 30}},
    {0.92, {215, 60, 10}},
    {1.00, {122, 4, 3}},
}};

// Part colours (hand_layout.hpp labels): a hue per finger, the distal part lighter.
constexpr std::array<Rgb, 13> kPartColours = {{
    {40, 40, 40},     // 0 background
    {205, 160, 120},  // 1 palm
    {170, 30, 30},    // 2 thumb metacarpal
    {235, 70, 50},    // 3 thumb proximal
    {255, 150, 130},  // 4 thumb distal
    {210, 160, 0},    // 5 index proximal
    {255, 235, 90},   // 6 index middle+distal
    {30, 150, 50},    // 7 middle proximal
    {130, 235, 110},  // 8 middle middle+distal
    {20, 100, 200},   // 9 ring proximal
    {110, 190, 255},  // 10 ring middle+distal
    {125, 45, 175},   // 11 little proximal
    {215, 145, 255},  // 12 little middle+distal
}};

constexpr std::array<Rgb, 8> kSeriesColours = {{
    {31, 100, 190},   // blue
    {240, 120, 20},   // orange
    {40, 160, 60},    // green
    {210, 40, 40},    // red
    {140, 90, 190},   // purple
    {140, 85, 70},    // brown
    {220, 100, 180},  // pink
    {20, 170, 180},   // teal
}};

}  // namespace

Rgb depth_gray(double depth_mm, double near_mm, double far_mm) {
  const double f = depth_fraction(depth_mm, near_mm, far_mm);
  if (std::isnan(f)) return colours::kBlack;
  // 255 (near) .. 60 (far): far surfaces stay distinguishable from "no measurement" (black).
  const auto level = static_cast<uint8_t>(std::lround(255.0 - f * (255.0 - 60.0)));
  return {level, level, level};
}

Rgb turbo(double t) {
  if (!std::isfinite(t)) t = 0.0;
  t = std::clamp(t, 0.0, 1.0);
  for (size_t i = 1; i < kTurboStops.size(); ++i) {
    if (t <= kTurboStops[i].t) {
      const Stop& a = kTurboStops[i - 1];
      const Stop& b = kTurboStops[i];
      return mix(a.colour, b.colour, (t - a.t) / (b.t - a.t));
    }
  }
  return kTurboStops.back().colour;
}

Rgb depth_turbo(double depth_mm, double near_mm, double far_mm) {
  const double f = depth_fraction(depth_mm, near_mm, far_mm);
  if (std::isnan(f)) return colours::kBlack;
  return turbo(1.0 - f);
}

Rgb part_colour(int label) {
  if (label < 0 || label >= static_cast<int>(kPartColours.size())) return {255, 0, 255};
  return kPartColours[static_cast<size_t>(label)];
}

Rgb series_colour(int i) {
  const auto n = static_cast<int>(kSeriesColours.size());
  return kSeriesColours[static_cast<size_t>(((i % n) + n) % n)];
}

}  // namespace handtrack::draw
