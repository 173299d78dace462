#pragma once
// User-specific hand model (Sec. 6): "a default hand model is scaled using three parameters: hand
// length, width, and variance of Gaussians. To find the scaling parameters for a user, we perform a
// greedy search over a fixed range for each scaling parameter. At each point on this parameter grid
// we evaluate the energy function value from Equation 2. The parameters that obtain the best energy
// are selected."
//
// Greedy: one scale parameter at a time (length, then width, then sigma), the others held, over
// a grid in [lo, hi]; at each grid point the model is rebuilt, the pose of every calibration frame
// re-fitted for a few iterations from its tracked pose, and the summed energy compared. Two rounds.

#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/hand_model.hpp"
#include "handtrack/core/tracker.hpp"

#include <filesystem>
#include <vector>

namespace handtrack {

struct CalibrationConfig {
  double lo = 0.85;      // fixed range of every scale parameter
  double hi = 1.15;
  double step = 0.025;
  int rounds = 2;        // passes over the three parameters
  int iterations = 10;   // pose re-fit per grid point and frame
};

struct CalibrationFrame {
  const DepthInput* input = nullptr;
  PoseParams pose = PoseParams::Zero();  // the tracked pose: where the re-fit starts
};

struct CalibrationResult {
  HandScale scale;
  double energy = 0.0;
  int evaluations = 0;  // grid points evaluated
};

CalibrationResult calibrate_hand_scale(const std::vector<CalibrationFrame>& frames, const TrackerConfig& tracker,
                                       const CalibrationConfig& config = {});

// A hand profile file (JSON: {"hand_length": .., "hand_width": .., "gaussian_sigma": ..}).
// Loading throws std::runtime_error naming the file and the field.
void save_hand_profile(const std::filesystem::path& file, const HandScale& scale);
HandScale load_hand_profile(const std::filesystem::path& file);

}  // namespace handtrack
