#include "handtrack/synth/hand_model.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <vector>

namespace handtrack::synth {
namespace {

using Eigen::Vector3d;

// Orthonormalises v against d: the component of v orthogonal to d, normalised.
Vector3d orthogonal_unit(const Vector3d& v, const Vector3d& d) { return (v - v.dot(d) * d).normalized(); }

FingerShape finger(const Vector3d& base, const Vector3d& direction, const Vector3d& normal,
                   std::array<double, 3> lengths, std::array<double, 4> radii) {
  FingerShape f;
  f.base_mm = base;
  f.direction = direction.normalized();
  f.normal = orthogonal_unit(normal, f.direction);
  f.bone_length_mm = lengths;
  f.radius_mm = radii;
  return f;
}

ConeSphere palm_piece(const Vector3d& a, const Vector3d& b, double ra, double rb) {
  return ConeSphere{a, b, ra, rb, kPalm};
}

// The palm's solids under the transverse arch (palm_arch_offset_mm). A piece across the palm (more
// x than y between its ends: the knuckle row, the cross pieces, the wrist) is a straight capsule
// that would cut the chord of the arch, so it is split into kArchSegments pieces whose ends follow
// it (radii linear along it); a piece along the palm (a metacarpal) has its two ends moved. With
// the whole palm bent (PalmArch::kBent) each end moves by the arch's offset o toward the palm's
// side; with the back alone (PalmArch::kBack) its centre moves o / 2 and its radius shrinks by
// o / 2, so the palm's front (centre + radius) stays where it was and its back moves by o.
std::vector<ConeSphere> arched_palm(const std::vector<ConeSphere>& palm, const SubjectScale& subject) {
  constexpr int kArchSegments = 4;
  const double share = subject.palm_arch == PalmArch::kBack ? 0.5 : 1.0;
  struct End {
    Vector3d centre;
    double radius;
  };
  const auto arched = [&](Vector3d p, double radius) {
    const double o = palm_arch_offset_mm(p.x(), subject);
    p.z() += share * o;
    return End{p, radius - (1.0 - share) * o};
  };
  std::vector<ConeSphere> out;
  for (const ConeSphere& c : palm) {
    const Vector3d d = c.b - c.a;
    const int segments = std::abs(d.x()) > std::abs(d.y()) ? kArchSegments : 1;
    for (int k = 0; k < segments; ++k) {
      const double t0 = static_cast<double>(k) / segments;
      const double t1 = static_cast<double>(k + 1) / segments;
      const End a = arched(c.a + t0 * d, c.radius_a + t0 * (c.radius_b - c.radius_a));
      const End b = arched(c.a + t1 * d, c.radius_a + t1 * (c.radius_b - c.radius_a));
      out.push_back(ConeSphere{a.centre, b.centre, a.radius, b.radius, c.label});
    }
  }
  return out;
}

}  // namespace

Eigen::Matrix<double, kNumPoseParams, 1> HandPose::to_params() const {
  Eigen::Matrix<double, kNumPoseParams, 1> p;
  p.segment<3>(0) = translation_mm;
  p.segment<3>(3) = rotation;
  for (int f = 0; f < kNumFingers; ++f) {
    for (int k = 0; k < 4; ++k) p(6 + 4 * f + k) = fingers[static_cast<size_t>(f)][static_cast<size_t>(k)];
  }
  return p;
}

HandPose HandPose::from_params(const Eigen::Matrix<double, kNumPoseParams, 1>& params) {
  HandPose pose;
  pose.translation_mm = params.segment<3>(0);
  pose.rotation = params.segment<3>(3);
  for (int f = 0; f < kNumFingers; ++f) {
    for (int k = 0; k < 4; ++k) pose.fingers[static_cast<size_t>(f)][static_cast<size_t>(k)] = params(6 + 4 * f + k);
  }
  return pose;
}

Eigen::Matrix3d camera_R_hand(const Eigen::Vector3d& rotation) {
  const Eigen::Matrix3d R0 = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
  const double angle = rotation.norm();
  if (angle < 1e-12) return R0;
  return Eigen::AngleAxisd(angle, rotation / angle).toRotationMatrix() * R0;
}

JointLimits JointLimits::defaults() {
  JointLimits limits;
  limits.lower[kThumb] = {-0.6, -0.4, -0.2, -0.3};
  limits.upper[kThumb] = {0.6, 0.9, 1.0, 1.3};
  for (int f = kIndex; f <= kLittle; ++f) {
    limits.lower[static_cast<size_t>(f)] = {-0.35, -0.3, 0.0, 0.0};
    limits.upper[static_cast<size_t>(f)] = {0.35, 1.6, 1.9, 1.3};
  }
  return limits;
}

HandPose JointLimits::clamp(HandPose pose) const {
  for (size_t f = 0; f < kNumFingers; ++f) {
    for (size_t k = 0; k < 4; ++k) pose.fingers[f][k] = std::clamp(pose.fingers[f][k], lower[f][k], upper[f][k]);
  }
  return pose;
}

bool JointLimits::contains(const HandPose& pose, double tolerance) const {
  for (size_t f = 0; f < kNumFingers; ++f) {
    for (size_t k = 0; k < 4; ++k) {
      const double v = pose.fingers[f][k];
      if (!(v >= lower[f][k] - tolerance && v <= upper[f][k] + tolerance)) return false;
    }
  }
  return true;
}

HandShape HandShape::mean_adult() {
  HandShape s;
  // Bases, rest directions, palmar normals, bone lengths and radii: the module brief's mean adult
  // right hand (about 85 mm wide at the knuckles, middle finger 92 mm, hand length ~190 mm).
  s.fingers[kThumb] = finger({20, 22, 8}, {0.70, 0.62, 0.35}, {-0.55, 0, 0.83}, {42, 32, 22}, {12, 10.5, 9.5, 8.5});
  s.fingers[kIndex] = finger({24, 90, 0}, {0.12, 1, 0}, {0, 0, 1}, {42, 25, 17}, {9, 8.5, 8, 7.5});
  s.fingers[kMiddle] = finger({4, 94, 0}, {0, 1, 0}, {0, 0, 1}, {46, 28, 18}, {9.2, 8.7, 8.2, 7.6});
  s.fingers[kRing] = finger({-14, 90, 0}, {-0.08, 1, 0}, {0, 0, 1}, {43, 27, 17}, {8.8, 8.3, 7.8, 7.2});
  s.fingers[kLittle] = finger({-30, 80, 0}, {-0.2, 1, 0}, {0, 0, 1}, {33, 20, 16}, {8, 7.5, 7, 6.5});

  // Palm slab (~85 mm wide at the knuckles, ~95 mm from the wrist crease to the knuckles, 26-30 mm
  // thick) from overlapping capsules: one per metacarpal, a knuckle row, two cross pieces that fill
  // the ridges between metacarpals, the thenar eminence over the thumb's metacarpal base and the
  // wrist. Radii 13-14 mm give the 26-28 mm thickness.
  s.palm = {
      palm_piece({15, 10, 0}, {23, 86, 0}, 13.0, 13.5),      // index metacarpal
      palm_piece({2, 8, 0}, {4, 90, 0}, 13.5, 13.5),         // middle metacarpal
      palm_piece({-10, 8, 0}, {-14, 86, 0}, 13.0, 13.0),     // ring metacarpal
      palm_piece({-19, 12, 0}, {-29, 76, 0}, 12.5, 12.0),    // little metacarpal
      palm_piece({-31, 77, 0}, {26, 87, 0}, 13.0, 14.0),     // knuckle row
      palm_piece({-25, 50, 0}, {24, 55, 0}, 13.5, 13.5),     // mid palm
      palm_piece({-20, 25, 0}, {20, 27, 0}, 13.5, 13.5),     // lower palm
      palm_piece({8, 12, 2}, {24, 36, 6}, 14.0, 13.0),       // thenar eminence (thumb metacarpal base)
      palm_piece({-16, 2, -2}, {15, 2, -2}, 16.0, 16.0),     // wrist
  };
  s.palm_centre_mm = Vector3d(0, 50, 0);
  // Forearm: a tapered capsule from just below the wrist (radius ~28) along -y_h, tilted toward
  // -z_h (away from the camera when the palm faces it), ~250 mm long, radius ~33 at the far end.
  const Vector3d forearm_dir = Vector3d(0, -1, -0.55).normalized();
  const Vector3d forearm_start(0, -24, -4);
  s.forearm = ConeSphere{forearm_start, forearm_start + 250.0 * forearm_dir, 26.0, 33.0, kBackground};
  return s;
}

HandShape HandShape::for_subject(const SubjectScale& subject) {
  HandShape s = mean_adult();
  s.subject = subject;
  const Vector3d scale(subject.width, subject.length, subject.width);
  const auto scale_point = [&](const Vector3d& p) -> Vector3d { return p.cwiseProduct(scale); };
  for (size_t k = 0; k < s.fingers.size(); ++k) {
    // Joint positions scale as in the tracker's model: base x by width, y by length, z unscaled
    // (only the thumb's base has z != 0). The solid palm below also thickens with width.
    FingerShape& f = s.fingers[k];
    f.base_mm.x() *= subject.width;
    f.base_mm.y() *= subject.length;
    for (auto& l : f.bone_length_mm) l *= subject.length * subject.finger_length[k];
    for (auto& r : f.radius_mm) r *= subject.width * subject.finger_girth;
  }
  for (auto* c : {&s.forearm}) {
    c->a = scale_point(c->a);
    c->b = scale_point(c->b);
    c->radius_a *= subject.width;
    c->radius_b *= subject.width;
  }
  for (auto& c : s.palm) {
    c.a = scale_point(c.a);
    c.b = scale_point(c.b);
    c.radius_a *= subject.width * subject.palm_thickness;
    c.radius_b *= subject.width * subject.palm_thickness;
  }
  s.palm_centre_mm = scale_point(s.palm_centre_mm);
  if (subject.palm_arch_mm != 0.0) {  // else the flat palm, byte for byte as before the arch
    s.palm = arched_palm(s.palm, subject);
    if (subject.palm_arch == PalmArch::kBent) {  // the knuckles ride on the bent palm
      for (auto& f : s.fingers) f.base_mm.z() += palm_arch_offset_mm(f.base_mm.x(), subject);
    }
  }
  return s;
}

double palm_arch_offset_mm(double x_mm, const SubjectScale& subject) {
  constexpr double kArchHalfWidthMm = 27.0;
  const double u = x_mm / (kArchHalfWidthMm * subject.width);
  return subject.palm_arch_mm * u * u;
}

Joints hand_frame_joints(const HandShape& shape, const HandPose& pose) {
  Joints j;
  j[kWristJoint] = Vector3d::Zero();
  for (int f = 0; f < kNumFingers; ++f) {
    const FingerShape& fs = shape.fingers[static_cast<size_t>(f)];
    const FingerAngles& q = pose.fingers[static_cast<size_t>(f)];
    const Vector3d axis = fs.flexion_axis();
    // R_1 = Rot(n, abd) Rot(a, flex1); then R_k = R_{k-1} Rot(a, flex_k) (axes in the rotated frame).
    Eigen::Matrix3d R = (Eigen::AngleAxisd(q[0], fs.normal) * Eigen::AngleAxisd(q[1], axis)).toRotationMatrix();
    Vector3d p = fs.base_mm;
    j[static_cast<size_t>(joint_index(f, 0))] = p;
    for (int bone = 0; bone < 3; ++bone) {
      if (bone > 0) R = R * Eigen::AngleAxisd(q[static_cast<size_t>(bone + 1)], axis).toRotationMatrix();
      p += fs.bone_length_mm[static_cast<size_t>(bone)] * (R * fs.direction);
      j[static_cast<size_t>(joint_index(f, bone + 1))] = p;
    }
  }
  return j;
}

Joints camera_frame_joints(const HandShape& shape, const HandPose& pose) {
  Joints j = hand_frame_joints(shape, pose);
  const Eigen::Matrix3d R = camera_R_hand(pose.rotation);
  for (auto& p : j) p = pose.translation_mm + R * p;
  return j;
}

Fingertips fingertips_from_joints(const Joints& joints) {
  Fingertips tips;
  for (int f = 0; f < kNumFingers; ++f) tips[static_cast<size_t>(f)] = joints[static_cast<size_t>(fingertip_joint(f))];
  return tips;
}

void posed_primitives(const HandShape& shape, const HandPose& pose, const Joints& camera_joints,
                      std::vector<ConeSphere>& out) {
  out.clear();
  const Eigen::Matrix3d R = camera_R_hand(pose.rotation);
  const auto to_camera = [&](const ConeSphere& c) {
    return ConeSphere{pose.translation_mm + R * c.a, pose.translation_mm + R * c.b, c.radius_a, c.radius_b, c.label};
  };
  for (int f = 0; f < kNumFingers; ++f) {
    const FingerShape& fs = shape.fingers[static_cast<size_t>(f)];
    for (int bone = 0; bone < 3; ++bone) {
      out.push_back(ConeSphere{camera_joints[static_cast<size_t>(joint_index(f, bone))],
                               camera_joints[static_cast<size_t>(joint_index(f, bone + 1))],
                               fs.radius_mm[static_cast<size_t>(bone)], fs.radius_mm[static_cast<size_t>(bone + 1)],
                               part_label(f, bone)});
    }
  }
  for (const auto& c : shape.palm) out.push_back(to_camera(c));
  if (!shape.forearm_shown) return;  // nor an upper arm beyond it
  ConeSphere forearm = to_camera(shape.forearm);
  if (shape.forearm_camera_direction) {
    forearm.b = forearm.a + (shape.forearm.b - shape.forearm.a).norm() * *shape.forearm_camera_direction;
  }
  out.push_back(forearm);
  // The upper arm: 30 % thicker than the forearm at the elbow, and as thick up to the shoulder.
  constexpr double kUpperArmGirth = 1.3;
  if (shape.upper_arm_camera_direction) {
    const double r = kUpperArmGirth * forearm.radius_b;
    out.push_back(
        ConeSphere{forearm.b, forearm.b + shape.upper_arm_mm * *shape.upper_arm_camera_direction, r, r, kBackground});
  }
}

void place_palm(HandPose& pose, const HandShape& shape, const Eigen::Matrix3d& turn, const Vector3d& palm_centre_mm) {
  const Eigen::AngleAxisd aa(turn);
  pose.rotation = aa.angle() * aa.axis();
  // Palm centre c = t + R palm_centre (hand frame) => t = c - R palm_centre.
  pose.translation_mm = palm_centre_mm - camera_R_hand(pose.rotation) * shape.palm_centre_mm;
}

void mirror_x(Joints& joints) {
  for (auto& j : joints) j.x() = -j.x();
}

void mirror_x(std::vector<ConeSphere>& solids) {
  for (auto& c : solids) {
    c.a.x() = -c.a.x();
    c.b.x() = -c.b.x();
  }
}

}  // namespace handtrack::synth
