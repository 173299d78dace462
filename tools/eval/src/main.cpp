// handtrack-eval: track sequence directories and score them against their ground truth with the
// paper's metrics (Sec. 7). SPEC.md "Evaluation output".
#include "handtrack/core/hand_calibration.hpp"
#include "handtrack/core/part_forest.hpp"
#include "handtrack/core/sequence.hpp"
#include "handtrack/core/tracker.hpp"
#include "handtrack/draw/plot.hpp"
#include "handtrack/eval/scoring.hpp"
#include "handtrack/common/cli.hpp"
#include "handtrack/tools/progress.hpp"

#include <CLI/CLI.hpp>

#include <chrono>
#include <filesystem>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <optional>

namespace fs = std::filesystem;
using namespace handtrack;

namespace {

constexpr const char* kProgram = "handtrack-eval";

std::string sequence_name(const fs::path& dir) {
  const auto name = fs::path(dir).lexically_normal().filename().string();
  return name.empty() ? fs::path(dir).lexically_normal().parent_path().filename().string() : name;
}

// What a sequence's hand.json says (SPEC.md "Sequence directory"): {"hands":["left"]}, which hand
// it shows, and, from handtrack-synth, "view" and "motion" (strings). Absent file: nothing known.
// Anything else in it is an error naming the file.
struct SequenceInfo {
  std::optional<Handedness> hand;
  std::string view;
  std::string motion;
};

SequenceInfo read_sequence_info(const fs::path& dir) {
  const fs::path file = dir / "hand.json";
  SequenceInfo info;
  if (!fs::exists(file)) return info;
  std::ifstream in(file);
  const auto j = nlohmann::json::parse(in, nullptr, false);
  const auto optional_string = [&](const char* key, std::string& out) {
    if (!j.contains(key)) return true;
    if (!j[key].is_string()) return false;
    out = j[key].get<std::string>();
    return true;
  };
  if (j.is_object() && j.contains("hands") && j["hands"].is_array() && j["hands"].size() == 1 &&
      j["hands"][0].is_string() && optional_string("view", info.view) && optional_string("motion", info.motion)) {
    const auto hand = j["hands"][0].get<std::string>();
    if (hand == "left") info.hand = Handedness::kLeft;
    if (hand == "right") info.hand = Handedness::kRight;
    if (info.hand) return info;
  }
  throw std::runtime_error(file.string() +
                           ": expected {\"hands\":[\"left\"]} or {\"hands\":[\"right\"]}, with optional string "
                           "\"view\" and \"motion\"");
}

// --tips-csv: one row per frame with the estimated and the true fingertips.
void write_tips_header(std::ostream& out) {
  out << "sequence,frame,time_s,state";
  for (const char* kind : {"est", "true"}) {
    for (int f = 0; f < kNumFingers; ++f) {
      for (const char axis : {'x', 'y', 'z'}) out << ',' << kind << f << '_' << axis;
    }
  }
  out << '\n';
}

void write_tips_row(std::ostream& out, const std::string& sequence, size_t frame, double time_s,
                    const TrackerOutput& estimate, const Fingertips& truth) {
  out << sequence << ',' << frame << ',' << time_s << ',' << static_cast<int>(estimate.state);
  for (const auto& tip : estimate.fingertips) out << ',' << tip.x() << ',' << tip.y() << ',' << tip.z();
  for (const auto& tip : truth) {
    if (tip) {
      out << ',' << tip->x() << ',' << tip->y() << ',' << tip->z();
    } else {
      out << ",,,";
    }
  }
  out << '\n';
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
  app.add_option("--hand", hand, "auto (default: both hands, the better fit chosen at every (re)start), right or left")
      ->check(CLI::IsMember({"right", "left", "auto"}));
  app.add_option("--energy", energy, "late-fusion (default, with the shipped forest) or depth-only")
      ->check(CLI::IsMember({"depth-only", "late-fusion"}));
  std::string forest_file;
  app.add_option("--forest", forest_file,
                 "part-classification forest for late fusion (default: the shipped one, $HANDTRACK_FOREST, "
                 "data/ or /usr/share/handtrack)")
      ->check(CLI::ExistingFile);
  app.add_option("--particles", config.particles, "pose particles per frame")->check(CLI::Range(1, 64));
  app.add_option("--iterations", config.optimizer.iterations, "optimizer iterations per particle")
      ->check(CLI::Range(1, 1000));
  app.add_option("--seed", config.seed, "random seed of the particle extrapolation");
  app.add_option("--w-col", config.weights.collision, "w_c, weight of E_col (Sec. 4.1)")->check(CLI::Range(0.0, 100.0));
  app.add_option("--w-lim", config.weights.limits, "w_l, weight of E_lim (Sec. 4.1)")->check(CLI::Range(0.0, 100.0));
  app.add_option("--w-smo", config.weights.smoothness, "w_s, weight of E_smo (Sec. 4.1)")->check(CLI::Range(0.0, 100.0));
  app.add_option("--fusion-label-weight", config.fusion_label_weight,
                 "late fusion: label share lambda of the common energy that picks the particle")
      ->check(CLI::Range(0.0, 1.0));
  bool oracle_labels = false;
  app.add_flag("--oracle-labels", oracle_labels,
               "late fusion with the sequence's ground-truth labels/ instead of the forest (diagnosis)");
  std::string hand_profile;
  app.add_option("--hand-profile", hand_profile, "hand profile (handtrack-calibrate): the user's hand scale (Sec. 6)");
  bool sim_only = false;
  app.add_flag("--sim-only", sim_only, "E_sim only: drop E_col, E_lim and E_smo (ablation of Fig. 6)");
  if (const auto exit_code = parse_command_line(app, argc, argv, kProgram, 1)) return *exit_code;
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
  if (sim_only) config.weights.collision = config.weights.limits = config.weights.smoothness = 0.0;

  try {
    if (!hand_profile.empty()) config.scale = load_hand_profile(hand_profile);
    std::optional<PartForest> forest;
    if (config.mode == EnergyMode::kLateFusion && !oracle_labels) forest.emplace(PartForest::load(forest_file));
    // --oracle-labels: each frame's labels/NNNNNN.png through FixedLabels, which points at this.
    std::vector<uint8_t> truth_labels;
    const FixedLabels oracle(&truth_labels);
    const PixelLabeller* labeller = forest ? static_cast<const PixelLabeller*>(&*forest) : nullptr;
    if (config.mode == EnergyMode::kLateFusion && oracle_labels) labeller = &oracle;
    std::vector<eval::SequenceScore> scores;
    std::vector<SequenceReader> readers;
    size_t total_frames = 0;
    for (const auto& d : dirs) {
      readers.emplace_back(d);
      if (!readers.back().has_groundtruth()) {
        const bool present = std::filesystem::exists(std::filesystem::path(d) / "groundtruth.csv");
        throw std::runtime_error(d + (present ? "/groundtruth.csv: no annotated frame in it, nothing to score"
                                              : ": no groundtruth.csv, nothing to score"));
      }
      if (oracle_labels && readers.back().frame_count() > 0 && !readers.back().labels(0)) {
        throw std::runtime_error(d + ": no labels/, needed by --oracle-labels");
      }
      total_frames += readers.back().frame_count();
    }
    std::ofstream tips_out;
    if (!tips_file.empty()) {
      tips_out.open(tips_file);
      if (!tips_out) throw std::runtime_error(tips_file + ": cannot write");
      write_tips_header(tips_out);
    }
    tools::Progress progress(kProgram);
    size_t done = 0;
    for (const auto& reader : readers) {
      Tracker tracker(config);
      const SequenceInfo info = read_sequence_info(reader.dir());
      eval::SequenceScorer scorer(sequence_name(reader.dir()), info.hand);
      double seconds = 0.0;
      for (size_t i = 0; i < reader.frame_count(); ++i) {
        const DepthImage depth = reader.depth(i);
        if (labeller == &oracle) truth_labels = reader.labels(i).value_or(Gray8Image{}).pixels;
        const auto t0 = std::chrono::steady_clock::now();
        const TrackerOutput out = tracker.track(depth, labeller);
        seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        scorer.add(out, reader.fingertips(i));
        if (tips_out.is_open()) {
          write_tips_row(tips_out, sequence_name(reader.dir()), i, static_cast<double>(i) / reader.camera().fps, out,
                         reader.fingertips(i));
        }
        progress.update(sequence_name(reader.dir()), static_cast<double>(++done) / static_cast<double>(total_frames));
      }
      scores.push_back(scorer.finish(seconds));
      scores.back().view = info.view;
      scores.back().motion = info.motion;
    }
    const auto total = eval::overall(scores);
    // A mean over no frame is not a result: every annotated frame got no pose (or a NaN one).
    if (total.scored == 0) {
      throw std::runtime_error("no frame could be scored: the tracker reported no hand in all " +
                               std::to_string(total.frames) + " frames with ground truth");
    }
    const auto groups = eval::group_scores(scores);
    const auto json = eval::to_json(scores, total, groups);
    if (!json_file.empty()) {
      std::ofstream out(json_file);
      if (!out) throw std::runtime_error(json_file + ": cannot write");
      out << json.dump(2) << "\n";
    }
    if (!csv_file.empty()) {
      std::ofstream out(csv_file);
      if (!out) throw std::runtime_error(csv_file + ": cannot write");
      out << "sequence,frame,error_mm\n";
      for (const auto& s : scores) {
        for (size_t i = 0; i < s.per_frame_error_mm.size(); ++i) out << s.name << "," << i << "," << s.per_frame_error_mm[i] << "\n";
      }
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
