#pragma once
// User-specific hand model (Sec. 6): "a default hand model is scaled using three parameters: hand
// length, width, and variance of Gaussians. To find the scaling parameters for a user, we perform a
// greedy search over a fixed range for each scaling parameter. At each point on this parameter grid
// we evaluate the energy function value from Equation 2. The parameters that obtain the best energy
// are selected."
//
// Greedy: one scale parameter at a time (length, then width, then sigma), the others held (sigma
// follows width in width's search, see below), over
// the grid lo, lo + step, .., hi; then a second pass of each within a few steps of the value found.
// At each grid point the model is rebuilt and the pose of every calibration frame re-fitted with
// eq. 2 (a few iterations, warm-started from the pose fitted at the neighbouring grid point, so the
// pose follows the scale), then the fit is scored.
//
// Deviation from the paper (measured, docs/TRACKER.md "Your hand model"): the score is not eq. 2.
// E_sim is normalised by E(C_I, C_I) alone, so it grows with the model (bigger Gaussians overlap
// more data) and drives the search to the grid corners. We score each frame by how much of the
// hand's area the model's surface and the data disagree on (surface_agreement in the .cpp: the
// model drawn as the solid its 1-sigma spheres sweep along each finger and across the palm, depths
// compared). Width and sigma trade off in a silhouette (a narrower hand with thicker fingers looks
// much the same), so the score carries a prior that sigma follows width, as finger thickness
// follows hand width in adult hands: kSigmaWidthPrior (log(sigma / width))^2, 0.005 at 5 %, about
// the score's own spread between neighbouring grid points.

#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/hand_model.hpp"
#include "handtrack/core/tracker.hpp"

#include <filesystem>
#include <optional>
#include <vector>

namespace handtrack {

struct CalibrationConfig {
  double lo = 0.85;      // the fixed range of every scale parameter (Sec. 6; the range is ours)
  double hi = 1.15;
  double step = 0.025;   // grid step: at most 1.25 % from the best grid value
  int rounds = 2;        // passes over the three parameters: the first over the whole range,
  int refine_steps = 2;  // the later ones this many steps either side of the value found
  int iterations = 10;   // pose re-fit per grid point and frame (Sec. 7's 10 iterations)
};

inline constexpr double kSigmaWidthPrior = 2.0;

struct CalibrationFrame {
  const DepthInput* input = nullptr;
  PoseParams pose = PoseParams::Zero();  // the tracked pose: where the re-fit starts
};

struct CalibrationResult {
  HandScale scale;
  double score = 0.0;      // the search's score at `scale`: mean surface agreement less the prior
  int evaluations = 0;     // grid points evaluated
};

// The configuration that tracks the frames a calibration is fitted on: `config` with the paper's
// w_s (kPapersSmoothness) instead of the tracker's lighter default, and without self-calibration
// (a scale changed part-way would leave the frames' poses of two models). Offline there is no lag to
// save, and the smoother poses are the better starts for the grid's re-fits: the seven subjects of
// test_hand_calibration over three seeds, 2 of 63 scale estimates beyond 5 % with w_s = 1 and 5 with
// 0.1 (mean error 1.98 against 2.25 %; docs/TRACKER.md, "w_s, the weight of E_smo").
TrackerConfig calibration_tracker_config(TrackerConfig config = {});

// Greedy grid search from `tracker.scale`; throws std::invalid_argument without frames or with a
// bad grid.
CalibrationResult calibrate_hand_scale(const std::vector<CalibrationFrame>& frames, const TrackerConfig& tracker,
                                       const CalibrationConfig& config = {});

// The frames a calibration uses: C_I and the tracked pose of frames that were tracked well
// (confidence >= min_confidence), at most one every `stride` frames, at most `max_frames`.
// C_I is segmented anew with the forearm cut kWristSlackMm further down the arm than tracking cuts
// it (tracking cuts just below the tracked model's wrist, which would bake the tracking model's
// length into the data); the score cuts the data at each candidate model's own wrist.
inline constexpr double kWristSlackMm = 40.0;  // ~20 % of a hand length: subjects up to 1.2x
// The calibration frames' quadtree is finer than tracking's (leaves down to one pixel, split until
// their depth range is under 5 mm, not 20): the poses re-fitted at each grid point follow the
// hand's outline to about a pixel, where the score's width differences lie (0.3 px for 5 %).
inline constexpr double kFineQuadtreeThresholdMm = 5.0;
class CalibrationSet {
 public:
  struct Options {
    int stride = 5;               // frames of a 60 fps sequence between two kept frames
    int max_frames = 12;
    double min_confidence = 0.8;  // TrackerOutput::confidence
  };
  CalibrationSet(Options options, const DepthInputConfig& input) : options_(options), input_config_(input) {}
  CalibrationSet() : CalibrationSet(Options{}, DepthInputConfig{}) {}

  // Offers one tracked frame: its depth, the tracker's output and the hint the tracker gives after
  // it (PoseTracker::hint()). Returns whether it was kept. The same as due() and then keep().
  bool offer(const DepthImage& depth, const TrackerOutput& tracked, const std::optional<HandHint>& hint);
  // The two halves of offer(), for a caller whose depth costs a copy: due() counts the frame and
  // says whether the set wants it (a good fit, `stride` frames after the last kept one, the set not
  // full); keep() then segments the depth of a frame that is due and keeps it if it shows a hand.
  bool due(const TrackerOutput& tracked, const std::optional<HandHint>& hint);
  bool keep(const DepthImage& depth, const TrackerOutput& tracked, const HandHint& hint);
  // Forgets the frames kept (another hand's frames come next).
  void clear();
  [[nodiscard]] bool full() const { return static_cast<int>(inputs_.size()) >= options_.max_frames; }
  [[nodiscard]] int size() const { return static_cast<int>(inputs_.size()); }
  // Views into this set: valid while it lives and is not offered more frames.
  [[nodiscard]] std::vector<CalibrationFrame> frames() const;

 private:
  Options options_;
  DepthInputConfig input_config_;
  int since_kept_ = 0;
  std::vector<DepthInput> inputs_;
  std::vector<PoseParams> poses_;
};

// A hand profile file (JSON: {"hand_length": .., "hand_width": .., "gaussian_sigma": ..}, each a
// factor of the default adult hand in [kMinProfileScale, kMaxProfileScale]).
// Loading throws std::runtime_error with one line naming the file and the field.
inline constexpr double kMinProfileScale = 0.5;
inline constexpr double kMaxProfileScale = 2.0;
void save_hand_profile(const std::filesystem::path& file, const HandScale& scale);
HandScale load_hand_profile(const std::filesystem::path& file);

}  // namespace handtrack
