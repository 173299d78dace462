// handtrack-calibrate: tracks a sequence directory (e.g. one recorded with handtrackd --record)
// with the default hand model, then searches the user's hand scale (Sec. 6, hand_calibration.hpp)
// and writes it as a hand profile for handtrackd (tracker.hand_profile) and handtrack-eval
// (--hand-profile).
#include "handtrack/core/camera_roll.hpp"
#include "handtrack/core/hand_calibration.hpp"
#include "handtrack/core/sequence.hpp"
#include "handtrack/core/tracker.hpp"
#include "handtrack/common/cli.hpp"
#include "handtrack/tools/tracker_options.hpp"

#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>

using namespace handtrack;

namespace {
constexpr const char* kProgram = "handtrack-calibrate";
}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Find the user's hand scale (length, width, Gaussian sigma; Sec. 6) from a sequence of the hand "
               "held open in front of the camera, and write it as a hand profile (JSON).",
               kProgram};
  std::string sequence;
  std::string out;
  CalibrationSet::Options keep;
  app.add_option("--sequence", sequence, "sequence directory (SPEC.md format; handtrackd --record DIR writes one)")
      ->required()
      ->check(CLI::ExistingDirectory);
  app.add_option("--out", out, "hand profile file to write (JSON)")->required();
  app.add_option("--frames", keep.max_frames, "frames to calibrate on")->check(CLI::Range(1, 100));
  app.add_option("--stride", keep.stride, "at least this many frames between two calibration frames")
      ->check(CLI::Range(1, 10000));
  std::string camera_roll = "0";
  tools::add_camera_roll_option(app, camera_roll, " (a sequence recorded by handtrackd with camera.roll set)");
  if (const auto exit_code = parse_command_line(app, argc, argv, kProgram, 1)) return *exit_code;
  const CameraRoll roll = *parse_camera_roll(camera_roll);  // one of the values the option's check let through

  try {
    const SequenceReader reader(sequence);
    const TrackerConfig config = calibration_tracker_config();
    Tracker tracker(config);
    CalibrationSet set(keep, config.input);
    DepthImage upright;
    for (size_t i = 0; i < reader.frame_count() && !set.full(); ++i) {
      const DepthImage camera_depth = reader.depth(i);
      const DepthImage& depth = upright_frame(camera_depth, roll, &upright);
      const auto tracked = tracker.track(depth);
      set.offer(depth, tracked, tracker.pose_tracker().hint());
    }
    if (set.size() == 0) {
      throw std::runtime_error(sequence + ": the hand was never tracked with confidence; record it open, 30-50 cm "
                                          "from the camera, palm toward it");
    }
    const auto start = std::chrono::steady_clock::now();
    const auto result = calibrate_hand_scale(set.frames(), config);
    const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
    save_hand_profile(out, result.scale);
    std::printf("hand_length %.3f  hand_width %.3f  gaussian_sigma %.3f  (%d frames, %d grid points, %.2f s) -> %s\n",
                result.scale.length, result.scale.width, result.scale.sigma, set.size(), result.evaluations,
                took.count(), out.c_str());
  } catch (const std::exception& e) {
    return report_error(kProgram, e.what(), 1);
  }
  return 0;
}
