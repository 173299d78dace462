#include "handtrack/core/optimizer.hpp"

#include <algorithm>
#include <cmath>

namespace handtrack {

OptimizerResult AdaptiveGradientAscent::maximise(const PoseEnergy& energy, const EnergyFrame& frame,
                                                 const PoseParams& start, PosedHand& scratch, int iterations) const {
  if (iterations < 0) iterations = config_.iterations;
  PoseParams initial_step;
  for (int j = 0; j < kNumPoseParams; ++j) {
    switch (param_kind(j)) {
      case ParamKind::kTranslation: initial_step[j] = config_.step_translation_mm; break;
      case ParamKind::kRotation: initial_step[j] = config_.step_rotation_rad; break;
      case ParamKind::kAngle: initial_step[j] = config_.step_angle_rad; break;
    }
  }
  PoseParams step = initial_step;
  PoseParams theta = start;
  PoseGradient gradient;
  PoseGradient previous = PoseGradient::Zero();
  OptimizerResult best{start, energy.evaluate(frame, start, scratch, &gradient)};
  for (int it = 0; it < iterations; ++it) {
    for (int j = 0; j < kNumPoseParams; ++j) {
      const double g = gradient[j];
      const double agreement = g * previous[j];
      double s = step[j];
      if (agreement > 0.0) s *= config_.grow;
      if (agreement < 0.0) s *= config_.shrink;
      step[j] = std::clamp(s, initial_step[j] * config_.min_step_factor, initial_step[j] * config_.max_step_factor);
      // After a flip the derivative is forgotten, so the next iteration neither grows nor shrinks.
      previous[j] = agreement < 0.0 ? 0.0 : g;
      if (agreement >= 0.0 && g != 0.0) theta[j] += g > 0.0 ? step[j] : -step[j];
    }
    // The last step's gradient would go unused: its energy alone (the same value, without the
    // gradient's second pass over the pairs and the chain to Theta).
    const bool last = it + 1 == iterations;
    const double e = energy.evaluate(frame, theta, scratch, last ? nullptr : &gradient);
    if (e > best.energy && std::isfinite(e)) best = {theta, e};
  }
  return best;
}

}  // namespace handtrack
