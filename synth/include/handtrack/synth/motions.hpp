#pragma once
// The seven motions of the Dexter 1 set (Sridhar et al. 2013/2015): adbadd, fingercount,
// fingerwave, flexex1, pinch, random, tigergrasp. Each runs slowly for the first half of the
// sequence and about 2.5x faster for the second half (a smooth speed ramp between the halves),
// stays within JointLimits::defaults(), keeps the palm at about 330-470 mm depth and moves the hand
// globally a little (random: fast rotation up to about +-55 deg about each camera axis).

#include "handtrack/synth/hand_model.hpp"

#include <array>
#include <string_view>

namespace handtrack::synth {

inline constexpr std::array<std::string_view, 7> kMotionNames = {"adbadd", "fingercount", "fingerwave", "flexex1",
                                                                 "pinch",  "random",      "tigergrasp"};
inline constexpr double kFastSpeedFactor = 2.5;  // fast half / slow half angular speed
inline constexpr double kSpeedRampSeconds = 0.3;  // the speed changes smoothly over this time

// One-line description of a motion for --list-motions ("" for an unknown name).
std::string_view motion_description(std::string_view name);

// The warped "motion time" in seconds of frame i of a sequence of `frames` at `fps`: speed 1 in the
// first half, kFastSpeedFactor in the second (a smoothstep ramp of kSpeedRampSeconds between), and
// beyond the end back and forth (frames 0..N-1, N-2..1, 0..N-1, ...). Every motion's clock.
double warped_motion_time(int frame, int frames, double fps);

class Motion {
 public:
  // Throws std::invalid_argument for an unknown name or frames < 1 or fps <= 0. The pinch pose is
  // solved for the given shape so that the thumb tip meets the index tip.
  Motion(std::string_view name, int frames, double fps, const HandShape& shape);

  // Pose of frame i (any i >= 0; beyond the sequence the motion plays back and forth, so the pose
  // stays continuous for an endless live camera).
  [[nodiscard]] HandPose pose(int frame) const;
  // Pose at a motion time (seconds; pose(i) = pose_at(motion_time(i))): a motion sampled with a
  // time offset (two_hand_motions.hpp: one hand lagging the other).
  [[nodiscard]] HandPose pose_at(double motion_time) const;
  // Warped "motion time" in seconds at frame i (speeds up by kFastSpeedFactor in the second half).
  [[nodiscard]] double motion_time(int frame) const;
  [[nodiscard]] std::string_view name() const { return kMotionNames[static_cast<size_t>(index_)]; }
  [[nodiscard]] int frames() const { return frames_; }

 private:
  int index_ = 0;
  int frames_ = 1;
  double fps_ = 60.0;
  HandShape shape_;
  JointLimits limits_ = JointLimits::defaults();
  std::array<FingerAngles, kNumFingers> pinch_{};  // solved pinch pose (thumb and index meet)
};

}  // namespace handtrack::synth
