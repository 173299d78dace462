// handtrack-kernels-bench: Google Benchmark micro-benchmarks of the tracker's kernels (issue 7) on
// realistic inputs: seven synthetic 320x240 frames (one per Dexter 1 motion, noise and a body
// behind the hand) and eight poses per frame near and off the true pose (energy_cases.hpp).
//
//   preprocessing   DepthInputBuilder::build without and with the part forest, the forest alone,
//                   E_free's map and E_unseen's weights of a frame, the palm's hollow of a fit,
//                   a frame turned upright (camera.roll)
//   E_sim           energy + gradient per factor, the optimised term and the plain reference
//   E               PoseEnergy::evaluate (posing the model, every term, the chain rule)
//   E_hand          the two-hand collision term alone, and E with another hand touching or apart
//   optimizer       one iteration of the adaptive gradient ascent (two evaluations), and ten
//
// Each iteration takes the next frame or (frame, pose) in turn. --forest FILE (before the
// --benchmark_* options) picks the part forest; the default is the shipped data/part_forest.htf.
#include "energy_cases.hpp"
#include "reference_energy.hpp"

#include "handtrack/core/camera_roll.hpp"
#include "handtrack/core/energy.hpp"
#include "handtrack/core/free_space.hpp"
#include "handtrack/core/optimizer.hpp"
#include "handtrack/core/palm_hollow.hpp"
#include "handtrack/core/part_forest.hpp"

#include <benchmark/benchmark.h>

#include <array>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

namespace {

using namespace handtrack;

std::string g_forest_path = handtrack::shipped_forest_path().value_or("");
constexpr double kLabelRadiusMm = 200.0;  // EnergyWeights' R_i

const std::vector<testing::EnergyCase>& cases() {
  static const auto all = testing::synthetic_energy_cases(7, 8);
  return all;
}

const HandModel& model() {
  static const HandModel m = HandModel::default_adult();
  return m;
}

// Every (frame, pose) with its posed model, for the E_sim kernels alone.
struct PosedCase {
  const DepthInput* input;
  PosedHand hand;
};
const std::vector<PosedCase>& posed_cases() {
  static const auto all = [] {
    std::vector<PosedCase> out;
    for (const auto& c : cases()) {
      for (const auto& pose : c.poses) out.push_back({&c.input, PosedHand(model(), pose)});
    }
    return out;
  }();
  return all;
}

const PartForest* forest(benchmark::State& state) {
  static const std::unique_ptr<PartForest> f = []() -> std::unique_ptr<PartForest> {
    try {
      return std::make_unique<PartForest>(PartForest::load(g_forest_path));
    } catch (const std::exception&) {
      return nullptr;
    }
  }();
  if (!f) state.SkipWithError(("cannot load the part forest " + g_forest_path).c_str());
  return f.get();
}

SimilarityFactor factor_of(const benchmark::State& state) {
  return state.range(0) == 0 ? SimilarityFactor::kDepth : SimilarityFactor::kLabel;
}

void BM_Preprocess(benchmark::State& state) {
  const PixelLabeller* labeller = nullptr;
  if (state.range(0) == 1 && (labeller = forest(state)) == nullptr) return;
  std::vector<HandHint> hints;
  for (const auto& c : cases()) hints.push_back(testing::hint_from_pose(c.truth));
  DepthInputBuilder builder;
  size_t i = 0;
  for (auto _ : state) {
    const DepthInput& in = builder.build(cases()[i].frame.depth, hints[i], labeller);
    benchmark::DoNotOptimize(in.self_similarity);
    i = (i + 1) % cases().size();
  }
}
BENCHMARK(BM_Preprocess)->ArgName("forest")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// turned 1: the hand's axis taken to point at the image's left edge, so that every frame is also
// labelled with its probes turned by a quarter turn (PartForestOptions::turned_readings): the cost
// of a hand from another image edge.
void BM_ForestLabels(benchmark::State& state) {
  const PartForest* f = forest(state);
  if (f == nullptr) return;
  std::vector<DepthInput> inputs;
  for (const auto& c : cases()) {
    inputs.push_back(c.input);
    if (state.range(0) == 1) inputs.back().finger_axis = Eigen::Vector3d(-1.0, 0.0, 0.0);
  }
  std::vector<uint8_t> labels;
  size_t i = 0;
  for (auto _ : state) {
    f->label(inputs[i], labels);
    benchmark::DoNotOptimize(labels.data());
    i = (i + 1) % inputs.size();
  }
}
BENCHMARK(BM_ForestLabels)->ArgName("turned")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// E_free's map of one frame (free_space.hpp): the hand's box and depth range, the cells marked
// free or not, the distance transform. Part of BM_Preprocess.
void BM_FreeSpaceMap(benchmark::State& state) {
  FreeSpaceMap map;
  size_t i = 0;
  for (auto _ : state) {
    const testing::EnergyCase& c = cases()[i];
    map.build(c.input.camera, c.frame.depth.depth_mm, c.input.hand_mask);
    benchmark::DoNotOptimize(map.cap_px());
    i = (i + 1) % cases().size();
  }
}
BENCHMARK(BM_FreeSpaceMap)->Unit(benchmark::kMicrosecond);

// A camera mounted turned (camera_roll.hpp): one frame's depth in mm turned upright, at 90 and 180
// deg (270 is 90's loop with the other axis reversed). Added to preprocessing when camera.roll is set.
void BM_TurnUpright(benchmark::State& state) {
  const CameraRoll roll = state.range(0) == 90 ? CameraRoll::k90 : CameraRoll::k180;
  DepthImage upright;
  size_t i = 0;
  for (auto _ : state) {
    turn_upright(cases()[i].frame.depth, roll, &upright);
    benchmark::DoNotOptimize(upright.depth_mm.data());
    i = (i + 1) % cases().size();
  }
}
BENCHMARK(BM_TurnUpright)->ArgName("roll")->Arg(90)->Arg(180)->Unit(benchmark::kMicrosecond);

// E_unseen's weights of one frame (unseen_fingers.hpp): the label histogram of the whole image
// (the frames' ground-truth labels) and the previous pose's rotation, once a frame while late
// fusion tracks. (These frames show the palm: the reach beyond the knuckles, measured only on a
// hand seen from behind, is not in this figure.)
void BM_UnseenFingers(benchmark::State& state) {
  std::vector<PosedHand> posed;
  for (const auto& c : cases()) posed.emplace_back(model(), c.truth);
  size_t i = 0;
  for (auto _ : state) {
    const UnseenFingers u = unseen_fingers(cases()[i].input, posed[i]);
    benchmark::DoNotOptimize(u.weight.data());
    i = (i + 1) % cases().size();
  }
}
BENCHMARK(BM_UnseenFingers)->Unit(benchmark::kMicrosecond);

// The palm's hollow (palm_hollow.hpp) of one frame's fit, here the rendered pose: read on a
// handedness trial's frames where the two hands' fits are mirror twins, never while one hand
// tracks.
void BM_PalmHollow(benchmark::State& state) {
  std::vector<TrackerOutput> fits;
  for (const auto& c : cases()) {
    const PosedHand posed(model(), c.truth);
    TrackerOutput fit;
    fit.joints = posed.joints();
    fit.palm_centre = posed.to_camera(model().palm_centre());
    fit.palm_normal = posed.camera_R_hand() * Eigen::Vector3d::UnitZ();
    fits.push_back(fit);
  }
  size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(palm_hollow_mm(cases()[i].input, fits[i]));
    i = (i + 1) % cases().size();
  }
}
BENCHMARK(BM_PalmHollow)->Unit(benchmark::kMicrosecond);

// E_sim and its gradient for one posed model: the optimised term (label: 0 depth, 1 label factor;
// capped: with the shipped coverage cap, two passes, or eq. 6's one).
void BM_Similarity(benchmark::State& state) {
  const SimilarityTerm term(factor_of(state), kLabelRadiusMm, state.range(1) != 0 ? kMeasuredCoverageCap : 0.0);
  size_t i = 0;
  for (auto _ : state) {
    const auto& c = posed_cases()[i];
    PoseGradient g = PoseGradient::Zero();
    benchmark::DoNotOptimize(term.evaluate(model(), c.hand, *c.input, &g));
    benchmark::DoNotOptimize(g.data());
    i = (i + 1) % posed_cases().size();
  }
}
BENCHMARK(BM_Similarity)->ArgNames({"label", "capped"})->Args({0, 0})->Args({1, 0})->Args({0, 1})->Args({1, 1});

// The same with the plain reference (every pair, libm exp, the chain one point at a time).
void BM_SimilarityReference(benchmark::State& state) {
  const SimilarityFactor factor = factor_of(state);
  size_t i = 0;
  for (auto _ : state) {
    const auto& c = posed_cases()[i];
    PoseGradient g = PoseGradient::Zero();
    benchmark::DoNotOptimize(reference::similarity(model(), c.hand, *c.input, factor, kLabelRadiusMm, &g));
    benchmark::DoNotOptimize(g.data());
    i = (i + 1) % posed_cases().size();
  }
}
BENCHMARK(BM_SimilarityReference)->ArgName("label")->Arg(0)->Arg(1);


// The other hand for E_hand (issue 14): the frame's true pose mirrored (a left hand), its wrist
// `gap_mm` to this hand's thumb side; 50 mm: the hands interpenetrate by about a finger, 600 mm:
// far apart. One obstacle per frame, built once.
const HandObstacle& other_hand(size_t frame, int gap_mm) {
  static const auto all = [] {
    std::vector<std::array<HandObstacle, 2>> out(cases().size());
    for (size_t i = 0; i < cases().size(); ++i) {
      for (size_t k = 0; k < 2; ++k) {
        PoseParams other = cases()[i].truth;
        other[0] = -(other[0] + (k == 0 ? 50.0 : 600.0));
        out[i][k].assign(model(), PosedHand(model(), other), true);
      }
    }
    return out;
  }();
  return all[frame][gap_mm == 50 ? 0 : 1];
}

// E_hand with its gradient (the optimised term, or the plain reference with range(1) = 1) against
// another hand range(0) mm away.
void BM_InterHand(benchmark::State& state) {
  const InterHandCollisionTerm term;
  const auto gap_mm = static_cast<int>(state.range(0));
  const bool plain = state.range(1) != 0;
  const size_t poses_per_frame = cases().front().poses.size();
  size_t i = 0;
  for (auto _ : state) {
    const auto& c = posed_cases()[i];
    const HandObstacle& other = other_hand(i / poses_per_frame, gap_mm);
    PoseGradient g = PoseGradient::Zero();
    benchmark::DoNotOptimize(plain ? reference::inter_hand(model(), c.hand, other, &g)
                                   : term.evaluate(model(), c.hand, other, &g));
    benchmark::DoNotOptimize(g.data());
    i = (i + 1) % posed_cases().size();
  }
}
BENCHMARK(BM_InterHand)->ArgNames({"gap_mm", "reference"})->Args({50, 0})->Args({600, 0})->Args({50, 1});

// The whole energy of eq. 2 with its gradient, as the optimizer calls it (E_smo on), with the label
// factor or not (range(0)), and another hand range(1) mm away (0: none; E_hand).
void BM_PoseEnergy(benchmark::State& state) {
  const PoseEnergy energy(factor_of(state), EnergyWeights{});
  const auto gap_mm = static_cast<int>(state.range(1));
  PosedHand hand;
  size_t i = 0;
  size_t k = 0;
  for (auto _ : state) {
    const auto& c = cases()[i];
    EnergyFrame frame{&model(), &c.input, &c.truth, &c.truth};
    if (gap_mm != 0) frame.other_hand = &other_hand(i, gap_mm);
    PoseGradient g;
    benchmark::DoNotOptimize(energy.evaluate(frame, c.poses[k], hand, &g));
    benchmark::DoNotOptimize(g.data());
    if (++k == c.poses.size()) {
      k = 0;
      i = (i + 1) % cases().size();
    }
  }
}
BENCHMARK(BM_PoseEnergy)->ArgNames({"label", "gap_mm"})->Args({0, 0})->Args({1, 0})->Args({0, 50})->Args({0, 600});

// AdaptiveGradientAscent::maximise from a pose off the truth: range(1) iterations (each one
// evaluation, plus one at the start).
void BM_Optimizer(benchmark::State& state) {
  const PoseEnergy energy(factor_of(state), EnergyWeights{});
  const AdaptiveGradientAscent optimizer;
  const auto iterations = static_cast<int>(state.range(1));
  PosedHand scratch;
  size_t i = 0;
  for (auto _ : state) {
    const auto& c = cases()[i];
    const EnergyFrame frame{&model(), &c.input, &c.truth, &c.truth};
    benchmark::DoNotOptimize(optimizer.maximise(energy, frame, c.poses.back(), scratch, iterations).energy);
    i = (i + 1) % cases().size();
  }
}
BENCHMARK(BM_Optimizer)->ArgNames({"label", "iterations"})->Args({0, 1})->Args({0, 10})->Args({1, 10})
    ->Unit(benchmark::kMicrosecond);

}  // namespace

int main(int argc, char** argv) {
  if (argc >= 3 && std::strcmp(argv[1], "--forest") == 0) {
    g_forest_path = argv[2];
    argv[2] = argv[0];
    argc -= 2;
    argv += 2;
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
