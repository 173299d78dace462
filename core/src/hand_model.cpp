#include "handtrack/core/hand_model.hpp"

#include "handtrack/core/kinematics.hpp"

#include <cmath>
#include <numbers>

namespace handtrack {
namespace {

using Eigen::Vector3d;

FingerChain chain(Vector3d base, Vector3d direction, Vector3d palmar_hint, std::array<double, 3> length) {
  direction.normalize();
  // Gram-Schmidt: the palmar normal must be orthogonal to the rest direction.
  Vector3d palmar = (palmar_hint - palmar_hint.dot(direction) * direction).normalized();
  return {base, direction, palmar, length};
}

// Radii (mm) at the start and end of each bone: the surface the 1-sigma spheres follow.
struct BoneRadii {
  std::array<std::array<double, 2>, kBonesPerFinger> r;
};

}  // namespace

double overlap_2d(double dist2, double sigma_p, double sigma_q) {
  const double sp2 = sigma_p * sigma_p;
  const double sq2 = sigma_q * sigma_q;
  const double s = sp2 + sq2;
  return 2.0 * std::numbers::pi * sp2 * sq2 / s * std::exp(-dist2 / (2.0 * s));
}

double overlap_3d(double dist2, double sigma_p, double sigma_q) {
  const double sp2 = sigma_p * sigma_p;
  const double sq2 = sigma_q * sigma_q;
  const double s = sp2 + sq2;
  const double k = sp2 * sq2 / s;
  return std::pow(2.0 * std::numbers::pi, 1.5) * k * std::sqrt(k) * std::exp(-dist2 / (2.0 * s));
}

HandModel HandModel::default_adult(const HandScale& scale) {
  HandModel m;
  m.scale_ = scale;
  // Mean adult right hand: bone lengths and knuckle positions after anthropometric averages
  // (middle finger 46/28/18 mm, palm 94 mm long, ~85 mm wide at the knuckles).
  m.fingers_[kThumb] = chain({20, 22, 8}, {0.70, 0.62, 0.35}, {-0.55, 0.0, 0.83}, {42, 32, 22});
  m.fingers_[kIndex] = chain({24, 90, 0}, {0.12, 1, 0}, {0, 0, 1}, {42, 25, 17});
  m.fingers_[kMiddle] = chain({4, 94, 0}, {0, 1, 0}, {0, 0, 1}, {46, 28, 18});
  m.fingers_[kRing] = chain({-14, 90, 0}, {-0.08, 1, 0}, {0, 0, 1}, {43, 27, 17});
  m.fingers_[kLittle] = chain({-30, 80, 0}, {-0.2, 1, 0}, {0, 0, 1}, {33, 20, 16});
  const std::array<BoneRadii, kNumFingers> radii = {{
      {{{{12, 10.5}, {10.5, 9.5}, {9.5, 8.5}}}},
      {{{{9, 8.5}, {8.5, 8}, {8, 7.5}}}},
      {{{{9.2, 8.7}, {8.7, 8.2}, {8.2, 7.6}}}},
      {{{{8.8, 8.3}, {8.3, 7.8}, {7.8, 7.2}}}},
      {{{{8, 7.5}, {7.5, 7}, {7, 6.5}}}},
  }};
  for (auto& f : m.fingers_) {
    f.base.x() *= scale.width;
    f.base.y() *= scale.length;
    for (auto& l : f.length_mm) l *= scale.length;
  }

  // Two Gaussians per bone; the last one sits at the tip (its 1-sigma sphere reaches the skin).
  static constexpr std::array<std::array<double, 2>, kBonesPerFinger> kAlong = {{{0.25, 0.75}, {0.3, 0.8}, {0.35, 1.0}}};
  for (int f = 0; f < kNumFingers; ++f) {
    for (int b = 0; b < kBonesPerFinger; ++b) {
      const auto& r = radii[static_cast<size_t>(f)].r[static_cast<size_t>(b)];
      for (double along : kAlong[static_cast<size_t>(b)]) {
        ModelGaussian g;
        g.bone = kBonesPerFinger * f + b;
        g.along = along;
        g.sigma_mm = (r[0] + along * (r[1] - r[0])) * scale.sigma;
        g.label = part_label(f, b);
        m.gaussians_.push_back(g);
      }
    }
  }
  // Knuckles: the heads of the metacarpals, index to little, kKnuckleDropMm toward the wrist from
  // each finger's base in the palm's plane. A hand seen from behind, or a fist, shows them most of
  // all; without them the palm rows end 17 mm short and a fit tips the hand to lay the top row over
  // them (docs/TRACKER.md, "Knuckles"). They come before the palm rows, so the last Gaussian stays a
  // row's (palm_half_thickness_mm).
  constexpr double kKnuckleDropMm = 10.0;
  for (int f = kIndex; f <= kLittle; ++f) {
    const Vector3d& base = m.fingers_[static_cast<size_t>(f)].base;
    ModelGaussian g;
    g.bone = kPalmBone;
    g.palm_position = {base.x(), base.y() - kKnuckleDropMm * scale.length, 0.0};
    g.sigma_mm = (f == kLittle ? 8.0 : 9.0) * scale.sigma;
    g.label = kPalm;
    m.gaussians_.push_back(g);
  }
  // Palm: three rows from the wrist to below the knuckles; sigma = half the palm thickness.
  struct PalmSpot {
    double x, y, sigma;
  };
  static constexpr PalmSpot kPalmSpots[] = {{-12, 15, 15}, {10, 15, 15},  {-24, 42, 14}, {-2, 42, 14}, {20, 42, 14},
                                       {-27, 70, 13}, {-8, 70, 13}, {11, 70, 13},   {27, 70, 13}};
  for (const auto& s : kPalmSpots) {
    ModelGaussian g;
    g.bone = kPalmBone;
    g.palm_position = {s.x * scale.width, s.y * scale.length, 0.0};
    g.sigma_mm = s.sigma * scale.sigma;
    g.label = kPalm;
    m.gaussians_.push_back(g);
  }

  // Anatomical limits (radians) after Simo Serra 2011 (Sec. 4.1, E_lim): [abd, flex1, flex2, flex3].
  for (int f = 0; f < kNumFingers; ++f) {
    const bool thumb = f == kThumb;
    const std::array<JointLimit, 4> lim =
        thumb ? std::array<JointLimit, 4>{{{-0.6, 0.6}, {-0.4, 0.9}, {-0.2, 1.0}, {-0.3, 1.3}}}
              : std::array<JointLimit, 4>{{{-0.35, 0.35}, {-0.3, 1.6}, {0.0, 1.9}, {0.0, 1.3}}};
    for (int d = 0; d < 4; ++d) m.limits_[static_cast<size_t>(4 * f + d)] = lim[static_cast<size_t>(d)];
  }

  // E_col counts pairs of Gaussians on different fingers, and the palm against the two outer bones
  // of each finger (a fingertip must not sink into the palm). Pairs on one finger or a finger's
  // first bone against the palm overlap by construction at every pose and are left out: counting
  // them would only resist flexion.
  const auto finger_of = [](int bone) { return bone == kPalmBone ? -1 : bone / kBonesPerFinger; };
  const auto n = static_cast<int>(m.gaussians_.size());
  for (int a = 0; a < n; ++a) {
    for (int b = a + 1; b < n; ++b) {
      const int ba = m.gaussians_[static_cast<size_t>(a)].bone;
      const int bb = m.gaussians_[static_cast<size_t>(b)].bone;
      const int fa = finger_of(ba);
      const int fb = finger_of(bb);
      if (fa == fb) continue;
      if (fa == -1 && bb % kBonesPerFinger == 0) continue;
      if (fb == -1 && ba % kBonesPerFinger == 0) continue;
      m.collision_pairs_.push_back({a, b});
    }
  }

  // E(C_h, C_h) at the rest pose (all ordered pairs, including each Gaussian with itself).
  const PosedHand rest(m, PoseParams::Zero());
  double e = 0.0;
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      e += overlap_3d((rest.centre(a) - rest.centre(b)).squaredNorm(), m.gaussians_[static_cast<size_t>(a)].sigma_mm,
                      m.gaussians_[static_cast<size_t>(b)].sigma_mm);
    }
  }
  m.self_similarity_ = e;
  return m;
}

Eigen::Vector3d HandModel::palm_centre() const {
  return {0.0, 0.5 * (fingers_[kMiddle].base.y()), 0.0};
}

double HandModel::palm_half_thickness_mm() const { return gaussians_.back().sigma_mm; }

double HandModel::palm_half_width_mm() const {
  double half_width = 0.0;
  for (const auto& g : gaussians_) {
    if (g.bone == kPalmBone) half_width = std::max(half_width, std::abs(g.palm_position.x()) + g.sigma_mm);
  }
  return half_width;
}

double HandModel::hand_length_mm() const {
  const auto& f = fingers_[kMiddle];
  return f.base.y() + f.length_mm[0] + f.length_mm[1] + f.length_mm[2];
}

}  // namespace handtrack
