// handtrack-eval: track sequence directories and score them against their ground truth with the
// paper's metrics (Sec. 7). SPEC.md "Evaluation output".
//
// Every sequence is tracked as handtrackd tracks, with HandsTracker (the frame shared out among
// hand slots, docs/TRACKER.md "Two hands"). A sequence whose hand.json names two hands is scored
// per hand (eval::HandsScorer, docs/SEQUENCES.md); a one-hand sequence with room for one hand,
// unless --max-hands 2 asks for room for two there too (a second hand reported is a phantom).
#include "handtrack/core/camera_roll.hpp"
#include "handtrack/core/hand_calibration.hpp"
#include "handtrack/core/hands_tracker.hpp"
#include "handtrack/core/part_forest.hpp"
#include "handtrack/core/sequence.hpp"
#include "handtrack/core/tracker.hpp"
#include "handtrack/draw/plot.hpp"
#include "handtrack/eval/scoring.hpp"
#include "handtrack/common/cli.hpp"
#include "handtrack/tools/output_file.hpp"
#include "handtrack/tools/progress.hpp"
#include "handtrack/tools/tracker_options.hpp"

#include <CLI/CLI.hpp>

#include <atomic>
#include <chrono>
#include <exception>
#include <filesystem>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <mutex>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

namespace fs = std::filesystem;
using namespace handtrack;

namespace {

constexpr const char* kProgram = "handtrack-eval";

std::string sequence_name(const fs::path& dir) {
  const auto name = fs::path(dir).lexically_normal().filename().string();
  return name.empty() ? fs::path(dir).lexically_normal().parent_path().filename().string() : name;
}

// What a sequence's hand.json says (SPEC.md "Sequence directory"): which hands it shows (read and
// checked by SequenceReader), and, from handtrack-synth, "view" and "motion" (strings), by which the
// scores are grouped. Absent file: nothing known. A view or motion that is not a string is an error
// naming the file.
struct SequenceInfo {
  std::vector<std::optional<Handedness>> hands;  // per ground-truth hand; one unknown without hand.json
  std::string view;
  std::string motion;
};

// hand.json's names (SequenceReader checked them: "right" or "left") in the tracker's words.
std::optional<Handedness> handedness_of(const std::string& name) {
  for (const Handedness h : {Handedness::kRight, Handedness::kLeft}) {
    if (name == to_string(h)) return h;
  }
  return std::nullopt;
}

SequenceInfo read_sequence_info(const SequenceReader& reader) {
  SequenceInfo info;
  info.hands.resize(static_cast<size_t>(reader.hand_count()));
  for (size_t k = 0; k < reader.hands().size(); ++k) info.hands[k] = handedness_of(reader.hands()[k]);
  const fs::path file = reader.dir() / "hand.json";
  if (!fs::exists(file)) return info;
  std::ifstream in(file);
  const auto j = nlohmann::json::parse(in, nullptr, false);
  for (const auto& [key, out] : {std::pair{"view", &info.view}, std::pair{"motion", &info.motion}}) {
    if (!j.contains(key)) continue;
    if (!j[key].is_string()) throw std::runtime_error(file.string() + ": field '" + key + "' must be a string");
    *out = j[key].get<std::string>();
  }
  return info;
}

// --tips-csv and --joints-csv: one row per frame with the estimated and the true points (mm),
// each point's columns named KIND STEM _AXIS: est0_x, ... true4_z for the fingertips (thumb..little),
// est_wrist_x, ... true_little_tip_z for the joints (SPEC.md's order). A true point not annotated is
// left empty.
struct PointColumns {
  std::vector<std::string> stems;  // one per point
  static PointColumns fingertips() {
    PointColumns c;
    for (int f = 0; f < kNumFingers; ++f) c.stems.push_back(std::to_string(f));
    return c;
  }
  static PointColumns joints() {
    PointColumns c;
    for (int j = 0; j < kNumJoints; ++j) c.stems.push_back("_" + std::string(joint_name(j)));
    return c;
  }
  void write_header(std::ostream& out) const {
    out << "sequence,frame,time_s,state";
    for (const char* kind : {"est", "true"}) {
      for (const auto& stem : stems) {
        for (const char axis : {'x', 'y', 'z'}) out << ',' << kind << stem << '_' << axis;
      }
    }
    out << '\n';
  }
};

// One row: the estimate's points, then the truth's (truth(k): point k, if annotated).
template <typename Estimated, typename Truth>
void write_points_row(std::ostream& out, const std::string& sequence, size_t frame, double time_s, TrackingState state,
                      const Estimated& estimated, size_t count, const Truth& truth) {
  out << sequence << ',' << frame << ',' << time_s << ',' << static_cast<int>(state);
  for (size_t k = 0; k < count; ++k) out << ',' << estimated[k].x() << ',' << estimated[k].y() << ',' << estimated[k].z();
  for (size_t k = 0; k < count; ++k) {
    if (const std::optional<Eigen::Vector3d> p = truth(k)) {
      out << ',' << p->x() << ',' << p->y() << ',' << p->z();
    } else {
      out << ",,,";
    }
  }
  out << '\n';
}

// The rows of one frame and hand for --tips-csv and --joints-csv (whichever are asked for).
void write_frame_rows(std::ostream* tips, std::ostream* joints, const std::string& sequence, size_t frame,
                      double time_s, const TrackerOutput& estimate, const Fingertips& true_tips,
                      const std::optional<Joints>& true_joints) {
  if (tips != nullptr) {
    write_points_row(*tips, sequence, frame, time_s, estimate.state, estimate.fingertips, kNumFingers,
                     [&](size_t k) { return true_tips[k]; });
  }
  if (joints != nullptr) {
    write_points_row(*joints, sequence, frame, time_s, estimate.state, estimate.joints, kNumJoints,
                     [&](size_t k) -> std::optional<Eigen::Vector3d> {
                       if (!true_joints) return std::nullopt;
                       return (*true_joints)[k];
                     });
  }
}

// The progress over all sequences' frames, which the --jobs workers share.
class SharedProgress {
 public:
  explicit SharedProgress(size_t total) : total_(total) {}
  void frame_done(const std::string& sequence) {
    const std::lock_guard lock(mutex_);
    progress_.update(sequence, static_cast<double>(++done_) / static_cast<double>(total_));
  }

 private:
  std::mutex mutex_;
  tools::Progress progress_{kProgram};
  size_t done_ = 0;
  size_t total_;
};

// What one worker's sequences share: the labeller (or the ground-truth labels behind
// --oracle-labels), the --tips-csv rows of the sequence at hand and the progress over all frames.
struct FrameLoop {
  CameraRoll roll = CameraRoll::k0;               // --camera-roll
  const PixelLabeller* labeller = nullptr;
  std::vector<uint8_t>* oracle_labels = nullptr;  // non-null: filled with each frame's labels/
  std::ostream* tips = nullptr;                   // non-null: --tips-csv
  std::ostream* joints = nullptr;                 // non-null: --joints-csv
  SharedProgress* progress = nullptr;
  const SequenceReader* warm_up = nullptr;        // non-null: --warm-up

  // One frame: turned upright (--camera-roll; into *turned), tracked, its hands turned back into
  // the camera's frame, where the truth is.
  HandsOutput track(HandsTracker& tracker, const DepthImage& camera_depth, DepthImage* turned) const {
    HandsOutput out = tracker.track(upright_frame(camera_depth, roll, turned), labeller);
    turn_to_camera(roll, &out);
    return out;
  }

  // --warm-up: every frame of that sequence tracked first, unscored, then one frame without a hand
  // (the hand has left), so that the scored sequence is a hand seen again in a session.
  void run_warm_up(HandsTracker& tracker, DepthImage* turned) const {
    if (warm_up == nullptr) return;
    for (size_t i = 0; i < warm_up->frame_count(); ++i) track(tracker, warm_up->depth(i), turned);
    DepthImage empty = warm_up->depth(0);
    std::fill(empty.depth_mm.begin(), empty.depth_mm.end(), 0.0F);
    track(tracker, empty, turned);
  }

  // Tracks every frame of `reader` (its warm-up first) and hands its output to score(i, output);
  // returns the seconds spent tracking.
  template <typename Score>
  double run(const SequenceReader& reader, HandsTracker& tracker, Score&& score) {
    DepthImage turned;
    run_warm_up(tracker, &turned);
    double seconds = 0.0;
    for (size_t i = 0; i < reader.frame_count(); ++i) {
      const DepthImage camera_depth = reader.depth(i);
      if (oracle_labels != nullptr) {
        const std::optional<Gray8Image> labels = reader.labels(i);
        oracle_labels->clear();  // a frame without labels/: none (FixedLabels then labels nothing)
        if (labels) turn_upright(labels->pixels, camera_depth.camera, roll, oracle_labels);
      }
      const auto t0 = std::chrono::steady_clock::now();
      const HandsOutput out = track(tracker, camera_depth, &turned);
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      score(i, out);
      progress->frame_done(sequence_name(reader.dir()));
    }
    return seconds;
  }
  [[nodiscard]] bool writes_points() const { return tips != nullptr || joints != nullptr; }
};

// One hand (SPEC.md): HandsTracker with room for one, scored by SequenceScorer.
eval::SequenceScore evaluate_one_hand(const SequenceReader& reader, const SequenceInfo& info, TrackerConfig config,
                                      FrameLoop& loop) {
  config.max_hands = 1;
  HandsTracker tracker(config);
  const std::string name = sequence_name(reader.dir());
  eval::SequenceScorer scorer(name, info.hands.front());
  TrackerOutput none;
  none.state = TrackingState::kNoHand;
  const double seconds = loop.run(
      reader, tracker,
      [&](size_t i, const HandsOutput& hands) {
        const TrackerOutput& out = hands.count > 0 ? hands.hands[0] : none;
        scorer.add(out, reader.fingertips(i), reader.joints(i));
        if (loop.writes_points()) {
          write_frame_rows(loop.tips, loop.joints, name, i, static_cast<double>(i) / reader.camera().fps, out,
                           reader.fingertips(i), reader.joints(i));
        }
      });
  return scorer.finish(seconds);
}

// Several hands: HandsTracker with room for `max_hands`, each ground-truth hand scored against the
// tracked hand matched to it (HandsScorer). --tips-csv: a row per ground-truth hand and frame, the
// sequence named NAME/hK, with its matched hand (state no_hand where none matched).
eval::SequenceScore evaluate_hands(const SequenceReader& reader, const SequenceInfo& info, TrackerConfig config,
                                   int max_hands, FrameLoop& loop) {
  config.max_hands = max_hands;
  HandsTracker tracker(config);
  const std::string name = sequence_name(reader.dir());
  eval::HandsScorer scorer(name, info.hands);
  std::vector<Fingertips> truth(info.hands.size());
  std::vector<std::optional<Joints>> joints(info.hands.size());
  const double seconds = loop.run(
      reader, tracker,
      [&](size_t i, const HandsOutput& out) {
        for (size_t k = 0; k < truth.size(); ++k) {
          truth[k] = reader.fingertips(i, static_cast<int>(k));
          joints[k] = reader.joints(i, static_cast<int>(k));
        }
        const std::span<const TrackerOutput> tracked(out.hands.data(), static_cast<size_t>(out.count));
        const eval::HandMatch match = scorer.add(tracked, truth, joints);
        if (!loop.writes_points()) return;
        for (size_t k = 0; k < truth.size(); ++k) {
          const int t = match.tracked_of_truth[k];
          write_frame_rows(loop.tips, loop.joints, name + "/h" + std::to_string(k), i,
                           static_cast<double>(i) / reader.camera().fps,
                           t >= 0 ? tracked[static_cast<size_t>(t)] : TrackerOutput{}, truth[k], joints[k]);
        }
      });
  return scorer.finish(seconds);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Track sequence directories and score them against ground truth (mean fingertip error, "
               "% of frames below 15/20/25/30 mm)."};
  std::vector<std::string> dirs;
  std::string json_file;
  std::string plot_file;
  std::string csv_file;
  std::string tips_file;
  std::string joints_file;
  std::string hand = "auto";
  std::string energy = "late-fusion";
  TrackerConfig config;
  app.add_option("sequences", dirs, "sequence directories (SPEC.md format, with groundtruth.csv)")
      ->required()
      ->check(CLI::ExistingDirectory);
  app.add_option("--json", json_file, "write the scores as JSON (SPEC.md)");
  app.add_option("--plot", plot_file, "write a PNG plot of the per-frame error");
  app.add_option("--csv", csv_file, "write per-frame errors as CSV (sequence,frame,error_mm)");
  app.add_option("--tips-csv", tips_file,
                 "write per-frame fingertips as CSV: sequence,frame,time_s,state, 15 estimated and 15 true "
                 "coordinates (mm; empty where not annotated); what scripts/filter-table smooths");
  app.add_option("--joints-csv", joints_file,
                 "write per-frame joints as CSV: sequence,frame,time_s,state, the 21 joints estimated and true "
                 "(est_wrist_x ... true_little_tip_z, mm; empty where the sequence has no joints.csv)");
  tools::add_hand_option(app, hand);
  std::string arrangement = "facing";
  tools::add_arrangement_option(app, arrangement);
  app.add_option("--energy", energy, "late-fusion (default, with the shipped forest) or depth-only")
      ->check(CLI::IsMember({"depth-only", "late-fusion"}));
  std::string forest_file;
  tools::add_forest_option(app, forest_file);
  app.add_option("--particles", config.particles, "pose particles per frame")->check(CLI::Range(1, 64));
  app.add_option("--iterations", config.optimizer.iterations, "optimizer iterations per particle")
      ->check(CLI::Range(1, 1000));
  app.add_option("--seed", config.seed, "random seed of the particle extrapolation");
  app.add_option("--w-col", config.weights.collision,
                 "w_c, weight of E_col (Sec. 4.1) in the (re)start search and its checks and in depth-only tracking")
      ->check(CLI::Range(0.0, 100.0));
  app.add_option("--w-col-tracking", config.weights.tracking_collision,
                 "w_c while late fusion tracks (default 0.5, measured best; docs/TRACKER.md, \"w_c while tracking\")")
      ->check(CLI::Range(0.0, 100.0));
  app.add_option("--w-lim", config.weights.limits, "w_l, weight of E_lim (Sec. 4.1)")->check(CLI::Range(0.0, 100.0));
  app.add_option("--w-smo", config.weights.smoothness, "w_s, weight of E_smo (Sec. 4.1)")->check(CLI::Range(0.0, 100.0));
  app.add_option("--coverage-cap", config.weights.coverage_cap,
                 "late fusion: c, E_sim's coverage cap while tracking (default 2, measured best; 0: the paper's E_sim; docs/TRACKER.md, \"E_sim's coverage cap\")")
      ->check(CLI::Range(0.0, 100.0));
  app.add_option("--slant-front", config.weights.slant_front,
                 "late fusion: k_max, how many sigma_h in front of a model Gaussian seen at a slant the surface may lie while tracking (default 1.5, measured best; 1: the paper's E_sim; docs/TRACKER.md, \"Surfaces seen at a slant\")")
      ->check(CLI::Range(1.0, 10.0));
  app.add_option("--w-unseen", config.weights.unseen_fingers,
                 "late fusion: w_u, weight of E_unseen while tracking (default 0.01, measured best; 0: the paper's energy; docs/TRACKER.md, \"Unseen fingers curl\")")
      ->check(CLI::Range(0.0, 100.0));
  app.add_option("--fusion-label-weight", config.fusion_label_weight,
                 "late fusion: label share lambda of the common energy that picks the particle")
      ->check(CLI::Range(0.0, 1.0));
  bool oracle_labels = false;
  app.add_flag("--oracle-labels", oracle_labels,
               "late fusion with the sequence's ground-truth labels/ instead of the forest (diagnosis)");
  std::string hand_profile;
  app.add_option("--hand-profile", hand_profile, "hand profile (handtrack-calibrate): the user's hand scale (Sec. 6)");
  app.add_option("--self-calibrate", config.self_calibrate,
                 "on (default): each hand's scale is calibrated from its frames held open toward the camera and then "
                 "tracked with, a handedness trial keeping the configured width and sigma (Sec. 6 made online; "
                 "docs/TRACKER.md, \"A hand calibrates itself\"); off: the default model's scale (or --hand-profile's) "
                 "throughout");
  std::string warm_up;
  app.add_option("--warm-up", warm_up,
                 "a sequence each tracker sees first, unscored, then a frame without a hand: every scored sequence a "
                 "hand seen again in a session (self-calibration keeps the scale it found; docs/TRACKER.md, \"A hand "
                 "calibrates itself\")")
      ->check(CLI::ExistingDirectory);
  app.add_option("--recheck-frames", config.recheck_interval_frames,
                 "recheck a fit whose running confidence is below recheck_below_confidence (0.8) every N frames "
                 "(default 30; 0: never; docs/TRACKER.md, \"Rechecks of a mediocre fit\")")
      ->check(CLI::Range(0, 100000));
  app.add_option("--handedness-recheck-frames", config.handedness_recheck_frames,
                 "try a hand whose fit stays below recheck_below_confidence as the other hand again every N frames "
                 "(default 60; 0: never; docs/TRACKER.md, \"Handedness by evidence over frames\")")
      ->check(CLI::Range(0, 100000));
  app.add_flag("--background-checks", config.background_checks,
               "checks searched on a thread of their own, as handtrackd does: frames never wait for a search, a "
               "check's result is taken when the other core has done it (the scores then vary from run to run; "
               "docs/TRACKER.md, \"Checks in the background\")");
  bool sim_only = false;
  app.add_flag("--sim-only", sim_only, "E_sim only: drop E_col, E_lim and E_smo (ablation of Fig. 6)");
  int jobs = 1;
  app.add_option("--jobs", jobs,
                 "sequences tracked at once, each on a thread of its own (default 1); the scores are the same, "
                 "the fps of each sequence is then measured beside the others")
      ->check(CLI::Range(1, 256));
  int max_hands = kMaxHands;
  app.add_option("--max-hands", max_hands,
                 "hands HandsTracker may report (default 2, as handtrackd); a one-hand sequence is tracked with "
                 "room for one hand unless this is given (a second hand reported there is a phantom)")
      ->check(CLI::Range(1, kMaxHands));
  app.add_option("--near-mm", config.input.near_mm, "near end of the working volume, mm (default 150, the paper's)")
      ->check(CLI::Range(1.0, 20000.0));
  app.add_option("--far-mm", config.input.far_mm,
                 "far end of the working volume, mm (default 600, the paper's; hands farther away are not seen)")
      ->check(CLI::Range(1.0, 20000.0));
  std::string camera_roll = "0";
  tools::add_camera_roll_option(app, camera_roll, " and its poses scored turned back");
  if (const auto exit_code = parse_command_line(app, argc, argv, kProgram, 1)) return *exit_code;
  if (config.input.far_mm <= config.input.near_mm) {
    return report_error(kProgram, "--far-mm must be greater than --near-mm", 1);
  }
  if (energy == "late-fusion" && forest_file.empty() && !oracle_labels) {
    const auto shipped = shipped_forest_path();
    if (!shipped) {
      return report_error(kProgram,
                          "no part forest found for late fusion: pass --forest MODEL, set $HANDTRACK_FOREST, or use "
                          "--energy depth-only",
                          1);
    }
    forest_file = shipped->string();
  }
  if (energy == "late-fusion") config.mode = EnergyMode::kLateFusion;
  parse_handedness_mode(hand, &config.handedness);  // one of the names CLI11 checked
  parse_camera_arrangement(arrangement, &config.arrangement);
  if (sim_only) {
    config.weights.collision = config.weights.tracking_collision = 0.0;
    config.weights.limits = config.weights.smoothness = 0.0;
  }

  try {
    if (!hand_profile.empty()) config.scale = load_hand_profile(hand_profile);
    if (!warm_up.empty() && oracle_labels) throw std::runtime_error("--warm-up: not with --oracle-labels");
    std::optional<SequenceReader> warm_up_reader;
    if (!warm_up.empty()) warm_up_reader.emplace(warm_up);
    std::optional<PartForest> forest;
    if (config.mode == EnergyMode::kLateFusion && !oracle_labels) forest.emplace(PartForest::load(forest_file));
    const bool use_oracle_labels = config.mode == EnergyMode::kLateFusion && oracle_labels;
    std::vector<SequenceReader> readers;
    size_t total_frames = 0;
    const bool hands_asked = app.count("--max-hands") > 0 && max_hands > 1;
    for (const auto& d : dirs) {
      readers.emplace_back(d);
      // Without annotated fingertips a sequence is scored for its handedness alone, where its
      // hand.json names the one hand it shows (a real recording labelled only with its hand).
      // Tracked hands are matched to several by their fingertips, so not with --max-hands 2.
      const std::size_t hands = readers.back().hands().size();
      if (!readers.back().has_groundtruth() && (hands != 1 || hands_asked)) {
        const bool present = std::filesystem::exists(std::filesystem::path(d) / "groundtruth.csv");
        throw std::runtime_error(
            d + (present ? "/groundtruth.csv: no annotated frame in it" : ": no groundtruth.csv") +
            (hands == 0 ? " and no hand.json naming its hand, nothing to score"
                        : ": tracked hands are matched to the sequence's by their annotated fingertips (one hand "
                          "without them is scored for its handedness alone, without --max-hands)"));
      }
      if (oracle_labels && readers.back().frame_count() > 0 && !readers.back().labels(0)) {
        throw std::runtime_error(d + ": no labels/, needed by --oracle-labels");
      }
      total_frames += readers.back().frame_count();
    }
    // The point files opened, and the other outputs checked, before anything is tracked: a path
    // that cannot be written is refused with one line.
    std::ofstream tips_out;
    std::ofstream joints_out;
    for (const auto& [file, out, columns] : {std::tuple{&tips_file, &tips_out, PointColumns::fingertips()},
                                             std::tuple{&joints_file, &joints_out, PointColumns::joints()}}) {
      if (file->empty()) continue;
      out->open(*file);
      if (!*out) throw std::runtime_error(*file + ": cannot write");
      columns.write_header(*out);
    }
    for (const std::string* file : {&json_file, &csv_file, &plot_file}) tools::check_writable(*file);
    // --jobs: workers take the sequences in turn, each tracked from its first frame by a tracker of
    // its own, so every score is what one job gives; the results are gathered in the given order.
    std::vector<eval::SequenceScore> scores(readers.size());
    std::vector<std::string> tips_rows(readers.size());
    std::vector<std::string> joints_rows(readers.size());
    std::vector<std::exception_ptr> failures(readers.size());
    SharedProgress progress(total_frames);
    std::atomic<size_t> next_sequence{0};
    const auto work = [&] {
      // --oracle-labels: each frame's labels/NNNNNN.png through FixedLabels, which points at this.
      std::vector<uint8_t> truth_labels;
      const FixedLabels oracle(&truth_labels);
      FrameLoop loop;
      loop.labeller = use_oracle_labels ? &oracle : forest ? static_cast<const PixelLabeller*>(&*forest) : nullptr;
      loop.oracle_labels = use_oracle_labels ? &truth_labels : nullptr;
      loop.roll = *parse_camera_roll(camera_roll);  // one of the values the option's check let through
      loop.progress = &progress;
      loop.warm_up = warm_up_reader ? &*warm_up_reader : nullptr;
      for (size_t i = next_sequence++; i < readers.size(); i = next_sequence++) {
        std::ostringstream tips;
        std::ostringstream joints;
        loop.tips = tips_file.empty() ? nullptr : &tips;
        loop.joints = joints_file.empty() ? nullptr : &joints;
        try {
          const SequenceInfo info = read_sequence_info(readers[i]);
          scores[i] = readers[i].hand_count() > 1 || hands_asked
                          ? evaluate_hands(readers[i], info, config, max_hands, loop)
                          : evaluate_one_hand(readers[i], info, config, loop);
          scores[i].view = info.view;
          scores[i].motion = info.motion;
        } catch (...) {
          failures[i] = std::current_exception();
          next_sequence = readers.size();  // the run fails: no worker starts another sequence
        }
        tips_rows[i] = std::move(tips).str();
        joints_rows[i] = std::move(joints).str();
      }
    };
    {
      std::vector<std::jthread> helpers;
      for (int j = 1; j < std::min(jobs, static_cast<int>(readers.size())); ++j) helpers.emplace_back(work);
      work();
    }
    for (const auto& failure : failures) {
      if (failure) std::rethrow_exception(failure);
    }
    for (const auto& rows : tips_rows) tips_out << rows;
    for (const auto& rows : joints_rows) joints_out << rows;
    const auto total = eval::overall(scores);
    // A mean over no frame is not a result: every annotated frame got no pose (or a NaN one). Nor is
    // a handedness over no frame, where nothing is annotated.
    const int annotated = total.scored + total.without_pose;
    if (annotated > 0 && total.scored == 0) {
      throw std::runtime_error("no frame could be scored: the tracker reported no hand in all " +
                               std::to_string(annotated) + " frames with ground truth");
    }
    if (annotated == 0 && total.hand_known_frames == 0) {
      throw std::runtime_error("no frame could be scored: no fingertip is annotated, and the tracker reported no hand "
                               "in any of the " + std::to_string(total.frames) + " frames");
    }
    const auto groups = eval::group_scores(scores);
    const auto json = eval::to_json(scores, total, groups);
    if (!json_file.empty()) {
      std::ofstream json_out(json_file);
      json_out << json.dump(2) << "\n";
      if (!json_out.flush()) throw std::runtime_error(json_file + ": cannot write");
    }
    if (!csv_file.empty()) {
      std::ofstream csv_out(csv_file);
      csv_out << "sequence,frame,error_mm\n";
      for (const auto& s : scores) {
        for (size_t i = 0; i < s.per_frame_error_mm.size(); ++i) {
          csv_out << s.name << "," << i << "," << s.per_frame_error_mm[i] << "\n";
        }
      }
      if (!csv_out.flush()) throw std::runtime_error(csv_file + ": cannot write");
    }
    if (!plot_file.empty()) {
      std::vector<draw::ErrorSeries> series;
      for (const auto& s : scores) series.push_back({s.name, s.per_frame_error_mm});
      draw::write_error_plot(plot_file, series);
    }
    // A human-readable table on stdout: the paper's Table 1 in our numbers.
    std::fputs(eval::format_table(scores, total, groups).c_str(), stdout);
  } catch (const std::exception& e) {
    return report_error(kProgram, e.what(), 1);
  }
  return 0;
}
