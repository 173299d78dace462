// handtrack-bench: the paper's speed table (Sec. 7, "Tracking Speed") in one process, on one
// synthetic 320x240 input: each configuration tracks the same pre-rendered frames on one thread;
// preprocessing (median, segmentation, forest labels, quadtree) and optimisation are timed apart.
// SPEC.md "Benchmark output". Besides the paper's three: one hand with room for two (the daemon's
// default, max_hands 2), and two hands (issue 14) with the second hand preprocessed and optimised on
// a side thread (the daemon's way) and all on the same thread; hand_overlap says how much of the
// two hands' optimisation ran at once. --runs N measures every configuration N times in rounds
// (each round all of them once, in order), so that a shared host's swings, 20 % from one minute
// to the next here (docs/BENCHMARKS.md), fall on every configuration alike; each figure is then
// the median of its N runs, and each run's fps is listed beside it.
#include "handtrack/core/part_forest.hpp"
#include "handtrack/core/hands_tracker.hpp"
#include "handtrack/common/side_thread.hpp"
#include "handtrack/synth/synthetic_camera.hpp"
#include "handtrack/common/cli.hpp"
#include "handtrack/tools/output_file.hpp"
#include "handtrack/tools/progress.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <functional>
#include <optional>
#include <string>
#include <vector>

using namespace handtrack;

namespace {

constexpr const char* kProgram = "handtrack-bench";

struct BenchConfig {
  std::string name;
  EnergyMode mode;
  int particles;
  int iterations;
  int max_hands = 1;
  bool two_hand_input = false;  // the two-hand scene, else the one-hand motion
  bool side_thread = false;     // a frame's second hand (preprocessing, optimisation) on a SideThread
  int check_iterations_per_frame = 0;  // TrackerConfig's: 0 checks at once, N spread over frames
  bool background_checks = false;      // TrackerConfig's: checks on a thread of their own
};

// Renders `frames` depth frames of `motion` by subject `seed` (noise, 320x240).
std::vector<DepthImage> render(const std::string& motion, int frames, uint64_t seed, CameraIntrinsics* camera) {
  synth::SynthOptions options;
  options.motion = motion;
  options.frames = frames;
  options.seed = seed;
  synth::SyntheticCamera synthetic(options);
  *camera = synthetic.camera();
  std::vector<DepthImage> input;
  for (int i = 0; i < frames; ++i) input.push_back(synthetic.render(i).depth);
  return input;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<size_t>(q * static_cast<double>(v.size() - 1) + 0.5)];
}

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// One run of one configuration over the frames.
struct Measurement {
  double fps = 0.0;
  double preprocess_ms = 0.0;  // medians over the frames
  double optimize_ms = 0.0;
  double p50_ms = 0.0;  // latency percentiles over the frames
  double p99_ms = 0.0;
  double hands_per_frame = 0.0;
  double hand_overlap = 0.0;
  // Each frame's own figures, for --frames-csv.
  struct Frame {
    double preprocess_ms;
    double optimize_ms;
    int hands;
    int iterations;  // the optimiser's, all hands together (TrackerOutput::iterations)
  };
  std::vector<Frame> frames;
};

// The median over runs of one figure of theirs (of an even count, the mean of the middle two).
double median_of(const std::vector<Measurement>& runs, double Measurement::*figure) {
  std::vector<double> v;
  for (const Measurement& m : runs) v.push_back(m.*figure);
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n == 0 ? 0.0 : n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"The paper's speed table: every configuration on the same synthetic 320x240 frames, one thread."};
  std::string json_file;
  std::string frames_csv;
  std::string forest_file = shipped_forest_path().value_or("");
  std::string motion = "random";
  std::string two_hand_motion = "two_apart";
  int frames = 300;
  uint64_t seed = 7;
  std::vector<std::string> only;
  app.add_option("--json", json_file, "write the table as JSON (SPEC.md)");
  app.add_option("--frames-csv", frames_csv,
                 "write each frame's figures as CSV: configuration,run,frame,preprocess_ms,optimize_ms,hands,"
                 "iterations (a search or a handedness trial shows as a frame of hundreds of iterations)");
  app.add_option("--forest", forest_file, "part forest for the late-fusion configuration")->check(CLI::ExistingFile);
  app.add_option("--motion", motion, "synthetic motion to track");
  app.add_option("--two-hand-motion", two_hand_motion, "synthetic two-hand scene of the two-hand configurations");
  app.add_option("--frames", frames, "frames per configuration")->check(CLI::Range(10, 100000));
  app.add_option("--seed", seed,
                 "subject of the synthetic scenes (hand size, noise; default 7): the search frames a scene draws "
                 "move the fps, so compare a change over several");
  app.add_option("--only", only, "measure only these configurations (by name; default: all)");
  int runs = 1;
  app.add_option("--runs", runs,
                 "measure every configuration this many times, in rounds, and report each figure's median over "
                 "the runs and each run's fps (a shared host swings from minute to minute)")
      ->check(CLI::Range(1, 100));
  if (const auto exit_code = parse_command_line(app, argc, argv, kProgram, 1)) return *exit_code;

  try {
    tools::check_writable(json_file);
    tools::check_writable(frames_csv);
    const PartForest forest = PartForest::load(forest_file);
    CameraIntrinsics camera;

    const std::vector<BenchConfig> configs = {
        {"depth_only_1p_10it", EnergyMode::kDepthOnly, 1, 10},
        {"depth_only_2p_10it", EnergyMode::kDepthOnly, 2, 10},
        {"late_fusion_2p_10it", EnergyMode::kLateFusion, 2, 10},
        {"late_fusion_2p_10it_max_hands_2", EnergyMode::kLateFusion, 2, 10, 2},
        {"two_hands_late_fusion_2p_10it", EnergyMode::kLateFusion, 2, 10, 2, true, true},
        {"two_hands_late_fusion_2p_10it_one_thread", EnergyMode::kLateFusion, 2, 10, 2, true, false},
        // The latency setting: checks spread over frames at 64 iterations a frame.
        {"depth_only_2p_10it_spread_checks", EnergyMode::kDepthOnly, 2, 10, 1, false, false, 64},
        {"late_fusion_2p_10it_spread_checks", EnergyMode::kLateFusion, 2, 10, 1, false, false, 64},
        // The other latency setting: checks searched on a thread of their own, on idle CPU time.
        {"late_fusion_2p_10it_background_checks", EnergyMode::kLateFusion, 2, 10, 1, false, false, 0, true},
        {"two_hands_late_fusion_2p_10it_background_checks", EnergyMode::kLateFusion, 2, 10, 2, true, true, 0, true}};
    for (const std::string& name : only) {
      if (std::none_of(configs.begin(), configs.end(), [&](const BenchConfig& bc) { return bc.name == name; }))
        throw std::runtime_error("--only: no configuration named '" + name + "'");
    }
    const auto measured = [&](const BenchConfig& bc) {
      return only.empty() || std::find(only.begin(), only.end(), bc.name) != only.end();
    };
    // The frames of each scene that a measured configuration tracks, rendered before any timing.
    const auto frames_of = [&](bool two_hand_scene, const std::string& scene) {
      const bool tracked = std::any_of(configs.begin(), configs.end(), [&](const BenchConfig& bc) {
        return measured(bc) && bc.two_hand_input == two_hand_scene;
      });
      return tracked ? render(scene, frames, seed, &camera) : std::vector<DepthImage>{};
    };
    const std::vector<DepthImage> one_hand = frames_of(false, motion);
    const std::vector<DepthImage> two_hands = frames_of(true, two_hand_motion);
    // One run of a configuration: the shipped tracker (handedness auto) over the frames, its two
    // steps timed apart.
    const auto run_once = [&](const BenchConfig& bc, const std::function<void(double)>& done_share) {
      TrackerConfig tc;
      tc.mode = bc.mode;
      tc.particles = bc.particles;
      tc.optimizer.iterations = bc.iterations;
      tc.max_hands = bc.max_hands;
      tc.check_iterations_per_frame = bc.check_iterations_per_frame;
      tc.background_checks = bc.background_checks;
      HandsInputs inputs(input_config(tc));
      HandsTracker tracker(tc);
      std::optional<SideThread> side;
      if (bc.side_thread) side.emplace();
      const PixelLabeller* labeller = bc.mode == EnergyMode::kLateFusion ? &forest : nullptr;
      const std::vector<DepthImage>& input = bc.two_hand_input ? two_hands : one_hand;
      HandsRequest request;
      const DepthImage* depth = nullptr;
      const std::function<void()> build_second = [&] { inputs.build_slot(1, *depth, request, labeller); };
      const std::function<void()> fit_second = [&] { tracker.fit(1, inputs); };
      Measurement m;
      std::vector<double> pre_ms, opt_ms, latency_ms;
      double hands = 0.0;
      double hand_ms = 0.0;  // sum over frames and hands of each hand's own optimisation
      double opt_total_ms = 0.0;
      const auto start = std::chrono::steady_clock::now();
      for (int i = 0; i < frames; ++i) {
        const auto t0 = std::chrono::steady_clock::now();
        request = tracker.request();
        depth = &input[static_cast<size_t>(i)];
        SideThread* const side_thread = side ? &*side : nullptr;
        run_slots(inputs.share(*depth, request), side_thread, build_second,
                  [&](int s) { inputs.build_slot(s, *depth, request, labeller); });
        const auto t1 = std::chrono::steady_clock::now();
        run_slots(tracker.begin(inputs), side_thread, fit_second, [&](int s) { tracker.fit(s, inputs); });
        const HandsOutput result = tracker.finish();
        pre_ms.push_back(std::chrono::duration<double, std::milli>(t1 - t0).count());
        opt_ms.push_back(ms_since(t1));
        opt_total_ms += opt_ms.back();
        latency_ms.push_back(pre_ms.back() + opt_ms.back());
        hands += result.count;
        int iterations = 0;
        for (int k = 0; k < result.count; ++k) {
          hand_ms += result.optimize_ms[static_cast<size_t>(k)];
          iterations += result.hands[static_cast<size_t>(k)].iterations;
        }
        m.frames.push_back({pre_ms.back(), opt_ms.back(), result.count, iterations});
        done_share(static_cast<double>(i + 1) / frames);
      }
      m.fps = frames / (ms_since(start) / 1000.0);
      m.preprocess_ms = percentile(pre_ms, 0.5);
      m.optimize_ms = percentile(opt_ms, 0.5);
      m.p50_ms = percentile(latency_ms, 0.5);
      m.p99_ms = percentile(latency_ms, 0.99);
      m.hands_per_frame = hands / frames;
      // How much of the hands' own optimisation ran at once: 1 = one after the other, 2 = two
      // hands entirely side by side.
      m.hand_overlap = opt_total_ms > 0.0 ? hand_ms / opt_total_ms : 0.0;
      return m;
    };

    std::vector<const BenchConfig*> chosen;
    for (const BenchConfig& bc : configs) {
      if (measured(bc)) chosen.push_back(&bc);
    }
    std::vector<std::vector<Measurement>> runs_of(chosen.size());
    tools::Progress progress(kProgram);
    const double total = static_cast<double>(runs) * static_cast<double>(chosen.size());
    for (int r = 0; r < runs; ++r) {
      for (size_t c = 0; c < chosen.size(); ++c) {
        const double before = static_cast<double>(r) * static_cast<double>(chosen.size()) + static_cast<double>(c);
        runs_of[c].push_back(
            run_once(*chosen[c], [&](double share) { progress.update(chosen[c]->name, (before + share) / total); }));
      }
    }
    progress.done();

    nlohmann::json out = nlohmann::json::object();
    std::printf("%-48s %8s %14s %12s %16s %8s%s\n", "configuration", "fps", "preprocess_ms", "optimize_ms",
                "latency p50/p99", "overlap", runs > 1 ? "  fps of each run" : "");
    for (size_t c = 0; c < chosen.size(); ++c) {
      const BenchConfig& bc = *chosen[c];
      const std::vector<Measurement>& m = runs_of[c];
      const double fps = median_of(m, &Measurement::fps);
      const double pre = median_of(m, &Measurement::preprocess_ms);
      const double opt = median_of(m, &Measurement::optimize_ms);
      const double p50 = median_of(m, &Measurement::p50_ms);
      const double p99 = median_of(m, &Measurement::p99_ms);
      const double overlap = median_of(m, &Measurement::hand_overlap);
      std::vector<double> fps_runs;
      std::string fps_list;
      for (const Measurement& run : m) {
        fps_runs.push_back(run.fps);
        fps_list += " " + std::to_string(static_cast<int>(std::lround(run.fps)));
      }
      out[bc.name] = {{"fps", fps},
                      {"preprocess_ms", pre},
                      {"optimize_ms", opt},
                      {"latency_ms", {{"p50", p50}, {"p99", p99}}},
                      {"particles", bc.particles},
                      {"iterations", bc.iterations},
                      {"max_hands", bc.max_hands},
                      {"hands_per_frame", median_of(m, &Measurement::hands_per_frame)},
                      {"hand_overlap", overlap},
                      {"width", camera.width},
                      {"height", camera.height},
                      {"frames", frames},
                      {"seed", seed},
                      {"runs", runs},
                      {"fps_runs", fps_runs}};
      std::printf("%-48s %8.1f %14.2f %12.2f %9.2f/%.2f %8.2f%s\n", bc.name.c_str(), fps, pre, opt, p50, p99, overlap,
                  runs > 1 ? (" " + fps_list).c_str() : "");
    }
    if (!frames_csv.empty()) {
      std::ofstream frames_out(frames_csv);
      frames_out << "configuration,run,frame,preprocess_ms,optimize_ms,hands,iterations\n";
      for (size_t c = 0; c < chosen.size(); ++c) {
        for (size_t r = 0; r < runs_of[c].size(); ++r) {
          const std::vector<Measurement::Frame>& fr = runs_of[c][r].frames;
          for (size_t i = 0; i < fr.size(); ++i) {
            frames_out << chosen[c]->name << ',' << r << ',' << i << ',' << fr[i].preprocess_ms << ','
                       << fr[i].optimize_ms << ',' << fr[i].hands << ',' << fr[i].iterations << '\n';
          }
        }
      }
      if (!frames_out.flush()) throw std::runtime_error(frames_csv + ": cannot write");
    }
    if (!json_file.empty()) {
      std::ofstream json_out(json_file);
      json_out << out.dump(2) << "\n";
      if (!json_out.flush()) throw std::runtime_error(json_file + ": cannot write");
    }
  } catch (const std::exception& e) {
    return report_error(kProgram, e.what(), 1);
  }
  return 0;
}
