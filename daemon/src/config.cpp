// handtrackd's configuration file: one table of fields (name, type, range, help) drives parsing,
// validation, --print-config and the docs, so a field cannot be parsed without being checked.
#include "handtrack/daemon/config.hpp"

#include "handtrack/core/camera_roll.hpp"
#include "handtrack/core/hand_calibration.hpp"
#include "handtrack/core/hands_tracker.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <variant>

namespace handtrack::daemon {

namespace {

using IntRef = int& (*)(DaemonConfig&);
using Int64Ref = int64_t& (*)(DaemonConfig&);
using Uint64Ref = uint64_t& (*)(DaemonConfig&);
using DoubleRef = double& (*)(DaemonConfig&);
using BoolRef = bool& (*)(DaemonConfig&);
using StringRef = std::string& (*)(DaemonConfig&);
// A field that takes one of a few names (the log level, the handedness).
struct ChoiceRef {
  const char* (*get)(DaemonConfig&);
  bool (*set)(DaemonConfig&, const std::string&);  // false: not one of `allowed`
  const char* allowed;                             // "a, b, c"
};
using Ref = std::variant<IntRef, Int64Ref, Uint64Ref, DoubleRef, BoolRef, StringRef, ChoiceRef>;

struct Field {
  const char* name;  // dotted TOML path
  Ref ref;
  double min;        // numbers: allowed range (inclusive); strings: minimum length
  double max;
  const char* help;  // one line, with the paper's section where the value comes from
  bool live;         // applied on SIGHUP
};

// A string as a TOML basic string literal (quotes and escapes).
std::string toml_quote(const std::string& s) {
  std::ostringstream out;
  out << toml::value<std::string>(s);
  return out.str();
}

constexpr double kMaxSeed = 9007199254740992.0;  // 2^53: exact in a TOML float too

// clang-format off
const std::vector<Field>& fields() {
  static const std::vector<Field> table = {
    // [daemon]
    {"daemon.source", StringRef{[](DaemonConfig& c) -> std::string& { return c.source; }}, 1, 4096,
     "openni2 | openni2:URI | oni:FILE.oni | seq:DIR | synthetic[:MOTION]", false},
    {"daemon.shm_name", StringRef{[](DaemonConfig& c) -> std::string& { return c.shm_name; }}, 1, 200,
     "POSIX shared-memory object name of the pose ring (no '/')", false},
    {"daemon.ring_capacity", IntRef{[](DaemonConfig& c) -> int& { return c.ring_capacity; }}, 2, 65536,
     "pose records kept in the ring", false},
    {"daemon.log_level",
     ChoiceRef{[](DaemonConfig& c) { return to_string(c.log_level); },
               [](DaemonConfig& c, const std::string& v) { return parse_log_level(v, &c.log_level); },
               "trace, debug, info, warn, error, off"},
     0, 0, "trace | debug | info | warn | error | off", true},
    {"daemon.fast", BoolRef{[](DaemonConfig& c) -> bool& { return c.fast; }}, 0, 0,
     "recordings and the synthetic camera: as fast as possible instead of at their frame rate", false},
    {"daemon.loop", BoolRef{[](DaemonConfig& c) -> bool& { return c.loop; }}, 0, 0,
     "recordings: start again at the end (otherwise the daemon exits at the end)", false},
    {"daemon.record_dir", StringRef{[](DaemonConfig& c) -> std::string& { return c.record_dir; }}, 0, 4096,
     "non-empty: write the raw depth there as a sequence directory", false},
    {"daemon.single_thread", BoolRef{[](DaemonConfig& c) -> bool& { return c.single_thread; }}, 0, 0,
     "all stages on one thread (the baseline the pipeline's overlap is measured against)", false},
    // [camera]: OpenNI2 depth mode
    {"camera.width", IntRef{[](DaemonConfig& c) -> int& { return c.source_options.width; }}, 16, 4096,
     "preferred depth width (Sec. 7: 320x240 at 60 fps; falls back to 640x480 at 30)", false},
    {"camera.height", IntRef{[](DaemonConfig& c) -> int& { return c.source_options.height; }}, 16, 4096,
     "preferred depth height", false},
    {"camera.fps", IntRef{[](DaemonConfig& c) -> int& { return c.source_options.fps; }}, 1, 1000,
     "preferred depth frame rate (the synthetic camera runs at it)", false},
    {"camera.roll", IntRef{[](DaemonConfig& c) -> int& { return c.camera_roll_deg; }}, -180, 270,
     "degrees the camera is mounted turned about its optical axis: 0, 90, 180 (upside down) or 270 (-90), as "
     "handtrack-synth's --roll; frames are tracked turned upright, poses published in the camera's own frame",
     false},
    // [synthetic]
    {"synthetic.frames", IntRef{[](DaemonConfig& c) -> int& { return c.source_options.synthetic_frames; }}, 2, 1000000,
     "frames in one pass of a synthetic motion (slow first half, fast second half)", false},
    {"synthetic.seed", Uint64Ref{[](DaemonConfig& c) -> uint64_t& { return c.source_options.seed; }}, 0, kMaxSeed,
     "subject scale and sensor noise of the synthetic camera", false},
    {"synthetic.prerender", BoolRef{[](DaemonConfig& c) -> bool& { return c.source_options.synthetic_prerender; }},
     0, 0,
     "render one period of frames into memory at start (2 (frames - 1) for one motion, 7 x frames for all; "
     "320x240: 150 KB each) and replay it, so that frames cost no CPU as a camera's (latency benchmarks)",
     false},
    // [pipeline]
    {"pipeline.queue_capacity", IntRef{[](DaemonConfig& c) -> int& { return c.pipeline.queue_capacity; }}, 1, 64,
     "frames each queue between two stages holds; the oldest is dropped when the optimizer falls behind", false},
    {"pipeline.pool_frames", IntRef{[](DaemonConfig& c) -> int& { return c.pipeline.pool_frames; }}, 0, 1024,
     "frames allocated at start (0: enough for every queue and stage)", false},
    {"pipeline.cpu_grab", IntRef{[](DaemonConfig& c) -> int& { return c.pipeline.cpu[0]; }}, -1, 1023,
     "CPU the grab thread is pinned to (-1: any)", false},
    {"pipeline.cpu_preprocess", IntRef{[](DaemonConfig& c) -> int& { return c.pipeline.cpu[1]; }}, -1, 1023,
     "CPU the preprocess thread is pinned to (-1: any)", false},
    {"pipeline.cpu_optimize", IntRef{[](DaemonConfig& c) -> int& { return c.pipeline.cpu[2]; }}, -1, 1023,
     "CPU the optimize thread is pinned to (-1: any)", false},
    {"pipeline.cpu_publish", IntRef{[](DaemonConfig& c) -> int& { return c.pipeline.cpu[3]; }}, -1, 1023,
     "CPU the publish thread is pinned to (-1: any)", false},
    {"pipeline.realtime_priority", IntRef{[](DaemonConfig& c) -> int& { return c.pipeline.realtime_priority; }}, 0, 99,
     "SCHED_FIFO priority of the stage threads, the preprocessing ones one below (0: normal scheduling, "
     "preprocessing at a nice value 5 higher; needs CAP_SYS_NICE)",
     false},
    {"pipeline.stall_timeout_ms", IntRef{[](DaemonConfig& c) -> int& { return c.pipeline.stall_timeout_ms; }}, 100, 600000,
     "a stage busy on one frame this long counts as stalled: watchdog pings and heartbeats stop", false},
    {"pipeline.stats_interval_ms", IntRef{[](DaemonConfig& c) -> int& { return c.pipeline.stats_interval_ms; }}, 100, 60000,
     "how often statistics go into the ring header and STATUS=", false},
    // [tracker] (Sec. 5, Sec. 7)
    {"tracker.particles", IntRef{[](DaemonConfig& c) -> int& { return c.tracker.particles; }}, 1, 64,
     "pose particles per frame (Sec. 7: best accuracy with 2)", true},
    {"tracker.extrapolation_mean", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.extrapolation_mean; }}, -5, 5,
     "mean of alpha in P_i = Theta^{t-1} + alpha (Theta^{t-1} - Theta^{t-2}) (Sec. 5)", true},
    {"tracker.extrapolation_sigma", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.extrapolation_sigma; }}, 0, 5,
     "standard deviation of alpha (Sec. 5)", true},
    {"tracker.handedness",
     ChoiceRef{[](DaemonConfig& c) { return to_string(c.tracker.handedness); },
               [](DaemonConfig& c, const std::string& v) { return parse_handedness_mode(v, &c.tracker.handedness); },
               "auto, left, right"},
     0, 0, "auto | left | right: which hand the tracker fits (auto: both from every (re)start, until several frames tell)",
     true},
    {"tracker.arrangement",
     ChoiceRef{[](DaemonConfig& c) { return to_string(c.tracker.arrangement); },
               [](DaemonConfig& c, const std::string& v) { return parse_camera_arrangement(v, &c.tracker.arrangement); },
               "facing, head-mounted"},
     0, 0,
     "facing | head-mounted: where the camera looks from (a camera facing the user, or one at the user's eyes); "
     "auto handedness expects the palm or the back toward it, and the right hand on the image's left or right, "
     "where the depth leaves it open",
     true},
    {"tracker.handedness_recheck_frames",
     IntRef{[](DaemonConfig& c) -> int& { return c.tracker.handedness_recheck_frames; }}, 0, 100000,
     "auto: a hand whose fit stays below recheck_below_confidence is tried as the other hand again every this many "
     "frames (0: never; never with check_iterations_per_frame > 0 or background_checks)",
     true},
    {"tracker.max_hands", IntRef{[](DaemonConfig& c) -> int& { return c.tracker.max_hands; }}, 1, kMaxHands,
     "hands tracked at once (each its own id, handedness and pose; optimized on two cores)", true},
    {"tracker.init_iterations", IntRef{[](DaemonConfig& c) -> int& { return c.tracker.init_iterations; }}, 1, 1000,
     "iterations of each (re)start hypothesis (the best 3 of its 24-48; the others 15)", true},
    {"tracker.lost_confidence", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.lost_confidence; }}, 0, 1,
     "confidence below which a frame counts toward a restart", true},
    {"tracker.lost_frames", IntRef{[](DaemonConfig& c) -> int& { return c.tracker.lost_frames; }}, 1, 1000,
     "low-confidence frames in a row that trigger a restart", true},
    {"tracker.min_start_confidence", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.min_start_confidence; }},
     0, 1, "a (re)start that explains less of the segmented surface reports no hand", true},
    {"tracker.suspect_confidence_ratio",
     DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.suspect_confidence_ratio; }}, 0, 1,
     "confidence below this share of its running level: a check against the restart poses starts, spread over the next frames", true},
    {"tracker.confidence_level_rate", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.confidence_level_rate; }},
     0.001, 1, "rate of the running confidence level (exponential average)", true},
    {"tracker.check_interval_frames", IntRef{[](DaemonConfig& c) -> int& { return c.tracker.check_interval_frames; }}, 1,
     1000, "at most one such check per this many frames", true},
    {"tracker.recheck_interval_frames",
     IntRef{[](DaemonConfig& c) -> int& { return c.tracker.recheck_interval_frames; }}, 0, 100000,
     "a fit whose running confidence stays below recheck_below_confidence is checked the same way every this many "
     "frames (0: never)",
     true},
    {"tracker.recheck_below_confidence",
     DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.recheck_below_confidence; }}, 0, 1,
     "running confidence below which a fit is rechecked every recheck_interval_frames", true},
    {"tracker.check_replace_margin",
     DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.check_replace_margin; }}, 0, 1,
     "a check's restart pose replaces the tracked one only when its fit score is higher by more than this", true},
    {"tracker.check_iterations_per_frame",
     IntRef{[](DaemonConfig& c) -> int& { return c.tracker.check_iterations_per_frame; }}, 0, 1000,
     "0: a check is made on one frame (10-16 ms); N: spread over frames, about N iterations each (64: every frame "
     "within about 3 ms, a gross error repaired in about 14 frames instead of 2)",
     true},
    {"tracker.background_checks", BoolRef{[](DaemonConfig& c) -> bool& { return c.tracker.background_checks; }}, 0, 0,
     "true: a check's whole search runs on a thread of its own on idle CPU time only, and no frame waits for it "
     "(check_iterations_per_frame unused; a gross error repaired once the idle CPU has done the search)",
     true},
    {"tracker.fusion_label_weight", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.fusion_label_weight; }},
     0, 1, "late fusion: share of the label similarity in the energy that picks the winning particle", true},
    {"tracker.energy_mode",
     ChoiceRef{[](DaemonConfig& c) { return to_string(c.tracker.mode); },
               [](DaemonConfig& c, const std::string& v) { return parse_energy_mode(v, &c.tracker.mode); },
               "late-fusion, depth-only"},
     0, 0,
     "late-fusion (one particle detection-guided by the part forest, Sec. 5) | depth-only (Sec. 4.1)", false},
    {"tracker.forest_model", StringRef{[](DaemonConfig& c) -> std::string& { return c.forest_model; }}, 0, 4096,
     "part-classification forest file for late fusion; empty: the shipped one (data/, /usr/share/handtrack)",
     false},
    {"tracker.hand_profile", StringRef{[](DaemonConfig& c) -> std::string& { return c.hand_profile; }}, 0, 4096,
     "hand profile file (handtrack-calibrate, Sec. 6): its scales replace tracker.scale; empty: tracker.scale",
     false},
    {"tracker.self_calibrate", BoolRef{[](DaemonConfig& c) -> bool& { return c.tracker.self_calibrate; }}, 0, 0,
     "true: each hand in view has its scale calibrated from its first frames held open toward the camera and is "
     "then tracked with it (a handedness trial keeps tracker.scale's or the profile's width and sigma); false: "
     "tracker.scale (or the profile) throughout",
     false},
    {"tracker.seed", Uint64Ref{[](DaemonConfig& c) -> uint64_t& { return c.tracker.seed; }}, 0, kMaxSeed,
     "random seed of the particle extrapolation", true},
    // [tracker.input] (Sec. 3.1, Sec. 4)
    {"tracker.input.median_radius_px", IntRef{[](DaemonConfig& c) -> int& { return c.tracker.input.median_radius_px; }}, 0, 5,
     "median filter radius (Sec. 4: 3x3 against flying pixels)", true},
    {"tracker.input.near_mm", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.input.near_mm; }}, 1, 10000,
     "working volume near plane (Sec. 4: 150 mm)", true},
    {"tracker.input.far_mm", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.input.far_mm; }}, 1, 20000,
     "working volume far plane (Sec. 4: 600 mm)", true},
    {"tracker.input.quadtree_threshold_mm", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.input.quadtree_threshold_mm; }}, 0.1, 1000,
     "epsilon_c: split a quadtree cell until its depth range is below this (Sec. 3.1: 20 mm)", true},
    {"tracker.input.quadtree_root_px", IntRef{[](DaemonConfig& c) -> int& { return c.tracker.input.quadtree_root_px; }}, 2, 512,
     "quadtree root cell side at 320 px width", true},
    {"tracker.input.quadtree_min_leaf_px", IntRef{[](DaemonConfig& c) -> int& { return c.tracker.input.quadtree_min_leaf_px; }}, 1, 64,
     "smallest quadtree cell at 320 px width", true},
    {"tracker.input.min_leaf_fill", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.input.min_leaf_fill; }}, 0, 1,
     "fraction of hand pixels a leaf needs", true},
    {"tracker.input.split_partial_leaf_fill", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.input.split_partial_leaf_fill; }}, 0, 1,
     "a leaf less full of hand pixels than this is split once more (0: never)", true},
    {"tracker.input.continuity_mm", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.input.continuity_mm; }}, 0.1, 1000,
     "neighbouring pixels closer than this are one surface (segmentation)", true},
    {"tracker.input.min_hand_area_mm2", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.input.min_hand_area_mm2; }}, 0, 1e6,
     "smaller blobs are noise, not a hand", true},
    {"tracker.input.hand_length_mm", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.input.hand_length_mm; }}, 50, 400,
     "wrist to middle fingertip, bounds the hand region", true},
    {"tracker.input.desk", BoolRef{[](DaemonConfig& c) -> bool& { return c.tracker.input.support_plane.enabled; }}, 0, 0,
     "take a desk, table or wall the hand touches out of the working volume before segmentation (ours)", true},
    {"tracker.input.desk_min_area_mm2",
     DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.input.support_plane.min_area_mm2; }}, 10000, 1e6,
     "a plane covering more of the working volume than this is a desk, not a hand (mm^2)", true},
    {"tracker.input.desk_band_mm", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.input.support_plane.band_mm; }},
     1, 100, "pixels within this of the desk's plane, or beyond it, are the desk's", true},
    {"tracker.input.drop_background", BoolRef{[](DaemonConfig& c) -> bool& { return c.tracker.input.drop_background; }}, 0, 0,
     "with the part forest: hand pixels it labels background (a held object, the forearm) leave the hand (ours)", true},
    {"tracker.input.drop_background_min_area_mm2",
     DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.input.drop_background_min_area_mm2; }}, 0, 1e6,
     "only connected background regions at least this large leave the hand (mm^2)", true},
    // [tracker.energy] (Sec. 4.1, Sec. 4.3)
    {"tracker.energy.w_c", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.weights.collision; }}, 0, 1000,
     "w_c, weight of the collision term E_col (Sec. 4.1: 1.0) in the (re)start search and its checks and in depth-only tracking", true},
    {"tracker.energy.w_c_tracking", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.weights.tracking_collision; }}, 0, 1000,
     "w_c while late fusion tracks (ours, not its (re)starts: 0.5, measured best; docs/TRACKER.md)", true},
    {"tracker.energy.w_l", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.weights.limits; }}, 0, 1000,
     "w_l, weight of the joint-limit term E_lim (Sec. 4.1: 0.2)", true},
    {"tracker.energy.w_s", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.weights.smoothness; }}, 0, 1000,
     "w_s, weight of the smoothness term E_smo (Sec. 4.1: 1.0; ours: 0.1, measured best, docs/TRACKER.md)", true},
    {"tracker.energy.w_h", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.weights.inter_hand; }}, 0, 1000,
     "w_h, weight of the collision term between two hands E_hand (ours: the paper tracks one hand)", true},
    {"tracker.energy.w_f", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.weights.free_space; }}, 0, 1000,
     "w_f, weight of the free-space term E_free: model parts over the background (ours, late fusion only; 0 = the paper's energy)", true},
    {"tracker.energy.w_u", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.weights.unseen_fingers; }}, 0, 1000,
     "w_u, weight of E_unseen: fingers the part labels do not see on a hand facing the camera curl (ours, late fusion's tracking only; 0 = the paper's energy; docs/TRACKER.md)", true},
    {"tracker.energy.coverage_cap", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.weights.coverage_cap; }}, 0, 100,
     "c, E_sim's coverage cap: an image Gaussian earns at most c times its own overlap, however many model parts cover it (ours, late fusion's tracking only, not its (re)starts; 0 = the paper's E_sim; docs/TRACKER.md)", true},
    {"tracker.energy.slant_front", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.weights.slant_front; }}, 1, 10,
     "k_max: a model part seen at a slant has the surface the camera sees up to k_max sigma_h in front of its Gaussians, the palm as a slab and each finger bone that points away from the camera as a capsule (ours, late fusion's tracking only; 1 = the paper's E_sim; docs/TRACKER.md)", true},
    {"tracker.energy.label_radius_mm", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.weights.label_radius_mm; }}, 1, 5000,
     "R_i, radius of influence of the label similarity factor (Sec. 4.3: 200 mm)", true},
    {"tracker.energy.smoothness_translation_per_mm", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.weights.smoothness_translation_per_mm; }}, 0, 1,
     "E_smo unit of translations per mm (1e-3: metres, balancing w_s = 1 in SI units)", true},
    // [tracker.optimizer] (Sec. 5, Sec. 7)
    {"tracker.optimizer.iterations", IntRef{[](DaemonConfig& c) -> int& { return c.tracker.optimizer.iterations; }}, 1, 1000,
     "gradient ascent iterations per particle (Sec. 7: fixed to 10)", true},
    {"tracker.optimizer.step_translation_mm", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.optimizer.step_translation_mm; }}, 1e-3, 100,
     "initial step of the translations", true},
    {"tracker.optimizer.step_rotation_rad", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.optimizer.step_rotation_rad; }}, 1e-5, 1,
     "initial step of the global rotation", true},
    {"tracker.optimizer.step_angle_rad", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.optimizer.step_angle_rad; }}, 1e-5, 1,
     "initial step of the joint angles", true},
    {"tracker.optimizer.grow", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.optimizer.grow; }}, 1, 10,
     "step growth while the derivative's sign holds (adaptive step, Sec. 5)", true},
    {"tracker.optimizer.shrink", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.optimizer.shrink; }}, 0.01, 1,
     "step shrink when the derivative's sign flips", true},
    {"tracker.optimizer.min_step_factor", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.optimizer.min_step_factor; }}, 1e-6, 1,
     "steps stay within [initial * this, initial * max_step_factor]", true},
    {"tracker.optimizer.max_step_factor", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.optimizer.max_step_factor; }}, 1, 1000,
     "steps stay within [initial * min_step_factor, initial * this]", true},
    // [tracker.scale] (Sec. 6)
    {"tracker.scale.length", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.scale.length; }}, 0.5, 2,
     "hand model length scale (Sec. 6)", true},
    {"tracker.scale.width", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.scale.width; }}, 0.5, 2,
     "hand model width scale (Sec. 6)", true},
    {"tracker.scale.sigma", DoubleRef{[](DaemonConfig& c) -> double& { return c.tracker.scale.sigma; }}, 0.5, 2,
     "scale of the model Gaussians' sigma (Sec. 6)", true},
  };
  return table;
}
// clang-format on

const Field* find_field(std::string_view name) {
  for (const auto& f : fields()) {
    if (name == f.name) return &f;
  }
  return nullptr;
}

std::string format_number(double value) {
  std::string text = fmt::format("{}", value);
  if (text.find_first_of(".eEn") == std::string::npos) text += ".0";
  return text;
}

std::string range_text(const Field& f) {
  return std::visit(
      [&](auto ref) -> std::string {
        using T = decltype(ref);
        if constexpr (std::is_same_v<T, DoubleRef>) {
          return fmt::format("allowed range {}..{}", format_number(f.min), format_number(f.max));
        } else if constexpr (std::is_same_v<T, IntRef> || std::is_same_v<T, Int64Ref> ||
                             std::is_same_v<T, Uint64Ref>) {
          return fmt::format("allowed range {}..{}", static_cast<int64_t>(f.min), static_cast<int64_t>(f.max));
        } else if constexpr (std::is_same_v<T, BoolRef>) {
          return "allowed: true or false";
        } else if constexpr (std::is_same_v<T, ChoiceRef>) {
          return std::string("allowed: ") + ref.allowed;
        } else {
          return fmt::format("allowed: a string of {} to {} characters", static_cast<int64_t>(f.min),
                             static_cast<int64_t>(f.max));
        }
      },
      f.ref);
}

[[noreturn]] void throw_config_error(const std::string& origin, const std::string& what) {
  throw ConfigError(origin + ": " + what);
}

// The field's value as it would be written in TOML.
std::string value_text(const Field& f, DaemonConfig& c) {
  return std::visit(
      [&](auto ref) -> std::string {
        using T = decltype(ref);
        if constexpr (std::is_same_v<T, DoubleRef>) {
          return format_number(ref(c));
        } else if constexpr (std::is_same_v<T, BoolRef>) {
          return ref(c) ? "true" : "false";
        } else if constexpr (std::is_same_v<T, StringRef>) {
          return toml_quote(ref(c));
        } else if constexpr (std::is_same_v<T, ChoiceRef>) {
          return fmt::format("\"{}\"", ref.get(c));
        } else {
          return fmt::format("{}", ref(c));
        }
      },
      f.ref);
}

}  // namespace

const char* to_string(LogLevel level) {
  switch (level) {
    case LogLevel::kTrace: return "trace";
    case LogLevel::kDebug: return "debug";
    case LogLevel::kInfo: return "info";
    case LogLevel::kWarn: return "warn";
    case LogLevel::kError: return "error";
    case LogLevel::kOff: return "off";
  }
  return "?";
}

bool parse_log_level(const std::string& text, LogLevel* level) {
  for (auto l : {LogLevel::kTrace, LogLevel::kDebug, LogLevel::kInfo, LogLevel::kWarn, LogLevel::kError,
                 LogLevel::kOff}) {
    if (text == to_string(l)) {
      *level = l;
      return true;
    }
  }
  return false;
}

const char* to_string(Stage stage) {
  switch (stage) {
    case Stage::kGrab: return "grab";
    case Stage::kPreprocess: return "preprocess";
    case Stage::kOptimize: return "optimize";
    case Stage::kPublish: return "publish";
  }
  return "?";
}

namespace {

void apply_node(DaemonConfig& c, const Field& f, const toml::node& node, const std::string& origin) {
  const std::string name = f.name;
  std::visit(
      [&](auto ref) {
        using T = decltype(ref);
        if constexpr (std::is_same_v<T, DoubleRef>) {
          if (auto v = node.value_exact<double>()) {
            ref(c) = *v;
          } else if (auto i = node.value_exact<int64_t>()) {
            ref(c) = static_cast<double>(*i);
          } else {
            throw_config_error(origin, fmt::format("{} must be a number ({})", name, range_text(f)));
          }
        } else if constexpr (std::is_same_v<T, BoolRef>) {
          auto v = node.value_exact<bool>();
          if (!v) throw_config_error(origin, fmt::format("{} must be true or false", name));
          ref(c) = *v;
        } else if constexpr (std::is_same_v<T, StringRef>) {
          auto v = node.value_exact<std::string>();
          if (!v) throw_config_error(origin, fmt::format("{} must be a string", name));
          ref(c) = *v;
        } else if constexpr (std::is_same_v<T, ChoiceRef>) {
          auto v = node.value_exact<std::string>();
          if (!v || !ref.set(c, *v)) {
            throw_config_error(origin, fmt::format("{} = {}: {}", name, v ? toml_quote(*v) : std::string("(not a string)"),
                                                   range_text(f)));
          }
        } else {
          auto v = node.value_exact<int64_t>();
          if (!v) throw_config_error(origin, fmt::format("{} must be an integer ({})", name, range_text(f)));
          if (static_cast<double>(*v) < f.min || static_cast<double>(*v) > f.max) {
            throw_config_error(origin, fmt::format("{} = {} is out of range ({})", name, *v, range_text(f)));
          }
          using V = std::remove_reference_t<decltype(ref(c))>;
          ref(c) = static_cast<V>(*v);
        }
      },
      f.ref);
}

void walk(DaemonConfig& c, const toml::table& table, const std::string& prefix, const std::string& origin) {
  for (const auto& [key, node] : table) {
    const std::string name = prefix.empty() ? std::string(key.str()) : prefix + "." + std::string(key.str());
    if (const auto* sub = node.as_table()) {
      walk(c, *sub, name, origin);
      continue;
    }
    const Field* f = find_field(name);
    if (f == nullptr) {
      throw_config_error(origin, fmt::format("unknown field '{}' (see handtrackd --print-config for the fields)", name));
    }
    apply_node(c, *f, node, origin);
  }
}

DaemonConfig from_table(const toml::table& table, const std::string& origin) {
  DaemonConfig c;
  walk(c, table, "", origin);
  validate(c, origin);
  if (!c.hand_profile.empty()) {
    try {
      c.tracker.scale = load_hand_profile(c.hand_profile);
    } catch (const std::exception& e) {
      throw_config_error(origin, std::string("tracker.hand_profile: ") + e.what());
    }
  }
  return c;
}

}  // namespace

void validate(const DaemonConfig& config, const std::string& origin) {
  DaemonConfig c = config;  // the accessors take a mutable config
  for (const auto& f : fields()) {
    std::visit(
        [&](auto ref) {
          using T = decltype(ref);
          if constexpr (std::is_same_v<T, BoolRef> || std::is_same_v<T, ChoiceRef>) {
            return;
          } else if constexpr (std::is_same_v<T, StringRef>) {
            const auto n = static_cast<double>(ref(c).size());
            if (n < f.min || n > f.max) throw_config_error(origin, fmt::format("{} = {}: {}", f.name, toml_quote(ref(c)), range_text(f)));
          } else {
            const auto v = static_cast<double>(ref(c));
            if (!std::isfinite(v) || v < f.min || v > f.max) {
              throw_config_error(origin, fmt::format("{} = {} is out of range ({})", f.name, value_text(f, c), range_text(f)));
            }
          }
        },
        f.ref);
  }
  if (!camera_roll_from_degrees(c.camera_roll_deg)) {
    throw_config_error(origin, fmt::format("camera.roll = {}: allowed: {}", c.camera_roll_deg, kCameraRollValues));
  }
  if (c.shm_name.find('/') != std::string::npos) {
    throw_config_error(origin, fmt::format("daemon.shm_name = {}: allowed: a name without '/'", toml_quote(c.shm_name)));
  }
  if (c.tracker.input.near_mm >= c.tracker.input.far_mm) {
    throw_config_error(origin, fmt::format("tracker.input.near_mm = {} must be less than tracker.input.far_mm = {}",
                                           format_number(c.tracker.input.near_mm), format_number(c.tracker.input.far_mm)));
  }
  if (c.tracker.input.quadtree_min_leaf_px > c.tracker.input.quadtree_root_px) {
    throw_config_error(origin, fmt::format("tracker.input.quadtree_min_leaf_px = {} must not exceed tracker.input.quadtree_root_px = {}",
                                           c.tracker.input.quadtree_min_leaf_px, c.tracker.input.quadtree_root_px));
  }
}

DaemonConfig parse_config(const std::string& toml_text, const std::string& name) {
  try {
    const toml::table table = toml::parse(toml_text, name);
    auto c = from_table(table, name);
    c.file = name;
    return c;
  } catch (const toml::parse_error& e) {
    const auto& where = e.source().begin;
    throw ConfigError(fmt::format("{}:{}:{}: TOML syntax error: {}", name, where.line, where.column, e.description()));
  }
}

DaemonConfig load_config(const std::filesystem::path& file, bool explicit_file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) {
    if (!explicit_file) return DaemonConfig{};
    throw ConfigError(file.string() + ": no such file");
  }
  if (std::filesystem::is_directory(file, ec)) throw ConfigError(file.string() + ": is a directory, not a TOML file");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ConfigError(file.string() + ": cannot read: " + std::strerror(errno));
  std::stringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError(file.string() + ": cannot read: " + std::strerror(errno));
  return parse_config(text.str(), file.string());
}

std::vector<std::string> changed_but_not_live(const DaemonConfig& a, const DaemonConfig& b) {
  DaemonConfig x = a;
  DaemonConfig y = b;
  std::vector<std::string> out;
  for (const auto& f : fields()) {
    if (!f.live && value_text(f, x) != value_text(f, y)) out.emplace_back(f.name);
  }
  return out;
}

std::string describe_config(const DaemonConfig& config) {
  DaemonConfig c = config;
  std::string out =
      "# handtrackd configuration (TOML). Every field is optional; the values below are the defaults,\n"
      "# the tracker's are the paper's (Sridhar et al., CVPR 2015). Command-line options override them.\n"
      "# Fields marked [live] are re-read on SIGHUP; the others need a restart.\n";
  std::string table;
  for (const auto& f : fields()) {
    const std::string name = f.name;
    const auto dot = name.rfind('.');
    const std::string t = name.substr(0, dot);
    if (t != table) {
      out += fmt::format("\n[{}]\n", t);
      table = t;
    }
    // Strings and the log level explain their values in the help text already.
    const bool own_range = std::holds_alternative<StringRef>(f.ref) || std::holds_alternative<ChoiceRef>(f.ref) ||
                           std::holds_alternative<BoolRef>(f.ref);
    out += fmt::format("# {}{}{}\n{} = {}\n", f.help, own_range ? "" : " (" + range_text(f) + ")",
                       f.live ? " [live]" : "", name.substr(dot + 1), value_text(f, c));
  }
  return out;
}

}  // namespace handtrack::daemon
