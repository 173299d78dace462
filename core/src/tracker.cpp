#include "handtrack/core/tracker.hpp"

#include "background_search.hpp"
#include "handtrack/core/palm_hollow.hpp"
#include "self_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace handtrack {

using Eigen::Vector3d;

namespace {
// A hand lost during a handedness trial (Tracker::optimise) is (re)started again every this many
// frames: on every frame, a hand that found no start made each trial frame cost a whole search
// (a pipeline frame 9-10 ms instead of 1.5).
constexpr int kTrialRestartFrames = 5;
// Pinch strength falls from 1 (tips touching) to 0 at this surface distance.
constexpr double kPinchOpenMm = 40.0;
}  // namespace

double TrackerOutput::score() const { return fit_score(confidence, label_agreement); }

namespace {

// The frame a camera takes of the scene's mirror image about x = 0 (Tracker): the rows reversed,
// the principal point mirrored.
// An image of `width` columns flipped left to right, row by row.
template <typename T>
void mirror_rows(const std::vector<T>& in, int width, std::vector<T>& out) {
  out.resize(in.size());
  const auto w = static_cast<std::ptrdiff_t>(width);
  for (std::ptrdiff_t row = 0; row + w <= static_cast<std::ptrdiff_t>(in.size()); row += w) {
    std::reverse_copy(in.begin() + row, in.begin() + row + w, out.begin() + row);
  }
}

void mirror_depth(const DepthImage& in, DepthImage& out) {
  out.camera = in.camera;
  out.camera.cx = static_cast<double>(in.camera.width - 1) - in.camera.cx;
  mirror_rows(in.depth_mm, in.camera.width, out.depth_mm);
  out.mirrored = !in.mirrored;
}

// A pose found in the mirrored frame, back in the camera's: every point and direction reflected.
void mirror_output(TrackerOutput& out) {
  for (auto& j : out.joints) j.x() = -j.x();
  for (auto& t : out.fingertips) t.x() = -t.x();
  out.palm_centre.x() = -out.palm_centre.x();
  out.palm_normal.x() = -out.palm_normal.x();
}

}  // namespace

TrackerInputs::TrackerInputs(const DepthInputConfig& config) : right_(config), left_(config) {}

void TrackerInputs::build(const DepthImage& depth, const InputRequest& request, const PixelLabeller* labeller,
                          const std::vector<uint8_t>* foreign, const std::vector<float>* median) {
  has_right_ = request.right;
  has_left_ = request.left;
  if (has_right_) {
    right_.build(depth, request.right_hint, labeller, foreign, median);
    if (median == nullptr) median = &right_.computed_median();
  }
  if (has_left_) {
    mirror_depth(depth, mirrored_);
    mirrored_foreign_.resize(depth.depth_mm.size());  // sized with the first left hand, foreign or not
    if (foreign != nullptr) mirror_rows(*foreign, depth.camera.width, mirrored_foreign_);
    mirrored_median_.resize(depth.depth_mm.size());  // likewise
    if (median != nullptr) mirror_rows(*median, depth.camera.width, mirrored_median_);
    left_.build(mirrored_, request.left_hint, labeller, foreign != nullptr ? &mirrored_foreign_ : nullptr,
                median != nullptr ? &mirrored_median_ : nullptr);
  }
}

namespace {
Handedness opposite(Handedness hand) { return hand == Handedness::kLeft ? Handedness::kRight : Handedness::kLeft; }

// The latency settings: a check's search spread over frames or made in the background, so that no
// tracked frame runs a whole search (TrackerConfig::check_iterations_per_frame, background_checks).
bool checks_off_the_frame(const TrackerConfig& config) {
  return config.check_iterations_per_frame > 0 || config.background_checks;
}
}  // namespace

Tracker::Tracker(const TrackerConfig& config)
    : right_(config), left_(config), inputs_(input_config(config)),
      current_(config.handedness == HandednessMode::kLeft ? Handedness::kLeft : Handedness::kRight),
      calibration_(config.self_calibrate ? std::make_unique<SelfCalibration>(config) : nullptr),
      configured_scale_(config.scale) {}

Tracker::~Tracker() = default;
Tracker::Tracker(Tracker&&) noexcept = default;
Tracker& Tracker::operator=(Tracker&&) noexcept = default;

void Tracker::resume(const TrackerOutput& last) {
  // The hand as it was last seen, its side as it was reported: no trial (the other hand's history
  // is of frames ago).
  current_ = last.handedness;
  side(current_).override_pose(last.params);
  side(opposite(current_)).reset();
  trial_pending_ = false;
  trial_frames_ = 0;
  retrial_ = false;
  frames_since_trial_ = 0;
}

void Tracker::reset() {
  right_.reset();
  left_.reset();
  trial_pending_ = true;
  trial_frames_ = 0;
  retrial_ = false;
  hand_id_ = 0;
}

InputRequest Tracker::request() const {
  const bool all = both();
  // In a trial, a hand that optimise() will not fit on this frame (lost, no (re)start due) gets no
  // input: with checks off the frame, a hand whose start found nothing cost a second hand's
  // preprocessing on each of the trial's frames (docs/BENCHMARKS.md). Both skipped (not seen: a
  // new trial restarts both) asks for both, as before.
  const bool skip_right = all && trial_skips(Handedness::kRight);
  const bool skip_left = all && trial_skips(Handedness::kLeft);
  InputRequest r;
  r.right = all ? !skip_right || skip_left : current_ == Handedness::kRight;
  r.left = all ? !skip_left || skip_right : current_ == Handedness::kLeft;
  if (r.right) r.right_hint = right_.hint();
  if (r.left) r.left_hint = left_.hint();
  return r;
}

TrackerOutput Tracker::fit(Handedness hand, const DepthInput& input) {
  TrackerOutput out = side(hand).optimise(input);
  if (hand == Handedness::kLeft) {
    mirror_output(out);
    out.handedness = Handedness::kLeft;
  }
  return out;
}

void Tracker::identify(TrackerOutput& out) {
  if (out.state == TrackingState::kNoHand) {
    hand_id_ = 0;
  } else if (hand_id_ == 0) {
    hand_id_ = ++last_hand_id_;
  }
  out.hand_id = hand_id_;
}

namespace {
// The hand of the two fits whose palm faces the camera, where exactly one does.
std::optional<Handedness> palm_toward_camera(const TrackerOutput& as_right, const TrackerOutput& as_left) {
  const bool right_palm = as_right.palm_normal.z() < 0.0;
  const bool left_palm = as_left.palm_normal.z() < 0.0;
  if (right_palm == left_palm) return std::nullopt;
  return right_palm ? Handedness::kRight : Handedness::kLeft;
}

// The hand of the two fits that shows the camera the side its arrangement expects (the palm, or
// for a head-mounted camera the back), where exactly one fit's palm faces the camera.
std::optional<Handedness> expected_side_toward_camera(const TrackerOutput& as_right, const TrackerOutput& as_left,
                                                      CameraArrangement arrangement) {
  const std::optional<Handedness> palm = palm_toward_camera(as_right, as_left);
  if (!palm || arrangement == CameraArrangement::kFacing) return palm;
  return opposite(*palm);
}

// A fit's palm faces the camera squarely (either side of it): its normal within 45 deg of the
// viewing axis.
bool squarely_facing(const TrackerOutput& fit) { return std::abs(fit.palm_normal.z()) > std::numbers::sqrt2 / 2.0; }

// Two fits that face the camera squarely, one with its palm and the other with its back: mirror
// images through the hand's plane.
bool mirror_twins(const TrackerOutput& as_right, const TrackerOutput& as_left) {
  const bool both_fitted = as_right.state != TrackingState::kNoHand && as_left.state != TrackingState::kNoHand;
  return both_fitted && squarely_facing(as_right) && squarely_facing(as_left) &&
         palm_toward_camera(as_right, as_left).has_value();
}

// One frame's handedness evidence: how much better the left hand's fit explains the hand than the
// right hand's (Tracker::weigh).
//
// Mostly the fit-score difference, labels and all: two fits of the same side facing the camera (a
// right hand's back against a left hand's back) differ in which edge carries the thumb, which only
// the part labels see. But two fits that both face the camera squarely, one with its palm and the
// other with its back, are mirror images through the hand's plane, and the labels favour the palm
// for a reason of their own: the forest labels palm views better than back views (data/
// part_forest.md: 90 against 82 % of pixels), and the palm-toward fit is labelled on the image
// where the hand looks like a palm view (the mirrored image for a left hand). On the flat hands of
// adbadd seen from the back the labels chose the palm-toward mirror image in most frames, while the
// depth alone (the fingers flex toward the palm, the thumb sits in front of it) chose the true hand,
// there: our renders' hand is the model's own, and on a hand whose back is convex the two fits
// explained it alike (0.91 and 0.90; docs/TRACKER.md, "A hollow palm and a convex back"). So for
// that pair the evidence is the confidence difference (docs/TRACKER.md, "Handedness by
// evidence over frames"), and the palm's hollow where the depth shows one (`hollow_mm`,
// palm_hollow.hpp: > 0 a palm faces the camera, < 0 the back): up to kHollowEvidence toward the fit
// that shows the camera that side, in full from kFullHollowMm.
double handedness_difference(const TrackerOutput& as_right, const TrackerOutput& as_left,
                             std::optional<double> hollow_mm) {
  if (!mirror_twins(as_right, as_left)) return as_left.score() - as_right.score();
  double difference = as_left.confidence - as_right.confidence;
  if (hollow_mm) {
    const double palm_shown = std::clamp(*hollow_mm / kFullHollowMm, -1.0, 1.0);
    const double toward_left = palm_toward_camera(as_right, as_left) == Handedness::kLeft ? 1.0 : -1.0;
    difference += kHollowEvidence * palm_shown * toward_left;
  }
  return difference;
}

// palm_hollow_mm of the pair's palm (the two share its plane), from the input of either hand that
// has one: a left hand's is the mirrored image, where its fit is mirrored back. Only for mirror
// twins, the one pair it tells apart.
std::optional<double> twins_hollow_mm(const TrackerOutput& as_right, const TrackerOutput& as_left,
                                      const DepthInput* right, const DepthInput* left) {
  if (!mirror_twins(as_right, as_left)) return std::nullopt;
  if (right != nullptr) return palm_hollow_mm(*right, as_right);
  if (left == nullptr) return std::nullopt;
  TrackerOutput in_mirrored_image = as_left;
  mirror_output(in_mirrored_image);
  return palm_hollow_mm(*left, in_mirrored_image);
}
}  // namespace

bool Tracker::both() const {
  return config().handedness == HandednessMode::kAuto && (trial_pending_ || trial_frames_ > 0);
}

bool Tracker::trial_restarts() const {
  return trial_frames_ == 0 || (!checks_off_the_frame(config()) && trial_frames_ % kTrialRestartFrames == 0);
}

bool Tracker::trial_skips(Handedness hand) const { return side(hand).lost() && !trial_restarts(); }

void Tracker::weigh(const TrackerOutput& as_right, const TrackerOutput& as_left, std::optional<double> hollow_mm) {
  // A hand seen on one frame can be either: a fist, a hand edge-on, or a flat hand whose palm or
  // back faces the camera (a right hand's palm and a left hand's back are mirror images through the
  // hand's plane, the same to the sphere model). As it moves, the fingers flex toward the palm of
  // the true hand only, and the wrong hand's fit explains less of it. So the evidence is the
  // fit-score difference left - right (handedness_difference) averaged over the trial's frames (a
  // hand that lost its fit scores 0), and the hand it favours is reported (docs/TRACKER.md,
  // "Handedness by evidence over frames").
  //
  // A hand whose (re)start has found nothing yet in this trial is no evidence either way: its
  // search missed, which says little about the shape (a fist seen from behind, fingercount
  // head-mounted s1: the right hand's search found nothing in the trial's first 5 frames, and those
  // frames, weighed in full, chose the left hand for the whole sequence). The frames count from
  // the first where both hands have had a fit, which starts the average; a hand that never has one
  // by the trial's end loses it.
  const int frames = trial_frames_ + 1;
  if (trial_frames_ == 0) {
    trial_fitted_ = {false, false};
    evidence_ = 0.0;
  }
  const bool weighed_before = trial_fitted_[0] && trial_fitted_[1];
  trial_fitted_[0] = trial_fitted_[0] || as_right.state != TrackingState::kNoHand;
  trial_fitted_[1] = trial_fitted_[1] || as_left.state != TrackingState::kNoHand;
  if (trial_fitted_[0] && trial_fitted_[1]) {
    const double difference = handedness_difference(as_right, as_left, hollow_mm);
    evidence_ = weighed_before ? evidence_ + config().handedness_evidence_rate * (difference - evidence_) : difference;
  } else if (frames >= config().handedness_trial_frames && trial_fitted_[0] != trial_fitted_[1]) {
    evidence_ = trial_fitted_[1] ? config().handedness_margin : -config().handedness_margin;
  }
  // Evidence within handedness_tie is a tie. With another hand in view (HandsTracker) a tie goes to
  // the hand that one is not: two hands in one frame are usually a left and a right one. So does
  // evidence short of handedness_margin where the other hand's is the clearer (expect()): the
  // clearer hand decides the pair. Clapping hands, side-on to the camera, stay in a trial with
  // evidence near the tie, and one of them turned to the other's side on evidence of 0.05, the
  // other following it within its tie, both wrong (docs/TRACKER.md, "Two hands"). Else, on
  // the trial's first frame, to the palm toward the camera, the common view of a desk camera facing
  // the user (the back, for a head-mounted camera: TrackerConfig::arrangement); later, the hand
  // reported so far is kept until the evidence leaves the tie (the palm
  // rule on every frame of a tie, replayed over the benchmark's logs: handedness 92.6 -> 92.0 %,
  // wrong for every hand seen from the back).
  //
  // A trial of a hand already chosen (retrial_: TrackerConfig::handedness_recheck_frames) reports
  // that hand throughout: it checks a tracked pose against a (re)start, where one clear frame of
  // the restarted hand is no evidence. The other hand takes over only if the evidence favours it by
  // handedness_margin at the end; the trial ends early, after a third of its frames, where the
  // evidence already favours the chosen hand by the margin (most find the chosen hand right).
  const bool tie = std::abs(evidence_) < config().handedness_tie;
  const bool clear = std::abs(evidence_) >= config().handedness_margin;
  const Handedness favoured = evidence_ > 0.0 ? Handedness::kLeft : Handedness::kRight;
  const bool confirmed = retrial_ && clear && favoured == current_ && 3 * frames >= config().handedness_trial_frames;
  const bool done = confirmed || (frames >= config().handedness_trial_frames && (clear || retrial_));
  const bool other_decides =
      expected_ && favoured != *expected_ && !clear && expected_clarity_ > std::abs(evidence_);
  if (retrial_) {
    if (done && clear) current_ = favoured;
  } else if (!tie && !other_decides) {
    current_ = favoured;
  } else if (expected_) {
    current_ = *expected_;
  } else if (trial_frames_ == 0) {
    current_ = expected_side_toward_camera(as_right, as_left, config().arrangement)
                   .value_or(evidence_ > 0.0 ? Handedness::kLeft : Handedness::kRight);
  }
  ++trial_frames_;
  trial_pending_ = false;
  if (done) {
    side(opposite(current_)).reset();
    trial_frames_ = 0;
    retrial_ = false;
    frames_since_trial_ = 0;
  }
}

TrackerOutput Tracker::optimise(const TrackerInputs& inputs) {
  const DepthInput* right = inputs.get(Handedness::kRight);
  const DepthInput* left = inputs.get(Handedness::kLeft);
  TrackerOutput out;
  // A trial's frame needs the input of each hand it fits (trial_skips: request() asked for no
  // other). One without (a pipelined frame preprocessed before the trial asked for it) is fitted as
  // outside a trial, and the trial waits for the next frame.
  const auto trial_ready = [&](Handedness hand, const DepthInput* input) {
    return input != nullptr || trial_skips(hand);
  };
  use_calibrated_model();
  if (both() && (right != nullptr || left != nullptr) && trial_ready(Handedness::kRight, right) &&
      trial_ready(Handedness::kLeft, left)) {
    // A trial: both hands, each from its history or its (re)start hypotheses; each hand's
    // suspect-fit checks go at the configured pace, as when it tracks alone. A hand lost later in
    // the trial scores 0 and is (re)started again every kTrialRestartFrames frames, a whole search
    // on one frame (10-16 ms), except with checks spread over frames or in the background (the
    // latency settings: no tracked frame runs a whole search), where it is not. Never (re)started,
    // the true hand that found no start on a fist was lost for good: fingercount 37.2 -> 45.1 mm,
    // handedness 77 -> 60 %.
    const auto trial_fit = [&](Handedness hand, const DepthInput* input) {
      return trial_skips(hand) ? TrackerOutput{} : fit(hand, *input);
    };
    const TrackerOutput as_right = trial_fit(Handedness::kRight, right);
    const TrackerOutput as_left = trial_fit(Handedness::kLeft, left);
    weigh(as_right, as_left, twins_hollow_mm(as_right, as_left, right, left));
    out = current_ == Handedness::kLeft ? as_left : as_right;
    // A hand that found no fit is not reported over one that did.
    const TrackerOutput& other = current_ == Handedness::kLeft ? as_right : as_left;
    if (out.state == TrackingState::kNoHand && other.state != TrackingState::kNoHand) out = other;
  } else if (const DepthInput* input = current_ == Handedness::kLeft ? left : right) {
    // One hand while it tracks (or when only one is considered).
    out = fit(current_, *input);
  } else {
    // Built for another hand than the current one (a pipeline's frame preprocessed before the
    // choice changed): fit the hand the frame was built for.
    const Handedness other = opposite(current_);
    if (inputs.get(other) != nullptr && config().handedness == HandednessMode::kAuto) {
      out = fit(other, *inputs.get(other));
      current_ = other;
    }
  }
  // The current hand lost (or never found), outside a trial or with the other hand of a trial lost
  // too: both hands from their (re)start on, in a new trial.
  if (side(current_).lost() && (trial_frames_ == 0 || side(opposite(current_)).lost())) {
    trial_pending_ = true;
    trial_frames_ = 0;
    retrial_ = false;
  } else if (config().handedness == HandednessMode::kAuto && !both()) {
    // A hand chosen by a trial and tracked alone since: put to a trial again while its fit stays
    // mediocre (TrackerConfig::handedness_recheck_frames). Its first frame is a whole (re)start
    // search of the other hand, which the latency settings (checks spread over frames or in the
    // background) make on no tracked frame: there, none.
    const int every = checks_off_the_frame(config()) ? 0 : config().handedness_recheck_frames;
    if (every > 0 && ++frames_since_trial_ >= every && side(current_).mediocre()) {
      trial_pending_ = true;
      retrial_ = true;
    }
  }
  out.iterations = right_.take_iterations() + left_.take_iterations();
  // 1 when only one hand is considered.
  out.handedness_confidence =
      config().handedness == HandednessMode::kAuto ? std::clamp(std::abs(evidence_), 0.0, 1.0) : 1.0;
  identify(out);
  if (calibration_) calibrate(inputs, out);
  return out;
}

void Tracker::wait_for_checks() {
  right_.wait_for_check();
  left_.wait_for_check();
  if (calibration_) calibration_->wait();
}

void Tracker::calibrate(const TrackerInputs& inputs, const TrackerOutput& out) {
  // The hand reported, in the frame its side's tracker fits (a trial's frames too: either hand's fit
  // of a flat hand has the hand's size). Not beside another hand, whose pixels the hand's
  // re-segmentation could take in.
  const DepthInput* input = inputs.get(out.handedness);
  if (beside_other_ || input == nullptr) return;
  if (const auto scale = calibration_->offer(*input, out, side(out.handedness).hint(), config().scale)) {
    const HandScale trial{scale->length, configured_scale_.width, configured_scale_.sigma};
    calibrated_.emplace(CalibratedModels{HandModel::default_adult(*scale), HandModel::default_adult(trial)});
    use_calibrated_model();
  }
}

void Tracker::use_calibrated_model() {
  // A handedness trial keeps the configured width and sigma: with the calibrated ones, hands of the
  // benchmark's sizes seen again lost their side from behind (99.5 -> 97.4 % right), a flat hand's
  // back and the other hand's palm told apart worse by a model of the hand's own width (not
  // understood; docs/TRACKER.md, "A hand calibrates itself"). set_model() copies only where the
  // scale differs.
  if (!calibrated_) return;
  const HandModel& model = both() ? calibrated_->trial : calibrated_->tracked;
  right_.set_model(model);
  left_.set_model(model);
}

TrackerOutput Tracker::track(const DepthImage& depth, const PixelLabeller* labeller) {
  inputs_.build(depth, request(), labeller);
  return optimise(inputs_);
}

// Depth-only tracking runs the paper's eq. 2: with E_free it lost the fists of fingercount and the
// fast half of random (the palm-view Dexter motions, 7 subjects: 13.2 -> 17.2 mm; docs/TRACKER.md
// "Free space"), and E_sim is eq. 6's, without the coverage cap; its w_c is the paper's too
// (EnergyWeights::tracking_collision is late fusion's).
EnergyWeights mode_weights(const TrackerConfig& config) {
  EnergyWeights weights = config.weights;
  if (config.mode == EnergyMode::kDepthOnly) {
    weights.free_space = 0.0;
    weights.coverage_cap = 0.0;
    weights.unseen_fingers = 0.0;
    weights.slant_front = 1.0;
  } else {
    weights.collision = config.weights.tracking_collision;
  }
  return weights;
}

// Measured, not explained: with E_sim's coverage cap in the (re)start search, the SR305 frames'
// right-hand fits got worse (230536/90: confidence 0.98 -> 0.60) and 3-7 of 17 turned into left
// hands; a hypothesis starts far from the hand, where the cap's closed image Gaussians may leave
// the fit less to climb on (docs/TRACKER.md, "E_sim's coverage cap"). The same for w_c below the
// paper's (EnergyWeights::tracking_collision): 4 of the 17 frames fitted as left hands.
EnergyWeights search_weights(const TrackerConfig& config) {
  EnergyWeights weights = mode_weights(config);
  weights.coverage_cap = 0.0;
  weights.collision = config.weights.collision;
  return weights;
}

DepthInputConfig input_config(const TrackerConfig& config) {
  DepthInputConfig input = config.input;
  input.free_space.enabled = mode_weights(config).free_space != 0.0;
  return input;
}

PoseTracker::PoseTracker(TrackerConfig config)
    : config_(config),
      search_(config),
      common_energy_(SimilarityFactor::kDepthAndLabel, mode_weights(config), config.fusion_label_weight),
      depth_energy_(SimilarityFactor::kDepth, mode_weights(config)),
      guided_energy_(SimilarityFactor::kDepthAndLabel, mode_weights(config)),
      optimizer_(config.optimizer),
      background_(config.background_checks ? std::make_unique<BackgroundSearch>(config) : nullptr),
      rng_(config.seed) {}

PoseTracker::~PoseTracker() = default;
PoseTracker::PoseTracker(PoseTracker&&) noexcept = default;
PoseTracker& PoseTracker::operator=(PoseTracker&&) noexcept = default;

void PoseTracker::set_model(const HandModel& model) {
  config_.scale = model.scale();
  search_.set_model(model);
}

void PoseTracker::reset() {
  previous_.reset();
  before_previous_.reset();
  low_confidence_run_ = 0;
  confidence_level_ = 0.0;
  next_check_ = CheckCause::kNone;
  check_ = {};
  if (background_) background_->cancel();
  frames_since_check_ = 0;
}

void PoseTracker::override_pose(const PoseParams& pose) {
  previous_ = pose;
  before_previous_ = pose;
  check_ = {};
  if (background_) background_->cancel();
}

void PoseTracker::wait_for_check() {
  if (background_) background_->wait();
}

std::optional<HandHint> PoseTracker::hint() const {
  // A check's hypotheses are placed on a freshly segmented hand, not where the doubted pose says.
  if (!previous_ || next_check_ != CheckCause::kNone) return std::nullopt;
  // Only the global transform matters (no PosedHand: nothing is allocated on the hot path).
  const Vector3d t = previous_->segment<3>(kTranslationParam);
  const Eigen::Matrix3d camera_R_hand = hand_rotation(*previous_);
  return HandHint{t + camera_R_hand * model().palm_centre(), t, camera_R_hand * Vector3d::UnitY()};
}

TrackerOutput PoseTracker::optimise(const DepthInput& input) {
  const auto no_hand = [&]() {
    reset();
    recovering_ = true;
    TrackerOutput none;  // no pose is invented: everything zero
    none.state = TrackingState::kNoHand;
    return none;
  };
  if (!input.has_hand()) return no_hand();
  EnergyFrame frame{&model(), &input, nullptr, nullptr, other_hand_};
  UnseenFingers unseen;
  SurfaceFronts fronts;
  OptimizerResult best{PoseParams::Zero(), -1e300};
  int winner = -1;
  bool guided_won = false;
  const bool fuse = search_.fuses(input);
  bool started = false;
  CheckOutcome check = CheckOutcome::kNone;
  if (!previous_) {
    // A (re)start: the frame of a whole search, where the background search's copies get their
    // room once (no allocation at its first check).
    if (background_) background_->reserve(input.camera.width, input.camera.height);
    best = search_.run(input, SearchPurpose::kStart).result;
    started = true;
    recovering_ = true;
  } else {
    frame.previous = &*previous_;
    frame.before_previous = before_previous_ ? &*before_previous_ : nullptr;
    // Fingers the labels do not see on a hand facing the camera curl (unseen_fingers.hpp): weighed
    // once a frame, from its labels, the segmented hand and the previous pose. Not beside another
    // hand, which can hide an outstretched finger as well (two_cross's left hand behind the right:
    // 9.9 -> 21.6 mm).
    const bool weigh_unseen =
        depth_energy_.weights().unseen_fingers != 0.0 && !input.pixel_labels.empty() && other_hand_ == nullptr;
    const bool slanted = depth_energy_.weights().slant_front > 1.0;
    if (weigh_unseen || slanted) previous_hand_.update(model(), *previous_);
    if (weigh_unseen) {
      unseen = unseen_fingers(input, previous_hand_);
      frame.unseen = &unseen;
    }
    // Surfaces seen at a slant lie further in front of the model's Gaussians (surface_fronts.hpp).
    if (slanted) {
      fronts = surface_fronts(model(), previous_hand_, depth_energy_.weights().slant_front);
      frame.fronts = &fronts;
    }
    const PoseParams velocity = before_previous_ ? PoseParams(*previous_ - *before_previous_) : PoseParams::Zero();
    std::normal_distribution<double> alpha(config_.extrapolation_mean, config_.extrapolation_sigma);
    for (int i = 0; i < config_.particles; ++i) {
      PoseParams particle = *previous_;
      for (int j = 0; j < kNumPoseParams; ++j) particle[j] += alpha(rng_) * velocity[j];
      const bool guided = fuse && i == config_.particles - 1;
      auto r = optimizer_.maximise(guided ? guided_energy_ : depth_energy_, frame, particle, scratch_);
      iterations_ += config_.optimizer.iterations;
      // Late fusion (Sec. 5): "the pose particle which converges with the best energy value is
      // chosen". The particles optimise different energies, so each is judged by one common energy.
      if (fuse) r.energy = common_energy_.evaluate(frame, r.params, scratch_, nullptr);
      if (r.energy > best.energy) {
        best = r;
        winner = i;
        guided_won = guided;
      }
    }
  }

  scratch_.update(model(), best.params);
  FitExplained explained = search_.explain(input, scratch_);
  // A suspected gross error: the tracked pose competes with the (re)start hypotheses, searched for
  // on this thread over the next frames (continue_check) or on the background thread
  // (background_check); a (re)start replaces it only when it explains clearly more of the hand on
  // the same frame (check_replace_margin), so a check cannot make good tracking worse by this
  // measure.
  std::optional<StartFit> fresh;
  if (background_ && previous_) {
    check = background_check(input, explained, fresh);
  } else {
    if (next_check_ != CheckCause::kNone && previous_) {
      // The hypotheses are placed on this frame's hand, segmented afresh (hint()), not where the
      // doubted pose says; the later frames of the check are segmented with the hint again (a
      // fresh segmentation on each of them lost the hand in one of them: docs/TRACKER.md).
      const HandPlace place = search_.place(input, SearchPurpose::kCheck);
      check_ = Check{true, next_check_, place, input.hand_centroid_mm, StartSearch::hypothesis_count(place), 0, 0, {}};
      search_.clear();
      next_check_ = CheckCause::kNone;
      // Spread over frames, the search starts on the next frame: this one's preprocessing, the
      // fresh segmentation, costs up to three times a tracked frame's, and a search slice on top
      // of it made it the slowest frame of a check (docs/BENCHMARKS.md, "A check's first frame").
      if (config_.check_iterations_per_frame > 0) check = CheckOutcome::kChecking;
    }
    if (check_.active && check == CheckOutcome::kNone) {
      fresh = continue_check(input, explained);
      check = fresh ? CheckOutcome::kRestartWon : check_.active ? CheckOutcome::kChecking : CheckOutcome::kTrackedKept;
    }
  }
  if (fresh) {
    best = fresh->result;
    explained = fresh->explained;
    winner = -1;
    guided_won = false;
    before_previous_.reset();  // no velocity from the wrong pose to the restart
    previous_.reset();
  }
  const double conf = explained.confidence;
  watch_confidence(conf, check);
  low_confidence_run_ = conf < config_.lost_confidence ? low_confidence_run_ + 1 : 0;
  if (low_confidence_run_ >= config_.lost_frames && previous_) {
    // The fit is clearly wrong: forget the history, so the next frame is segmented without the
    // wrong pose's hint and starts again from the open and closed hands. This frame reports
    // "recovering" with the pose it has.
    const PoseParams lost = best.params;
    reset();
    recovering_ = true;
    auto out = describe(lost, best.energy, TrackingState::kRecovering);
    out.confidence = conf;
    out.label_agreement = explained.label_agreement;
    out.winning_particle = winner;
    return out;
  } else if (conf >= config_.lost_confidence) {
    recovering_ = false;
  }
  // What the hand model cannot explain from any start is not a hand (a shoulder or a desk edge
  // reaching into the working volume): report no hand rather than invent a pose.
  if (started && conf < config_.min_start_confidence) return no_hand();
  before_previous_ = previous_;
  previous_ = best.params;
  auto out = describe(best.params, best.energy, recovering_ ? TrackingState::kRecovering : TrackingState::kTracking);
  out.confidence = conf;
  out.label_agreement = explained.label_agreement;
  out.winning_particle = winner;
  out.detection_guided_won = guided_won;
  return out;
}

std::optional<StartFit> PoseTracker::continue_check(const DepthInput& input, const FitExplained& tracked) {
  // StartSearch::run()'s search, about check_iterations_per_frame iterations a frame: hypotheses
  // screened on each frame (placed where the check's first frame found the hand), then the best
  // refined together, each frame continuing from the last (the hand moves meanwhile), and the best
  // of them compared with the tracked pose on the last frame.
  const int per_frame_iterations = config_.check_iterations_per_frame;
  const bool at_once = per_frame_iterations <= 0;
  if (check_.screened < check_.starts) {
    const auto per_frame = static_cast<size_t>(std::max(1, per_frame_iterations / StartSearch::kScreenIterations));
    const size_t end = at_once ? check_.starts : std::min(check_.starts, check_.screened + per_frame);
    // Placed where the check's first frame found the hand, moved as the segmented hand's centroid
    // has moved since.
    HandPlace place = check_.place;
    place.palm_centre_mm += input.hand_centroid_mm - check_.centroid_mm;
    for (; check_.screened < end; ++check_.screened) search_.screen(input, place, check_.screened);
    if (check_.screened == check_.starts) search_.keep_best(input);
    if (!at_once) return std::nullopt;
  }
  const int rest = search_.refine_iterations() - check_.refined;
  const int slice = std::max(1, per_frame_iterations / static_cast<int>(search_.kept()));
  const bool last = at_once || slice >= rest;
  const int iterations = last ? rest : slice;
  check_.refined += iterations;
  const StartFit best = search_.refine(input, iterations);
  if (!last) return std::nullopt;
  check_.active = false;
  return best.explained.score() > tracked.score() + config_.check_replace_margin ? std::optional<StartFit>(best)
                                                                                 : std::nullopt;
}

PoseTracker::CheckOutcome PoseTracker::background_check(const DepthInput& input, const FitExplained& tracked,
                                                        std::optional<StartFit>& fresh) {
  if (next_check_ != CheckCause::kNone) {
    // The search runs on copies of this frame's input (segmented afresh: hint()) and of the other
    // hand as it is now; while the last search's result is still under way (a cancelled one
    // finishing) the check waits for the next frame.
    if (!background_->submit(input, other_hand_, model())) return CheckOutcome::kNone;
    check_ = Check{true, next_check_, {}, input.hand_centroid_mm, 0, 0, 0, tracked};
    next_check_ = CheckCause::kNone;
    return CheckOutcome::kChecking;
  }
  if (!check_.active) return CheckOutcome::kNone;
  const std::optional<StartFit> found = background_->take();
  if (!found) return CheckOutcome::kChecking;
  check_.active = false;
  // Compared with the tracked pose on the check's frame, as a check on this thread compares them.
  if (found->explained.score() <= check_.tracked.score() + config_.check_replace_margin) {
    return CheckOutcome::kTrackedKept;
  }
  // The (re)start is of a frame some frames ago: moved as the segmented hand has moved since, and
  // fitted to this frame with the tracking's iterations. It replaces the tracked pose where it
  // explains this frame better too (the tracked pose may have found the hand meanwhile).
  PoseParams moved = found->result.params;
  moved.segment<3>(kTranslationParam) += input.hand_centroid_mm - check_.centroid_mm;
  const StartFit now = search_.fit(input, moved, config_.optimizer.iterations);
  if (now.explained.score() <= tracked.score()) return CheckOutcome::kTrackedKept;
  fresh = now;
  return CheckOutcome::kRestartWon;
}

void PoseTracker::watch_confidence(double conf, CheckOutcome check) {
  // A gross error shows as a sudden fall of the confidence (a knocked-off pose: 0.7-0.9 -> 0.15-0.5
  // on the synthetic motions) that the lost rule (an absolute threshold) misses while the wrong
  // pose still covers part of the hand. The level does not follow a suspect confidence down, so a
  // (re)start that is better than the wrong pose but still poor is checked again; a check that
  // keeps the tracked pose accepts its confidence as the level, so a pose that merely explains
  // less (a hand turned sideways) is not checked again and again.
  //
  // A wrong pose that never fell (a (re)start that chose it) is only found by looking again: a
  // level below recheck_below_confidence is rechecked every recheck_interval_frames frames. A
  // recheck that keeps the tracked pose leaves the level alone: nothing fell, and a fall that
  // comes while it runs (a fist forming that the fit does not follow) must still be suspect.
  const bool first = confidence_level_ <= 0.0;
  const bool suspect = !first && conf < config_.suspect_confidence_ratio * confidence_level_;
  if (first || (check == CheckOutcome::kTrackedKept && check_.cause == CheckCause::kFall)) {
    confidence_level_ = conf;
  } else if (!suspect) {
    confidence_level_ += config_.confidence_level_rate * (conf - confidence_level_);
  }
  frames_since_check_ = check == CheckOutcome::kNone ? frames_since_check_ + 1 : 0;
  const bool recheck = config_.recheck_interval_frames > 0 && frames_since_check_ >= config_.recheck_interval_frames &&
                       confidence_level_ < config_.recheck_below_confidence;
  const bool due = !check_.active && frames_since_check_ >= config_.check_interval_frames;
  next_check_ = !due      ? CheckCause::kNone
                : suspect ? CheckCause::kFall
                : recheck ? CheckCause::kRecheck
                          : CheckCause::kNone;
}

TrackerOutput PoseTracker::describe(const PoseParams& params, double energy,
                                    TrackingState state) {
  TrackerOutput out;
  out.state = state;
  out.params = params;
  out.energy = energy;
  out.scale = config_.scale;
  scratch_.update(model(), params);
  out.joints = scratch_.joints();
  for (int f = 0; f < kNumFingers; ++f) out.fingertips[static_cast<size_t>(f)] = scratch_.fingertip(f);
  out.palm_centre = scratch_.to_camera(model().palm_centre());
  out.palm_normal = scratch_.camera_R_hand() * Vector3d::UnitZ();
  // Tip Gaussians are the last of each finger's list: surface distance = centre distance - radii.
  const auto tip_sigma = [&](int finger) {
    return model().gaussians()[static_cast<size_t>(kBonesPerFinger * 2 * finger + 5)].sigma_mm;
  };
  out.pinch_distance_mm = std::max(0.0, (out.fingertips[kThumb] - out.fingertips[kIndex]).norm() -
                                            tip_sigma(kThumb) - tip_sigma(kIndex));
  out.pinch_strength = std::clamp(1.0 - out.pinch_distance_mm / kPinchOpenMm, 0.0, 1.0);
  return out;
}

}  // namespace handtrack
