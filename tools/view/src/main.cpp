// handtrack-view: renders what the tracker sees and fits in one frame to a PNG (see --help).
#include "render.hpp"
#include "tracked_hands.hpp"

#include "handtrack/core/camera.hpp"
#include "handtrack/core/hands_tracker.hpp"
#include "handtrack/core/part_forest.hpp"
#include "handtrack/core/png_io.hpp"
#include "handtrack/core/sequence.hpp"
#include "handtrack/common/cli.hpp"
#include "handtrack/tools/tracker_options.hpp"

#include <CLI/CLI.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <iostream>
#include <optional>
#include <stdexcept>
#include <string>

namespace fs = std::filesystem;

namespace {

constexpr const char* kProgram = "handtrack-view";
constexpr int kExitBadInput = 1;  // missing or corrupt files, frame out of range
constexpr int kExitUsage = 2;     // wrong command line

int fail(const std::string& message, int code) {
  return handtrack::report_error(kProgram, message, code);
}

// A usage mistake found after parsing (exit 2), as opposed to bad input data (exit 1).
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Args {
  std::string seq;
  std::optional<int> frame;
  int every = 0;
  std::string depth;
  std::string camera;
  std::string labels;
  std::optional<double> fx, fy, cx, cy, depth_scale;
  std::string out;
  std::optional<int> iterations, init_iterations, particles;
  int max_hands = handtrack::TrackerConfig{}.max_hands;  // handtrackd's default (tracker.max_hands)
  std::optional<double> near_mm, far_mm, slant_front;
  bool crop = false;
  int panel_height = 0;
  std::string energy = "late-fusion";
  std::string arrangement = "facing";
  std::string hand = "auto";
  std::string forest;
  std::string camera_roll = "0";
};

// --camera-roll: the frame, its labels and its true fingertips as the tracker sees them, turned
// upright (what the panels show; the poses stay in that image's frame).
struct Upright {
  handtrack::CameraRoll roll = handtrack::CameraRoll::k0;
  handtrack::DepthImage depth;

  const handtrack::DepthImage& frame(const handtrack::DepthImage& camera_depth) {
    return handtrack::upright_frame(camera_depth, roll, &depth);
  }
  [[nodiscard]] handtrack::Gray8Image labels(const handtrack::Gray8Image& camera_labels,
                                            const handtrack::CameraIntrinsics& camera) const {
    handtrack::Gray8Image out;
    const handtrack::CameraIntrinsics upright = handtrack::upright_camera(camera, roll);
    out.width = upright.width;
    out.height = upright.height;
    handtrack::turn_upright(camera_labels.pixels, camera, roll, &out.pixels);
    return out;
  }
  [[nodiscard]] handtrack::Fingertips tips(handtrack::Fingertips camera_tips) const {
    for (auto& t : camera_tips) {
      if (t) t = handtrack::turn_to_upright(roll, *t);
    }
    return camera_tips;
  }
  [[nodiscard]] std::string caption() const {
    return roll == handtrack::CameraRoll::k0 ? "" : "\nturned upright: roll " + std::to_string(degrees(roll));
  }
};

handtrack::TrackerConfig tracker_config(const Args& a) {
  handtrack::TrackerConfig config;
  config.max_hands = a.max_hands;
  if (a.iterations) config.optimizer.iterations = *a.iterations;
  if (a.init_iterations) config.init_iterations = *a.init_iterations;
  if (a.particles) config.particles = *a.particles;
  if (a.slant_front) config.weights.slant_front = *a.slant_front;
  if (a.near_mm) config.input.near_mm = *a.near_mm;
  if (a.far_mm) config.input.far_mm = *a.far_mm;
  if (config.input.far_mm <= config.input.near_mm) throw UsageError("--far-mm must be greater than --near-mm");
  if (a.energy == "late-fusion") config.mode = handtrack::EnergyMode::kLateFusion;
  handtrack::parse_camera_arrangement(a.arrangement, &config.arrangement);  // one of the names CLI11 checked
  handtrack::parse_handedness_mode(a.hand, &config.handedness);           // likewise
  return config;
}

handtrack::view::RenderOptions render_options(const Args& a) { return {a.crop, a.panel_height}; }

// The part forest of late fusion (handtrack-eval's rule: --forest, else the shipped one), or none
// for depth-only.
std::optional<handtrack::PartForest> load_forest(const Args& a) {
  if (a.energy != "late-fusion") return std::nullopt;
  std::string file = a.forest;
  if (file.empty()) {
    const auto shipped = handtrack::shipped_forest_path();
    if (!shipped) {
      throw UsageError("no part forest found for late fusion: pass --forest MODEL, set $HANDTRACK_FOREST, or use "
                       "--energy depth-only");
    }
    file = shipped->string();
  }
  return handtrack::PartForest::load(file);
}

const handtrack::PixelLabeller* labeller(const std::optional<handtrack::PartForest>& forest) {
  return forest ? &*forest : nullptr;
}

// Shows "frame i/n, ETA" on a terminal; silent otherwise (SPEC.md "Programs").
class Progress {
 public:
  explicit Progress(size_t total) : total_(total), enabled_(isatty(STDERR_FILENO) != 0 && total > 1) {}
  ~Progress() {
    if (enabled_ && shown_) std::cerr << "\n";
  }
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  void step(size_t done) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (done < total_ && now - last_ < std::chrono::milliseconds(200)) return;
    last_ = now;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    const double eta = done > 0 ? elapsed / static_cast<double>(done) * static_cast<double>(total_ - done) : 0.0;
    std::fprintf(stderr, "\r%s: frame %zu/%zu, %.0f s left   ", kProgram, done, total_, eta);
    shown_ = true;
  }

 private:
  size_t total_;
  bool enabled_;
  bool shown_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_{};
};

fs::path numbered(const fs::path& out, int frame) {
  char number[16];
  std::snprintf(number, sizeof number, "_%06d", frame);
  return out.parent_path() / (out.stem().string() + number + out.extension().string());
}

int run_sequence(const Args& a) {
  if (!a.frame && a.every <= 0) throw UsageError("--seq needs --frame N or --every K");
  const handtrack::SequenceReader reader(a.seq);
  const size_t count = reader.frame_count();
  if (count == 0) throw std::runtime_error(a.seq + ": sequence has no depth frames");
  if (a.frame && (*a.frame < 0 || static_cast<size_t>(*a.frame) >= count)) {
    throw std::runtime_error(a.seq + ": frame " + std::to_string(*a.frame) + " out of range (the sequence has " +
                             std::to_string(count) + " frames, 0.." + std::to_string(count - 1) + ")");
  }
  const size_t last = a.frame ? static_cast<size_t>(*a.frame) : count - 1;
  handtrack::HandsTracker tracker(tracker_config(a));
  const auto forest = load_forest(a);
  Progress progress(last + 1);
  int written = 0;
  Upright upright{*handtrack::parse_camera_roll(a.camera_roll), {}};
  for (size_t i = 0; i <= last; ++i) {
    const handtrack::DepthImage camera_depth = reader.depth(i);
    const handtrack::DepthImage& depth = upright.frame(camera_depth);
    const handtrack::HandsOutput output = tracker.track(depth, labeller(forest));
    progress.step(i + 1);
    const bool wanted = a.every > 0 ? i % static_cast<size_t>(a.every) == 0 || (a.frame && i == last) : i == last;
    if (!wanted) continue;
    auto labels = reader.labels(i);
    if (labels) labels = upright.labels(*labels, camera_depth.camera);
    handtrack::view::FrameView view;
    view.depth = &depth;
    const auto hands = handtrack::view::tracked_hands(tracker, output);
    view.hands = handtrack::view::hand_views(hands);
    view.labels = labels ? &*labels : nullptr;
    view.labels_caption = "labels (sequence)";
    for (int h = 0; h < reader.hand_count(); ++h) {  // every ground-truth hand annotated in this frame
      const handtrack::Fingertips tips = upright.tips(reader.fingertips(i, h));
      if (std::any_of(tips.begin(), tips.end(), [](const auto& t) { return t.has_value(); })) {
        view.truth_tips.push_back(tips);
      }
    }
    view.name =
        fs::path(a.seq).filename().string() + " frame " + std::to_string(reader.frame_number(i)) + upright.caption();
    const fs::path file = a.every > 0 ? numbered(a.out, reader.frame_number(i)) : fs::path(a.out);
    handtrack::write_png_rgb(file, handtrack::view::render_frame(view, render_options(a)));
    ++written;
  }
  if (a.every > 0) std::cout << kProgram << ": wrote " << written << " images next to " << a.out << "\n";
  return 0;
}

handtrack::CameraIntrinsics single_frame_camera(const Args& a, int width, int height) {
  handtrack::CameraIntrinsics camera;
  if (!a.camera.empty()) {
    camera = handtrack::read_camera_json(a.camera);
    if (camera.width != width || camera.height != height) {
      throw std::runtime_error(a.camera + ": camera is " + std::to_string(camera.width) + "x" +
                               std::to_string(camera.height) + " but " + a.depth + " is " + std::to_string(width) +
                               "x" + std::to_string(height));
    }
  } else {
    if (!a.fx && !a.fy) throw UsageError("--depth needs --camera FILE or the intrinsics --fx/--fy (and --cx/--cy)");
    camera.width = width;
    camera.height = height;
    camera.fx = a.fx.value_or(a.fy.value_or(0.0));
    camera.fy = a.fy.value_or(camera.fx);
    camera.cx = 0.5 * (width - 1);
    camera.cy = 0.5 * (height - 1);
    camera.depth_scale_mm = 1.0;
  }
  if (a.fx) camera.fx = *a.fx;
  if (a.fy) camera.fy = *a.fy;
  if (a.cx) camera.cx = *a.cx;
  if (a.cy) camera.cy = *a.cy;
  if (a.depth_scale) camera.depth_scale_mm = *a.depth_scale;
  if (const std::string problem = camera.problem(); !problem.empty()) {
    throw UsageError("bad intrinsics: " + problem);
  }
  return camera;
}

int run_single(const Args& a) {
  if (a.every > 0) throw UsageError("--every needs --seq");
  const handtrack::Gray16Image raw = handtrack::read_png_gray16(a.depth);
  const handtrack::CameraIntrinsics camera = single_frame_camera(a, raw.width, raw.height);
  Upright upright{*handtrack::parse_camera_roll(a.camera_roll), {}};
  const handtrack::DepthImage camera_depth = handtrack::DepthImage::from_raw(camera, raw.pixels);
  const handtrack::DepthImage& depth = upright.frame(camera_depth);
  std::optional<handtrack::Gray8Image> labels;
  if (!a.labels.empty()) {
    labels = handtrack::read_png_gray8(a.labels);
    if (labels->width != raw.width || labels->height != raw.height) {
      throw std::runtime_error(a.labels + ": label image is " + std::to_string(labels->width) + "x" +
                               std::to_string(labels->height) + ", depth is " + std::to_string(raw.width) + "x" +
                               std::to_string(raw.height));
    }
    labels = upright.labels(*labels, camera);
  }
  // One frame: the tracker's (re)start path, the open hand placed at the segmented hand.
  handtrack::HandsTracker tracker(tracker_config(a));
  const auto forest = load_forest(a);
  const handtrack::HandsOutput output = tracker.track(depth, labeller(forest));
  handtrack::view::FrameView view;
  view.depth = &depth;
  const auto hands = handtrack::view::tracked_hands(tracker, output);
  view.hands = handtrack::view::hand_views(hands);
  view.labels = labels ? &*labels : nullptr;
  view.labels_caption = "labels " + fs::path(a.labels).filename().string();
  view.name = fs::path(a.depth).filename().string() + upright.caption();
  handtrack::write_png_rgb(a.out, handtrack::view::render_frame(view, render_options(a)));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Render a depth frame to PNG: (a) depth with the segmented hand tinted green, (b) the quadtree image "
      "Gaussians, (c) the fitted hand model (Gaussians by part, skeleton, fingertips), (d) part labels if any.\n"
      "Two hands (--max-hands 2, the default): each hand's pixels, model and fingertips in a colour of its own "
      "(orange, violet), labelled '#id side confidence' by the hand; ground-truth fingertips of every hand.\n"
      "A sequence frame is tracked from frame 0 on, so its pose is a tracked one; a single --depth frame "
      "is fitted from scratch (the tracker's start path).",
      kProgram};
  Args a;
  auto* seq = app.add_option("--seq", a.seq, "Sequence directory (SPEC.md format)");
  app.add_option("--frame", a.frame, "Frame index in --seq (0-based); frames 0..N are tracked")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--every", a.every, "With --seq: write every K-th frame as OUT_NNNNNN.png (up to --frame, or all)")
      ->check(CLI::PositiveNumber);
  auto* depth = app.add_option("--depth", a.depth, "A single 16-bit depth PNG");
  app.add_option("--camera", a.camera, "camera.json for --depth");
  app.add_option("--fx", a.fx, "Focal length x, px (with --depth)");
  app.add_option("--fy", a.fy, "Focal length y, px (default: --fx)");
  app.add_option("--cx", a.cx, "Principal point x, px (default: image centre)");
  app.add_option("--cy", a.cy, "Principal point y, px (default: image centre)");
  app.add_option("--depth-scale", a.depth_scale, "mm per raw depth unit (default 1; RealSense SR305: 0.125)");
  app.add_option("--labels", a.labels, "With --depth: an 8-bit part-label PNG to show in panel (d)");
  app.add_option("--out", a.out, "Output PNG")->required();
  app.add_option("--iterations", a.iterations, "Optimizer iterations per frame (default 10)")
      ->check(CLI::Range(1, 10000));
  app.add_option("--init-iterations", a.init_iterations,
                 "Iterations of each (re)start hypothesis, e.g. for a single frame (default 80)")
      ->check(CLI::Range(1, 10000));
  app.add_option("--particles", a.particles, "Pose particles per frame (default 2)")->check(CLI::Range(1, 64));
  app.add_option("--max-hands", a.max_hands,
                 "Hands to track at once, 1 or 2 (default 2, as handtrackd's tracker.max_hands); 1 draws the "
                 "frame as a single-hand tracker sees it")
      ->check(CLI::Range(1, handtrack::kMaxHands));
  app.add_option("--near-mm", a.near_mm, "Near end of the working volume, mm (default 150)")
      ->check(CLI::Range(1.0, 10000.0));
  app.add_option("--far-mm", a.far_mm, "Far end of the working volume, mm (default 600)")
      ->check(CLI::Range(1.0, 10000.0));
  app.add_option("--energy", a.energy, "late-fusion (default, with the shipped forest) or depth-only")
      ->check(CLI::IsMember({"late-fusion", "depth-only"}));
  app.add_option("--slant-front", a.slant_front,
                 "k_max of the surface fronts while late fusion tracks (default 1.5; 1: the paper's E_sim), as "
                 "handtrackd's tracker.energy.slant_front")
      ->check(CLI::Range(1.0, 10.0));
  handtrack::tools::add_arrangement_option(app, a.arrangement);
  handtrack::tools::add_camera_roll_option(app, a.camera_roll, " and drawn so");
  handtrack::tools::add_hand_option(app, a.hand);
  handtrack::tools::add_forest_option(app, a.forest);
  app.add_flag("--crop", a.crop, "Zoom all panels onto the segmented hand");
  app.add_option("--panel-height", a.panel_height, "Panel height in px (default: image height; 360 with --crop)")
      ->check(CLI::Range(32, 4096));
  seq->excludes(depth);
  for (const char* name : {"--camera", "--fx", "--fy", "--cx", "--cy", "--depth-scale", "--labels"}) {
    app.get_option(name)->excludes(seq);
  }

  if (const auto exit_code = handtrack::parse_command_line(app, argc, argv, kProgram, kExitUsage)) {
    return *exit_code;
  }
  if (a.seq.empty() == a.depth.empty()) return fail("give either --seq DIR or --depth FILE.png (see --help)", kExitUsage);

  try {
    return a.seq.empty() ? run_single(a) : run_sequence(a);
  } catch (const UsageError& e) {
    return fail(std::string(e.what()) + " (see --help)", kExitUsage);
  } catch (const std::exception& e) {
    return fail(e.what(), kExitBadInput);
  }
}
