#pragma once
// The paper's metrics (Sec. 7, "Error Metrics"): per frame, the mean Euclidean distance over the
// annotated fingertips; per sequence, the mean of that over the scored frames and the percentage of
// frames with an error below 15, 20, 25 and 30 mm (after Qian et al. 2014).
//
// Several hands (issue 14; ours, the paper tracks one): each frame's tracked hands are matched to
// its ground-truth hands by position (match_hands), and each ground-truth hand is scored as a
// sequence of its own (HandsScorer), with the multi-hand failures besides: misses, the wrong side,
// identity swaps and phantom hands.

#include "handtrack/core/sequence.hpp"
#include "handtrack/core/tracker.hpp"

#include <nlohmann/json.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace handtrack::eval {

inline constexpr std::array<int, 4> kThresholdsMm = {15, 20, 25, 30};

// Mean distance (mm) between the tracked and the annotated fingertips; NaN when no fingertip is
// annotated. A frame without a pose (state no_hand) scores +infinity: it is below no threshold.
double fingertip_error_mm(const TrackerOutput& out, const Fingertips& truth);

// The 21 joints (SPEC.md: joints.csv) by their place on the hand, each scored apart besides the
// paper's fingertips: the wrist, then each finger's joints from its base (the thumb's CMC, MCP and
// IP in the places of the other fingers' MCP, PIP and DIP). Where the fingertips' error comes from:
// a hand placed or turned wrongly moves the wrist and the bases, a wrong flexion only the joints
// beyond them.
inline constexpr std::array<const char*, 5> kJointKinds = {"wrist", "mcp", "pip", "dip", "tip"};

// The joint errors of the frames with a pose and annotated joints, summed: per frame the mean
// distance over all 21 joints (the mean joint error of the hand-pose literature) and over each
// kind's joints.
struct JointErrors {
  int frames = 0;
  double sum_mm = 0.0;
  std::array<double, kJointKinds.size()> kind_sum_mm{};

  void add(const Joints& tracked, const Joints& truth);
  void add(const JointErrors& other);
  [[nodiscard]] double mean_mm() const;                    // NaN: no frame
  [[nodiscard]] double kind_mean_mm(size_t kind) const;  // likewise
};

struct SequenceScore {
  std::string name;
  int frames = 0;              // frames tracked
  int scored = 0;              // frames with annotations and a pose
  int without_pose = 0;        // annotated frames where the tracker reported no hand
  int nan_poses = 0;           // frames whose pose had a non-finite number (must stay 0)
  int guided_wins = 0;         // late fusion: frames the detection-guided particle won
  double mean_error_mm = 0.0;  // over scored frames (NaN: none)
  double max_error_mm = 0.0;
  std::array<double, kThresholdsMm.size()> pct_below{};  // over annotated frames (NaN: none)
  double fps = 0.0;            // single-threaded tracking rate (preprocessing + optimisation)
  // Handedness (SPEC.md: DIR/hand.json says which hand a sequence shows): of the frames with a
  // pose, how many were reported as a left hand, and, where the sequence says, as the right hand.
  std::optional<Handedness> expected_hand;
  int posed_frames = 0;
  int left_frames = 0;
  int hand_known_frames = 0;  // posed frames of sequences that say their hand
  int hand_correct = 0;
  std::vector<double> per_frame_error_mm;  // NaN = not annotated, inf = no pose
  // What the sequence's hand.json says besides its hand ("" where it does not): the camera
  // arrangement (handtrack-synth --view) and the motion; the benchmark's groups.
  std::string view;
  std::string motion;
  // Several hands (HandsScorer; empty and 0 when scored as one hand). Per ground-truth hand its own
  // score: name "hand K", expected_hand its side, per_frame_error_mm its errors (inf: missed, i.e.
  // no tracked hand matched it), posed_frames / hand_correct over the frames it was matched, and
  // identity_swaps. The sequence's own per-frame error pools the fingertips of all hands (a frame
  // with a missed hand is a miss); its handedness counts sum the hands'.
  std::vector<SequenceScore> hands;
  int identity_swaps = 0;  // a hand's matched hand_id changed between two consecutive matched frames
  int phantom_frames = 0;  // frames with a tracked hand matched to no ground-truth hand
  int phantom_hands = 0;   // such tracked hands, summed over the frames
  // Where the sequence has joints.csv: its frames' joint errors (HandsScorer: all hands').
  JointErrors joints;
};

// Sequences pooled by a property (overall() of each group), e.g. "view" -> {"back": ..., "palm": ...}.
struct ScoreGroups {
  std::string by;  // "motion", "view" or "hand"
  std::vector<SequenceScore> groups;  // name = the property's value
};
// The groups by motion, view and hand, each only where at least one sequence says its value.
std::vector<ScoreGroups> group_scores(const std::vector<SequenceScore>& sequences);

// Accumulates one sequence's frames.
class SequenceScorer {
 public:
  explicit SequenceScorer(std::string name, std::optional<Handedness> expected_hand = std::nullopt) {
    score_.name = std::move(name);
    score_.expected_hand = expected_hand;
  }
  // One frame: the fingertips annotated, and the 21 joints where the sequence has them.
  void add(const TrackerOutput& out, const Fingertips& truth, const std::optional<Joints>& joints = std::nullopt);
  SequenceScore finish(double tracking_seconds);

 private:
  SequenceScore score_;
};

// All frames of all sequences pooled (the paper's overall figures); per-hand scores pooled by the
// hand's index.
SequenceScore overall(const std::vector<SequenceScore>& sequences);

// A tracked hand farther than this from every ground-truth hand (fingertip centroids) is matched to
// none: a phantom. About a hand's length: a fit on the right hand is well within it, a fit on the
// other hand (>= 150 mm away in the two-hand scenes when apart) outside.
inline constexpr double kHandMatchRadiusMm = 100.0;

// One frame's assignment of tracked to ground-truth hands.
struct HandMatch {
  std::vector<int> truth_of_tracked;  // per tracked hand: its ground-truth hand, -1 for none
  std::vector<int> tracked_of_truth;  // per ground-truth hand: its tracked hand, -1 for none
};
// The distance of a tracked hand to a ground-truth hand: between the centroids of the fingertips
// annotated in `truth` and of the same fingers of `tracked`,
//   d = | (1/n) sum_f (tracked_f - truth_f) |,  f over the n annotated fingers;
// none when no fingertip is annotated, or the tracked hand has no pose.
std::optional<double> hand_distance_mm(const TrackerOutput& tracked, const Fingertips& truth);
// The assignment (each hand in at most one pair, pairs only within `radius_mm`) with the most pairs,
// and among those the smallest total distance: an exhaustive search, as there are a few hands.
HandMatch match_hands(std::span<const TrackerOutput> tracked, std::span<const Fingertips> truth,
                      double radius_mm = kHandMatchRadiusMm);

// Accumulates one sequence whose frames may show several hands, tracked by HandsTracker.
class HandsScorer {
 public:
  // `truth_hands`: each ground-truth hand's side, in the order of the ground-truth blocks (nullopt:
  // the sequence does not say).
  HandsScorer(std::string name, const std::vector<std::optional<Handedness>>& truth_hands);
  // One frame: the tracked hands and each ground-truth hand's fingertips (truth.size() = the hands
  // given to the constructor), and its joints where the sequence has them (empty, or one per hand).
  // Returns the frame's match.
  HandMatch add(std::span<const TrackerOutput> tracked, std::span<const Fingertips> truth,
                std::span<const std::optional<Joints>> joints = {});
  SequenceScore finish(double tracking_seconds);

 private:
  SequenceScore score_;
  std::vector<uint32_t> last_id_;  // per ground-truth hand: the id matched in the last frame, 0: none
};

// The paper's Table 1 in our numbers: one row per sequence and the overall row, as text.
// Then, one block per grouping: "by view", one row per view, and so on; and where sequences were
// scored per hand, "per hand": a row per ground-truth hand.
std::string format_table(const std::vector<SequenceScore>& sequences, const SequenceScore& total,
                         const std::vector<ScoreGroups>& groups = {});

// SPEC.md "Evaluation output", and "groups": {"view": {"back": {...}, ...}, "hand": {...}}; where
// sequences were scored per hand, their "hands": [{...}, {...}] and phantoms (docs/SEQUENCES.md).
nlohmann::json to_json(const std::vector<SequenceScore>& sequences, const SequenceScore& total,
                       const std::vector<ScoreGroups>& groups = {});

}  // namespace handtrack::eval
