#pragma once
// Gradient ascent with adaptive step length (Sec. 5: "we adopt the fast gradient-based optimizer
// with adaptive step length proposed by Stoll et al. 2011"). Each parameter j keeps its own step
// s_j and moves by s_j sign(dE/dTheta_j); s_j grows by `grow` while the sign of its derivative
// holds and shrinks by `shrink` when it flips (the step overshot a maximum; that move is then not
// repeated). The sign makes the update independent of how the terms scale the gradient in mm and
// radians; the best pose seen is returned, so a last overshoot costs nothing.

#include "handtrack/core/energy.hpp"

namespace handtrack {

struct OptimizerConfig {
  int iterations = 10;              // Sec. 5 / Sec. 7: "we therefore fixed the number of iterations to be 10"
  double step_translation_mm = 2.0; // initial steps per parameter kind
  double step_rotation_rad = 0.02;
  double step_angle_rad = 0.05;
  double grow = 1.2;
  double shrink = 0.5;
  double min_step_factor = 0.01;    // steps stay within [initial * min_step_factor,
  double max_step_factor = 8.0;     //                    initial * max_step_factor]
};

struct OptimizerResult {
  PoseParams params = PoseParams::Zero();
  double energy = 0.0;
};

class AdaptiveGradientAscent {
 public:
  explicit AdaptiveGradientAscent(OptimizerConfig config = {}) : config_(config) {}
  // Maximises `energy` from `start` for `iterations` steps (config's when < 0).
  OptimizerResult maximise(const PoseEnergy& energy, const EnergyFrame& frame, const PoseParams& start,
                           PosedHand& scratch, int iterations = -1) const;
  [[nodiscard]] const OptimizerConfig& config() const { return config_; }

 private:
  OptimizerConfig config_;
};

}  // namespace handtrack
