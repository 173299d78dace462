#include "handtrack/synth/motions.hpp"

#include "angles.hpp"

#include <Eigen/Dense>
#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace handtrack::synth {
namespace {

using Eigen::Vector3d;
using HandAngles = std::array<FingerAngles, kNumFingers>;

// Period of one cycle of each motion in slow-half seconds (kMotionNames order; random uses its own
// incommensurate frequencies). Chosen for joint speeds of ~1.5-2.5 rad/s slow, ~4-6 rad/s fast.
constexpr std::array<double, 7> kCycleSeconds = {2.0, 8.0, 2.5, 2.4, 2.4, 1.0, 4.0};
constexpr int kRandomMotion = 5;

constexpr std::array<std::string_view, 7> kDescriptions = {
    "finger abduction/adduction: the fingers spread and close",
    "counting 1..5: index, middle, ring, little, thumb extend in turn from a fist, then fold back",
    "a wave of flexion across the fingers, index to little, thumb following",
    "all fingers flex into a fist and extend together",
    "thumb-index pinch: the thumb tip meets the index tip, the other fingers relax",
    "fast global rotation (up to ~55 deg about each camera axis) with mild finger motion",
    "claw (PIP/DIP flexed, MCP extended), then grasp (all joints flexed), then open"};

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3.0 - 2.0 * x);
}
// Integral of smoothstep from 0 to x (x unclamped): x^3 - x^4/2 on [0, 1], linear beyond.
double smoothstep_integral(double x) {
  if (x <= 0.0) return 0.0;
  if (x >= 1.0) return 0.5 + (x - 1.0);
  return x * x * x - 0.5 * x * x * x * x;
}
// 0 -> 1 -> 0 over one period, zero velocity at both ends.
double wave(double phase) { return 0.5 - 0.5 * std::cos(kTwoPi * phase); }

HandAngles lerp(const HandAngles& from, const HandAngles& to, double s) {
  HandAngles out{};
  for (size_t f = 0; f < kNumFingers; ++f) {
    for (size_t k = 0; k < 4; ++k) out[f][k] = from[f][k] + s * (to[f][k] - from[f][k]);
  }
  return out;
}
FingerAngles lerp(const FingerAngles& from, const FingerAngles& to, double s) {
  FingerAngles out{};
  for (size_t k = 0; k < 4; ++k) out[k] = from[k] + s * (to[k] - from[k]);
  return out;
}

// Thumb abd > 0 swings the thumb toward the index finger (adduction), < 0 away from it.
// Finger abd > 0 swings toward the little finger side.
const HandAngles kOpen = {{{0.0, 0.0, 0.05, 0.1},
                           {-0.05, 0.05, 0.1, 0.05},
                           {0.0, 0.05, 0.1, 0.05},
                           {0.05, 0.05, 0.1, 0.05},
                           {0.12, 0.05, 0.1, 0.05}}};
const HandAngles kFist = {{{0.35, 0.55, 0.6, 0.75},
                           {0.05, 1.45, 1.75, 1.0},
                           {0.0, 1.5, 1.75, 1.0},
                           {-0.05, 1.5, 1.75, 1.0},
                           {-0.1, 1.45, 1.7, 1.0}}};
const HandAngles kAdducted = {{{0.4, 0.0, 0.05, 0.1},
                               {0.1, 0.05, 0.05, 0.05},
                               {0.0, 0.05, 0.05, 0.05},
                               {-0.1, 0.05, 0.05, 0.05},
                               {-0.2, 0.05, 0.05, 0.05}}};
const HandAngles kSpread = {{{-0.5, -0.1, 0.0, 0.0},
                             {-0.3, 0.0, 0.05, 0.05},
                             {0.0, 0.0, 0.05, 0.05},
                             {0.22, 0.0, 0.05, 0.05},
                             {0.35, 0.0, 0.05, 0.05}}};
const HandAngles kClaw = {{{-0.2, 0.2, 0.6, 0.8},
                           {-0.1, 0.0, 1.5, 1.1},
                           {0.0, 0.0, 1.55, 1.1},
                           {0.08, 0.0, 1.5, 1.1},
                           {0.18, 0.0, 1.45, 1.05}}};
const HandAngles kGrasp = {{{0.2, 0.6, 0.6, 0.7},
                            {0.0, 1.3, 1.55, 1.0},
                            {0.0, 1.35, 1.6, 1.0},
                            {0.0, 1.35, 1.55, 1.0},
                            {0.0, 1.3, 1.5, 1.0}}};
const HandAngles kCurl = {{{0.2, 0.4, 0.5, 0.6},
                           {-0.05, 1.2, 1.3, 0.8},
                           {0.0, 1.2, 1.3, 0.8},
                           {0.05, 1.2, 1.3, 0.8},
                           {0.12, 1.2, 1.3, 0.8}}};

struct Key {
  double phase;
  HandAngles angles;
};

// Cyclic keyframe interpolation with smoothstep easing (zero joint velocity at each key).
HandAngles keyframes(const std::vector<Key>& keys, double phase) {
  phase -= std::floor(phase);
  for (size_t i = 0; i < keys.size(); ++i) {
    const Key& a = keys[i];
    const bool last = i + 1 == keys.size();
    const double end = last ? 1.0 : keys[i + 1].phase;
    if (phase >= a.phase && phase < end) {
      const HandAngles& b = last ? keys.front().angles : keys[i + 1].angles;
      return lerp(a.angles, b, smoothstep((phase - a.phase) / (end - a.phase)));
    }
  }
  return keys.front().angles;
}

// Counting pose: the first `count` fingers of (index, middle, ring, little, thumb) extended.
HandAngles counting(int count) {
  HandAngles h = kFist;
  constexpr std::array<int, 5> order = {kIndex, kMiddle, kRing, kLittle, kThumb};
  for (int i = 0; i < count; ++i) {
    const auto f = static_cast<size_t>(order[static_cast<size_t>(i)]);
    h[f] = kOpen[f];
  }
  return h;
}

// Pinch: other fingers relaxed; thumb and index solved so the tip spheres touch (centre distance
// = sum of the tip radii), by damped Gauss-Newton on 7 angles with a prior toward a natural pinch.
HandAngles solve_pinch(const HandShape& shape, const JointLimits& limits) {
  HandPose pose;
  pose.fingers = {{{0.1, 0.5, 0.4, 0.4}, {0.0, 0.6, 0.8, 0.5}, {0.0, 0.3, 0.5, 0.3}, {0.05, 0.35, 0.55, 0.3},
                   {0.12, 0.4, 0.6, 0.35}}};
  const HandPose prior = pose;
  const double contact_mm = shape.fingers[kThumb].radius_mm[3] + shape.fingers[kIndex].radius_mm[3];
  constexpr double kPriorWeightMmPerRad = 4.0;
  constexpr int kVars = 7;  // thumb abd, flex1..3, index flex1..3
  const auto var = [](HandPose& p, int i) -> double& {
    return i < 4 ? p.fingers[kThumb][static_cast<size_t>(i)] : p.fingers[kIndex][static_cast<size_t>(i - 3)];
  };
  const auto value = [](const HandPose& p, int i) {
    return i < 4 ? p.fingers[kThumb][static_cast<size_t>(i)] : p.fingers[kIndex][static_cast<size_t>(i - 3)];
  };
  const auto residuals = [&](const HandPose& p) {
    Eigen::Matrix<double, 1 + kVars, 1> r;
    const Joints j = hand_frame_joints(shape, p);
    r(0) = (j[fingertip_joint(kThumb)] - j[fingertip_joint(kIndex)]).norm() - contact_mm;
    for (int i = 0; i < kVars; ++i) r(1 + i) = kPriorWeightMmPerRad * (value(p, i) - value(prior, i));
    return r;
  };
  double lambda = 1e-2;
  for (int iter = 0; iter < 200; ++iter) {
    const auto r = residuals(pose);
    Eigen::Matrix<double, 1 + kVars, kVars> J;
    for (int i = 0; i < kVars; ++i) {
      HandPose p = pose;
      var(p, i) += 1e-6;
      J.col(i) = (residuals(p) - r) / 1e-6;
    }
    const Eigen::Matrix<double, kVars, kVars> H =
        J.transpose() * J + lambda * Eigen::Matrix<double, kVars, kVars>::Identity();
    const Eigen::Matrix<double, kVars, 1> step = H.ldlt().solve(-J.transpose() * r);
    HandPose next = pose;
    for (int i = 0; i < kVars; ++i) var(next, i) += step(i);
    next = limits.clamp(next);
    if (residuals(next).squaredNorm() < r.squaredNorm()) {
      pose = next;
      lambda = std::max(1e-6, lambda * 0.3);
    } else {
      lambda *= 10.0;
    }
  }
  return pose.fingers;
}

struct Global {
  Vector3d palm_centre_mm;
  Vector3d euler_rad;  // rotation Rz(z) Ry(y) Rx(x) about the palm centre, applied before R0
};

Global gentle_sway(double tau) {
  return {Vector3d(8.0 + 30.0 * std::sin(kTwoPi * 0.11 * tau), 5.0 + 20.0 * std::sin(kTwoPi * 0.07 * tau + 1.0),
                   400.0 + 45.0 * std::sin(kTwoPi * 0.09 * tau + 2.0)),
          Vector3d(0.15 * std::sin(kTwoPi * 0.10 * tau + 0.5), 0.20 * std::sin(kTwoPi * 0.08 * tau + 1.5),
                   0.12 * std::sin(kTwoPi * 0.12 * tau + 2.5))};
}

Global fast_rotation(double tau) {
  // ~0.95 rad (54 deg) amplitude: peak ~100 deg/s slow, ~250 deg/s fast.
  return {Vector3d(5.0 + 20.0 * std::sin(kTwoPi * 0.13 * tau), 5.0 + 15.0 * std::sin(kTwoPi * 0.17 * tau + 1.0),
                   430.0 + 30.0 * std::sin(kTwoPi * 0.11 * tau + 2.0)),
          Vector3d(0.95 * std::sin(kTwoPi * 0.29 * tau), 0.95 * std::sin(kTwoPi * 0.25 * tau + 1.0),
                   0.90 * std::sin(kTwoPi * 0.33 * tau + 2.0))};
}

}  // namespace

std::string_view motion_description(std::string_view name) {
  for (size_t i = 0; i < kMotionNames.size(); ++i) {
    if (kMotionNames[i] == name) return kDescriptions[i];
  }
  return {};
}

Motion::Motion(std::string_view name, int frames, double fps, const HandShape& shape)
    : frames_(frames), fps_(fps), shape_(shape) {
  const auto it = std::find(kMotionNames.begin(), kMotionNames.end(), name);
  if (it == kMotionNames.end()) {
    std::string all;
    for (auto n : kMotionNames) all += (all.empty() ? "" : ", ") + std::string(n);
    throw std::invalid_argument("unknown motion '" + std::string(name) + "' (expected one of: " + all + ")");
  }
  if (frames < 1) throw std::invalid_argument("frames must be >= 1, got " + std::to_string(frames));
  if (!(fps > 0.0 && std::isfinite(fps))) throw std::invalid_argument("fps must be > 0");
  index_ = static_cast<int>(it - kMotionNames.begin());
  if (index_ == 4) pinch_ = solve_pinch(shape_, limits_);
}

double Motion::motion_time(int frame) const { return warped_motion_time(frame, frames_, fps_); }

double warped_motion_time(int frame, int frames, double fps) {
  frame = std::max(frame, 0);
  // Play back and forth beyond the end: frames 0..N-1, N-2..1, 0..N-1, ...
  if (frames > 1 && frame >= frames) {
    const int period = 2 * (frames - 1);
    const int k = frame % period;
    frame = k < frames ? k : period - k;
  } else if (frames == 1) {
    frame = 0;
  }
  // Speed 1 in the first half, kFastSpeedFactor in the second, smoothstep ramp of
  // kSpeedRampSeconds centred on the midpoint; tau = integral of the speed.
  const double t = frame / fps;
  const double mid = 0.5 * frames / fps;
  const double w = kSpeedRampSeconds;
  const auto x = [&](double time) { return (time - (mid - 0.5 * w)) / w; };
  return t + (kFastSpeedFactor - 1.0) * w * (smoothstep_integral(x(t)) - smoothstep_integral(x(0.0)));
}

HandPose Motion::pose(int frame) const { return pose_at(motion_time(frame)); }

HandPose Motion::pose_at(double tau) const {
  const double phase = tau / kCycleSeconds[static_cast<size_t>(index_)];
  HandAngles angles = kOpen;
  Global global = gentle_sway(tau);
  switch (index_) {
    case 0:  // adbadd
      angles = lerp(kAdducted, kSpread, wave(phase));
      break;
    case 1:  // fingercount
      angles = keyframes({{0.0, counting(0)},
                          {0.09, counting(1)},
                          {0.18, counting(2)},
                          {0.27, counting(3)},
                          {0.36, counting(4)},
                          {0.45, counting(5)},
                          {0.55, counting(5)},
                          {0.64, counting(4)},
                          {0.73, counting(3)},
                          {0.82, counting(2)},
                          {0.91, counting(1)}},
                         phase);
      break;
    case 2:  // fingerwave: index leads, each next finger lags 0.15 of a cycle, the thumb 0.6
      for (int f = kIndex; f <= kLittle; ++f) {
        const auto i = static_cast<size_t>(f);
        angles[i] = lerp(kOpen[i], kCurl[i], wave(phase - 0.15 * (f - 1)));
      }
      angles[kThumb] = lerp(kOpen[kThumb], kCurl[kThumb], wave(phase - 0.6));
      break;
    case 3:  // flexex1
      angles = lerp(kOpen, kFist, wave(phase));
      break;
    case 4:  // pinch: open, close to the pinch, hold, release
      angles = keyframes({{0.0, kOpen}, {0.4, pinch_}, {0.6, pinch_}}, phase);
      break;
    case kRandomMotion:
      global = fast_rotation(tau);
      for (int f = 0; f < kNumFingers; ++f) {
        const auto i = static_cast<size_t>(f);
        angles[i] = lerp(kOpen[i], kFist[i], 0.45 * wave(0.35 * tau - 0.12 * f));
      }
      break;
    default:  // tigergrasp
      angles = keyframes({{0.0, kOpen}, {0.25, kClaw}, {0.4, kClaw}, {0.6, kGrasp}, {0.75, kGrasp}}, phase);
      break;
  }
  HandPose pose;
  pose.fingers = angles;
  const Eigen::Matrix3d delta = (Eigen::AngleAxisd(global.euler_rad.z(), Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(global.euler_rad.y(), Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(global.euler_rad.x(), Vector3d::UnitX()))
                                    .toRotationMatrix();
  place_palm(pose, shape_, delta, global.palm_centre_mm);  // rotates about the palm centre
  return limits_.clamp(pose);
}

}  // namespace handtrack::synth
