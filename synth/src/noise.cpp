#include "handtrack/synth/noise.hpp"

#include <algorithm>
#include <array>
#include <cmath>
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

}  // namespace handtrack::synth
