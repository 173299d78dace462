#pragma once
// Frame-to-frame hand tracking (Sec. 5): several pose particles per frame, each initialised by
// extrapolating the two previous poses with random factors and optimised with the adaptive
// gradient ascent; the particle with the best final energy wins. A tracker starts (and restarts
// after the fit is clearly wrong) from an open hand placed at the segmented hand.
//
// Threading: a PoseTracker is used by one thread at a time. preprocess() and optimise() touch
// disjoint state, so a pipeline may run preprocess() of frame t+1 while optimise() runs on frame t
// as long as each has its own DepthInputBuilder (see HandHint).

#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/energy.hpp"
#include "handtrack/core/hand_model.hpp"
#include "handtrack/core/optimizer.hpp"
#include "handtrack/core/sequence.hpp"

#include <cstdint>
#include <optional>
#include <random>

namespace handtrack {

enum class TrackingState : uint8_t { kNoHand = 0, kTracking = 1, kRecovering = 2 };
const char* to_string(TrackingState state);

// Which hand a pose is of. The hand model is a right hand; a left hand is tracked as the right
// hand of the mirrored image (Tracker, below).
enum class Handedness : uint8_t { kRight = 0, kLeft = 1 };
const char* to_string(Handedness hand);  // "right", "left"
// Which hands a Tracker considers: one, or both (chosen at every (re)start by the better fit).
enum class HandednessMode : uint8_t { kRight, kLeft, kAuto };

// Which energies the particles optimise (Sec. 5).
enum class EnergyMode {
  kDepthOnly,   // every particle: the depth-only energy (Sec. 4.1)
  kLateFusion,  // all but one particle depth-only, one the detection-guided energy (Sec. 4.3)
};
// Late fusion as we read the paper (measurements in docs/TRACKER.md, "Late fusion"):
// - the detection-guided particle optimises "an augmented version of the depth-only energy"
//   (Sec. 1): E_sim = 0.5 (E_sim[Delta] + E_sim[Delta_l]) (SimilarityFactor::kDepthAndLabel).
//   Sec. 4.3's literal reading, Delta replaced by Delta_l, leaves depth to the label factor, whose
//   R_i = 200 mm barely constrains it; that particle never won.
// - "the pose particle which converges with the best energy value is chosen" (Sec. 5): the particles
//   are compared by one common energy, E with E_sim = (1 - lambda) E_sim[Delta] + lambda E_sim[Delta_l],
//   lambda = TrackerConfig::fusion_label_weight. With lambda = 0 (the depth-only energy) the right
//   pose of a closed hand loses to the wrong one the depth-only energy prefers (docs/TRACKER.md).
const char* to_string(EnergyMode mode);

struct TrackerConfig {
  EnergyMode mode = EnergyMode::kDepthOnly;
  DepthInputConfig input;
  EnergyWeights weights;
  OptimizerConfig optimizer;
  HandScale scale;
  int particles = 2;                 // Sec. 7: "the best accuracy was with 2 particles"
  // Sec. 5: P_i = Theta^{t-1} + alpha_ij (Theta^{t-1} - Theta^{t-2}), alpha_ij ~ N(mean, sigma).
  double extrapolation_mean = 0.5;
  double extrapolation_sigma = 0.5;
  // Late fusion: lambda, the label share of the common energy's E_sim (ours; the paper does not say
  // which energy compares the particles). Measured over 0 / 0.25 / 0.5: 0.25 was best.
  double fusion_label_weight = 0.25;
  int init_iterations = 40;          // iterations for a (re)start from the open hand
  double lost_confidence = 0.3;      // below this for `lost_frames` frames in a row: restart
  int lost_frames = 3;
  // Gross errors (issue 4; ours, the paper has no re-initialisation beyond Sec. 5's start): a
  // confidence below `suspect_confidence_ratio` x its running level (an exponential average with
  // rate `confidence_level_rate`) makes the next frame be segmented afresh and also fitted from the
  // (re)start hypotheses; the tracked pose is replaced only by a (re)start that explains more of the
  // hand. At most one such check per `check_interval_frames` frames. (Measured: docs/TRACKER.md,
  // "Recovery".)
  double suspect_confidence_ratio = 0.75;
  double confidence_level_rate = 0.1;
  int check_interval_frames = 5;
  // A (re)start must explain at least this much of the segmented surface, or there is no hand.
  double min_start_confidence = 0.6;
  uint64_t seed = 1;
};

struct TrackerOutput {
  TrackingState state = TrackingState::kNoHand;
  PoseParams params = PoseParams::Zero();
  Joints joints{};
  std::array<Eigen::Vector3d, kNumFingers> fingertips{};
  Eigen::Vector3d palm_centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d palm_normal = Eigen::Vector3d::Zero();  // out of the palm, camera frame
  double energy = 0.0;
  double confidence = 0.0;           // fraction of the hand's depth explained by the model, in [0, 1]
  double pinch_distance_mm = 0.0;    // thumb tip to index tip, surface to surface
  double pinch_strength = 0.0;       // 1 = touching, 0 = apart (>= 40 mm)
  int winning_particle = -1;         // -1: a (re)start, not a particle
  bool detection_guided_won = false;  // late fusion: the detection-guided particle won
  Handedness handedness = Handedness::kRight;
  // How clearly the last choice of hand was made, in [0, 1]: the chosen hand's confidence minus
  // the other's at that (re)start (1 when only one hand is considered).
  double handedness_confidence = 1.0;
  // Which hand this is: a number that stays the same while the hand stays in view (through
  // "recovering" frames and a change of the chosen hand) and is new each time a hand appears after
  // a frame without one; 0 when there is no hand. Counts from 1 within one Tracker.
  uint32_t hand_id = 0;
};

class PoseTracker {
 public:
  explicit PoseTracker(TrackerConfig config = {});

  // Where segmentation should look for the hand in the next frame: none before the first pose,
  // after the fit was lost, and before a check against a (re)start (the next frame is segmented
  // afresh). Allocates nothing.
  [[nodiscard]] std::optional<HandHint> hint() const;
  // Optimises the pose for one frame's C_I and updates the history.
  TrackerOutput optimise(const DepthInput& input);
  // Forget the history: the next frame starts from the open hand.
  void reset();
  // Replaces the tracker's belief about the last pose (both previous poses) by `pose`: how tests
  // knock the tracker off to check that it recovers.
  void override_pose(const PoseParams& pose);

  [[nodiscard]] const HandModel& model() const { return model_; }
  [[nodiscard]] const TrackerConfig& config() const { return config_; }
  void set_scale(const HandScale& scale);
  // Open (or closed) hand placed at the segmented hand of `input` (Sec. 5's start pose), turned by
  // `in_plane_offset_rad` about the camera axis.
  [[nodiscard]] PoseParams initial_pose(const DepthInput& input, double in_plane_offset_rad = 0.0,
                                        bool closed = false) const;
  // How much of the segmented hand the posed model explains, in [0, 1].
  [[nodiscard]] double confidence(const DepthInput& input, const PosedHand& hand) const;

 private:
  TrackerOutput describe(const PoseParams& params, double energy, TrackingState state);
  // A pose and how much of the segmented hand it explains.
  struct Fit {
    OptimizerResult result{PoseParams::Zero(), -1e300};
    double confidence = -1.0;
  };
  // Sec. 5's start: every (re)start hypothesis optimised on `input`, the best by confidence.
  Fit restart(const DepthInput& input);
  // After a frame's fit: tracks the running confidence level and decides whether the next frame
  // checks the tracked pose against a (re)start.
  enum class CheckOutcome { kNone, kTrackedKept, kRestartWon };
  void watch_confidence(double confidence, CheckOutcome check);
  // Late fusion with part labels on the leaves.
  [[nodiscard]] bool fuses(const DepthInput& input) const;

  TrackerConfig config_;
  HandModel model_;
  // Late fusion: the particles' common energy at `params` (see EnergyMode).

  PoseEnergy energy_;            // depth-only (Sec. 4.1)
  PoseEnergy guided_energy_;     // detection-guided (Sec. 4.3), augmented: depth and label factors
  PoseEnergy common_energy_;     // late fusion: compares the particles (label share fusion_label_weight)
  AdaptiveGradientAscent optimizer_;
  PosedHand scratch_;
  std::mt19937_64 rng_;
  std::optional<PoseParams> previous_;
  std::optional<PoseParams> before_previous_;
  int low_confidence_run_ = 0;
  bool recovering_ = false;
  double confidence_level_ = 0.0;     // running level of the tracked pose's confidence
  bool check_next_ = false;           // the next frame: fresh segmentation and a (re)start too
  int frames_since_check_ = 0;
};

// preprocess + optimise on one thread: what handtrack-eval and the single-threaded path use.
// Depth image -> pose, for one hand at a time: the preprocessing (DepthInputBuilder) and the
// optimiser (PoseTracker) of one hand, and the choice of hand.
//
// A left hand is the mirror image of a right hand about the camera's x = 0 plane, which the camera
// sees exactly as the image flipped left to right with the principal point at
// u = (width - 1) - cx (pixel centres at integer u). So a left hand is tracked as the right hand of
// the mirrored image, by a second builder and tracker that only ever see mirrored images, and its
// joints, fingertips, palm centre and normal are mirrored back (x negated); `params` stay those of
// the right-hand model in the mirrored image. With HandednessMode::kAuto both hands are fitted at
// every (re)start (no hand yet, lost, recovering) and the one that explains more of the hand
// (confidence) is kept; while it tracks, only it runs.
class Tracker {
 public:
  explicit Tracker(TrackerConfig config = {}, HandednessMode mode = HandednessMode::kRight);
  TrackerOutput track(const DepthImage& depth, const PixelLabeller* labeller = nullptr);
  // The current hand's last input and tracker (for a left hand: of the mirrored image).
  [[nodiscard]] const DepthInput& last_input() const { return side(current_).builder.last(); }
  [[nodiscard]] PoseTracker& pose_tracker() { return side(current_).pose; }
  void reset();

 private:
  struct Side {
    explicit Side(const TrackerConfig& config) : builder(config.input), pose(config) {}
    DepthInputBuilder builder;
    PoseTracker pose;
  };
  [[nodiscard]] const Side& side(Handedness hand) const { return hand == Handedness::kLeft ? left_ : right_; }
  Side& side(Handedness hand) { return hand == Handedness::kLeft ? left_ : right_; }
  TrackerOutput track_as(Handedness hand, const DepthImage& depth, const PixelLabeller* labeller);
  void identify(TrackerOutput& out);  // sets out.hand_id

  HandednessMode mode_;
  Side right_;
  Side left_;
  Handedness current_ = Handedness::kRight;
  double handedness_confidence_ = 1.0;
  bool tracking_ = false;  // the current hand tracked in the last frame
  uint32_t hand_id_ = 0;   // of the hand in view; 0: none in the last frame
  uint32_t last_hand_id_ = 0;
  DepthImage mirrored_;    // scratch: the mirrored frame for the left hand
};

}  // namespace handtrack
