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
//   6. Structured light and stereo (Sensor::kStructuredLight; off in the generic model):
//      - the projector's shadow: a projector (or second camera) at x = projector_x_mm in the camera
//        frame, rectified (same orientation, same rows), lights a point P seen at column u along its
//        own column x_p = u - fx projector_x_mm / z. Along a row, of the points on one projector
//        column only the nearest is lit; the others read 0. Beside every surface nearer than what is
//        behind it lies a band of fx |projector_x_mm| (1 / z_near - 1 / z_far) pixels without depth,
//        on the side away from the projector.
//      - correlated noise: the N(0, 1) of item 1 is a smooth field, white noise blurred by a
//        Gaussian of noise_correlation_px pixels (standard deviation) and scaled back to unit
//        variance, as block-matching sensors give (neighbouring pixels share most of their window).
//      Measured on the SR305 frames of ../shared/data/real-sr305 (640x480, f 476 px; 230536/90): the
//      band without depth to the image right of the hand is 14-20 px wide where the hand at 540-565
//      mm stands in front of the body at 840-900 mm, fx |b| (1/z_near - 1/z_far) with |b| of 46-64
//      mm; the depth's residual from a quadratic over 30 x 30 px correlates 0.75 at 5 px and 0.59 at
//      8 px, a Gaussian blur of about 5 px at that width.

#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

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
  double projector_x_mm = 0.0;        // 0: no projector shadow
  double noise_correlation_px = 0.0;  // 0: independent per pixel

  [[nodiscard]] double sigma_mm(double depth_mm) const { return sigma_k_per_mm * depth_mm * depth_mm; }
};

// Classes of depth sensor whose artefacts the synthetic camera imitates.
enum class Sensor {
  kGeneric,          // items 1-5 above (the benchmark's camera)
  kStructuredLight,  // and item 6 as the SR305 frames show it: a projector 50 mm to the camera's left
                     // (its shadow to the image right of a nearer surface), noise correlated over
                     // 2.5 px at 320 px wide
};
std::string_view sensor_name(Sensor sensor);  // "generic", "structured-light"
std::optional<Sensor> parse_sensor(std::string_view name);
// The noise of `sensor` in an image `width` pixels wide (the correlation scales with it).
NoiseParams sensor_noise(Sensor sensor, int width);

// Item 6's shadow: for a clean depth image (mm, row-major; a non-finite value is no surface) seen
// with focal length fx, 1 where the projector at projector_x_mm lights the pixel's surface, 0 where
// a surface nearer by more than 10 mm lies on the same projector column of the row (or the pixel has
// no surface). Each pixel covers one projector column's width about x_p in a z-buffer of the row.
std::vector<uint8_t> projector_lit(std::span<const float> depth_mm, int width, int height, double fx,
                                   double projector_x_mm);

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
  // Item 6's correlated noise: width x height N(0, 1) values (row-major), white noise blurred by a
  // Gaussian of `sigma_px` (> 0) pixels and scaled back to unit variance.
  std::vector<float> correlated_normals(int width, int height, double sigma_px);

 private:
  uint64_t state_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace handtrack::synth
