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
#include "handtrack/core/start_search.hpp"

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <utility>

namespace handtrack {

enum class TrackingState : uint8_t { kNoHand = 0, kTracking = 1, kRecovering = 2 };
const char* to_string(TrackingState state);

// Which hand a pose is of. The hand model is a right hand; a left hand is tracked as the right
// hand of the mirrored image (Tracker, below).
enum class Handedness : uint8_t { kRight = 0, kLeft = 1 };
const char* to_string(Handedness hand);  // "right", "left"
// Which hands a Tracker considers: one, or both (chosen at every (re)start by the better fit).
enum class HandednessMode : uint8_t { kRight, kLeft, kAuto };
const char* to_string(HandednessMode mode);  // "right", "left", "auto"
bool parse_handedness_mode(const std::string& text, HandednessMode* mode);
// Where the camera looks at the user's hands from (ours): what the depth cannot tell. A right
// hand's palm and a left hand's back are mirror images through the hand's plane, one surface to
// the camera where the hand is flat, so where a hand's evidence leaves its side open the tracker
// goes by the arrangement (Tracker::weigh, HandsTracker):
//   kFacing       a camera facing the user (on a desk or a screen): a hand shows its palm, and
//                 of two hands the right one is on the image's left;
//   kHeadMounted  a camera at the user's eyes (a headset) looking where the hands reach: a hand
//                 shows its back, and the right hand is on the image's right.
enum class CameraArrangement : uint8_t { kFacing, kHeadMounted };
const char* to_string(CameraArrangement arrangement);  // "facing", "head-mounted"
bool parse_camera_arrangement(const std::string& text, CameraArrangement* arrangement);

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
const char* to_string(EnergyMode mode);  // "late-fusion", "depth-only"
bool parse_energy_mode(const std::string& text, EnergyMode* mode);

struct TrackerConfig {
  // PoseTracker's default: depth-only (it has no labels unless given a labeller); handtrackd and
  // handtrack-eval default to late fusion with the shipped forest.
  EnergyMode mode = EnergyMode::kDepthOnly;
  HandednessMode handedness = HandednessMode::kAuto;  // Tracker only (a PoseTracker is one hand)
  CameraArrangement arrangement = CameraArrangement::kFacing;  // auto handedness's open choices
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
  // Iterations per (re)start hypothesis. 40 left the start of adbadd (palm view) 30 mm off for 40
  // frames with the forest of all views; 80: the broadened benchmark 27.9 -> 26.1 mm (right hands,
  // 3 seeds, 150 frames), the palm view 10.1 -> 9.6 mm.
  int init_iterations = 80;
  double lost_confidence = 0.3;      // below this for `lost_frames` frames in a row: restart
  int lost_frames = 3;
  // Gross errors (issue 4; ours, the paper has no re-initialisation beyond Sec. 5's start): a
  // confidence below `suspect_confidence_ratio` x its running level (an exponential average with
  // rate `confidence_level_rate`) makes the next frame be segmented afresh and also fitted from the
  // (re)start hypotheses; the tracked pose is replaced only by a (re)start that explains clearly
  // more of the hand (check_replace_margin). At most one such check per `check_interval_frames`
  // frames. (Measured: docs/TRACKER.md, "Recovery".)
  double suspect_confidence_ratio = 0.75;
  double confidence_level_rate = 0.1;
  int check_interval_frames = 5;
  // A wrong fit that no fall of the confidence betrays (a (re)start that chose the wrong pose and
  // kept it) is checked the same way every `recheck_interval_frames` frames while the running
  // level is below `recheck_below_confidence`; 0 frames: never. A fit that explains most of the
  // hand is never rechecked (docs/TRACKER.md, "Rechecks of a mediocre fit").
  int recheck_interval_frames = 30;
  double recheck_below_confidence = 0.8;
  // A check's (re)start pose replaces the tracked one only when its fit score (fit_score: the
  // share of the hand explained times the share of labels agreeing) is higher by more than this.
  // Two fits a few hundredths apart are a coin flip: on the broadened benchmark (seeds 1-6)
  // replacements by less than 0.1 made the fingertip error worse on average, by more made it
  // better (docs/TRACKER.md, "Rechecks of a mediocre fit").
  double check_replace_margin = 0.1;
  // 0: a check is made on one frame (10-16 ms here). N > 0: spread over frames at about N optimiser
  // iterations per frame on top of tracking (PoseTracker::continue_check): at 64, 4 hypotheses
  // screened per frame, then each kept one refined by 21 (depth-only) or 10 (late fusion)
  // iterations, 10-19 frames in all. A latency setting: spread checks keep every tracked frame
  // within about 3 ms, but repair a gross error in about 14 frames instead of 2 and cost the
  // broadened benchmark 0.5 mm (docs/TRACKER.md, "Checks spread over frames").
  int check_iterations_per_frame = 0;
  // true: a check's whole (re)start search runs on a thread of its own at the lowest scheduling
  // priority (SCHED_IDLE: only CPU time no other thread wants) on a copy of the check's first frame,
  // and its result is taken at the first frame after it finishes (check_iterations_per_frame is
  // then unused). No tracked frame waits for a search; a gross error is repaired when the idle CPU
  // has done the search (a few frames at a camera's rate), and on a machine with no idle CPU only
  // by the lost rule. As with checks spread over frames, a hand chosen by a trial is not put to a
  // trial again and a hand lost during a trial is not (re)started again (Tracker). handtrackd's
  // default; the library's is false, which keeps every run of handtrack-eval the same
  // (docs/TRACKER.md, "Checks in the background").
  bool background_checks = false;
  // A (re)start must explain at least this much of the segmented surface, or there is no hand.
  double min_start_confidence = 0.6;
  // Auto handedness (Tracker; ours): the hand is chosen by evidence over frames, not on one frame.
  // From every (re)start both hands are tracked, each by its own PoseTracker, in a trial of at least
  // `handedness_trial_frames` frames: the evidence is an exponential average (rate
  // `handedness_evidence_rate`) of the fit-score difference between the left and the right hand,
  // and the hand it favours is reported. The trial ends, and the other hand is dropped, once the
  // average is clear by `handedness_margin` after the minimum frames; until then both go on.
  // Evidence within `handedness_tie` is a tie (Tracker::weigh; a flat hand, depth-only, stays
  // within +-0.005 from either side), which leaves the hand as the trial's first frame chose it. One
  // frame's choice was wrong for whole sequences: a fist is explained as well by either hand
  // (docs/TRACKER.md, "Handedness by evidence over frames").
  double handedness_margin = 0.15;
  double handedness_tie = 0.05;
  int handedness_trial_frames = 30;
  double handedness_evidence_rate = 0.05;
  // A hand chosen by a trial whose fit stays mediocre (its running confidence below
  // recheck_below_confidence) is put to a trial again every `handedness_recheck_frames` frames: the
  // other hand from its (re)start, side by side for handedness_trial_frames frames (fewer where the
  // evidence soon favours the chosen hand by handedness_margin), and taken only if the evidence
  // then favours it by that margin (Tracker::weigh); 0: never, and never with checks spread over
  // frames. A fist at the trial's start is explained as well by either hand, and the wrong one, once
  // chosen, stayed (docs/TRACKER.md, "Handedness by evidence over frames").
  int handedness_recheck_frames = 60;
  // Hands per frame (HandsTracker; 1..kMaxHands): hands_tracker.hpp.
  int max_hands = 2;
  // A surface that a new hand's (re)start found to be no hand is not tried again for this many
  // frames (HandsTracker).
  int new_hand_retry_frames = 15;
  // A hand that finds no fit while another hand is seen (hidden behind it) keeps its slot and id,
  // unreported, for this many frames: where it shows again near its last pose it is the same hand
  // (HandsTracker).
  int hidden_hand_frames = 20;
  // Each hand that comes into view has its scale calibrated from its frames held open toward the
  // camera, and is then tracked with it; a handedness trial keeps `scale`'s width and sigma
  // (Tracker; src/self_calibration.hpp). false: `scale` always.
  bool self_calibrate = true;
  uint64_t seed = 1;
};

// The preprocessing a tracker with `config` needs: config.input, with the free-space map only where
// an energy reads it (late fusion with w_f > 0: PoseTracker). Every TrackerInputs and HandsInputs
// made for a tracker is made with this.
DepthInputConfig input_config(const TrackerConfig& config);
// The weights of `config`'s energies: E_free (w_f), E_sim's coverage cap and the tracking w_c
// (EnergyWeights::tracking_collision) only with late fusion.
EnergyWeights mode_weights(const TrackerConfig& config);
// The weights of the (re)start search and its checks (StartSearch): mode_weights() with E_sim as
// eq. 6, without the coverage cap, and the paper's w_c (EnergyWeights::collision).
EnergyWeights search_weights(const TrackerConfig& config);

// N points at the origin (Eigen leaves a default-constructed vector uninitialised).
template <size_t N>
std::array<Eigen::Vector3d, N> zero_points() {
  std::array<Eigen::Vector3d, N> points;
  points.fill(Eigen::Vector3d::Zero());
  return points;
}

struct TrackerOutput {
  TrackingState state = TrackingState::kNoHand;
  PoseParams params = PoseParams::Zero();
  Joints joints = zero_points<kNumJoints>();
  std::array<Eigen::Vector3d, kNumFingers> fingertips = zero_points<kNumFingers>();
  Eigen::Vector3d palm_centre = Eigen::Vector3d::Zero();
  Eigen::Vector3d palm_normal = Eigen::Vector3d::Zero();  // out of the palm, camera frame
  double energy = 0.0;
  double confidence = 0.0;           // fraction of the hand's depth explained by the model, in [0, 1]
  // With part labels: how far they agree with the fitted model (FitExplained), else -1.
  double label_agreement = -1.0;
  double pinch_distance_mm = 0.0;    // thumb tip to index tip, surface to surface
  double pinch_strength = 0.0;       // 1 = touching, 0 = apart (>= 40 mm)
  int winning_particle = -1;         // -1: a (re)start, not a particle
  // Optimiser iterations this frame took, both hands' trackers together (Tracker): 2 x 10 while
  // it tracks, a few dozen more while a check spread over frames runs, hundreds at a (re)start and
  // at a check made at once.
  int iterations = 0;
  bool detection_guided_won = false;  // late fusion: the detection-guided particle won
  Handedness handedness = Handedness::kRight;
  // How clearly the hand was told apart from the other, in [0, 1]: the running evidence of the
  // handedness trial (Tracker::weigh: the average fit-score difference of the two hands) as of its
  // last frame (1 when only one hand is considered).
  double handedness_confidence = 1.0;
  // Which hand this is: a number that stays the same while the hand stays in view (through
  // "recovering" frames and a change of the chosen hand) and is new each time a hand appears after
  // a frame without one; 0 when there is no hand. Counts from 1 within one Tracker.
  uint32_t hand_id = 0;
  // The hand model's scale this pose is of (TrackerConfig::scale, or what self-calibration found).
  HandScale scale;
  // fit_score() of this pose (below).
  [[nodiscard]] double score() const;
};

class BackgroundSearch;
class SelfCalibration;

class PoseTracker {
 public:
  explicit PoseTracker(TrackerConfig config = {});
  ~PoseTracker();
  PoseTracker(PoseTracker&&) noexcept;
  PoseTracker& operator=(PoseTracker&&) noexcept;

  // Where segmentation should look for the hand in the next frame: none before the first pose,
  // after the fit was lost, and before a check against a (re)start (the next frame is segmented
  // afresh). Allocates nothing.
  [[nodiscard]] std::optional<HandHint> hint() const;
  // Optimiser iterations since the last call (TrackerOutput::iterations); a background search's
  // are its thread's, not counted.
  int take_iterations() { return std::exchange(iterations_, 0) + search_.take_iterations(); }
  // No tracked pose: the next frame (re)starts.
  [[nodiscard]] bool lost() const { return !previous_; }
  // The running confidence of the tracked pose is below TrackerConfig::recheck_below_confidence.
  [[nodiscard]] bool mediocre() const {
    return previous_ && confidence_level_ < config_.recheck_below_confidence;
  }
  // Optimises the pose for one frame's C_I and updates the history.
  TrackerOutput optimise(const DepthInput& input);
  // Forget the history: the next frame starts from the open hand.
  void reset();
  // Replaces the tracker's belief about the last pose (both previous poses) by `pose`: how tests
  // knock the tracker off to check that it recovers.
  void override_pose(const PoseParams& pose);
  // With background checks: blocks until the check under way (if any) has finished, so that the
  // next optimise() takes its result, as if the camera had waited for it (tests).
  void wait_for_check();

  [[nodiscard]] const HandModel& model() const { return search_.model(); }
  [[nodiscard]] const TrackerConfig& config() const { return config_; }
  // Tracks with `model` (a default adult at another scale) from the next frame on: copied into
  // this tracker's storage, without allocating where it has the same structure.
  void set_model(const HandModel& model);
  // Another hand in the frame, in this tracker's camera frame, that the fit must not enter
  // (E_hand); null: none. It must outlive the optimise() calls that use it.
  void set_other_hand(const HandObstacle* other) {
    other_hand_ = other;
    search_.set_other_hand(other);
  }

 private:
  TrackerOutput describe(const PoseParams& params, double energy, TrackingState state);
  // Why a check is made: the confidence fell (suspect), or a mediocre fit is looked at again.
  enum class CheckCause { kNone, kFall, kRecheck };
  // What a frame did about a check: none under way, one under way, one ended with the tracked
  // pose kept or replaced.
  enum class CheckOutcome { kNone, kChecking, kTrackedKept, kRestartWon };
  // A suspect-fit check on this frame's thread, one slice of the (re)start search per frame (all
  // of it on one frame when check_iterations_per_frame is 0): the fit that replaces the tracked
  // pose (`tracked`: how well it explains this frame), or nullopt.
  std::optional<StartFit> continue_check(const DepthInput& input, const FitExplained& tracked);
  // A check on the background thread (TrackerConfig::background_checks): started on this frame's
  // input (next_check_), or taken when it has finished; a (re)start that won becomes the history,
  // moved as the segmented hand has moved since its frame.
  CheckOutcome background_check(const DepthInput& input, const FitExplained& tracked, std::optional<StartFit>& fresh);
  // After a frame's fit: tracks the running confidence level and decides whether the next frame
  // checks the tracked pose against a (re)start.
  void watch_confidence(double confidence, CheckOutcome check);

  TrackerConfig config_;
  StartSearch search_;  // the (re)starts, the checks on this thread, and explain()
  // Late fusion: the particles' common energy at `params` (see EnergyMode).
  PoseEnergy common_energy_;     // late fusion: compares the particles (label share fusion_label_weight)
  // The particles' energies (mode_weights, the coverage cap included): depth-only, and with late
  // fusion detection-guided for the last particle.
  PoseEnergy depth_energy_;
  PoseEnergy guided_energy_;
  AdaptiveGradientAscent optimizer_;
  PosedHand scratch_;
  PosedHand previous_hand_;  // the previous pose, posed for its surface fronts and the unseen fingers
  std::unique_ptr<BackgroundSearch> background_;  // TrackerConfig::background_checks
  const HandObstacle* other_hand_ = nullptr;
  std::mt19937_64 rng_;
  std::optional<PoseParams> previous_;
  std::optional<PoseParams> before_previous_;
  int low_confidence_run_ = 0;
  bool recovering_ = false;
  double confidence_level_ = 0.0;     // running level of the tracked pose's confidence
  CheckCause next_check_ = CheckCause::kNone;  // the next frame starts a check
  struct Check {
    bool active = false;
    CheckCause cause = CheckCause::kNone;
    HandPlace place;      // of the check's first frame
    Eigen::Vector3d centroid_mm = Eigen::Vector3d::Zero();  // of its segmented hand
    size_t starts = 0;    // hypotheses to screen
    size_t screened = 0;  // of them so far
    int refined = 0;      // refinement iterations done (of each kept hypothesis)
    FitExplained tracked;  // background checks: the tracked pose on the check's first frame
  } check_;
  int frames_since_check_ = 0;
  int iterations_ = 0;  // take_iterations()
};

// Background checks' searches that have finished (TrackerConfig::background_checks), in this
// process, dropped ones included: a statistic, and how tests see that the search thread ran.
uint64_t background_searches_finished();
// Hands' self-calibrations (TrackerConfig::self_calibrate) whose scale was taken, in this process:
// how tests see that a hand was calibrated.
uint64_t self_calibrations_taken();

// What the next frame's preprocessing should build for a Tracker: the inputs of the hands it will
// fit, each with its segmentation hint (the mirrored frame's hint for the left hand).
struct InputRequest {
  bool right = true;
  bool left = false;
  std::optional<HandHint> right_hint;
  std::optional<HandHint> left_hint;
};

// One frame's preprocessed inputs, for the hands an InputRequest asked for: the right hand's from
// the frame, the left hand's from its mirror image (see Tracker). Storage is reused between
// frames; a pipeline keeps one per frame in flight, so frame t+1 is preprocessed while frame t is
// optimised.
class TrackerInputs {
 public:
  explicit TrackerInputs(const DepthInputConfig& config = {});
  // `foreign`: pixels that are not this hand's, `median`: the median-filtered frame if the caller
  // has it (DepthInputBuilder::build), or null. Both hands' inputs share one median filter: the
  // left hand's is the right hand's mirrored (the 3x3 window and its edge padding are symmetric).
  void build(const DepthImage& depth, const InputRequest& request, const PixelLabeller* labeller = nullptr,
             const std::vector<uint8_t>* foreign = nullptr, const std::vector<float>* median = nullptr);
  // Null when not built for this frame.
  [[nodiscard]] const DepthInput* get(Handedness hand) const {
    if (hand == Handedness::kLeft) return has_left_ ? &left_.last() : nullptr;
    return has_right_ ? &right_.last() : nullptr;
  }

 private:
  DepthInputBuilder right_;
  DepthInputBuilder left_;
  DepthImage mirrored_;
  std::vector<uint8_t> mirrored_foreign_;
  std::vector<float> mirrored_median_;
  bool has_right_ = false;
  bool has_left_ = false;
};

// Depth image -> pose, for one hand at a time: the optimisers (PoseTracker) of either hand and the
// choice of hand; the preprocessing is TrackerInputs, which a pipeline runs on another thread.
//
// A left hand is the mirror image of a right hand about the camera's x = 0 plane, which the camera
// sees exactly as the image flipped left to right with the principal point at
// u = (width - 1) - cx (pixel centres at integer u). So a left hand is tracked as the right hand of
// the mirrored image, by a second PoseTracker that only ever sees mirrored inputs, and its joints,
// fingertips, palm centre and normal are mirrored back (x negated); `params` stay those of the
// right-hand model in the mirrored image. With HandednessMode::kAuto both hands are fitted from
// every (re)start of the current hand and tracked side by side in a trial of at least
// TrackerConfig::handedness_trial_frames frames; the hand that the running fit-score evidence
// favours is reported, and the other is dropped once the evidence is clear
// (TrackerConfig::handedness_margin). While only one hand runs, tracking costs what it did.
//
// Threading: request() and optimise() on one thread; TrackerInputs::build() anywhere, on inputs
// the optimising thread does not read at the time.
class Tracker {
 public:
  explicit Tracker(const TrackerConfig& config = {});
  ~Tracker();
  Tracker(Tracker&&) noexcept;
  Tracker& operator=(Tracker&&) noexcept;
  // What the next frame needs: both hands at a (re)start in auto mode, else the current one.
  [[nodiscard]] InputRequest request() const;
  // Fits the hand(s) on inputs built for request() (or for an older request: a hand whose input
  // is missing is not fitted; with neither, the frame has no hand).
  TrackerOutput optimise(const TrackerInputs& inputs);
  // Both steps on this thread: what handtrack-eval and the single-threaded path use.
  TrackerOutput track(const DepthImage& depth, const PixelLabeller* labeller = nullptr);
  // The current hand's input of track()'s last frame and its tracker (for a left hand: of the
  // mirrored image); the input is null when that hand was not preprocessed.
  [[nodiscard]] const DepthInput* last_input() const { return inputs_.get(current_); }
  [[nodiscard]] PoseTracker& pose_tracker() { return side(current_); }
  // The hand model (both hands' trackers share its scale; a left hand's is the right-hand model
  // of the mirrored image).
  [[nodiscard]] const HandModel& model() const { return right_.model(); }
  [[nodiscard]] const TrackerConfig& config() const { return right_.config(); }
  void reset();
  // Another hand in the frame that this one must not enter (HandsTracker): its Gaussians as the
  // right hand's tracker sees them (camera frame) and as the left hand's does (mirrored); null:
  // none.
  void set_other_hand(const HandObstacle* as_right, const HandObstacle* as_left) {
    right_.set_other_hand(as_right);
    left_.set_other_hand(as_left);
    beside_other_ = as_right != nullptr || as_left != nullptr;
  }
  // Which hand this one probably is (HandsTracker: not the other hand in view, or, while neither
  // hand's side has been told, the one its place in the image says), for choices within
  // handedness_tie, and for choices short of handedness_margin while the other hand's side is the
  // clearer choice (`other_clarity`: its handedness_confidence); nullopt: no expectation.
  void expect(std::optional<Handedness> hand, double other_clarity = 0.0) {
    expected_ = hand;
    expected_clarity_ = other_clarity;
  }
  // Track both hands again from the next frame, in a new trial (HandsTracker: both hands in view
  // were chosen as the same hand); a trial under way goes on.
  void question_handedness() { trial_pending_ = trial_pending_ || trial_frames_ == 0; }
  // Carry on from `last` (a pose this tracker reported) at the next frame, as if it had just been
  // tracked: HandsTracker's way back for a hand hidden behind the other, instead of a (re)start.
  void resume(const TrackerOutput& last);
  // With background checks: blocks until both hands' checks and the self-calibration under way
  // have finished (PoseTracker::wait_for_check; tests).
  void wait_for_checks();

 private:
  [[nodiscard]] const PoseTracker& side(Handedness hand) const { return hand == Handedness::kLeft ? left_ : right_; }
  PoseTracker& side(Handedness hand) { return hand == Handedness::kLeft ? left_ : right_; }
  // Both hands this frame: a trial under way or due.
  [[nodiscard]] bool both() const;
  // This frame of a trial (re)starts a lost hand: its first frame, and every kTrialRestartFrames
  // frames unless checks are off the frame (spread or in the background).
  [[nodiscard]] bool trial_restarts() const;
  // A hand the trial does not fit on this frame (lost, and no (re)start due): request() does not
  // ask for its input.
  [[nodiscard]] bool trial_skips(Handedness hand) const;
  // One frame of a handedness trial: the evidence from both hands' fits (and, for mirror twins, the
  // palm's hollow: palm_hollow.hpp), the hand it favours (current_), and the trial's end.
  void weigh(const TrackerOutput& as_right, const TrackerOutput& as_left, std::optional<double> hollow_mm);
  TrackerOutput fit(Handedness hand, const DepthInput& input);
  void identify(TrackerOutput& out);  // sets out.hand_id
  // Offers the frame to the hand's self-calibration (TrackerConfig::self_calibrate) and takes the
  // scale it finds.
  void calibrate(const TrackerInputs& inputs, const TrackerOutput& out);
  // Both hands' models as the frame needs them: the calibrated one, or in a handedness trial the
  // trial's (calibrated_).
  void use_calibrated_model();

  PoseTracker right_;
  PoseTracker left_;
  TrackerInputs inputs_;  // track()'s
  Handedness current_ = Handedness::kRight;
  std::optional<Handedness> expected_;  // expect()
  double expected_clarity_ = 0.0;
  // Handedness trial (TrackerConfig::handedness_trial_frames): due at the next frame with both
  // hands' inputs, its frames so far (0: none under way), and the running evidence (the average
  // fit-score difference left - right; TrackerOutput::handedness_confidence is its size).
  bool trial_pending_ = true;
  int trial_frames_ = 0;
  double evidence_ = 0.0;
  // Per hand (right, left): whether it has had a fit in this trial (its frames are weighed from the
  // first on which both have).
  std::array<bool, 2> trial_fitted_{};
  // A trial of a hand already chosen (TrackerConfig::handedness_recheck_frames): the chosen hand
  // is reported throughout and kept unless the evidence is clear at the end. Frames since the last
  // trial ended.
  bool retrial_ = false;
  int frames_since_trial_ = 0;
  uint32_t hand_id_ = 0;   // of the hand in view; 0: none in the last frame
  uint32_t last_hand_id_ = 0;
  bool beside_other_ = false;  // set_other_hand(): another hand in view
  std::unique_ptr<SelfCalibration> calibration_;  // null: TrackerConfig::self_calibrate off
  // The self-calibrated hand: tracked with the scale found, and fitted in a handedness trial with
  // the length found but the configured width and sigma (self_calibration.hpp). Built once per
  // calibration, so that a trial's start and end copy a model and allocate nothing.
  struct CalibratedModels {
    HandModel tracked;
    HandModel trial;
  };
  HandScale configured_scale_;
  std::optional<CalibratedModels> calibrated_;
};

}  // namespace handtrack
