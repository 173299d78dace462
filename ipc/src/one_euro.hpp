#pragma once
// The One Euro filter (Casiez, Roussel and Vogel, "1 Euro Filter: A Simple Speed-based Low-pass
// Filter for Noisy Input in Interactive Systems", CHI 2012) for one 3D point.
//
// An exponential smoother x^_i = x^_{i-1} + a (x_i - x^_{i-1}) whose smoothing factor follows the
// point's speed: slow points are smoothed hard (jitter goes), fast ones lightly (lag stays small).
//   a(f_c, dt) = 1 / (1 + tau / dt),  tau = 1 / (2 pi f_c)        (a first-order low-pass at f_c)
//   dx_i  = (x_i - x^_{i-1}) / dt,   dx^_i = dx^_{i-1} + a(f_d, dt) (dx_i - dx^_{i-1})
//   f_c,i = f_min + beta |dx^_i|
//   x^_i  = x^_{i-1} + a(f_c,i, dt) (x_i - x^_{i-1})
// For a point the speed is the norm of the 3D velocity, so its three coordinates share one cutoff
// (the paper filters each scalar separately; a shared cutoff keeps a point from being smoothed
// more along one axis than another).
//
// Thread roles: reentrant: one filter per thread at a time.
#include <cmath>
#include <numbers>

namespace handtrack::ipc::detail {

struct OneEuroParams {
  double min_cutoff_hz;  // f_min
  double beta;           // per (mm/s)
  double d_cutoff_hz;    // f_d
};

class OneEuroPoint {
 public:
  // Smoothing factor of a first-order low-pass with cutoff `cutoff_hz` sampled every `dt_s`.
  static double alpha(double cutoff_hz, double dt_s) noexcept {
    const double tau = 1.0 / (2.0 * std::numbers::pi * cutoff_hz);
    return 1.0 / (1.0 + tau / dt_s);
  }

  // Filters `x` (in place) taken `dt_s` > 0 after the previous sample; the first passes through.
  void filter(float x[3], double dt_s, const OneEuroParams& p) noexcept {
    if (!primed_) {
      for (int k = 0; k < 3; ++k) {
        value_[k] = x[k];
        speed_[k] = 0.0;
      }
      primed_ = true;
      return;
    }
    const double a_d = alpha(p.d_cutoff_hz, dt_s);
    double speed2 = 0.0;
    for (int k = 0; k < 3; ++k) {
      speed_[k] += a_d * ((x[k] - value_[k]) / dt_s - speed_[k]);
      speed2 += speed_[k] * speed_[k];
    }
    const double a = alpha(p.min_cutoff_hz + p.beta * std::sqrt(speed2), dt_s);
    for (int k = 0; k < 3; ++k) {
      value_[k] += a * (x[k] - value_[k]);
      x[k] = static_cast<float>(value_[k]);
    }
  }

  void reset() noexcept { primed_ = false; }

 private:
  double value_[3] = {0, 0, 0};  // x^_{i-1}
  double speed_[3] = {0, 0, 0};  // dx^_{i-1}, mm/s
  bool primed_ = false;
};

}  // namespace handtrack::ipc::detail
