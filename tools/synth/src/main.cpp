// handtrack-synth: renders a synthetic depth sequence with ground truth (SPEC.md "Sequence
// directory"): camera.json, depth/, labels/, groundtruth.csv, joints.csv, hand.json, plus poses.csv
// (the 26 pose parameters of each frame) and subject.json (the subject's scales and bone lengths).
// A two-hand motion (two_hand_motions.hpp) writes both hands' ground truth, hand 0 (right) then
// hand 1 (left), as docs/SEQUENCES.md describes.

#include "handtrack/core/sequence.hpp"
#include "handtrack/synth/synthetic_camera.hpp"
#include "handtrack/common/cli.hpp"
#include "handtrack/tools/progress.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>

namespace fs = std::filesystem;
using handtrack::synth::SynthOptions;

namespace {

constexpr const char* kProgram = "handtrack-synth";

int fail(const std::string& message) { return handtrack::report_error(kProgram, message, 1); }

// "L,W" -> SubjectScale; throws std::invalid_argument.
handtrack::synth::SubjectScale parse_subject(const std::string& text) {
  const auto comma = text.find(',');
  if (comma == std::string::npos) throw std::invalid_argument("--subject-scale wants L,W (e.g. 1.05,0.95)");
  handtrack::synth::SubjectScale s;
  try {
    size_t used_l = 0, used_w = 0;
    const std::string l = text.substr(0, comma), w = text.substr(comma + 1);
    s.length = std::stod(l, &used_l);
    s.width = std::stod(w, &used_w);
    if (used_l != l.size() || used_w != w.size()) throw std::invalid_argument("trailing characters");
  } catch (const std::exception&) {
    throw std::invalid_argument("--subject-scale wants two numbers L,W, got '" + text + "'");
  }
  const auto ok = [](double v) { return std::isfinite(v) && v >= 0.5 && v <= 2.0; };
  if (!ok(s.length) || !ok(s.width)) throw std::invalid_argument("--subject-scale values must be within [0.5, 2]");
  return s;
}

// Refuses to mix a new sequence into an old one unless --force, which removes what we write.
void prepare_output(const fs::path& dir, bool force) {
  if (fs::exists(dir) && !fs::is_directory(dir)) throw std::runtime_error(dir.string() + " exists and is not a directory");
  const bool has_sequence = fs::exists(dir / "camera.json") || fs::exists(dir / "depth");
  if (!has_sequence) return;
  if (!force) throw std::runtime_error(dir.string() + " already holds a sequence (use --force to replace it)");
  for (const char* name : {"depth", "labels", "preview"}) fs::remove_all(dir / name);
  for (const char* name : {"camera.json", "groundtruth.csv", "joints.csv", "poses.csv", "subject.json", "hand.json"}) {
    fs::remove(dir / name);
  }
}

// Per finger: bone lengths, radii and base of one hand's shape.
nlohmann::json fingers_json(const handtrack::synth::HandShape& shape) {
  nlohmann::json bones = nlohmann::json::object();
  for (int f = 0; f < handtrack::kNumFingers; ++f) {
    const auto& fs_ = shape.fingers[static_cast<size_t>(f)];
    bones[std::string(handtrack::kFingerNames[static_cast<size_t>(f)])] = {
        {"bone_lengths_mm", fs_.bone_length_mm}, {"radii_mm", fs_.radius_mm},
        {"base_mm", {fs_.base_mm.x(), fs_.base_mm.y(), fs_.base_mm.z()}}};
  }
  return bones;
}

// One hand's scales: its size and its proportions (the fingers' own lengths and radii are in
// "fingers").
void add_scales(nlohmann::json& j, const handtrack::synth::SubjectScale& s) {
  j["length_scale"] = s.length;
  j["width_scale"] = s.width;
  j["finger_length_scales"] = s.finger_length;
  j["finger_girth_scale"] = s.finger_girth;
  j["palm_thickness_scale"] = s.palm_thickness;
  j["palm_arch_mm"] = s.palm_arch_mm;
  j["palm_arch_shape"] = std::string(handtrack::synth::palm_arch_name(s.palm_arch));
}

// The subject: one hand's scales and fingers at the top level; for a two-hand motion "hands", one
// object per hand (its side, scales and fingers) in the order of the ground-truth blocks.
void write_subject_json(const fs::path& file, const handtrack::synth::SyntheticCamera& cam) {
  const auto& o = cam.options();
  nlohmann::json j = {{"generator", kProgram},
                      {"motion", o.motion},
                      {"frames", o.frames},
                      {"seed", o.seed},
                      {"noise", o.noise},
                      {"noise_sigma_k_per_mm", o.noise_params.sigma_k_per_mm},
                      {"projector_x_mm", o.noise_params.projector_x_mm},
                      {"noise_correlation_px", o.noise_params.noise_correlation_px},
                      {"background", std::string(handtrack::synth::background_name(o.background))},
                      {"ball_radius_mm", o.ball_radius_mm},
                      {"bottle_radius_mm", o.bottle_radius_mm},
                      {"proportions", std::string(handtrack::synth::proportions_name(o.proportions))},
                      {"arm", std::string(handtrack::synth::arm_name(o.arm))},
                      {"roll_deg", o.roll_deg},
                      {"pose_parameters", "poses.csv: frame, t_x,t_y,t_z (mm, wrist), r_x,r_y,r_z (axis-angle, "
                                          "R = exp(r) diag(1,-1,-1)), thumb..little abd,flex1,flex2,flex3 (rad)"}};
  if (cam.hand_count() == 1) {
    add_scales(j, cam.subject());
    j["hand"] = std::string(handtrack::synth::handedness_name(o.hand));
    j["view"] = std::string(handtrack::synth::view_name(o.view));
    j["fingers"] = fingers_json(cam.shape());
  } else {
    j["pose_parameters"] = j["pose_parameters"].get<std::string>() +
                           "; hand 1's columns prefixed h1_, its pose the right-hand model's whose mirror image "
                           "(x -> -x) it is";
    j["view"] = std::string(handtrack::synth::view_name(handtrack::synth::two_hand_view(o.motion)));
    j["hands"] = nlohmann::json::array();
    for (int k = 0; k < cam.hand_count(); ++k) {
      nlohmann::json hand = {{"hand", k == 0 ? "right" : "left"}, {"fingers", fingers_json(cam.shape(k))}};
      add_scales(hand, cam.subject(k));
      j["hands"].push_back(std::move(hand));
    }
  }
  std::ofstream out(file);
  if (!out) throw std::runtime_error(file.string() + ": cannot write");
  out << j.dump(1) << "\n";
}

// SPEC.md "Sequence directory": hand.json, which hands the sequence shows; ours besides: the motion
// and (one hand) the view, by which handtrack-eval groups its scores. A two-hand scene has its own
// arrangement, no view.
void write_hands(handtrack::SequenceWriter& writer, const handtrack::synth::SyntheticCamera& cam) {
  const auto& o = cam.options();
  if (cam.hand_count() == 1) {
    writer.write_hands({std::string(handtrack::synth::handedness_name(o.hand))},
                       {{"view", std::string(handtrack::synth::view_name(o.view))}, {"motion", o.motion}});
  } else {
    writer.write_hands({"right", "left"}, {{"motion", o.motion}});
  }
}

// poses.csv: the frame, then per hand the 26 parameters (hand k's columns prefixed as in
// groundtruth.csv: h1_tx, ...).
class PosesCsv {
 public:
  PosesCsv(const fs::path& file, int hands) : file_(file), out_(file), hands_(hands) {
    if (!out_) throw std::runtime_error(file.string() + ": cannot write");
    out_ << "frame";
    for (int h = 0; h < hands; ++h) {
      const std::string prefix = handtrack::hand_column_prefix(h);
      for (const char* q : {"tx", "ty", "tz", "rx", "ry", "rz"}) out_ << "," << prefix << q;
      for (auto name : handtrack::kFingerNames) {
        for (const char* q : {"_abd", "_flex1", "_flex2", "_flex3"}) out_ << "," << prefix << name << q;
      }
    }
    out_ << "\n";
  }
  void write(const handtrack::synth::SynthFrame& frame) {
    char buf[32];
    out_ << frame.frame;
    for (int h = 0; h < hands_; ++h) {
      const auto p = frame.hands[static_cast<size_t>(h)].pose.to_params();
      for (int i = 0; i < p.size(); ++i) {
        std::snprintf(buf, sizeof buf, ",%.6f", p(i));
        out_ << buf;
      }
    }
    out_ << "\n";
    if (!out_) throw std::runtime_error(file_.string() + ": write failed");
  }

 private:
  fs::path file_;
  std::ofstream out_;
  int hands_ = 1;
};

std::string motion_description(const std::string& name) {
  const auto one = handtrack::synth::motion_description(name);
  return std::string(one.empty() ? handtrack::synth::two_hand_motion_description(name) : one);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Render a synthetic depth sequence of a capsule hand performing one of the Dexter 1 motions, with "
               "ground truth (fingertips, 21 joints, part labels) in the sequence-directory format of SPEC.md.",
               kProgram};
  SynthOptions options;
  std::string motion;
  std::string out_dir;
  std::string subject;
  std::string background;
  std::string hand = "right";
  std::string view = "palm";
  bool list_views = false;
  int frames = 300;
  int width = 320;
  int height = 240;
  bool list = false;
  bool force = false;
  bool preview = false;
  bool no_labels = false;
  app.add_flag("--list-motions", list, "List the motions and exit");
  app.add_flag("--list-views", list_views, "List the views (camera arrangements) and exit");
  app.add_option("--motion", motion, "Motion: adbadd, fingercount, fingerwave, flexex1, pinch, random, tigergrasp; "
                                     "two hands: two_apart, two_clap, two_cross, two_pinch");
  app.add_option("--frames", frames, "Number of frames (slow first half, fast second half)")
      ->check(CLI::Range(1, 1000000));
  app.add_option("--out", out_dir, "Output sequence directory");
  app.add_option("--seed", options.seed, "Seed for the subject (unless --subject-scale) and the noise");
  app.add_option("--subject-scale", subject, "Subject scales L,W (length, width; 1 = mean adult; default: drawn "
                                             "from the seed within +-10%)");
  std::string proportions = "mean";
  app.add_option("--proportions", proportions,
                 "mean (default: the mean adult's, scaled by the subject's size) or varied (each hand's finger "
                 "lengths, finger girth and palm thickness drawn from the seed as well)");
  app.add_option("--palm-arch", options.palm_arch_mm,
                 "Arch the palm about its long axis: its sides (the index and little fingers' knuckles) this many mm "
                 "toward the palm's side, as a real hand's transverse arch (default 0: flat)")
      ->check(CLI::Range(0.0, 20.0));
  std::string palm_arch_shape = "bent";
  app.add_option("--palm-arch-shape", palm_arch_shape,
                 "What --palm-arch bends: bent (default: the whole palm and the knuckles on it) or back (the back "
                 "of the hand alone; the palm's front stays flat, as a real palm's does)")
      ->needs("--palm-arch");
  app.add_flag("--noise,!--no-noise", options.noise, "Sensor noise model on (default) or off");
  app.add_option("--background", background,
                 "Background: body (default; head-mounted view and two_reach: table), table, desk (the hand rests on it), "
                 "near-body (a user close to the camera: torso and head inside the working volume) or none");
  double ball_radius_mm = 0.0;
  app.add_option("--ball", ball_radius_mm, "Radius (mm) of a ball held against the palm (default 0: none)")
      ->check(CLI::Range(0.0, 100.0));
  double bottle_radius_mm = 0.0;
  app.add_option("--bottle", bottle_radius_mm,
                 "Radius (mm) of a bottle (its axis 130 mm long) held against the palm across its width, an object "
                 "the forest never saw (default 0: none; not with --ball)")
      ->check(CLI::Range(0.0, 100.0))
      ->excludes("--ball");
  app.add_option("--hand", hand, "right (default) or left: the right hand's exact mirror image (not with a "
                                 "two-hand motion: it shows both)");
  app.add_option("--view", view, "Camera arrangement (see --list-views): palm (default), back, side, "
                                 "fingers-toward, fingers-away, head-mounted (not with a two-hand motion: "
                                 "it places both hands itself)");
  app.add_option("--width", width, "Image width (intrinsics scale with it)")->check(CLI::Range(16, 4096));
  app.add_option("--height", height, "Image height (intrinsics scale with it)")->check(CLI::Range(16, 4096));
  app.add_option("--depth-offset", options.depth_offset_mm,
                 "Move the hand this many mm along the ray through its palm centre in every frame: negative nearer "
                 "the camera, positive farther (default 0: where the view puts it; one-hand motions)")
      ->check(CLI::Range(-250.0, 250.0));
  app.add_option("--roll", options.roll_deg,
                 "Turn the camera about its optical axis by this many degrees: the hand, forearm and scene turn "
                 "together in the image, so the forearm enters from another edge (default 0; 90: from the image's "
                 "left in the desk views; one-hand motions, not with --background desk or --arm shoulder)")
      ->check(CLI::Range(-180.0, 180.0));
  std::string arm = "forearm";
  app.add_option("--arm", arm,
                 "How much of the arm to render: forearm (default: it ends at the elbow), none (the hand alone, cut "
                 "at the wrist, as renderers of a hand model without an arm draw it) or shoulder (on past the elbow "
                 "to the shoulder of a user facing the camera; desk views); none and shoulder: one-hand motions");
  double fov_deg = 0.0;
  app.add_option("--fov", fov_deg,
                 "Horizontal field of view in degrees (default: the SPEC.md camera's 70.9; a Kinect's is about 58, a "
                 "RealSense D435's 87)")
      ->check(CLI::Range(20.0, 150.0));
  std::string sensor = "generic";
  app.add_option("--sensor", sensor,
                 "Sensor class whose artefacts the noise imitates: generic (default: independent noise per pixel, "
                 "flying pixels, dropouts) or structured-light (as the SR305 frames show it: a projector 50 mm to "
                 "the camera's left whose shadow has no depth, and noise correlated over neighbouring pixels)");
  double projector_x_mm = 0.0;
  app.add_option("--projector-x", projector_x_mm,
                 "With --sensor structured-light: the projector's offset along the camera's x axis in mm (default "
                 "-50; positive: to the camera's right, its shadow to the image left of nearer surfaces)")
      ->check(CLI::Range(-200.0, 200.0));
  double noise_correlation_px = 0.0;
  app.add_option("--noise-correlation", noise_correlation_px,
                 "With --sensor structured-light: the standard deviation in pixels of the blur that correlates the "
                 "depth noise (default 2.5 at 320 px wide, scaled with --width; 0: independent per pixel)")
      ->check(CLI::Range(0.0, 50.0));
  app.add_flag("--preview", preview, "Also write preview/NNNNNN.png (depth gray | labels in colour)");
  app.add_flag("--no-labels", no_labels, "Do not write labels/");
  app.add_flag("--force", force, "Replace a sequence already in --out");

  if (const auto exit_code = handtrack::parse_command_line(app, argc, argv, kProgram, 1)) return *exit_code;

  if (list) {
    for (auto name : handtrack::synth::kMotionNames) {
      std::cout << name << "\t" << handtrack::synth::motion_description(name) << "\n";
    }
    for (auto name : handtrack::synth::kTwoHandMotionNames) {
      std::cout << name << "\t" << handtrack::synth::two_hand_motion_description(name) << "\n";
    }
    return 0;
  }
  if (list_views) {
    for (auto v : handtrack::synth::kViews) {
      std::cout << handtrack::synth::view_name(v) << "\t" << handtrack::synth::view_description(v) << "\n";
    }
    return 0;
  }
  if (motion.empty()) return fail("--motion is required (see --list-motions)");
  if (out_dir.empty()) return fail("--out is required");
  if (motion_description(motion).empty()) return fail("unknown motion '" + motion + "' (see --list-motions)");
  if (handtrack::synth::is_two_hand_motion(motion)) {
    // Refused rather than ignored: a left-hand or back-view sequence asked for would silently be
    // something else.
    for (const char* option : {"--hand", "--view"}) {
      if (app.count(option) > 0) {
        return fail(std::string(option) + " does not apply to the two-hand motion '" + motion +
                    "' (it shows a right and a left hand in its own arrangement)");
      }
    }
  }
  const auto arrangement = handtrack::synth::parse_view(view);
  if (!arrangement) return fail("unknown view '" + view + "' (see --list-views)");
  const auto bg = background.empty() ? handtrack::synth::default_background(motion, *arrangement)
                                      : handtrack::synth::parse_background(background);
  if (!bg) return fail("--background must be body, table, desk, near-body or none, got '" + background + "'");
  const auto handedness = handtrack::synth::parse_handedness(hand);
  if (!handedness) return fail("--hand must be right or left, got '" + hand + "'");
  const auto shape_proportions = handtrack::synth::parse_proportions(proportions);
  if (!shape_proportions) return fail("--proportions must be mean or varied, got '" + proportions + "'");
  const auto arch_shape = handtrack::synth::parse_palm_arch(palm_arch_shape);
  if (!arch_shape) return fail("--palm-arch-shape must be bent or back, got '" + palm_arch_shape + "'");
  const auto shown_arm = handtrack::synth::parse_arm(arm);
  if (!shown_arm) return fail("--arm must be none, forearm or shoulder, got '" + arm + "'");
  const auto sensor_class = handtrack::synth::parse_sensor(sensor);
  if (!sensor_class) return fail("--sensor must be generic or structured-light, got '" + sensor + "'");
  for (const char* option : {"--projector-x", "--noise-correlation"}) {
    if (app.count(option) > 0 && *sensor_class != handtrack::synth::Sensor::kStructuredLight) {
      return fail(std::string(option) + " needs --sensor structured-light");
    }
  }

  try {
    options.motion = motion;
    options.frames = frames;
    options.background = *bg;
    options.ball_radius_mm = ball_radius_mm;
    options.bottle_radius_mm = bottle_radius_mm;
    options.hand = *handedness;
    options.proportions = *shape_proportions;
    options.palm_arch = *arch_shape;
    options.arm = *shown_arm;
    options.view = *arrangement;
    options.camera = app.count("--fov") > 0 ? handtrack::synth::camera_with_fov(width, height, fov_deg)
                                            : handtrack::synth::default_camera(width, height);
    options.noise_params = handtrack::synth::sensor_noise(*sensor_class, width);
    if (app.count("--projector-x") > 0) options.noise_params.projector_x_mm = projector_x_mm;
    if (app.count("--noise-correlation") > 0) options.noise_params.noise_correlation_px = noise_correlation_px;
    if (!subject.empty()) options.subject = parse_subject(subject);
    handtrack::synth::SyntheticCamera cam(options);

    const fs::path dir(out_dir);
    prepare_output(dir, force);
    handtrack::SequenceWriter writer(dir, cam.camera());
    write_subject_json(dir / "subject.json", cam);
    write_hands(writer, cam);
    PosesCsv poses(dir / "poses.csv", cam.hand_count());
    if (preview) fs::create_directories(dir / "preview");

    handtrack::tools::Progress progress(kProgram);
    handtrack::synth::SynthFrame frame;
    for (int i = 0; i < frames; ++i) {
      cam.render(i, frame);
      writer.write_depth(i, frame.depth);
      if (!no_labels) writer.write_labels(i, frame.labels);
      for (int h = 0; h < frame.hand_count; ++h) {
        writer.write_fingertips(i, frame.hands[static_cast<size_t>(h)].fingertips, h);
        writer.write_joints(i, frame.hands[static_cast<size_t>(h)].joints, h);
      }
      poses.write(frame);
      if (preview) handtrack::write_png_rgb(handtrack::frame_file(dir / "preview", i), preview_image(frame));
      progress.update("frames", static_cast<double>(i + 1) / frames);
    }
    writer.flush();
  } catch (const std::invalid_argument& e) {
    return fail(e.what());
  } catch (const std::exception& e) {
    return fail(e.what());
  }
  return 0;
}
