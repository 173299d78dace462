// StartSearch (start_search.hpp): the (re)start hypotheses, their successive halving, and how
// much of the segmented hand a fit explains.
#include "handtrack/core/start_search.hpp"

#include "handtrack/core/tracker.hpp"

#include <Eigen/Geometry>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace handtrack {

using Eigen::Vector3d;

namespace {
// (Re)start hypotheses: the open hand of Sec. 5 and, since a hand often enters or is lost as a
// fist, a closed hand; each turned by a few in-plane rotations (rad) around the segmented axis.
constexpr std::array<double, 3> kStartRotations = {0.0, 0.4, -0.4};
constexpr std::array<bool, 2> kStartClosed = {false, true};
// ... each with the palm toward the camera, the back of the hand, and either edge (the thumb's,
// the little finger's): turned about the hand's finger axis (rad). Without the edges a hand seen
// side-on was fitted as a flattened hand of the other side (docs/TRACKER.md, "Every view").
constexpr std::array<double, 4> kStartTurns = {0.0, std::numbers::pi, 0.5 * std::numbers::pi,
                                               -0.5 * std::numbers::pi};
// Successive halving (StartSearch::run): after screening, this many of the best go on.
constexpr size_t kRefinedStarts = 3;
// The part labels choose among fits that explain the depth about as well as the most confident
// one: a fit whose confidence falls short of the most confident refined fit's by more than this
// is not chosen for its label agreement (ours). On real depth the forest, trained on renders,
// mislabels: in SR305 frame 230536/130 it calls most of an open hand's fingers "palm", and the
// right hand's search chose a fit with its fingers bunched over the palm (confidence 0.61, label
// agreement 0.68) over one on the fingers (0.97, 0.35), so the frame was taken for a left hand in
// every run. On the benchmark the labels' choices that this keeps (a fist, a flat hand seen from
// behind) lie within it: 0.15 cost the back view 1.2 mm and 3 points of handedness, 0.25 and 0.3
// left seeds 1-6 as they were (docs/TRACKER.md, "Labels that contradict the depth").
constexpr double kLabelChoiceLead = 0.25;
// Hypotheses in one plane (the image's or along the 3D axis): turns x closed x rotations; at most
// two planes.
constexpr size_t kStartsPerPlane = kStartTurns.size() * kStartClosed.size() * kStartRotations.size();
constexpr size_t kMaxStarts = 2 * kStartsPerPlane;
// A hand whose segmented axis points this much toward or away from the camera (|a_z|, the sine of
// the angle out of the image plane: 45 deg) is also started with its fingers along that axis in 3D:
// a hand reaching forward under a head-mounted camera, fingers pointing at a desk camera.
constexpr double kOutOfPlaneAxisMinZ = 0.7;
bool out_of_image_plane(const HandPlace& place) { return std::abs(place.finger_axis.z()) >= kOutOfPlaneAxisMinZ; }
// A fist seen along its fingers (toward or away from the camera) shows a round blob whose
// segmented axis lies in the image plane and may point either way (toward the forearm or from
// it), and the closed hypotheses, with their fingers in that plane, start far from it: with the
// fingers toward the camera 44-57 mm, and with the search's E_col they end 35-90 mm off
// (fingercount: docs/TRACKER.md, "A fist at a (re)start"). So where the axis lies in the image
// plane and the hand is no longer than a fist, eight more closed hands: palm or back toward the
// camera, at either end of the axis, tipped kFistTipRad toward or away from the camera (toward:
// 0.6, 0.9 and 1.2 rad ended 17.5, 16.5 and 16.9 mm off on fingercount's first frame, seed 1; away
// the same angle, not scanned). Not where the axis points out of the image plane: there the
// along-axis hypotheses cover it, and tipped fists won the head-mounted view's fists in wrong poses
// (flexex1 head-mounted right s3: 37.6 -> 63.1 mm). Not for a longer hand: tipped fists of the
// wrong hand won flat open real hands (SR305 frame 231615/40 turned to the left hand).
constexpr double kFistTipRad = 0.9;
constexpr size_t kTippedFists = 8;
// A hand is no longer than a fist where its length in the image plane (StartSearch::place) is at
// most this, times the model's length scale: an adult fist from the wrist to the knuckles is about
// 100-110 mm. Measured lengths on fingercount's first frame (a fist; seeds 1-3): 87-90 mm seen
// along the fingers toward the camera, 94-102 away from it, 95-110 from the back, 109-122 from the
// side; open hands seen flat 140-176 mm; the 19 real SR305 hands 132-176 mm (two of them segmented
// on their first frame as a 70-75 mm sliver).
constexpr double kFistLengthMm = 115.0;
// Closed hand: [abd, flex1, flex2, flex3] for the thumb, then for each finger.
constexpr std::array<double, 4> kClosedThumb = {0.3, 0.6, 0.5, 0.5};
constexpr std::array<double, 4> kClosedFinger = {0.0, 1.3, 1.5, 0.9};
constexpr double kClosedFingersInFrontMm = 40.0;

// confidence(): the share of the hand's data explained by the fitted model, times the share of
// model Gaussians that sit on data. Not from the paper: set with the recovery check of issue 4
// (docs/TRACKER.md "Recovery") and kept since.
// A model Gaussian whose centre is nearer the camera than this is behind it (cannot project).
constexpr double kMinProjectableDepthMm = 1.0;
// A data leaf is explained by a model Gaussian that covers it in the image and whose surface is
// within this depth of the leaf: kExplainSigmas model sigmas plus kExplainMarginMm of noise.
constexpr double kExplainSigmas = 2.0;
constexpr double kExplainMarginMm = 10.0;
// A model Gaussian "floats" (counts against the fit) when the data under its centre is missing or
// farther than its surface by more than kFloatSigmas sigmas plus kFloatMarginMm; data nearer the
// camera merely occludes it.
constexpr double kFloatSigmas = 3.0;
constexpr double kFloatMarginMm = 20.0;
}  // namespace

double fit_score(double confidence, double label_agreement) {
  return label_agreement < 0.0 ? confidence : confidence * label_agreement;
}


StartSearch::StartSearch(const TrackerConfig& config)
    : init_iterations_(config.init_iterations),
      late_fusion_(config.mode == EnergyMode::kLateFusion),
      model_(HandModel::default_adult(config.scale)),
      energy_(SimilarityFactor::kDepth, search_weights(config)),
      guided_energy_(SimilarityFactor::kDepthAndLabel, search_weights(config)),
      optimizer_(config.optimizer),
      scratch_(model_, PoseParams::Zero()),
      scale_(config.scale) {
  screened_.reserve(kMaxStarts);
}

void StartSearch::set_model(const HandModel& model) {
  if (model.scale() == scale_) return;
  scale_ = model.scale();
  model_ = model;  // vectors of the same sizes: copied into their storage
}


StartHypothesis StartSearch::hypothesis(const HandPlace& place, size_t k) {
  // Hypothesis k: by plane (the image's, then along the 3D axis), turn, closed, and in-plane
  // rotation, the last changing fastest; or, after the image plane's, a tipped fist (turn, then
  // end of the axis, then toward or away from the camera).
  StartHypothesis start;
  if (k >= kStartsPerPlane && !out_of_image_plane(place)) {
    const size_t t = k - kStartsPerPlane;
    start.closed = true;
    start.turn_rad = t % 2 == 0 ? 0.0 : std::numbers::pi;
    start.in_plane_offset_rad = (t / 2) % 2 == 0 ? 0.0 : std::numbers::pi;
    start.tip_rad = t < kTippedFists / 2 ? -kFistTipRad : kFistTipRad;
    return start;
  }
  const size_t in_plane = k % kStartsPerPlane;
  start.along_axis_3d = k >= kStartsPerPlane;
  start.turn_rad = kStartTurns[in_plane / (kStartClosed.size() * kStartRotations.size())];
  start.closed = kStartClosed[(in_plane / kStartRotations.size()) % kStartClosed.size()];
  start.in_plane_offset_rad = kStartRotations[in_plane % kStartRotations.size()];
  return start;
}

size_t StartSearch::hypothesis_count(const HandPlace& place) {
  if (out_of_image_plane(place)) return kMaxStarts;
  return place.fist_sized ? kStartsPerPlane + kTippedFists : kStartsPerPlane;
}

HandPlace StartSearch::place(const DepthInput& input, SearchPurpose purpose) const {
  HandPlace place{input.palm_centre_mm, input.finger_axis, false};
  // Tipped fists at (re)starts only: in checks of a tracked pose they won over fists seen from the
  // back as they closed, whose tracking then walked off (flexex1 back left s4: 17.6 -> 34.6 mm;
  // docs/TRACKER.md, "Fists tipped toward and away from the camera").
  if (purpose == SearchPurpose::kCheck) return place;
  // The hand's length in the image plane: the spread of its points (x, y in mm) along their
  // principal direction, times sqrt(12), the length of a uniform bar with that spread.
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  Eigen::Matrix2d sum_sq = Eigen::Matrix2d::Zero();
  int pixels = 0;
  for_each_hand_point(input, [&](const Vector3d& point) {
    const Eigen::Vector2d p = point.head<2>();
    sum += p;
    sum_sq += p * p.transpose();
    ++pixels;
  });
  double length_mm = 0.0;
  if (pixels > 0) {
    const Eigen::Vector2d mean = sum / pixels;
    const Eigen::Matrix2d cov = sum_sq / pixels - mean * mean.transpose();
    length_mm = std::sqrt(12.0 * std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov).eigenvalues()(1)));
  }
  place.fist_sized = length_mm <= kFistLengthMm * scale_.length;
  return place;
}

PoseParams StartSearch::initial_pose(const HandPlace& place, const StartHypothesis& start) const {
  // Frontal open hand (r = 0: fingers toward -y in the image) turned in the image plane onto the
  // hand's axis: rotation phi about the camera z maps (0,-1) to (sin phi, -cos phi). The back of
  // the hand faces the camera after half a turn about the finger axis (the camera y axis at r = 0)
  // first: R = Rz(phi) Ry(pi).
  const Vector3d& axis = place.finger_axis;
  const double phi = std::atan2(axis.x(), -axis.y()) + start.in_plane_offset_rad;
  PoseParams params = PoseParams::Zero();
  Eigen::Matrix3d turn = Eigen::AngleAxisd(phi, Vector3d::UnitZ()).toRotationMatrix() *
                         Eigen::AngleAxisd(start.turn_rad, Vector3d::UnitY()).toRotationMatrix();
  if (start.along_axis_3d) {
    // Then tipped about the camera-frame axis perpendicular to both (the image-plane direction and
    // the 3D axis) until the fingers run along the 3D axis: the palm (or back) stays as square to
    // the camera as that allows.
    const Vector3d in_plane = turn * Vector3d(0, -1, 0);
    const Vector3d along = (Eigen::AngleAxisd(start.in_plane_offset_rad, Vector3d::UnitZ()) * axis).normalized();
    turn = Eigen::Quaterniond::FromTwoVectors(in_plane, along).toRotationMatrix() * turn;
  }
  if (start.tip_rad != 0.0) {
    // About f x z, f the fingers' direction (in the image plane): f -> f cos(tip) + z sin(tip).
    const Vector3d fingers = turn * Vector3d(0, -1, 0);
    turn = Eigen::AngleAxisd(start.tip_rad, fingers.cross(Vector3d::UnitZ()).normalized()).toRotationMatrix() * turn;
  }
  params.segment<3>(kRotationParam) = rotation_log(turn);
  if (start.closed) {
    for (int f = 0; f < kNumFingers; ++f) {
      for (int d = 0; d < 4; ++d) {
        params[angle_param(f, d)] = (f == kThumb ? kClosedThumb : kClosedFinger)[static_cast<size_t>(d)];
      }
    }
  }
  // The segmented palm centre is a surface point; the model's palm centre lies behind it: half a
  // palm thickness behind the palm or the back, half the palm's width behind an edge. A closed hand
  // with its palm toward the camera shows its curled fingers, which lie in front of the palm by
  // about two finger thicknesses.
  // (Measured the other way, as the depth of the posed model's nearest surface along the ray
  // through its palm centre, this put the fists of fingercount 75 mm off.)
  const double palm_half_thickness = model_.palm_half_thickness_mm();
  const double palm_half_width = model_.palm_half_width_mm();
  // cos(turn): 1 with the palm toward the camera, -1 with the back (the curled fingers behind it).
  const double palm_toward = std::max(0.0, std::cos(start.turn_rad));
  const double facing = std::abs(std::cos(start.turn_rad));
  const double behind_surface = facing * palm_half_thickness + (1.0 - facing) * palm_half_width +
                                (start.closed ? palm_toward * kClosedFingersInFrontMm : 0.0);
  const Vector3d target = place.palm_centre_mm + Vector3d(0, 0, behind_surface);
  // The model's palm centre turned as the pose turns it (no PosedHand: a check screens hypotheses
  // on the hot path, where nothing is allocated).
  const Vector3d centre = hand_rotation(params) * model_.palm_centre();
  params.segment<3>(kTranslationParam) = target - centre;
  return params;
}

FitExplained StartSearch::explain(const DepthInput& input, const PosedHand& hand) const {
  if (input.gaussians.empty()) return {};
  const auto& cam = input.camera;
  const auto& gaussians = model_.gaussians();
  struct Projected {
    double u, v, sigma, depth, reach;
  };
  std::array<Projected, 64> projected{};
  const int m = std::min<int>(hand.gaussian_count(), static_cast<int>(projected.size()));
  int bad = 0;
  for (int p = 0; p < m; ++p) {
    const Vector3d& mu = hand.centre(p);
    const double sigma_h = gaussians[static_cast<size_t>(p)].sigma_mm;
    if (mu.z() < kMinProjectableDepthMm) {
      ++bad;
      projected[static_cast<size_t>(p)] = {-1e9, -1e9, 0, 0, 0};
      continue;
    }
    const Eigen::Vector2d uv = cam.project(mu);
    projected[static_cast<size_t>(p)] = {uv.x(), uv.y(), sigma_h * cam.focal() / mu.z(), mu.z() - sigma_h,
                                         kExplainSigmas * sigma_h + kExplainMarginMm};
    // A model Gaussian over no data or over background floats in empty space; one behind data
    // nearer the camera is merely occluded.
    const int u = static_cast<int>(std::lround(uv.x()));
    const int v = static_cast<int>(std::lround(uv.y()));
    if (u < 0 || v < 0 || u >= cam.width || v >= cam.height) {
      ++bad;
      continue;
    }
    const float d = input.filtered_mm[static_cast<size_t>(v) * cam.width + u];
    const double surface = mu.z() - sigma_h;
    if (d <= 0.0F || d > surface + kFloatSigmas * sigma_h + kFloatMarginMm) ++bad;
  }
  // Each leaf is explained by the covering model Gaussian nearest to it (relative to its reach in
  // the image); a labelled leaf agrees when that Gaussian is of the same finger (or both palm).
  double covered = 0.0;
  double total = 0.0;
  double labelled = 0.0;
  double agreeing = 0.0;
  for (const auto& q : input.gaussians) {
    const double area = static_cast<double>(q.side_px) * q.side_px;
    total += area;
    int nearest = -1;
    double nearest_ratio = 1.0;
    for (int p = 0; p < m; ++p) {
      const auto& pr = projected[static_cast<size_t>(p)];
      const double du = pr.u - q.u;
      const double dv = pr.v - q.v;
      const double r = pr.sigma + 0.5 * q.side_px;
      const double ratio = (du * du + dv * dv) / (r * r);
      if (ratio < nearest_ratio && std::abs(pr.depth - q.depth_mm) < pr.reach) {
        nearest = p;
        nearest_ratio = ratio;
        if (q.label == kBackground) break;  // any covering Gaussian explains an unlabelled leaf
      }
    }
    if (nearest < 0) continue;
    covered += area;
    if (q.label != kBackground) {
      labelled += area;
      if (part_finger(q.label) == part_finger(gaussians[static_cast<size_t>(nearest)].label)) agreeing += area;
    }
  }
  const double coverage = total > 0.0 ? covered / total : 0.0;
  return {coverage * (1.0 - static_cast<double>(bad) / std::max(1, m)), labelled > 0.0 ? agreeing / labelled : -1.0};
}

StartFit StartSearch::fit_from(const DepthInput& input, const PoseParams& from, int iterations,
                                const PoseEnergy& with) {
  const EnergyFrame frame{&model_, &input, nullptr, nullptr, other_hand_};
  const auto r = optimizer_.maximise(with, frame, from, scratch_, iterations);
  iterations_ += iterations;
  scratch_.update(model_, r.params);
  return StartFit{r, explain(input, scratch_)};
}

const PoseEnergy& StartSearch::start_energy(const DepthInput& input) const {
  return fuses(input) ? guided_energy_ : energy_;
}

void StartSearch::screen(const DepthInput& input, const HandPlace& place, size_t k) {
  screened_.push_back(fit_from(input, initial_pose(place, hypothesis(place, k)),
                               std::min(kScreenIterations, init_iterations_), start_energy(input)));
}

void StartSearch::keep_best(const DepthInput& input) {
  // The kRefinedStarts best by fit score go on, each with the start energy and, with late fusion,
  // also with the depth-only energy: on real depth the forest (trained on renders) mislabels, and
  // the guided energy alone fitted 3 of 7 SR305 frames as the other hand (docs/TRACKER.md, "Real
  // frames"). With late fusion the most confident screened hypothesis goes on too, with the
  // depth-only energy, where none of those is as confident: the fit the depth favours, whatever
  // the labels say of it (in SR305 230536/130 it was fourth by score; kLabelChoiceLead).
  if (screened_.empty()) return;
  const auto kept = std::min(kRefinedStarts, screened_.size());
  std::partial_sort(screened_.begin(), screened_.begin() + static_cast<std::ptrdiff_t>(kept), screened_.end(),
                    better);
  if (&start_energy(input) == &energy_) {
    screened_.resize(kept);
    return;
  }
  // The first of the most confident: a kept one wherever one of them is as confident.
  const auto most_confident = std::max_element(
      screened_.begin(), screened_.end(),
      [](const StartFit& a, const StartFit& b) { return a.explained.confidence < b.explained.confidence; });
  const bool kept_it = most_confident < screened_.begin() + static_cast<std::ptrdiff_t>(kept);
  const StartFit extra = *most_confident;
  screened_.resize(kept);
  for (size_t k = 0; k < kept; ++k) screened_.push_back(screened_[k]);
  if (!kept_it) screened_.push_back(extra);
}

StartFit StartSearch::refine(const DepthInput& input, int iterations) {
  // screened_ after keep_best(): the start energy's candidates first, then (late fusion)
  // the depth-only ones.
  double most_confident = 0.0;
  for (size_t k = 0; k < screened_.size(); ++k) {
    const PoseEnergy& with = k < kRefinedStarts ? start_energy(input) : energy_;
    screened_[k] = iterations > 0 ? fit_from(input, screened_[k].result.params, iterations, with) : screened_[k];
    most_confident = std::max(most_confident, screened_[k].explained.confidence);
  }
  // The best by fit score of those that explain the depth about as well as the most confident.
  StartFit best;
  for (const StartFit& fit : screened_) {
    if (fit.explained.confidence >= most_confident - kLabelChoiceLead && better(fit, best)) best = fit;
  }
  return best;
}

bool StartSearch::better(const StartFit& a, const StartFit& b) {
  // By score; on a tie (the same share explained), by energy.
  return a.explained.score() > b.explained.score() + 1e-9 ||
         (a.explained.score() > b.explained.score() - 1e-9 && a.result.energy > b.result.energy);
}

StartFit StartSearch::run(const DepthInput& input, SearchPurpose purpose, const std::atomic<bool>* stop) {
  // The hypotheses are compared by confidence, not energy: E_sim has no notion of occlusion, so
  // a wrong pose that pushes the big palm Gaussians onto the visible surface can out-score the right
  // one (seen on fists), while it explains little of the hand's outline. No temporal prior: the
  // history is what is in doubt. With late fusion the hypotheses optimise the detection-guided
  // energy (Sec. 4.3): the part labels say where the palm and each finger are, which the open and
  // closed hands do not know (docs/TRACKER.md "Recovery": 17 of 21 knocked-off trackers back
  // within 30 frames with the depth-only energy, 21 with this one).
  //
  // Successive halving: every hypothesis gets kScreenIterations, then only the kRefinedStarts best
  // (by fit score) get the rest of init_iterations. All hypotheses to the end cost 24-48 x 80
  // iterations, 40-100 ms on one frame at every start (and check made at once).
  clear();
  const HandPlace place = this->place(input, purpose);
  for (size_t k = 0; k < hypothesis_count(place); ++k) {
    if (stop != nullptr && stop->load(std::memory_order_relaxed)) return {};
    screen(input, place, k);
  }
  keep_best(input);
  return refine(input, refine_iterations());
}

bool StartSearch::fuses(const DepthInput& input) const {
  // Late fusion needs part labels on the leaves; without them every particle is depth-only.
  return late_fusion_ &&
         std::any_of(input.gaussians.begin(), input.gaussians.end(),
                     [](const ImageGaussian& g) { return g.label != kBackground; });
}

}  // namespace handtrack
