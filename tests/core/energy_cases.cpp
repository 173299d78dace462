#include "energy_cases.hpp"

#include "handtrack/core/tracker.hpp"
#include "handtrack/synth/motions.hpp"

#include <random>
#include <string>

namespace handtrack::testing {

HandHint hint_from_pose(const PoseParams& pose) {
  PoseTracker tracker{TrackerConfig{}};
  tracker.override_pose(pose);
  return *tracker.hint();
}

std::vector<EnergyCase> synthetic_energy_cases(int frames, int poses_per_frame, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto perturbed = [&](const PoseParams& truth, double translation_mm, double rotation_rad, double angle_rad) {
    PoseParams p = truth;
    for (int j = 0; j < kNumPoseParams; ++j) {
      const double scale = param_kind(j) == ParamKind::kTranslation ? translation_mm
                           : param_kind(j) == ParamKind::kRotation  ? rotation_rad
                                                                    : angle_rad;
      p[j] += scale * unit(rng);
    }
    return p;
  };

  std::vector<EnergyCase> cases;
  DepthInputBuilder builder;
  for (int i = 0; i < frames; ++i) {
    synth::SynthOptions options;
    options.motion = std::string(synth::kMotionNames[static_cast<size_t>(i) % synth::kMotionNames.size()]);
    options.seed = seed + static_cast<uint64_t>(i);
    synth::SyntheticCamera camera(options);
    EnergyCase c;
    c.frame = camera.render(37 * i % options.frames);
    c.truth = c.frame.pose.to_params();
    const FixedLabels labels(&c.frame.labels.pixels);
    c.input = builder.build(c.frame.depth, hint_from_pose(c.truth), &labels);
    c.poses.push_back(c.truth);
    for (int k = 1; k < poses_per_frame; ++k) {
      c.poses.push_back(k % 2 == 1 ? perturbed(c.truth, 5.0, 0.05, 0.1) : perturbed(c.truth, 30.0, 0.3, 0.6));
    }
    cases.push_back(std::move(c));
  }
  return cases;
}

}  // namespace handtrack::testing
