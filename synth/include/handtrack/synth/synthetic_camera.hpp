#pragma once
// SyntheticCamera: renders depth frames with ground truth of a capsule hand performing one of the
// Dexter 1 motions, or of two hands in one of the two-hand scenes (two_hand_motions.hpp), with an
// optional sensor noise model and background. Used by handtrack-synth (sequence directories) and by
// the daemon's `synthetic[:MOTION]` live source.
//
//   SyntheticCamera cam(SynthOptions{.motion = "pinch", .frames = 300});
//   SynthFrame f;
//   for (int i = 0; i < 300; ++i) cam.render(i, f);  // f.depth, f.labels, f.joints, f.fingertips
//
// Frames are a pure function of (options, frame index): random access, deterministic.
// Thread roles: reentrant (render() reuses internal buffers): one SyntheticCamera per thread.

#include "handtrack/core/camera.hpp"
#include "handtrack/core/png_io.hpp"
#include "handtrack/core/sequence.hpp"
#include "handtrack/synth/hand_model.hpp"
#include "handtrack/synth/motions.hpp"
#include "handtrack/synth/noise.hpp"
#include "handtrack/synth/two_hand_motions.hpp"
#include "handtrack/synth/views.hpp"

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

namespace handtrack::synth {

enum class Background {
  kNone,   // only the hand and forearm
  kBody,   // a torso plane 700-850 mm away (and a head), the forearm reaching toward it
  kTable,  // a plane tilted like a table top, below and behind the hand (>= ~600 mm in view)
  kDesk,   // a desk the forearm lies on and the hand rests on, in every frame (one-hand motions only)
  kNearBody,  // a user close to the camera: a rounded torso (about 430-600 mm), neck and head
              // (about 485-560 mm; its size and the body's place vary with the seed) inside the
              // working volume behind the hand
};
std::string_view background_name(Background background);
std::optional<Background> parse_background(std::string_view name);
// The background `motion` seen in `view` is rendered over unless told otherwise: a head-mounted
// camera looks down at a table (a two-hand motion: in its own arrangement, seen_in), any other
// arrangement at the user's body behind the hand.
Background default_background(std::string_view motion, View view);

// Which hand is shown. The hand model is a right hand; a left hand is its mirror image about the
// camera's x = 0 plane, which a pinhole camera sees exactly as the right hand's image flipped left
// to right when the right hand is rendered with the principal point at u = (width - 1) - cx:
// (u_left - cx) = -(u_right - cx_right). So the left hand's depth, labels and joints are exact,
// not an approximation, and share the subject, motion and noise of the right hand of that seed.
enum class Handedness { kRight, kLeft };
std::string_view handedness_name(Handedness hand);  // "right", "left"
std::optional<Handedness> parse_handedness(std::string_view name);

// Each hand's proportions beyond its size (SubjectScale): kMean, the mean adult's, which every
// subject had before 2026-11-30; kVaried, drawn from the seed for each hand, whatever its size
// (every finger's length +-6 % on its own, the fingers' girth and the palm's thickness +-15 %): the
// hands of people, and of other renderers, differ in more than their length and width.
enum class Proportions { kMean, kVaried };
std::string_view proportions_name(Proportions proportions);  // "mean", "varied"
std::optional<Proportions> parse_proportions(std::string_view name);

// What --palm-arch bends (SubjectScale::palm_arch).
std::string_view palm_arch_name(PalmArch arch);  // "bent", "back"
std::optional<PalmArch> parse_palm_arch(std::string_view name);

// How much of the arm the scene shows: the hand alone, cut at the wrist, as renderers of a hand
// model without an arm show it; the forearm to a rounded elbow (the
// default); or the arm on past the elbow to the shoulder (views.hpp, with_upper_arm).
enum class Arm { kNone, kForearm, kShoulder };
std::string_view arm_name(Arm arm);  // "none", "forearm", "shoulder"
std::optional<Arm> parse_arm(std::string_view name);

// The SPEC.md camera (fx 224.502, fy 230.494 at 320x240, principal point at the image centre,
// 60 fps, 1 mm depth units) with the focal lengths scaled to width x height.
CameraIntrinsics default_camera(int width = 320, int height = 240);

// The SPEC.md camera with another horizontal field of view (the SPEC.md camera's: 70.9 deg; a
// Kinect's about 58, a RealSense D435's 87): fx = (width / 2) / tan(fov / 2), fy in the SPEC.md
// camera's proportion to fx. Throws std::invalid_argument outside [20, 150] deg.
CameraIntrinsics camera_with_fov(int width, int height, double horizontal_fov_deg);

struct SynthOptions {
  // One of kMotionNames, or of kTwoHandMotionNames: a right and a left hand (then `hand` must stay
  // kRight and `view` kPalm: the scene places both hands itself).
  std::string motion = "flexex1";
  int frames = 300;                     // sequence length: slow first half, fast second half
  uint64_t seed = 1;                    // subject (when not given), noise
  // nullopt: length and width scale drawn from the seed in [0.9, 1.1], for each hand of a two-hand
  // motion its own; given: every hand's.
  std::optional<SubjectScale> subject;
  // kVaried: each hand's proportions drawn from the seed, replacing the subject's.
  Proportions proportions = Proportions::kMean;
  // > 0: every hand's palm arched, its sides this far (mm, at most 20) toward the palm's side at
  // the mean metacarpal head's distance from the middle (SubjectScale::palm_arch_mm); 0: flat.
  double palm_arch_mm = 0.0;
  // What the arch bends: the whole palm (the default) or its back alone (SubjectScale::palm_arch).
  PalmArch palm_arch = PalmArch::kBent;
  bool noise = true;
  Background background = Background::kBody;
  CameraIntrinsics camera = default_camera();
  NoiseParams noise_params;
  Handedness hand = Handedness::kRight;
  View view = View::kPalm;  // the camera arrangement (views.hpp): the motion turned and placed
  // > 0: a ball of this radius (mm, at most 100) held against the palm, moving with it (one-hand
  // motions); not the hand (label 0). The grasping motions close the fingers around it.
  double ball_radius_mm = 0.0;
  // > 0: a bottle of this radius (mm, at most 100; a capsule, its axis 130 mm long between the
  // centres of its round ends) held against the palm across its width, moving with it (one-hand
  // motions; not with a ball); not the hand (label 0). An object the forest never saw in training:
  // it learned only balls (docs/TRACKER.md, "A held object").
  double bottle_radius_mm = 0.0;
  // The hand moved this far along the ray through its palm centre in every frame: < 0 nearer the
  // camera, > 0 farther (mm, within [-250, 250]; one-hand motions). The motion's own movement
  // and the scene behind the hand stay as they are.
  double depth_offset_mm = 0.0;
  // How much of the arm is drawn (one-hand motions, but for the default). The forearm ends in a
  // rounded elbow, which a wide lens shows (docs/TRACKER.md, "Other cameras").
  Arm arm = Arm::kForearm;
  // The camera turned about its optical axis by this many degrees (within [-180, 180]; one-hand
  // motions, not with the desk or the upper arm): the hand, its forearm and the scene behind turn
  // together in the image, so the forearm enters from another edge (90: from the image's left for
  // the desk views).
  double roll_deg = 0.0;
};

// The virtual camera as handtrackd's `synthetic[:MOTION]` source shows it: `frames` per pass of
// `motion`, subject and noise from `seed`, noise on, over its default background (a body behind the
// hand; two_reach's table), default_camera() at `fps`. Tests render the daemon's frames (and their
// ground truth) with the same options.
SynthOptions live_camera_options(const std::string& motion, int frames, uint64_t seed, int fps);

// The ground truth of one hand in a frame.
struct SynthHand {
  Handedness hand = Handedness::kRight;
  HandPose pose;          // the right-hand model's pose (a left hand shows its mirror image)
  Joints joints;          // 21 joints, mm, camera frame (TIP = tip-sphere centre)
  Fingertips fingertips;  // the 5 TIP joints, all present
};

struct SynthFrame {
  int frame = 0;
  // pose, joints and fingertips: hand 0's (the only hand of a one-hand motion).
  HandPose pose;         // the right-hand model's pose (a left hand shows its mirror image)
  DepthImage depth;      // mm, 0 = no measurement (noisy when options.noise)
  Gray8Image labels;     // part labels of hand_layout.hpp (every hand's 1..12); 0 = background, forearm, or no depth
  Joints joints;         // 21 joints, mm, camera frame (TIP = tip-sphere centre)
  Fingertips fingertips;  // the 5 TIP joints, all present
  // Every hand: hands[0 .. hand_count). A two-hand motion: hands[0] right, hands[1] left.
  int hand_count = 1;
  std::array<SynthHand, kTwoHands> hands{};
  // Two-hand motions: which hand each pixel shows, 0 = none (background, no depth), k + 1 =
  // hands[k] (its forearm too). Empty (0 x 0) for one-hand motions.
  Gray8Image hand_index;
};

class SyntheticCamera {
 public:
  // Throws std::invalid_argument for an unknown motion, frames < 1, unusable intrinsics or a subject
  // scale outside [0.5, 2].
  explicit SyntheticCamera(SynthOptions options);
  ~SyntheticCamera();
  SyntheticCamera(SyntheticCamera&&) noexcept;
  SyntheticCamera& operator=(SyntheticCamera&&) noexcept;
  SyntheticCamera(const SyntheticCamera&) = delete;
  SyntheticCamera& operator=(const SyntheticCamera&) = delete;

  // Renders frame i (any i >= 0; past options.frames the motion plays back and forth) into `out`,
  // reusing its buffers: no allocation once `out` has the right size.
  void render(int frame, SynthFrame& out);
  [[nodiscard]] SynthFrame render(int frame);
  // Renders an arbitrary pose (e.g. a random one within JointLimits, for training the part forest)
  // with this camera's subject, background and noise; `frame` only seeds the noise. out.frame =
  // frame, out.pose = pose. One-hand motions only (std::logic_error otherwise).
  void render_pose(const HandPose& pose, int frame, SynthFrame& out);

  // The pose of hand `hand` in frame i (the motion's, seen in options.view; the right-hand model's
  // for a left hand too): no image, cheap.
  [[nodiscard]] HandPose pose(int frame, int hand = 0) const;

  // 1, or 2 for a two-hand motion.
  [[nodiscard]] int hand_count() const;
  [[nodiscard]] const SynthOptions& options() const;  // options().subject: hand 0's
  [[nodiscard]] const CameraIntrinsics& camera() const;
  [[nodiscard]] const SubjectScale& subject(int hand = 0) const;
  [[nodiscard]] const HandShape& shape(int hand = 0) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// Debug picture of a frame: depth as gray (near = bright; 0 = black) beside the part labels in
// colour, width 2 x image width.
RgbImage preview_image(const SynthFrame& frame);

}  // namespace handtrack::synth
