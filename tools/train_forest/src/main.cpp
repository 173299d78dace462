// handtrack-train-forest: trains the hand-part classification forest of Sec. 4.3 on labelled
// synthetic renders (docs/FOREST.md), evaluates a model on held-out synthetic frames
// (--evaluate), and labels real depth frames into colour PNGs (--apply).

#include "handtrack/core/part_forest.hpp"
#include "handtrack/core/png_io.hpp"
#include "handtrack/draw/colormap.hpp"
#include "handtrack/train_forest/forest_data.hpp"
#include "handtrack/train_forest/trainer.hpp"
#include "handtrack/common/cli.hpp"
#include "handtrack/tools/output_file.hpp"
#include "handtrack/tools/progress.hpp"

#include <CLI/CLI.hpp>
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>

namespace fs = std::filesystem;
using namespace handtrack;

namespace {

constexpr const char* kProgram = "handtrack-train-forest";
// Held-out data (never trained on): motion subjects from these synth seeds, random-pose scenes
// from this data-set seed.
constexpr uint64_t kHeldOutMotionSeed = 900001;
constexpr uint64_t kHeldOutSceneSeed = 0xE7A1'0000'0000ULL;

int fail(const std::string& message) { return handtrack::report_error(kProgram, message, 1); }


// CPU time of the calling thread: label() timings that other processes on the machine disturb less.
double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string percent(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f %%", 100.0 * x);
  return buf;
}

struct EvalSummary {
  forest::HeldOutResult motions;
  std::array<forest::Confusion, synth::kViews.size()> views;  // the held-out motions in each view
  std::array<forest::Confusion, synth::kViews.size()> varied_views;  // the same, hands of varied proportions
  forest::Confusion facing;  // held-out random poses, palm toward the camera (+- the SceneOptions ranges)
  forest::Confusion turned;  // held-out random poses turned any way (back, side, fingers toward / away)
  double ms_per_frame = 0.0;
  double hand_pixels = 0.0;  // mean per timed frame
};

EvalSummary evaluate(const PartForest& model, int frames_per_motion, int scenes) {
  EvalSummary s;
  s.motions = forest::evaluate_motions(model, kHeldOutMotionSeed, frames_per_motion);
  const auto held_out = [&](size_t view, synth::Proportions proportions) {
    return forest::evaluate_motions(model, kHeldOutMotionSeed, frames_per_motion, synth::kViews[view], proportions)
        .overall;
  };
  s.views[0] = s.motions.overall;  // kViews[0] is palm, the held-out motions as evaluated above
  for (size_t v = 1; v < synth::kViews.size(); ++v) s.views[v] = held_out(v, synth::Proportions::kMean);
  for (size_t v = 0; v < synth::kViews.size(); ++v) s.varied_views[v] = held_out(v, synth::Proportions::kVaried);
  forest::SceneOptions facing;
  facing.turned_fraction = 0.0;
  facing.view_fraction = 0.0;
  forest::SceneOptions turned;
  turned.turned_fraction = 1.0;
  turned.view_fraction = 1.0;
  s.facing = forest::evaluate_scenes(model, kHeldOutSceneSeed, scenes, facing);
  s.turned = forest::evaluate_scenes(model, kHeldOutSceneSeed, scenes, turned);
  // Labelling time alone, on the held-out motion frames' inputs.
  DepthInputBuilder builder;
  synth::SynthOptions options;
  options.motion = "random";
  options.frames = 241;
  options.seed = kHeldOutMotionSeed;
  synth::SyntheticCamera cam(options);
  std::vector<uint8_t> labels;
  double total = 0.0;
  double pixels = 0.0;
  constexpr int kTimedFrames = 40;
  constexpr int kRepeats = 5;
  for (int i = 0; i < kTimedFrames; ++i) {
    const DepthInput& in = builder.build(cam.render(i * 6).depth, std::nullopt);
    const double t0 = thread_cpu_seconds();
    for (int r = 0; r < kRepeats; ++r) model.label(in, labels);
    total += thread_cpu_seconds() - t0;
    pixels += in.hand_pixels;
  }
  s.ms_per_frame = 1000.0 * total / (kTimedFrames * kRepeats);
  s.hand_pixels = pixels / kTimedFrames;
  return s;
}

void print_evaluation(std::ostream& out, const PartForest& model, const EvalSummary& s) {
  out << "model: " << model.trees().size() << " trees, " << model.node_count() << " nodes, depth " << model.max_depth()
      << ", stride " << model.options().stride_px << "\n";
  out << "held-out motions (" << s.motions.frames << " frames, " << s.motions.overall.total()
      << " hand pixels): accuracy " << percent(s.motions.overall.accuracy()) << " (hand parts only "
      << percent(s.motions.overall.part_accuracy()) << ")\n";
  for (size_t m = 0; m < synth::kMotionNames.size(); ++m) {
    out << "  " << synth::kMotionNames[m] << ": " << percent(s.motions.per_motion[m].accuracy()) << "\n";
  }
  out << "held-out motions per view:\n";
  for (size_t v = 0; v < synth::kViews.size(); ++v) {
    out << "  " << synth::view_name(synth::kViews[v]) << ": " << percent(s.views[v].accuracy()) << " (hand parts only "
        << percent(s.views[v].part_accuracy()) << "); hands of varied proportions " << percent(s.varied_views[v].accuracy())
        << "\n";
  }
  for (const auto& [name, c] : {std::pair{"palm toward the camera", &s.facing}, std::pair{"turned any way", &s.turned}}) {
    out << "held-out random poses, " << name << " (" << c->total() << " hand pixels): accuracy "
        << percent(c->accuracy()) << " (hand parts only " << percent(c->part_accuracy()) << ")\n";
  }
  forest::Confusion all = s.motions.overall;
  all.add(s.facing);
  all.add(s.turned);
  out << "confusion, all held-out frames (% of each truth row):\n" << all.table();
  char buf[160];
  std::snprintf(buf, sizeof buf, "%.3f ms (thread CPU time) per 320x240 frame of %.0f hand pixels", s.ms_per_frame,
                s.hand_pixels);
  out << "label() time: " << buf << "\n";
}

int apply(const PartForest& model, const std::vector<std::string>& inputs, const fs::path& out_dir,
          const CameraIntrinsics& camera_in, double far_mm) {
  fs::create_directories(out_dir);
  DepthInputConfig config;
  config.far_mm = far_mm;
  DepthInputBuilder builder(config);
  std::vector<uint8_t> labels;
  for (const auto& file : inputs) {
    const Gray16Image raw = read_png_gray16(file);
    if (raw.channels != 1) throw std::runtime_error(file + ": not a grayscale depth image");
    CameraIntrinsics camera = camera_in;
    camera.width = raw.width;
    camera.height = raw.height;
    const DepthImage depth = DepthImage::from_raw(camera, raw.pixels);
    const DepthInput& in = builder.build(depth, std::nullopt);
    const auto t0 = std::chrono::steady_clock::now();
    model.label(in, labels);
    const double ms = 1000.0 * seconds_since(t0);
    // Left: depth (gray, hand mask tinted); right: part labels over a dim depth.
    RgbImage img;
    img.width = 2 * raw.width;
    img.height = raw.height;
    img.channels = 3;
    img.pixels.assign(static_cast<size_t>(img.width) * static_cast<size_t>(img.height) * 3, 0);
    std::array<int, kPartForestClasses> hist{};
    for (int y = 0; y < raw.height; ++y) {
      for (int x = 0; x < raw.width; ++x) {
        const size_t i = static_cast<size_t>(y) * static_cast<size_t>(raw.width) + static_cast<size_t>(x);
        const draw::Rgb g = draw::depth_gray(depth.depth_mm[i], 300.0, far_mm + 300.0);
        const draw::Rgb left = in.hand_mask[i] ? draw::mix(g, draw::colours::kBlue, 0.3) : g;
        const draw::Rgb right = in.hand_mask[i] ? draw::part_colour(labels[i]) : draw::shade(g, 0.35);
        if (in.hand_mask[i]) ++hist[labels[i]];
        const size_t l = (static_cast<size_t>(y) * static_cast<size_t>(img.width) + static_cast<size_t>(x)) * 3;
        const size_t r = l + static_cast<size_t>(raw.width) * 3;
        img.pixels[l] = left.r;
        img.pixels[l + 1] = left.g;
        img.pixels[l + 2] = left.b;
        img.pixels[r] = right.r;
        img.pixels[r + 1] = right.g;
        img.pixels[r + 2] = right.b;
      }
    }
    const fs::path p(file);
    const fs::path out = out_dir / (p.parent_path().filename().string() + "_" + p.stem().string() + ".png");
    write_png_rgb(out, img);
    std::cout << out.string() << ": " << in.hand_pixels << " hand pixels, " << ms << " ms; classes";
    for (int c = 0; c < kPartForestClasses; ++c) std::cout << " " << hist[static_cast<size_t>(c)];
    std::cout << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Train the hand-part classification forest (Sec. 4.3 of Sridhar et al. 2015; Shotton et al. 2011 "
               "depth features) on labelled synthetic renders, evaluate a model on held-out synthetic frames, or "
               "label real depth frames.",
               kProgram};
  forest::TrainOptions train;
  train.threads = static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
  forest::SceneOptions scene;
  std::string out;
  std::string evaluate_model;
  std::string apply_model;
  std::vector<std::string> inputs;
  std::string output_dir = "forest_labels";
  int images = 3000;
  int eval_frames = 30;
  int eval_scenes = 300;
  int stride = PartForestOptions{}.stride_px;
  double fx = Sr305Camera::kFx, fy = Sr305Camera::kFy, cx = Sr305Camera::kCx, cy = Sr305Camera::kCy,
         depth_scale = Sr305Camera::kDepthScaleMm, far_mm = 900.0;
  app.add_option("--out", out, "Model file to write (training)");
  app.add_option("--trees", train.trees, "Number of trees (paper: 3)")->check(CLI::Range(1, 64));
  app.add_option("--depth", train.max_depth, "Maximum tree depth (paper: 22)")->check(CLI::Range(1, 40));
  app.add_option("--images", images, "Synthetic training images (paper: 50,000)")->check(CLI::Range(1, 10000000));
  app.add_option("--pixels-per-image", train.pixels_per_image, "Hand pixels sampled per image and tree (paper: 2000)")
      ->check(CLI::Range(1, 100000));
  app.add_option("--candidates", train.candidates, "Feature/threshold pairs tried per node (paper: 4000)")
      ->check(CLI::Range(1, 1000000));
  app.add_option("--thresholds", train.thresholds_per_feature, "Thresholds tried per random feature")
      ->check(CLI::Range(1, 1000));
  app.add_option("--min-leaf", train.min_leaf_samples, "Fewest training pixels on each side of a split")
      ->check(CLI::Range(1, 1000000));
  app.add_option("--turned-fraction", scene.turned_fraction,
                 "Share of the random poses turned any way (back, side, fingers toward or away)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--view-fraction", scene.view_fraction,
                 "Share of the motion images seen in another view than palm (back, side, fingers toward or away, "
                 "head-mounted)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--motion-fraction", scene.motion_fraction, "Share of images from the motion scripts")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--ball-fraction", scene.ball_fraction,
                 "Share of images with a ball held against the palm (radius 20-45 mm), its pixels background")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--bottle-share", scene.bottle_share,
                 "Of the images with a held object, the share holding a bottle (handtrack-synth --bottle: a capsule "
                 "across the palm, radius 20-45 mm) instead of a ball")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--body-fraction", scene.body_fraction,
                 "Share of images of the body inside the working volume without the hand (a head, the rest of a "
                 "torso: what a free hand slot would be given), all background")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--varied-fraction", scene.varied_fraction,
                 "Share of images whose hand has varied proportions (finger lengths, girth, palm thickness: "
                 "handtrack-synth --proportions varied)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--distance-spread-mm", scene.distance_spread_mm,
                 "Motion images moved nearer or farther along their palm ray by up to this many mm (handtrack-synth "
                 "--depth-offset; default 0: where the motions hold the hand)")
      ->check(CLI::Range(0.0, 250.0));
  app.add_flag("--distance-farther-only", scene.distance_farther_only,
               "With --distance-spread-mm: the motion images moved farther only, by 0 to the spread");
  app.add_option("--rolled-fraction", scene.rolled_fraction,
                 "Share of the motion images seen through a camera rolled about its axis, by an angle uniform in "
                 "[-180, 180] deg (handtrack-synth --roll: the forearm from any image edge)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--armless-fraction", scene.armless_fraction,
                 "Share of images whose hand is drawn without its arm, cut at the wrist (handtrack-synth --arm none)")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--pose-far-mm", scene.far_mm, "Farthest palm depth of the random poses (from 250 mm)")
      ->check(CLI::Range(300.0, 1500.0))
      ->capture_default_str();
  app.add_option("--volume-far-mm", scene.volume_far_mm,
                 "Far end of the working volume the training frames are segmented in")
      ->check(CLI::Range(300.0, 1500.0))
      ->capture_default_str();
  std::string probes = "image";
  app.add_option("--probes", probes,
                 "image (the paper's: offsets in the image's axes) or hand (offsets turned with the hand's in-plane "
                 "axis, the one the segmentation finds without a hint: a forearm from any image edge is probed alike)")
      ->check(CLI::IsMember({"image", "hand"}))
      ->capture_default_str();
  app.add_option("--seed", train.seed, "Seed of the data set and of the training");
  app.add_option("--threads", train.threads, "Worker threads (default: all cores)")->check(CLI::Range(1, 256));
  app.add_option("--evaluate", evaluate_model, "Evaluate MODEL on held-out synthetic frames and print the "
                                               "accuracy and the confusion matrix");
  app.add_option("--eval-frames", eval_frames, "Held-out frames per motion script")->check(CLI::Range(1, 10000));
  app.add_option("--eval-scenes", eval_scenes, "Held-out random-pose frames")->check(CLI::Range(0, 100000));
  app.add_option("--stride", stride, "Classify one pixel per STRIDE x STRIDE block, per 320 px of width (--evaluate, --apply)")
      ->capture_default_str()
      ->check(CLI::Range(1, 16));
  app.add_option("--apply", apply_model, "Label depth PNGs (--input) with MODEL into colour PNGs in --output-dir");
  app.add_option("--input", inputs, "Depth PNGs for --apply (16-bit, raw units)");
  app.add_option("--output-dir", output_dir, "Where --apply writes its PNGs");
  app.add_option("--fx", fx, "--apply camera fx (default: the RealSense SR305 640x480)");
  app.add_option("--fy", fy, "--apply camera fy");
  app.add_option("--cx", cx, "--apply camera cx");
  app.add_option("--cy", cy, "--apply camera cy");
  app.add_option("--depth-scale", depth_scale, "--apply raw depth unit in mm")->check(CLI::PositiveNumber);
  app.add_option("--far-mm", far_mm, "--apply far end of the working volume (mm)")->check(CLI::PositiveNumber);

  if (const auto exit_code = handtrack::parse_command_line(app, argc, argv, kProgram, 1)) return *exit_code;
  train.hand_aligned = probes == "hand";

  try {
    if (!apply_model.empty()) {
      if (inputs.empty()) return fail("--apply needs --input PNG...");
      PartForest model = PartForest::load(apply_model, PartForestOptions{stride});
      CameraIntrinsics camera;
      camera.fx = fx;
      camera.fy = fy;
      camera.cx = cx;
      camera.cy = cy;
      camera.depth_scale_mm = depth_scale;
      return apply(model, inputs, output_dir, camera, far_mm);
    }
    if (!evaluate_model.empty()) {
      const PartForest model = PartForest::load(evaluate_model, PartForestOptions{stride});
      print_evaluation(std::cout, model, evaluate(model, eval_frames, eval_scenes));
      return 0;
    }
    if (out.empty()) return fail("--out is required to train (or use --evaluate / --apply; see --help)");
    if (train.seed == kHeldOutSceneSeed) return fail("--seed collides with the held-out data set's seed");
    // Before half an hour of rendering and training; a forest already there (the shipped one, say)
    // stays as it is until the new one replaces it.
    handtrack::tools::check_writable(out);

    handtrack::tools::Progress progress(kProgram);
    const auto t0 = std::chrono::steady_clock::now();
    const auto data = forest::make_dataset(train.seed, images, scene, train.threads, 150, [&](int done) {
      progress.update("rendering", static_cast<double>(done) / images);
    });
    progress.done();
    const double render_s = seconds_since(t0);
    std::ostringstream command;
    command << kProgram << " --out " << fs::path(out).filename().string() << " --trees " << train.trees << " --depth "
            << train.max_depth << " --images " << images << " --pixels-per-image " << train.pixels_per_image
            << " --candidates " << train.candidates << " --thresholds " << train.thresholds_per_feature
            << " --min-leaf " << train.min_leaf_samples << " --motion-fraction " << scene.motion_fraction
            << " --turned-fraction " << scene.turned_fraction << " --view-fraction " << scene.view_fraction
            << " --ball-fraction " << scene.ball_fraction << " --bottle-share " << scene.bottle_share
            << " --body-fraction " << scene.body_fraction
            << " --varied-fraction " << scene.varied_fraction << " --distance-spread-mm " << scene.distance_spread_mm
            << (scene.distance_farther_only ? " --distance-farther-only" : "")
            << " --armless-fraction " << scene.armless_fraction << " --rolled-fraction " << scene.rolled_fraction
            << " --pose-far-mm " << scene.far_mm
            << " --volume-far-mm " << scene.volume_far_mm << " --probes " << probes << " --seed " << train.seed;
    const auto t1 = std::chrono::steady_clock::now();
    progress.restart();
    PartForest model = forest::train_forest(data, scene.camera, train, command.str(), [&](const forest::TrainProgress& p) {
      const double f = (p.tree + static_cast<double>(p.samples_done) / static_cast<double>(p.samples_total)) / train.trees;
      progress.update("tree " + std::to_string(p.tree + 1) + "/" + std::to_string(train.trees), f);
    });
    progress.done();
    const double train_s = seconds_since(t1);
    // Scored at stride 1 (every pixel), whatever the default stride, so the metadata is fixed by
    // the seed alone.
    model.set_options(PartForestOptions{1});
    const EvalSummary eval = evaluate(model, eval_frames, eval_scenes);
    // The metadata holds only what the seed determines (no times, no thread count), so the same
    // command writes the same file byte for byte.
    std::ostringstream meta;
    char buf[160];
    std::snprintf(buf, sizeof buf,
                  "\nheld-out accuracy: motions %.1f %%, random poses %.1f %% (palm toward) and %.1f %% (turned)",
                  100.0 * eval.motions.overall.accuracy(), 100.0 * eval.facing.accuracy(),
                  100.0 * eval.turned.accuracy());
    meta << command.str() << buf;
    PartForestInfo info = model.info();
    info.metadata = meta.str();
    model = PartForest(model.trees(), std::move(info));
    model.save(out);
    std::cout << meta.str() << "\n";
    std::snprintf(buf, sizeof buf, "render %.0f s, train %.0f s on %d threads", render_s, train_s, train.threads);
    std::cout << buf << "\n";
    std::snprintf(buf, sizeof buf, "%.1f", static_cast<double>(fs::file_size(out)) / (1024.0 * 1024.0));
    std::cout << "wrote " << out << " (" << buf << " MiB)\n";
    print_evaluation(std::cout, model, eval);
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  return 0;
}
