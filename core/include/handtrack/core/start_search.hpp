#pragma once
// StartSearch: Sec. 5's (re)start, widened to every view a hand can show a camera (docs/TRACKER.md,
// "Every view"): pose hypotheses placed on the segmented hand (open and closed; palm, back and
// either edge toward the camera; a few in-plane rotations; along the hand's 3D axis where it points
// at or away from the camera), optimised by successive halving, and the best by fit score.
// PoseTracker searches with one at a (re)start and to check a suspect fit; a BackgroundSearch runs
// another on a thread of its own (TrackerConfig::background_checks).
//
// Thread roles: thread-bound; each search object has its own model, energies and scratch.
#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/energy.hpp"
#include "handtrack/core/hand_model.hpp"
#include "handtrack/core/optimizer.hpp"

#include <atomic>
#include <cstddef>
#include <utility>
#include <vector>

namespace handtrack {

struct TrackerConfig;

// How well a fit explains the segmented hand, for choosing between fits (the (re)start hypotheses,
// the tracked pose against a (re)start, one hand against the other): the confidence, times the
// label agreement where there are part labels. Without the labels a hand fitted with its thumb on
// its little finger's side explains the depth about as well as the right one (a right hand's back
// fitted as a left hand's back: docs/TRACKER.md, "Every view").
double fit_score(double confidence, double label_agreement);

// How much of the segmented hand a posed model explains (StartSearch::explain).
struct FitExplained {
  double confidence = 0.0;  // in [0, 1]
  // Of the labelled hand pixels the model explains, the share whose part label (Sec. 4.3) names
  // the finger (or the palm) of the model Gaussian that explains them; -1 without labels.
  double label_agreement = -1.0;
  [[nodiscard]] double score() const { return fit_score(confidence, label_agreement); }
};

// A pose and how much of the segmented hand it explains.
struct StartFit {
  OptimizerResult result{PoseParams::Zero(), -1e300};
  FitExplained explained{-1.0, -1.0};
};

// Where a (re)start places its hypotheses: the segmented hand's palm centre and finger axis.
struct HandPlace {
  Eigen::Vector3d palm_centre_mm = Eigen::Vector3d::Zero();
  Eigen::Vector3d finger_axis = Eigen::Vector3d(0, -1, 0);
  // At a (re)start, the segmented hand is no longer in the image plane than a fist
  // (StartSearch::place): tipped fists are tried too.
  bool fist_sized = false;
};

// What a search is for: a (re)start, where there is no pose to go on, or a check of a tracked
// pose, which a search's best replaces only where it explains the hand better.
enum class SearchPurpose { kStart, kCheck };

// One (re)start hypothesis: Sec. 5's open hand, or a closed one, placed at the segmented hand.
struct StartHypothesis {
  double in_plane_offset_rad = 0.0;  // turned about the camera axis away from the segmented axis
  bool closed = false;               // a fist instead of the open hand
  // Turned about the hand's finger axis: 0 the palm toward the camera, pi the back, +-pi/2 a side
  // (the thumb's or the little finger's edge) toward it.
  double turn_rad = 0.0;
  bool along_axis_3d = false;        // fingers along the segmented axis in 3D, not in the image plane
  // Then tipped about the image-plane axis across the fingers: negative toward the camera,
  // positive away from it.
  double tip_rad = 0.0;
};

class StartSearch {
 public:
  // Every hypothesis gets this many iterations first (screen()), and only the best few the rest of
  // TrackerConfig::init_iterations (refine()).
  static constexpr int kScreenIterations = 15;

  explicit StartSearch(const TrackerConfig& config);
  // The model of another search of the same structure (a default adult at another scale): copied
  // into this one's storage, without allocating, where its scale differs.
  void set_model(const HandModel& model);
  // Another hand in the frame that the fits must not enter; null: none. It must outlive the
  // searches that use it.
  void set_other_hand(const HandObstacle* other) { other_hand_ = other; }
  [[nodiscard]] const HandModel& model() const { return model_; }

  // The whole search on one frame: every hypothesis screened, the best refined; the best fit.
  // `stop` (may be null) set: it returns at the next hypothesis with a fit to be dropped.
  StartFit run(const DepthInput& input, SearchPurpose purpose, const std::atomic<bool>* stop = nullptr);
  // One pose `iterations` further on `input` with the energy the hypotheses optimise.
  StartFit fit(const DepthInput& input, const PoseParams& from, int iterations) {
    return fit_from(input, from, iterations, start_energy(input));
  }
  // The same in pieces, for a search spread over frames: where the hypotheses go on `input`'s
  // segmented hand, forget the last search, the number of hypotheses at `place` (24, 32 for a hand
  // no longer than a fist, 48 for a hand out of the image plane), screen the k-th, keep the best
  // screened, refine the kept ones `iterations` further (the best of them).
  [[nodiscard]] HandPlace place(const DepthInput& input, SearchPurpose purpose) const;
  void clear() { screened_.clear(); }
  static size_t hypothesis_count(const HandPlace& place);
  void screen(const DepthInput& input, const HandPlace& place, size_t k);
  void keep_best(const DepthInput& input);
  [[nodiscard]] size_t kept() const { return screened_.size(); }
  StartFit refine(const DepthInput& input, int iterations);
  // Refinement iterations a kept hypothesis gets after screening.
  [[nodiscard]] int refine_iterations() const { return std::max(0, init_iterations_ - kScreenIterations); }

  [[nodiscard]] PoseParams initial_pose(const HandPlace& place, const StartHypothesis& start) const;
  [[nodiscard]] FitExplained explain(const DepthInput& input, const PosedHand& hand) const;
  // Late fusion with part labels on the leaves.
  [[nodiscard]] bool fuses(const DepthInput& input) const;
  // By fit score; on a tie (the same share explained), by energy.
  static bool better(const StartFit& a, const StartFit& b);
  // Optimiser iterations since the last call.
  int take_iterations() { return std::exchange(iterations_, 0); }

 private:
  static StartHypothesis hypothesis(const HandPlace& place, size_t k);
  StartFit fit_from(const DepthInput& input, const PoseParams& from, int iterations, const PoseEnergy& with);
  [[nodiscard]] const PoseEnergy& start_energy(const DepthInput& input) const;

  int init_iterations_;
  bool late_fusion_;
  HandModel model_;
  // The energies a search optimises (search_weights): depth-only (Sec. 4.1), detection-guided
  // (Sec. 4.3).
  PoseEnergy energy_;
  PoseEnergy guided_energy_;
  AdaptiveGradientAscent optimizer_;
  PosedHand scratch_;
  HandScale scale_;  // model_'s
  std::vector<StartFit> screened_;  // the hypotheses after screening, then the kept ones
  const HandObstacle* other_hand_ = nullptr;
  int iterations_ = 0;
};

}  // namespace handtrack
