#include "handtrack/synth/synthetic_camera.hpp"

#include "raycaster.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <utility>
#include <vector>

namespace handtrack::synth {
namespace {

using Eigen::Vector3d;

// Random streams (Rng::stream purposes), so that changing one use never shifts another.
constexpr uint64_t kSubjectStream = 0x5B1EC7;
constexpr uint64_t kNoiseStream = 0x0015E;
constexpr uint64_t kBodyStream = 0xB0D1;  // Background::kNearBody's build
constexpr uint64_t kProportionStream = 0x960B0;
constexpr double kSubjectSpread = 0.10;  // random subjects: scales within +-10 % (module brief)
// Proportions::kVaried, uniform draws: each finger's length within +-6 %, the fingers' girth and the
// palm's thickness within +-15 % (chosen as plausible spreads between adult hands, not fitted to
// anthropometric data).
constexpr double kFingerLengthSpread = 0.06;
constexpr double kGirthSpread = 0.15;
// Two-hand scenes draw both hands into one z-buffer with hand k's solids labelled
// part_label | (k + 1) << kHandTagShift, so that each pixel says which hand it shows; the tag is
// split off into SynthFrame::hand_index afterwards.
constexpr int kHandTagShift = 4;
static_assert(kNumPartLabels < (1 << kHandTagShift), "the part labels must fit below the hand tag");
static_assert(kTwoHands << kHandTagShift <= 0xFF, "the tagged labels must fit a label byte");

PlanePatch make_patch(const Vector3d& origin, const Vector3d& normal, double half_u, double half_v) {
  PlanePatch p;
  p.origin = origin;
  p.normal = normal.normalized();
  p.axis_u = Vector3d::UnitY().cross(p.normal).normalized();
  p.axis_v = p.normal.cross(p.axis_u).normalized();
  p.half_u = half_u;
  p.half_v = half_v;
  p.label = kBackground;
  return p;
}

// The desk of Background::kDesk, placed in every frame and moved until it touches the farthest
// point of what rests on it, then kDeskContactMm further (a contact area, not a point):
// - palm, back and side views (the forearm across the image): the forearm lies on the desk and the
//   hand rests on it where it reaches down to it; the desk faces the camera as much as that allows
//   (its normal is the viewing direction without its component along the forearm);
// - fingers toward or away from the camera: the desk faces the camera and rises away from it
//   toward the image top (normal (0, -0.3, -1)) and touches the hand; the forearm, which points
//   along the viewing direction, would hold the hand far from it, and goes into it instead;
// - head-mounted: a table under the hand (the table background's normal (0, -1, -0.5)), touched
//   by the hand; the forearm comes from above it, near the camera.
constexpr double kDeskContactMm = 3.0;
// Up from a table top toward a head-mounted camera (Background::kTable and the head-mounted desk).
const Vector3d kTableUp = Vector3d(0.0, -1.0, -0.5).normalized();

PlanePatch desk_under(std::span<const ConeSphere> primitives, View view) {
  const bool forearm_on_desk = view == View::kPalm || view == View::kBack || view == View::kSide;
  // Into the desk.
  Vector3d down = view == View::kHeadMounted ? Vector3d(-kTableUp) : Vector3d(0.0, 0.3, 1.0);
  if (forearm_on_desk) {
    down = Vector3d::UnitZ();
    for (const auto& p : primitives) {
      if (p.label != kBackground) continue;  // the forearm
      const Vector3d along = (p.b - p.a).normalized();
      down -= down.dot(along) * along;
    }
  }
  down.normalize();
  double far = -std::numeric_limits<double>::infinity();
  for (const auto& p : primitives) {
    if (p.label == kBackground && !forearm_on_desk) continue;
    far = std::max({far, down.dot(p.a) + p.radius_a, down.dot(p.b) + p.radius_b});
  }
  return make_patch(down * (far - kDeskContactMm), -down, 0.0, 0.0);
}

constexpr double kMaxHeldRadiusMm = 100.0;  // a held ball's or bottle's
constexpr double kMaxDepthOffsetMm = 250.0;
constexpr double kMaxPalmArchMm = 20.0;  // twice what a cupped hand shows at its knuckles
// The palm's half thickness (its pieces' radii, hand_model.cpp): a held ball rests on its surface.
constexpr double kPalmHalfThicknessMm = 13.5;

// Half the length of a held bottle's axis, between the centres of its round ends.
constexpr double kBottleHalfAxisMm = 65.0;

// The object held against the palm, if any: a ball of radius r, its centre r beyond the palm's
// surface along the palmar normal (+z of the hand frame: toward the camera when the palm faces it),
// opposite the palm centre; or a bottle of radius r there, its axis along the palm's width (x of
// the hand frame).
std::optional<ConeSphere> held_object(const HandShape& shape, const HandPose& pose, const SynthOptions& options) {
  const bool bottle = options.bottle_radius_mm > 0.0;
  const double r = bottle ? options.bottle_radius_mm : options.ball_radius_mm;
  if (!(r > 0.0)) return std::nullopt;
  const Eigen::Matrix3d R = camera_R_hand(pose.rotation);
  const Vector3d c = pose.translation_mm + R * (shape.palm_centre_mm + Vector3d(0.0, 0.0, kPalmHalfThicknessMm + r));
  const Vector3d half_axis = bottle ? Vector3d(R.col(0) * kBottleHalfAxisMm) : Vector3d::Zero();
  return ConeSphere{c - half_axis, c + half_axis, r, r, kBackground};
}

// The one of `values` that `name_of` names `name`.
template <typename E>
std::optional<E> by_name(std::string_view name, std::initializer_list<E> values, std::string_view (*name_of)(E)) {
  for (E e : values) {
    if (name_of(e) == name) return e;
  }
  return std::nullopt;
}

}  // namespace

std::string_view background_name(Background background) {
  switch (background) {
    case Background::kNone:
      return "none";
    case Background::kBody:
      return "body";
    case Background::kTable:
      return "table";
    case Background::kDesk:
      return "desk";
    case Background::kNearBody:
      return "near-body";
  }
  return "none";
}

std::optional<Background> parse_background(std::string_view name) {
  return by_name(name, {Background::kNone, Background::kBody, Background::kTable, Background::kDesk, Background::kNearBody},
                 background_name);
}

Background default_background(std::string_view motion, View view) {
  return seen_in(motion, view) == View::kHeadMounted ? Background::kTable : Background::kBody;
}

std::string_view proportions_name(Proportions proportions) {
  return proportions == Proportions::kVaried ? "varied" : "mean";
}

std::optional<Proportions> parse_proportions(std::string_view name) {
  return by_name(name, {Proportions::kMean, Proportions::kVaried}, proportions_name);
}

std::string_view palm_arch_name(PalmArch arch) { return arch == PalmArch::kBack ? "back" : "bent"; }

std::optional<PalmArch> parse_palm_arch(std::string_view name) {
  return by_name(name, {PalmArch::kBent, PalmArch::kBack}, palm_arch_name);
}

std::string_view arm_name(Arm arm) {
  switch (arm) {
    case Arm::kNone:
      return "none";
    case Arm::kForearm:
      return "forearm";
    case Arm::kShoulder:
      return "shoulder";
  }
  return "forearm";
}

std::optional<Arm> parse_arm(std::string_view name) {
  return by_name(name, {Arm::kNone, Arm::kForearm, Arm::kShoulder}, arm_name);
}

std::string_view handedness_name(Handedness hand) { return hand == Handedness::kLeft ? "left" : "right"; }

std::optional<Handedness> parse_handedness(std::string_view name) {
  return by_name(name, {Handedness::kRight, Handedness::kLeft}, handedness_name);
}

namespace {

// The camera the right hand is rendered with: for a left hand, the principal point mirrored
// (synthetic_camera.hpp, Handedness), so that flipping the image gives the left hand in `camera`.
CameraIntrinsics render_camera(const SynthOptions& options) {
  CameraIntrinsics c = options.camera;
  if (options.hand == Handedness::kLeft) c.cx = static_cast<double>(c.width - 1) - c.cx;
  return c;
}

// The right hand's frame, rendered with render_camera(), into the left hand's: the image rows
// reversed left to right, the joints' x negated.
void mirror(SynthFrame& f) {
  const int w = f.depth.camera.width;
  for (int v = 0; v < f.depth.camera.height; ++v) {
    const auto row = static_cast<std::ptrdiff_t>(v) * w;
    std::reverse(f.depth.depth_mm.begin() + row, f.depth.depth_mm.begin() + row + w);
    std::reverse(f.labels.pixels.begin() + row, f.labels.pixels.begin() + row + w);
  }
  mirror_x(f.joints);
  for (auto& t : f.fingertips) {
    if (t) t->x() = -t->x();
  }
}

}  // namespace

CameraIntrinsics default_camera(int width, int height) {
  CameraIntrinsics c;
  c.width = width;
  c.height = height;
  c.fx = SpecCamera::kFx * width / SpecCamera::kWidth;
  c.fy = SpecCamera::kFy * height / SpecCamera::kHeight;
  c.cx = 0.5 * width;
  c.cy = 0.5 * height;
  c.depth_scale_mm = 1.0;
  c.fps = SpecCamera::kFps;
  return c;
}

CameraIntrinsics camera_with_fov(int width, int height, double horizontal_fov_deg) {
  if (!(horizontal_fov_deg >= 20.0 && horizontal_fov_deg <= 150.0)) {
    throw std::invalid_argument("field of view must be within [20, 150] deg, got " + std::to_string(horizontal_fov_deg));
  }
  CameraIntrinsics c = default_camera(width, height);
  c.fx = 0.5 * width / std::tan(0.5 * horizontal_fov_deg * M_PI / 180.0);
  c.fy = c.fx * (SpecCamera::kFy / SpecCamera::kFx);
  return c;
}

struct SyntheticCamera::State {
  SynthOptions options;
  std::array<HandShape, kTwoHands> shapes;  // [1]: two-hand motions only
  std::optional<Motion> motion;             // a one-hand motion
  std::optional<TwoHandMotion> two_hands;   // or a two-hand scene
  Raycaster raycaster;
  std::vector<ConeSphere> primitives;
  // The static scene, drawn once; each frame starts from a copy of it and draws the hand (a
  // z-buffer does not care about the order).
  Raycaster background;

  // The camera's turn about its optical axis (SynthOptions::roll_deg): camera-frame points turn by it.
  Eigen::Matrix3d roll;

  State(SynthOptions o, const std::array<HandShape, kTwoHands>& s)
      : options(std::move(o)),
        shapes(s),
        raycaster(render_camera(options)),
        background(render_camera(options)),
        roll(Eigen::AngleAxisd(options.roll_deg * M_PI / 180.0, Vector3d::UnitZ()).toRotationMatrix()) {
    // A forearm drawn along a camera-frame direction (views.hpp view_shape) turns with the camera.
    for (HandShape& shape : shapes) {
      if (shape.forearm_camera_direction) shape.forearm_camera_direction = roll * *shape.forearm_camera_direction;
    }
    if (is_two_hand_motion(options.motion)) {
      two_hands.emplace(options.motion, options.frames, options.camera.fps, shapes);
    } else {
      motion.emplace(options.motion, options.frames, options.camera.fps, shapes[0]);
    }
  }

  // The raycaster's scene into out.depth and out.labels: with the noise model, or clean within range.
  void develop(int frame, SynthFrame& out) const;
  void apply_noise(int frame, SynthFrame& out) const;
  void render_two_hands(int frame, SynthFrame& out);
};

SyntheticCamera::SyntheticCamera(SynthOptions options) {
  if (auto why = options.camera.problem(); !why.empty()) throw std::invalid_argument("camera: " + why);
  if (is_two_hand_motion(options.motion) && (options.hand != Handedness::kRight || options.view != View::kPalm)) {
    throw std::invalid_argument("motion '" + options.motion +
                                "' shows a right and a left hand in its own arrangement: no hand or view to choose");
  }
  // What only a scene of one hand has: a two-hand motion places both hands itself.
  const char* one_hand_only = options.background == Background::kDesk ? "the desk background"
                              : options.ball_radius_mm > 0.0          ? "a held ball"
                              : options.bottle_radius_mm > 0.0        ? "a held bottle"
                              : options.depth_offset_mm != 0.0        ? "a depth offset"
                              : options.arm == Arm::kShoulder         ? "the upper arm"
                              : options.arm == Arm::kNone             ? "a hand without its arm"
                              : options.roll_deg != 0.0               ? "a rolled camera"
                                                                      : nullptr;
  if (is_two_hand_motion(options.motion) && one_hand_only != nullptr) {
    throw std::invalid_argument("motion '" + options.motion + "': " + one_hand_only + " is for one-hand motions");
  }
  for (const auto& [object, radius] : {std::pair{"ball", options.ball_radius_mm}, {"bottle", options.bottle_radius_mm}}) {
    if (!(radius >= 0.0 && radius <= kMaxHeldRadiusMm)) {
      throw std::invalid_argument(std::string(object) + " radius must be within [0, 100] mm");
    }
  }
  if (options.ball_radius_mm > 0.0 && options.bottle_radius_mm > 0.0) {
    throw std::invalid_argument("one held object at a time: a ball or a bottle");
  }
  if (!(std::abs(options.depth_offset_mm) <= kMaxDepthOffsetMm)) {
    throw std::invalid_argument("depth offset must be within [-250, 250] mm");
  }
  if (!(std::abs(options.roll_deg) <= 180.0)) throw std::invalid_argument("roll must be within [-180, 180] deg");
  if (options.roll_deg != 0.0 && (options.background == Background::kDesk || options.arm == Arm::kShoulder)) {
    throw std::invalid_argument("a rolled camera is not drawn with the desk or the upper arm (both are placed in the "
                                "camera's frame)");
  }
  std::array<SubjectScale, kTwoHands> subjects;
  if (options.subject) {
    const auto ok = [](double s) { return std::isfinite(s) && s >= 0.5 && s <= 2.0; };
    const SubjectScale& given = *options.subject;
    if (!ok(given.length) || !ok(given.width)) {
      throw std::invalid_argument("subject scale must be within [0.5, 2], got " + std::to_string(given.length) +
                                  "," + std::to_string(given.width));
    }
    if (!std::all_of(given.finger_length.begin(), given.finger_length.end(), ok) || !ok(given.finger_girth) ||
        !ok(given.palm_thickness)) {
      throw std::invalid_argument(
          "subject proportions (finger lengths, girth, palm thickness) must be within [0.5, 2]");
    }
    subjects.fill(*options.subject);
  } else {
    // Hand k from its own stream; hand 0's is the one-hand motions' subject of that seed.
    for (size_t k = 0; k < kTwoHands; ++k) {
      Rng rng = Rng::stream(options.seed, kSubjectStream, k);
      subjects[k].length = rng.uniform(1.0 - kSubjectSpread, 1.0 + kSubjectSpread);
      subjects[k].width = rng.uniform(1.0 - kSubjectSpread, 1.0 + kSubjectSpread);
    }
  }
  if (options.proportions == Proportions::kVaried) {
    for (size_t k = 0; k < kTwoHands; ++k) {
      Rng rng = Rng::stream(options.seed, kProportionStream, k);
      for (double& l : subjects[k].finger_length) l = rng.uniform(1.0 - kFingerLengthSpread, 1.0 + kFingerLengthSpread);
      subjects[k].finger_girth = rng.uniform(1.0 - kGirthSpread, 1.0 + kGirthSpread);
      subjects[k].palm_thickness = rng.uniform(1.0 - kGirthSpread, 1.0 + kGirthSpread);
    }
  }
  if (!(options.palm_arch_mm >= 0.0 && options.palm_arch_mm <= kMaxPalmArchMm)) {
    throw std::invalid_argument("palm arch must be within [0, 20] mm");
  }
  for (auto& subject : subjects) {
    subject.palm_arch_mm = options.palm_arch_mm;
    subject.palm_arch = options.palm_arch;
  }
  options.subject = subjects[0];  // hand 0's, as options() reports it
  // The arrangement holds the forearm (views.hpp view_shape): a two-hand scene's for both hands.
  const View arrangement = seen_in(options.motion, options.view);
  const auto shape_of = [&](const SubjectScale& subject) {
    HandShape shape = view_shape(arrangement, HandShape::for_subject(subject));
    switch (options.arm) {
      case Arm::kNone:
        return without_arm(std::move(shape));
      case Arm::kShoulder:
        return with_upper_arm(arrangement, std::move(shape));
      case Arm::kForearm:
        break;
    }
    return shape;
  };
  const std::array<HandShape, kTwoHands> shapes{shape_of(subjects[0]), shape_of(subjects[1])};
  state_ = std::make_unique<State>(std::move(options), shapes);
  State& s = *state_;
  std::vector<PlanePatch> planes;
  std::vector<ConeSphere> background_solids;
  switch (s.options.background) {
    case Background::kNone:
      break;
    case Background::kBody:
      // Torso: a 440 x 800 mm patch facing the camera, 700-850 mm away (beyond the tracker's
      // 150-600 mm working volume), slightly turned; neck and head above it.
      planes.push_back(make_patch({30, 250, 780}, {0.15, -0.08, -1.0}, 220.0, 400.0));
      background_solids.push_back(ConeSphere{{30, -150, 790}, {30, -200, 800}, 55.0, 55.0, kBackground});
      background_solids.push_back(ConeSphere{{30, -270, 810}, {30, -270, 810}, 95.0, 95.0, kBackground});
      break;
    case Background::kDesk:  // drawn with the hand, in every frame (desk_under)
      break;
    case Background::kNearBody: {
      // The torso as a capsule of radius 220 mm (rounded: no plane for the tracker's desk
      // detection) whose top, seen in the lower half of the image, is about 430-600 mm away; neck
      // and a head (radius 65-85 mm, about 485-560 mm away) above it: inside the tracker's 150-600
      // mm working volume, just behind the hand and touching its forearm; 90 mm farther in the
      // views whose fingers curl toward it (views.hpp near_body_behind_mm). The body's place and
      // the head's size vary with the seed (its own stream: the subject and noise are as with the
      // other backgrounds).
      Rng rng = Rng::stream(s.options.seed, kBodyStream, 0);
      Vector3d at(rng.uniform(-60.0, 60.0), rng.uniform(-30.0, 30.0), rng.uniform(-30.0, 30.0));
      at.z() += near_body_behind_mm(arrangement);
      const double head = rng.uniform(65.0, 85.0);
      background_solids.push_back(
          ConeSphere{at + Vector3d(30, 330, 640), at + Vector3d(30, 900, 640), 220.0, 220.0, kBackground});
      background_solids.push_back(
          ConeSphere{at + Vector3d(30, -100, 590), at + Vector3d(30, 110, 620), 45.0, 45.0, kBackground});
      const Vector3d head_centre = at + Vector3d(30, -95 - head, 560);
      background_solids.push_back(ConeSphere{head_centre, head_centre, head, head, kBackground});
      break;
    }
    case Background::kTable:
      // A table top through (0, 250, 750) mm rising away from the camera (normal up and toward the
      // camera): at the bottom of the image ~610 mm, crossing the image centre at ~1 m.
      planes.push_back(make_patch({0, 250, 750}, kTableUp, 0.0, 0.0));
      break;
  }
  if (s.options.roll_deg != 0.0) {
    const Eigen::Matrix3d& r = s.roll;
    for (auto& p : planes) {
      p.origin = r * p.origin;
      p.normal = r * p.normal;
      p.axis_u = r * p.axis_u;
      p.axis_v = r * p.axis_v;
    }
    for (auto& c : background_solids) {
      c.a = r * c.a;
      c.b = r * c.b;
    }
  }
  s.background.clear();
  for (const auto& p : background_solids) s.background.draw(p);
  for (const auto& p : planes) s.background.draw(p);
}

SyntheticCamera::~SyntheticCamera() = default;
SyntheticCamera::SyntheticCamera(SyntheticCamera&&) noexcept = default;
SyntheticCamera& SyntheticCamera::operator=(SyntheticCamera&&) noexcept = default;

int SyntheticCamera::hand_count() const { return state_->two_hands ? kTwoHands : 1; }
const SynthOptions& SyntheticCamera::options() const { return state_->options; }
const CameraIntrinsics& SyntheticCamera::camera() const { return state_->options.camera; }
const SubjectScale& SyntheticCamera::subject(int hand) const { return shape(hand).subject; }
const HandShape& SyntheticCamera::shape(int hand) const {
  if (hand < 0 || hand >= hand_count()) throw std::out_of_range("no hand " + std::to_string(hand));
  return state_->shapes[static_cast<size_t>(hand)];
}

HandPose SyntheticCamera::pose(int frame, int hand) const {
  const State& s = *state_;
  (void)shape(hand);  // range check
  if (s.two_hands) return s.two_hands->pose(frame)[static_cast<size_t>(hand)];
  HandPose p = view_pose(s.options.view, s.motion->pose(frame), s.shapes[0]);
  if (s.options.depth_offset_mm != 0.0) {
    // Along the palm centre's ray: the hand keeps its place in the image and grows or shrinks.
    const Vector3d palm = p.translation_mm + camera_R_hand(p.rotation) * s.shapes[0].palm_centre_mm;
    p.translation_mm += palm * (s.options.depth_offset_mm / palm.z());
  }
  if (s.options.roll_deg != 0.0) {
    // camera_R_hand = exp(r) R0 turns into roll exp(r) R0; the wrist turns about the lens.
    const Eigen::AngleAxisd exp_r(s.roll * camera_R_hand(p.rotation) * camera_R_hand(Vector3d::Zero()).transpose());
    p.rotation = exp_r.angle() * exp_r.axis();
    p.translation_mm = s.roll * p.translation_mm;
  }
  return p;
}

SynthFrame SyntheticCamera::render(int frame) {
  SynthFrame out;
  render(frame, out);
  return out;
}

void SyntheticCamera::render(int frame, SynthFrame& out) {
  if (state_->two_hands) {
    state_->render_two_hands(frame, out);
  } else {
    render_pose(pose(frame), frame, out);
  }
}

void SyntheticCamera::render_pose(const HandPose& pose, int frame, SynthFrame& out) {
  State& s = *state_;
  if (s.two_hands) throw std::logic_error("render_pose: one-hand motions only, not " + s.options.motion);
  const HandShape& shape = s.shapes[0];
  out.frame = frame;
  out.pose = pose;
  out.joints = camera_frame_joints(shape, out.pose);
  out.fingertips = fingertips_from_joints(out.joints);

  posed_primitives(shape, out.pose, out.joints, s.primitives);
  s.raycaster = s.background;  // same sizes: no allocation
  for (const auto& p : s.primitives) s.raycaster.draw(p);
  if (const auto held = held_object(shape, out.pose, s.options)) s.raycaster.draw(*held);
  if (s.options.background == Background::kDesk) {
    // The hand and the forearm rest on it; the upper arm, posed last, rises from it to the shoulder.
    const size_t resting = s.primitives.size() - (shape.upper_arm_camera_direction ? 1 : 0);
    s.raycaster.draw(desk_under(std::span<const ConeSphere>(s.primitives.data(), resting), s.options.view));
  }
  s.develop(frame, out);
  if (s.options.hand == Handedness::kLeft) mirror(out);
  out.hand_count = 1;
  out.hands[0] = SynthHand{s.options.hand, out.pose, out.joints, out.fingertips};
  out.hand_index.width = out.hand_index.height = 0;
  out.hand_index.pixels.clear();
}

void SyntheticCamera::State::render_two_hands(int frame, SynthFrame& out) {
  const TwoHandPoses poses = two_hands->pose(frame);
  raycaster = background;  // same sizes: no allocation
  for (size_t k = 0; k < kTwoHands; ++k) {
    SynthHand& hand = out.hands[k];
    hand.hand = k == 0 ? Handedness::kRight : Handedness::kLeft;
    hand.pose = poses[k];
    hand.joints = camera_frame_joints(shapes[k], hand.pose);
    posed_primitives(shapes[k], hand.pose, hand.joints, primitives);
    if (hand.hand == Handedness::kLeft) {  // the model's mirror image, in 3D: one z-buffer for both
      mirror_x(hand.joints);
      mirror_x(primitives);
    }
    hand.fingertips = fingertips_from_joints(hand.joints);
    for (auto& p : primitives) {
      p.label |= static_cast<int>(k + 1) << kHandTagShift;
      raycaster.draw(p);
    }
  }
  out.frame = frame;
  out.hand_count = kTwoHands;
  out.pose = out.hands[0].pose;
  out.joints = out.hands[0].joints;
  out.fingertips = out.hands[0].fingertips;
  develop(frame, out);
  // Split the tags off: labels keep the part, hand_index the hand.
  out.hand_index.width = out.labels.width;
  out.hand_index.height = out.labels.height;
  out.hand_index.channels = 1;
  out.hand_index.pixels.resize(out.labels.pixels.size());
  constexpr uint8_t kPartMask = (1 << kHandTagShift) - 1;
  for (size_t i = 0; i < out.labels.pixels.size(); ++i) {
    out.hand_index.pixels[i] = static_cast<uint8_t>(out.labels.pixels[i] >> kHandTagShift);
    out.labels.pixels[i] &= kPartMask;
  }
}

void SyntheticCamera::State::develop(int frame, SynthFrame& out) const {
  const CameraIntrinsics& cam = options.camera;
  const size_t n = static_cast<size_t>(cam.width) * static_cast<size_t>(cam.height);
  out.depth.camera = cam;
  out.depth.depth_mm.resize(n);
  out.labels.width = cam.width;
  out.labels.height = cam.height;
  out.labels.channels = 1;
  out.labels.pixels.resize(n);
  if (options.noise) {
    apply_noise(frame, out);
  } else {
    const auto& clean = raycaster.depth_mm();
    const auto& labels = raycaster.labels();
    const auto lo = static_cast<float>(options.noise_params.min_range_mm);
    const auto hi = static_cast<float>(options.noise_params.max_range_mm);
    for (size_t i = 0; i < n; ++i) {
      const float z = clean[i];
      const bool valid = z >= lo && z <= hi;
      out.depth.depth_mm[i] = valid ? z : 0.0f;
      out.labels.pixels[i] = valid ? labels[i] : uint8_t{0};
    }
  }
}

void SyntheticCamera::State::apply_noise(int frame, SynthFrame& out) const {
  const NoiseParams& np = options.noise_params;
  const int w = options.camera.width;
  const int h = options.camera.height;
  const auto& clean = raycaster.depth_mm();
  const auto& labels = raycaster.labels();
  const auto& incidence = raycaster.incidence_cos();
  Rng rng = Rng::stream(options.seed, kNoiseStream, static_cast<uint64_t>(frame));
  // Item 6 of noise.hpp. The scene is the right hand's world for a left hand (mirrored after
  // develop()), so the projector sits on the other side in it.
  const double projector_x = options.hand == Handedness::kLeft ? -np.projector_x_mm : np.projector_x_mm;
  const std::vector<uint8_t> lit =
      projector_x != 0.0 ? projector_lit(clean, w, h, options.camera.fx, projector_x) : std::vector<uint8_t>{};
  const std::vector<float> smooth_normals =
      np.noise_correlation_px > 0.0 ? rng.correlated_normals(w, h, np.noise_correlation_px) : std::vector<float>{};
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const size_t i = static_cast<size_t>(v) * static_cast<size_t>(w) + static_cast<size_t>(u);
      double z = clean[i];
      out.depth.depth_mm[i] = 0.0f;
      out.labels.pixels[i] = 0;
      if (!std::isfinite(z) || (!lit.empty() && lit[i] == 0)) continue;
      // Flying pixels: the neighbour across the largest depth jump (no surface = +inf depth, an
      // infinite jump).
      double jump = 0.0;
      double neighbour = z;
      const auto consider = [&](size_t k) {
        const double zn = clean[k];
        const double d = std::abs(zn - z);
        if (d > jump) {
          jump = d;
          neighbour = zn;
        }
      };
      if (u > 0) consider(i - 1);
      if (u + 1 < w) consider(i + 1);
      if (v > 0) consider(i - static_cast<size_t>(w));
      if (v + 1 < h) consider(i + static_cast<size_t>(w));
      if (jump > np.edge_threshold_mm && rng.uniform() < np.flying_pixel_probability) {
        if (!std::isfinite(neighbour)) continue;  // dropped
        z += rng.uniform(0.1, 0.9) * (neighbour - z);
      }
      // Dropouts: anywhere, and increasingly at grazing incidence.
      if (rng.uniform() < np.dropout_probability) continue;
      const double grazing = np.grazing_dropout_max * std::clamp(1.0 - incidence[i] / np.grazing_cos, 0.0, 1.0);
      if (grazing > 0.0 && rng.uniform() < grazing) continue;
      // sigma(z) = k z^2, then quantisation.
      z += np.sigma_mm(z) * (smooth_normals.empty() ? rng.fast_normal() : smooth_normals[i]);
      if (np.quantization_mm > 0.0 && z > 0.0) {
        // Round half up (z > 0); a cast instead of std::round keeps this inline in the pixel loop.
        z = static_cast<double>(static_cast<int64_t>(z / np.quantization_mm + 0.5)) * np.quantization_mm;
      }
      if (z < np.min_range_mm || z > np.max_range_mm) continue;
      out.depth.depth_mm[i] = static_cast<float>(z);
      out.labels.pixels[i] = labels[i];
    }
  }
}

RgbImage preview_image(const SynthFrame& frame) {
  static constexpr std::array<std::array<uint8_t, 3>, kNumPartLabels + 1> kPalette = {{
      {0, 0, 0},        // background
      {200, 200, 200},  // palm
      {255, 60, 60},    {200, 0, 0},     {120, 0, 0},    // thumb
      {255, 170, 0},    {170, 100, 0},                   // index
      {240, 240, 0},    {140, 140, 0},                   // middle
      {0, 220, 80},     {0, 120, 40},                    // ring
      {60, 140, 255},   {0, 50, 170},                    // little
  }};
  const int w = frame.depth.width();
  const int h = frame.depth.height();
  RgbImage img;
  img.width = 2 * w;
  img.height = h;
  img.channels = 3;
  img.pixels.assign(static_cast<size_t>(img.width) * static_cast<size_t>(h) * 3, 0);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const float z = frame.depth.at(u, v);
      const size_t left = (static_cast<size_t>(v) * static_cast<size_t>(img.width) + static_cast<size_t>(u)) * 3;
      const size_t right = left + static_cast<size_t>(w) * 3;
      // Near (250 mm) bright, far (1000 mm) dark; no measurement black.
      const auto g = z > 0 ? static_cast<uint8_t>(std::clamp(255.0 - (z - 250.0) * (215.0 / 750.0), 40.0, 255.0))
                           : uint8_t{0};
      img.pixels[left] = img.pixels[left + 1] = img.pixels[left + 2] = g;
      const int label = frame.labels.pixels[static_cast<size_t>(v) * static_cast<size_t>(w) + static_cast<size_t>(u)];
      const auto& c = kPalette[static_cast<size_t>(std::clamp(label, 0, kNumPartLabels))];
      if (label == 0 && z > 0) {
        img.pixels[right] = img.pixels[right + 1] = img.pixels[right + 2] = static_cast<uint8_t>(g / 3);
      } else {
        img.pixels[right] = c[0];
        img.pixels[right + 1] = c[1];
        img.pixels[right + 2] = c[2];
      }
    }
  }
  return img;
}

SynthOptions live_camera_options(const std::string& motion, int frames, uint64_t seed, int fps) {
  SynthOptions o;
  o.motion = motion;
  o.frames = frames;
  o.seed = seed;
  o.noise = true;
  o.background = default_background(motion, o.view);
  o.camera = default_camera();
  o.camera.fps = fps;
  return o;
}

}  // namespace handtrack::synth
