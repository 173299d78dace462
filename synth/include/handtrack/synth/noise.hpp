#pragma once
// Sensor noise model of the synthetic camera (all of it deterministic given the seed and frame).
//
//   1. Depth noise: z' = z + N(0, sigma(z)^2), sigma(z) = k z^2 (the quadratic growth of
//      triangulation and ToF range noise). k = 9.375e-6 /mm gives sigma = 1.5 mm at 400 mm,
//      0.84 mm at 300 mm and 2.3 mm at 500 mm: the 1-2 mm at arm's length of close-range sensors
//      (Creative Senz3D / RealSense SR300 class). A chosen value, not measured here.
//   2. Flying pixels: a pixel next to a depth discontinuity (> edge_threshold_mm to a 4-neighbour)
//      takes, with probability flying_pixel_probability, an intermediate depth
//      z + s (z_n - z), s ~ U(0.1, 0.9), toward the neighbour across the edge; where the neighbour
//      has no surface at all, the pixel is dropped instead with that probability.
//   3. Dropouts: every pixel with probability dropout_probability, plus at grazing angles: with
//      c = |cos| of the angle between viewing ray and surface normal, probability
//      grazing_dropout_max * clamp(1 - c / grazing_cos, 0, 1).
//   4. Range: depth outside [min_range_mm, max_range_mm] reads 0 ("no measurement").
//   5. Quantisation to quantization_mm (1 mm).

#include <cstdint>

namespace handtrack::synth {

struct NoiseParams {
  double sigma_k_per_mm = 9.375e-6;         // sigma(z) = k z^2: 1.5 mm at 400 mm
  double edge_threshold_mm = 15.0;          // depth jump that makes a discontinuity
  double flying_pixel_probability = 0.3;    // per pixel on a discontinuity
  double dropout_probability = 0.003;       // per pixel, anywhere
  double grazing_cos = 0.25;                // dropouts start below |cos| = 0.25 (~75.5 deg)
  double grazing_dropout_max = 0.9;         // ... and reach this probability at 90 deg
  double quantization_mm = 1.0;
  double min_range_mm = 100.0;
  double max_range_mm = 1500.0;

  [[nodiscard]] double sigma_mm(double depth_mm) const { return sigma_k_per_mm * depth_mm * depth_mm; }
};

// A small deterministic generator (splitmix64; Box-Muller normals) so that frames are identical on
// every platform and standard library, unlike std::normal_distribution.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  // Seeds a stream from several values (e.g. seed, frame, purpose).
  static Rng stream(uint64_t seed, uint64_t a, uint64_t b = 0);

  uint64_t next();
  double uniform();  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  double normal();   // N(0, 1), Box-Muller (exact)
  // N(0, 1) from one uniform through a 4096-interval table of the inverse normal CDF with linear
  // interpolation (about 10x cheaper than normal(); tails clipped beyond ~3.5 sigma, which lowers
  // the variance by < 0.5 %). Used per pixel.
  double fast_normal();

 private:
  uint64_t state_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace handtrack::synth
