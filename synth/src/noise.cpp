#include "handtrack/synth/noise.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>

namespace handtrack::synth {

uint64_t Rng::next() {
  // splitmix64 (Steele, Lea, Flood 2014): a Weyl sequence through a 64-bit finaliser.
  state_ += 0x9E3779B97F4A7C15ULL;
  uint64_t z = state_;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

Rng Rng::stream(uint64_t seed, uint64_t a, uint64_t b) {
  Rng mix(seed);
  const uint64_t s1 = mix.next() ^ (a * 0xD6E8FEB86659FD93ULL);
  Rng mix2(s1);
  const uint64_t s2 = mix2.next() ^ (b * 0xA0761D6478BD642FULL);
  Rng mix3(s2);
  return Rng(mix3.next());
}

double Rng::uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

double Rng::normal() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  const double u1 = 1.0 - uniform();  // (0, 1]
  const double u2 = uniform();
  const double radius = std::sqrt(-2.0 * std::log(u1));
  const double angle = 2.0 * std::numbers::pi * u2;
  spare_ = radius * std::sin(angle);
  has_spare_ = true;
  return radius * std::cos(angle);
}

namespace {

constexpr int kTableIntervals = 4096;

// Phi^-1 by bisection on Phi(x) = erfc(-x / sqrt 2) / 2 (once, at first use).
double inverse_normal_cdf(double p) {
  double lo = -10.0, hi = 10.0;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(-mid / std::numbers::sqrt2) < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

const std::array<double, kTableIntervals + 1>& inverse_normal_table() {
  static const auto table = [] {
    std::array<double, kTableIntervals + 1> t{};
    constexpr double edge = 0.5 / kTableIntervals;
    for (int i = 0; i <= kTableIntervals; ++i) {
      t[static_cast<size_t>(i)] = inverse_normal_cdf(std::clamp(static_cast<double>(i) / kTableIntervals, edge, 1.0 - edge));
    }
    return t;
  }();
  return table;
}

}  // namespace

double Rng::fast_normal() {
  const auto& table = inverse_normal_table();
  const double x = uniform() * kTableIntervals;
  const auto i = static_cast<size_t>(x);
  const double frac = x - static_cast<double>(i);
  return table[i] + frac * (table[i + 1] - table[i]);
}

std::vector<float> Rng::correlated_normals(int width, int height, double sigma_px) {
  // White noise over the image and a margin of the kernel's reach, so that the border pixels are
  // as smooth as the rest; blurred along rows, then columns. A separable kernel g (sum 1) leaves
  // white noise with variance (sum g_i^2)^2, hence the scale.
  const int reach = static_cast<int>(std::ceil(3.0 * sigma_px));
  std::vector<double> g(static_cast<size_t>(2 * reach + 1));
  double sum = 0.0;
  for (int k = -reach; k <= reach; ++k) {
    sum += g[static_cast<size_t>(k + reach)] = std::exp(-0.5 * k * k / (sigma_px * sigma_px));
  }
  double sum_sq = 0.0;
  for (double& w : g) {
    w /= sum;
    sum_sq += w * w;
  }
  // g convolved with `src` at `src[0], src[step], ..., src[2 reach step]`.
  const auto blur = [&g, reach](const float* src, size_t step) {
    double acc = 0.0;
    for (int k = 0; k <= 2 * reach; ++k) acc += g[static_cast<size_t>(k)] * src[static_cast<size_t>(k) * step];
    return acc;
  };
  const int pw = width + 2 * reach;
  const int ph = height + 2 * reach;
  std::vector<float> white(static_cast<size_t>(pw) * static_cast<size_t>(ph));
  for (float& x : white) x = static_cast<float>(fast_normal());
  std::vector<float> rows(static_cast<size_t>(width) * static_cast<size_t>(ph));
  for (int v = 0; v < ph; ++v) {
    for (int u = 0; u < width; ++u) {
      rows[static_cast<size_t>(v) * width + u] = static_cast<float>(blur(&white[static_cast<size_t>(v) * pw + u], 1));
    }
  }
  std::vector<float> out(static_cast<size_t>(width) * static_cast<size_t>(height));
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      out[static_cast<size_t>(v) * width + u] =
          static_cast<float>(blur(&rows[static_cast<size_t>(v) * width + u], static_cast<size_t>(width)) / sum_sq);
    }
  }
  return out;
}

std::string_view sensor_name(Sensor sensor) {
  return sensor == Sensor::kStructuredLight ? "structured-light" : "generic";
}

std::optional<Sensor> parse_sensor(std::string_view name) {
  for (Sensor s : {Sensor::kGeneric, Sensor::kStructuredLight}) {
    if (sensor_name(s) == name) return s;
  }
  return std::nullopt;
}

NoiseParams sensor_noise(Sensor sensor, int width) {
  NoiseParams p;
  if (sensor == Sensor::kStructuredLight) {
    p.projector_x_mm = -50.0;
    p.noise_correlation_px = 2.5 * width / 320.0;
  }
  return p;
}

std::vector<uint8_t> projector_lit(std::span<const float> depth_mm, int width, int height, double fx,
                                   double projector_x_mm) {
  // A surface this much nearer on a pixel's projector column shades it; neighbouring pixels this
  // close in depth are one surface, which covers the projector columns between theirs.
  constexpr float kSurfaceStepMm = 10.0f;
  std::vector<uint8_t> lit(depth_mm.size(), 1);
  // The projector's row as a z-buffer over its columns round(x_p), shifted by `margin` (the image's
  // width): a surface shifted further lies outside the projector's image and is left lit.
  const long margin = width;
  std::vector<float> zbuf(static_cast<size_t>(width + 2 * margin));
  const auto bin = [&](int u, float z) { return std::lround(u - fx * projector_x_mm / z) + margin; };
  const auto inside = [&](long b) { return b >= 0 && b < static_cast<long>(zbuf.size()); };
  const auto has_surface = [](float z) { return std::isfinite(z) && z > 0.0f; };
  for (int v = 0; v < height; ++v) {
    const std::span<const float> row = depth_mm.subspan(static_cast<size_t>(v) * width, static_cast<size_t>(width));
    std::fill(zbuf.begin(), zbuf.end(), std::numeric_limits<float>::infinity());
    for (int u = 0; u < width; ++u) {
      const float z = row[static_cast<size_t>(u)];
      if (!has_surface(z)) continue;
      long lo = bin(u, z), hi = lo;
      if (u + 1 < width && has_surface(row[static_cast<size_t>(u) + 1]) &&
          std::abs(row[static_cast<size_t>(u) + 1] - z) < kSurfaceStepMm) {
        const long next = bin(u + 1, row[static_cast<size_t>(u) + 1]);
        lo = std::min(lo, next);
        hi = std::max(hi, next);
      }
      for (long b = std::max(lo, 0L); b <= std::min(hi, static_cast<long>(zbuf.size()) - 1); ++b) {
        zbuf[static_cast<size_t>(b)] = std::min(zbuf[static_cast<size_t>(b)], z);
      }
    }
    for (int u = 0; u < width; ++u) {
      const float z = row[static_cast<size_t>(u)];
      const long b = has_surface(z) ? bin(u, z) : 0;
      lit[static_cast<size_t>(v) * width + static_cast<size_t>(u)] =
          has_surface(z) && (!inside(b) || z <= zbuf[static_cast<size_t>(b)] + kSurfaceStepMm);
    }
  }
  return lit;
}

}  // namespace handtrack::synth
