#pragma once
// Camera arrangements (views) of the synthetic hand, orthogonal to the motion: each turns the
// motion's pose rigidly about the palm centre (the articulation and the motion's own small global
// movement stay) and places it where that arrangement puts a hand, with the scene behind it.
//
//   palm            a desk camera facing the user, the palm toward it (the Dexter motions' view)
//   back            the same camera, the back of the hand toward it (pointing at the screen):
//                   half a turn about the finger axis
//   side            the thumb side toward the camera: a quarter turn about the finger axis
//   fingers-toward  the fingers tipped 50 deg toward the camera (the forearm recedes)
//   fingers-away    the fingers tipped 50 deg away from it (the forearm comes nearer)
//   head-mounted    an egocentric camera behind and above a hand reaching forward: the back of
//                   the hand toward the camera, the fingers 65 deg away from it, the palm centre
//                   330 mm away, the forearm coming up from below the camera into the image
//                   bottom (its nearest pixels 120-240 mm away, about the working volume's near
//                   plane of 150 mm), a table below
//
// The rotations are applied in the hand frame, before the motion's: R = R_motion Rx(tip) Ry(turn),
// where Ry(turn) turns about the hand's own finger axis (y_h) and Rx(tip) about its x_h axis (at
// the rest pose, R_motion = R0, the camera x axis: positive tips the fingers, pointing up in the
// image, toward the camera). So the motion's own turning (a roll about the viewing axis) stays
// what it is, about the camera's axes, around the view's orientation.
#include "handtrack/synth/hand_model.hpp"

#include <array>
#include <optional>
#include <string_view>

namespace handtrack::synth {

enum class View { kPalm, kBack, kSide, kFingersToward, kFingersAway, kHeadMounted };

inline constexpr std::array<View, 6> kViews = {View::kPalm,          View::kBack,        View::kSide,
                                               View::kFingersToward, View::kFingersAway, View::kHeadMounted};

std::string_view view_name(View view);
std::optional<View> parse_view(std::string_view name);
std::string_view view_description(View view);  // one line for --list-views

// How much farther a user close to the camera (Background::kNearBody) sits in `view` than in the
// palm view: 90 mm where the fingers curl or tip toward the body (the back and side views, fingers
// tipped away). As near as in the palm view they went up to 46 mm into the head (subjects 1-7),
// and touching, hand and body are one surface to a tracker; 0 where the fingers curl toward the
// camera.
double near_body_behind_mm(View view);

// The motion's pose seen in `view`: turned about the palm centre and, where the arrangement fixes
// it, moved to its distance from the camera. kPalm returns `pose` unchanged.
HandPose view_pose(View view, const HandPose& pose, const HandShape& shape);

// `shape` with its forearm as `view` holds it. The desk views keep HandShape's forearm, rigid in
// the hand frame. The head-mounted view brings it up from below the camera, whatever the motion
// does with the hand (the wrist bends): rigid in the hand frame it would point at the lens
// whenever a motion rolls or tips the hand toward it, and cover the hand or the whole image.
HandShape view_shape(View view, HandShape shape);

// `shape` with an upper arm from its elbow back to the shoulder of a user facing a desk camera
// (300 mm for the mean adult, with the subject's length; away from the camera, up and toward the
// image's left, the right shoulder's side), where `view` is a desk view. A head-mounted camera's
// elbow is below the camera and its upper arm behind it: unchanged.
HandShape with_upper_arm(View view, HandShape shape);

// `shape` without its forearm: the hand alone, cut at the wrist (the palm's heel stays), as
// renderers of a hand model without an arm draw it.
HandShape without_arm(HandShape shape);

}  // namespace handtrack::synth
