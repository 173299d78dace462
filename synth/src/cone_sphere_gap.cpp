// surface_gap_mm (hand_model.hpp): how far apart two cone-spheres are, for motions where hands
// touch (two_clap solves the separation at which the palms meet) and for the tests that check that
// two hands never pass through each other.
#include "handtrack/synth/hand_model.hpp"

#include <algorithm>
#include <limits>

namespace handtrack::synth {
namespace {

using Eigen::Vector3d;

// Golden-section iterations per search: the bracket shrinks by 0.618^30 ~ 5e-7 of the solid's
// length (~1e-4 mm on the 250 mm forearm).
constexpr int kGoldenIterations = 30;

// min over x in [0, 1] of a convex f: golden-section search, plus both ends (where the minimum of a
// convex function on an interval often is).
template <typename F>
double minimise_convex(F&& f) {
  constexpr double kInvPhi = 0.6180339887498949;  // 1 / golden ratio
  double lo = 0.0, hi = 1.0;
  double x1 = hi - kInvPhi * (hi - lo), x2 = lo + kInvPhi * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  for (int i = 0; i < kGoldenIterations; ++i) {
    if (f1 <= f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - kInvPhi * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + kInvPhi * (hi - lo);
      f2 = f(x2);
    }
  }
  return std::min({f1, f2, f(0.0), f(1.0)});
}

// A ball that holds the whole cone-sphere: centred between its ends, radius half its length plus
// its larger end radius.
double bounding_radius(const ConeSphere& c) { return 0.5 * (c.b - c.a).norm() + std::max(c.radius_a, c.radius_b); }

}  // namespace

double surface_gap_mm(const ConeSphere& a, const ConeSphere& b) {
  // f(s, t) = |p(s) - q(t)| - r(s) - r'(t) is jointly convex, so g(s) = min_t f(s, t) is convex
  // in s: two nested one-dimensional searches find the joint minimum.
  const auto f = [&](double s, double t) {
    const Vector3d p = a.a + s * (a.b - a.a);
    const Vector3d q = b.a + t * (b.b - b.a);
    const double rp = a.radius_a + s * (a.radius_b - a.radius_a);
    const double rq = b.radius_a + t * (b.radius_b - b.radius_a);
    return (p - q).norm() - rp - rq;
  };
  return minimise_convex([&](double s) { return minimise_convex([&](double t) { return f(s, t); }); });
}

double surface_gap_mm(const std::vector<ConeSphere>& a, const std::vector<ConeSphere>& b) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& x : a) {
    for (const auto& y : b) {
      // The bounding balls' gap is a lower bound of the solids' gap: skip pairs that cannot win.
      const double bound =
          (0.5 * (x.a + x.b) - 0.5 * (y.a + y.b)).norm() - bounding_radius(x) - bounding_radius(y);
      if (bound >= best) continue;
      best = std::min(best, surface_gap_mm(x, y));
    }
  }
  return best;
}

}  // namespace handtrack::synth
