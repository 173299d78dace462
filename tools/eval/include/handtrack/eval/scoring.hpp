#pragma once
// The paper's metrics (Sec. 7, "Error Metrics"): per frame, the mean Euclidean distance over the
// annotated fingertips; per sequence, the mean of that over the scored frames and the percentage of
// frames with an error below 15, 20, 25 and 30 mm (after Qian et al. 2014).

#include "handtrack/core/sequence.hpp"
#include "handtrack/core/tracker.hpp"

#include <nlohmann/json.hpp>

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace handtrack::eval {

inline constexpr std::array<int, 4> kThresholdsMm = {15, 20, 25, 30};

// Mean distance (mm) between the tracked and the annotated fingertips; NaN when no fingertip is
// annotated. A frame without a pose (state no_hand) scores +infinity: it is below no threshold.
double fingertip_error_mm(const TrackerOutput& out, const Fingertips& truth);

struct SequenceScore {
  std::string name;
  int frames = 0;              // frames tracked
  int scored = 0;              // frames with annotations and a pose
  int without_pose = 0;        // annotated frames where the tracker reported no hand
  int nan_poses = 0;           // frames whose pose had a non-finite number (must stay 0)
  int guided_wins = 0;         // late fusion: frames the detection-guided particle won
  double mean_error_mm = 0.0;  // over scored frames
  double max_error_mm = 0.0;
  std::array<double, kThresholdsMm.size()> pct_below{};  // over annotated frames
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
  void add(const TrackerOutput& out, const Fingertips& truth);
  SequenceScore finish(double tracking_seconds);

 private:
  SequenceScore score_;
};

// All frames of all sequences pooled (the paper's overall figures).
SequenceScore overall(const std::vector<SequenceScore>& sequences);

// The paper's Table 1 in our numbers: one row per sequence and the overall row, as text.
// Then, one block per grouping: "by view", one row per view, and so on.
std::string format_table(const std::vector<SequenceScore>& sequences, const SequenceScore& total,
                         const std::vector<ScoreGroups>& groups = {});

// SPEC.md "Evaluation output".
// SPEC.md "Evaluation output", and "groups": {"view": {"back": {...}, ...}, "hand": {...}}.
nlohmann::json to_json(const std::vector<SequenceScore>& sequences, const SequenceScore& total,
                       const std::vector<ScoreGroups>& groups = {});

}  // namespace handtrack::eval
