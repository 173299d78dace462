#pragma once
// Two hands at once (issue 14): scenes with a right and a left hand in one depth image, for the
// multi-hand tracker (core/hands_tracker.hpp). Each hand's fingers move as in one of the Dexter
// motions (motions.hpp, with the same slow first and fast second half); the scene moves the hands:
//
//   two_apart  both palms toward the camera, 175-225 mm apart (palm centres), 385-455 mm away;
//              the right hand does fingerwave, the left flexex1
//   two_clap   the palms face each other (each turned 75 deg from the camera about the vertical),
//              approach from 200 mm apart, touch (the separation solved for the two subjects), part:
//              a 2 s cycle, the fingers flat
//   two_cross  the right hand passes in front (palm ~360 mm away) of the left (~490 mm): they cross
//              in the image and swap sides, and back (a 4 s cycle); the fingers do adbadd (right)
//              and fingerwave (left)
//   two_pinch  both hands pinch (each pinch solved for its subject), the left 0.8 s behind, the
//              palms turned 20 deg toward each other, ~210 mm apart
//   two_reach  a head-mounted camera over both hands reaching forward (views.hpp's head-mounted
//              arrangement for each: the backs toward the camera, the fingers 65 deg away, the
//              forearms up from below the camera, a table below), the right hand on the image's
//              right, palm centres ~200 mm apart; the right hand pinches, the left does fingerwave
//
// Hand 0 is a right hand, hand 1 a left hand. Both are given as poses of the right-hand model; hand
// 1 is shown as the mirror image about the camera's x = 0 plane (hand_model.hpp mirror_x), as a
// one-hand left hand is (synthetic_camera.hpp, Handedness). The scenes are therefore written once,
// for "design" poses in which each hand is a right hand on the side the camera sees the right hand
// on: the image's left (x < 0) for a desk camera facing the user, the image's right (x > 0) for a
// head-mounted one; hand 1's design pose, mirrored, lands on the other side. As for one hand, the
// forearms leave the image (or the working volume) below the hands.

#include "handtrack/synth/motions.hpp"
#include "handtrack/synth/views.hpp"

#include <array>
#include <optional>
#include <string_view>

namespace handtrack::synth {

inline constexpr std::array<std::string_view, 5> kTwoHandMotionNames = {"two_apart", "two_clap", "two_cross",
                                                                        "two_pinch", "two_reach"};
inline constexpr int kTwoHands = 2;

[[nodiscard]] bool is_two_hand_motion(std::string_view name);
// One-line description for --list-motions ("" for a name that is not a two-hand motion).
std::string_view two_hand_motion_description(std::string_view name);
// The camera arrangement a two-hand scene is seen in (views.hpp): kHeadMounted for two_reach,
// kPalm (a desk camera facing the user) for the others and for a name that is not a two-hand motion.
[[nodiscard]] View two_hand_view(std::string_view name);
// The arrangement `motion` is rendered in: a two-hand scene's own, else `view` (SynthOptions::view).
[[nodiscard]] View seen_in(std::string_view motion, View view);

// The poses of hand 0 (right) and hand 1 (left: shown mirrored) of one frame.
using TwoHandPoses = std::array<HandPose, kTwoHands>;

class TwoHandMotion {
 public:
  // shapes[k]: hand k's subject. Throws std::invalid_argument for an unknown name, frames < 1 or
  // fps <= 0. two_clap solves where the palms touch and two_pinch each hand's pinch for the shapes.
  TwoHandMotion(std::string_view name, int frames, double fps, const std::array<HandShape, kTwoHands>& shapes);

  // Both poses of frame i (any i >= 0; beyond the sequence back and forth, as Motion).
  [[nodiscard]] TwoHandPoses pose(int frame) const;
  [[nodiscard]] double motion_time(int frame) const { return warped_motion_time(frame, frames_, fps_); }
  [[nodiscard]] std::string_view name() const { return kTwoHandMotionNames[static_cast<size_t>(index_)]; }
  // two_clap: the palm centres' separation (mm, along the camera's x axis) at which the hands touch.
  [[nodiscard]] double clap_contact_mm() const { return clap_contact_mm_; }

 private:
  int index_ = 0;
  int frames_ = 1;
  double fps_ = 60.0;
  std::array<HandShape, kTwoHands> shapes_;
  // Each hand's articulation: the fingers of a one-hand motion (none: two_clap's flat hands).
  std::array<std::optional<Motion>, kTwoHands> fingers_;
  double clap_contact_mm_ = 0.0;
};

}  // namespace handtrack::synth
