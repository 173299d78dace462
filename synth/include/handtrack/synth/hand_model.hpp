#pragma once
// The synthetic hand: a kinematic skeleton (the same definition the tracker's skeleton follows) and a
// geometry of cone-spheres (capsules with possibly different end radii) that is deliberately NOT the
// tracker's Gaussian mixture, so that tracking synthetic frames measures more than self-consistency.
//
// Frames (mm):
//   hand frame   origin = wrist joint centre; x_h radial (thumb side), y_h distal (toward the
//                fingers), z_h = x_h x y_h = out of the palm (palmar normal).
//   camera frame x right, y down, z forward.
//   camera_p = t + R hand_p,  R = exp(r) R0,  R0 = diag(1,-1,-1): r = 0 means palm facing the camera,
//   fingers pointing up in the image (-y camera), thumb toward +x camera.
//
// Finger chain f (thumb..little): base b_f, rest direction d_f, palmar normal n_f, flexion axis
// a_f = d_f x n_f, bone lengths L1..L3, angles [abd, flex1, flex2, flex3]:
//   R_1 = Rot(n_f, abd) Rot(a_f, flex1);  j_1 = b_f + L1 R_1 d_f   (PIP; thumb MCP)
//   R_2 = R_1 Rot(a_f, flex2);            j_2 = j_1 + L2 R_2 d_f   (DIP; thumb IP)
//   R_3 = R_2 Rot(a_f, flex3);            j_3 = j_2 + L3 R_3 d_f   (TIP = centre of the tip sphere)
// Rot(a, phi) d = d cos(phi) + (a x d) sin(phi) and a_f x d_f = n_f, so positive flexion moves the
// finger toward n_f, i.e. toward the palm.

#include "handtrack/core/hand_layout.hpp"
#include "handtrack/core/sequence.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>  // cross()

#include <array>
#include <optional>
#include <vector>

namespace handtrack::synth {

// Per finger [abd, flex1, flex2, flex3] in radians (thumb: abd, CMC, MCP, IP).
using FingerAngles = std::array<double, 4>;

// The 26 pose parameters of Sec. 3.2 in the order used by poses.csv:
// t (3, mm), r (3, axis-angle, rad), then thumb..little [abd, flex1, flex2, flex3].
struct HandPose {
  Eigen::Vector3d translation_mm = Eigen::Vector3d::Zero();  // t: the wrist joint in the camera frame
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();        // r: R = exp(r) R0
  std::array<FingerAngles, kNumFingers> fingers{};

  [[nodiscard]] Eigen::Matrix<double, kNumPoseParams, 1> to_params() const;
  static HandPose from_params(const Eigen::Matrix<double, kNumPoseParams, 1>& params);
};

// R = exp(r) R0 with R0 = diag(1,-1,-1).
Eigen::Matrix3d camera_R_hand(const Eigen::Vector3d& rotation);

// Anatomical joint limits (radians) that every motion respects.
struct JointLimits {
  std::array<FingerAngles, kNumFingers> lower{};
  std::array<FingerAngles, kNumFingers> upper{};

  // thumb abd [-0.6,0.6], CMC [-0.4,0.9], MCP [-0.2,1.0], IP [-0.3,1.3];
  // fingers abd [-0.35,0.35], MCP [-0.3,1.6], PIP [0,1.9], DIP [0,1.3].
  static JointLimits defaults();
  [[nodiscard]] HandPose clamp(HandPose pose) const;
  [[nodiscard]] bool contains(const HandPose& pose, double tolerance = 1e-9) const;
};

// A subject's size relative to the mean adult hand: `length` scales bone lengths and the hand
// frame's y coordinates, `width` scales x coordinates and all radii. Finger bases keep their z (as
// in the tracker's HandModel::default_adult); the palm and forearm solids scale z by `width`.
// Proportions on top of the size (ours; the tracker's model scales by length, width and sigma only,
// Sec. 6): each finger's bones by `finger_length[f]` (thumb..little), the fingers' radii by
// `finger_girth` and the palm's solids' radii (its thickness) by `palm_thickness`. All 1: the mean
// adult's proportions, which every subject had before (SynthOptions::proportions).
// `palm_arch_mm`: the transverse metacarpal arch, its sides toward the palm's side of the hand;
// 0 (the default) is the flat palm every render had before (SynthOptions::palm_arch_mm).
// `palm_arch`: what bends, the whole palm (kBent: both faces and the fingers' bases) or its back
// alone (kBack: the front stays flat, the palm thinner toward its sides, as a real palm's soft
// front fills the hollow its bones make).
enum class PalmArch { kBent, kBack };
struct SubjectScale {
  double length = 1.0;
  double width = 1.0;
  std::array<double, kNumFingers> finger_length{1.0, 1.0, 1.0, 1.0, 1.0};
  double finger_girth = 1.0;
  double palm_thickness = 1.0;
  double palm_arch_mm = 0.0;
  PalmArch palm_arch = PalmArch::kBent;
};

struct FingerShape {
  Eigen::Vector3d base_mm = Eigen::Vector3d::Zero();  // b_f, hand frame
  Eigen::Vector3d direction = Eigen::Vector3d::UnitY();  // d_f, unit
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();     // n_f, unit, orthogonal to d_f
  std::array<double, 3> bone_length_mm{};
  // Skin radius at the base joint, the ends of bones 1 and 2, and the tip (each bone is a
  // cone-sphere from one radius to the next).
  std::array<double, 4> radius_mm{};

  [[nodiscard]] Eigen::Vector3d flexion_axis() const { return direction.cross(normal); }
};

// A cone-sphere: the convex hull of the spheres (a, radius_a) and (b, radius_b); a == b is a sphere.
struct ConeSphere {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  double radius_a = 0.0;
  double radius_b = 0.0;
  int label = kBackground;  // hand_layout.hpp part label; 0 for the forearm
};

struct HandShape {
  SubjectScale subject;
  std::array<FingerShape, kNumFingers> fingers{};
  std::vector<ConeSphere> palm;  // rigid in the hand frame, label kPalm (includes the wrist region)
  ConeSphere forearm;            // rigid in the hand frame, label 0
  bool forearm_shown = true;     // false: the hand alone, cut at the wrist (views.hpp, without_arm)
  // When set, the forearm leaves its start (forearm.a, still rigid in the hand frame) along this
  // unit direction of the camera frame, whatever the hand's rotation: the wrist bends, and the
  // elbow stays where the arrangement puts it (the head-mounted view: views.hpp, view_shape).
  std::optional<Eigen::Vector3d> forearm_camera_direction;
  // When set, an upper arm (label 0) runs from the forearm's far end, the elbow, this far along
  // this direction of the camera frame to the shoulder: a real arm does not end at the elbow
  // (views.hpp, with_upper_arm).
  std::optional<Eigen::Vector3d> upper_arm_camera_direction;
  double upper_arm_mm = 0.0;
  Eigen::Vector3d palm_centre_mm = Eigen::Vector3d::Zero();  // hand frame; motions orbit around it

  // The mean adult right hand (scale 1.0) of the module brief.
  static HandShape mean_adult();
  // mean_adult() scaled: lengths and y by subject.length, x, z and radii by subject.width, then
  // each finger's bones, the fingers' radii and the palm's radii by the subject's proportions,
  // then the palm arched by subject.palm_arch_mm (palm_arch_offset_mm).
  static HandShape for_subject(const SubjectScale& subject);
};

// The transverse arch of the palm at hand-frame x (mm, the hand already scaled): how far toward the
// palm's side (+z) the palm's back (and with PalmArch::kBent its front and the fingers' bases)
// there is moved, arch (x / x_a)^2 with
// x_a = 27 mm x width, the mean metacarpal head's distance from the middle finger's. The index and
// little fingers' knuckles (x = 24 and -30 mm) sit 0.8 and 1.2 x arch toward the palm, the middle
// finger's (x = 4) 0.02 x arch: the ends of a hand's transverse arch, which real palms have and
// the flat default does not.
double palm_arch_offset_mm(double x_mm, const SubjectScale& subject);

// The 21 joints (SPEC.md order: wrist, then thumb..little MCP/CMC, PIP, DIP, TIP) in the hand frame.
Joints hand_frame_joints(const HandShape& shape, const HandPose& pose);
// The 21 joints in the camera frame (mm).
Joints camera_frame_joints(const HandShape& shape, const HandPose& pose);
// Fingertips (thumb..little; the TIP joints, i.e. the tip-sphere centres) in the camera frame.
Fingertips fingertips_from_joints(const Joints& joints);

// All primitives of the posed hand in the camera frame: 15 phalanges (labels from part_label()),
// the palm, the forearm and, where the shape has one, the upper arm. `out` is cleared and refilled
// (no allocation once it has grown).
void posed_primitives(const HandShape& shape, const HandPose& pose, const Joints& camera_joints,
                      std::vector<ConeSphere>& out);

// The global part of a pose: turned by `turn` = exp(r) (so camera_R_hand = turn R0) and placed so
// that the palm centre is at `palm_centre_mm` (camera frame): r = log(turn), t = c - R palm_centre.
// The fingers are left as they are.
void place_palm(HandPose& pose, const HandShape& shape, const Eigen::Matrix3d& turn,
                const Eigen::Vector3d& palm_centre_mm);

// The mirror image about the camera's x = 0 plane, x -> -x: how the right-hand model shows a left
// hand (synthetic_camera.hpp, Handedness). A mirrored cone-sphere is a cone-sphere.
void mirror_x(Joints& joints);
void mirror_x(std::vector<ConeSphere>& solids);

// Distance (mm) between the surfaces of two cone-spheres, negative where they overlap. A
// cone-sphere is the union of the balls B(a + s (b - a), r_a + s (r_b - r_a)), s in [0, 1] (the
// convex hull of its end spheres), so the gap is
//   min_{s,t in [0,1]} |p(s) - q(t)| - r(s) - r'(t),
// a convex function of (s, t) (a norm of an affine map minus affine terms), minimised here by
// nested golden-section searches to ~1e-3 mm. Where they overlap the value is minus the deepest
// overlap of two of those balls.
double surface_gap_mm(const ConeSphere& a, const ConeSphere& b);
// The smallest gap between any solid of `a` and any of `b` (e.g. two hands, to check that they
// touch but never pass through each other).
double surface_gap_mm(const std::vector<ConeSphere>& a, const std::vector<ConeSphere>& b);

}  // namespace handtrack::synth
