#pragma once
// The tracker options that handtrack-eval and handtrack-view share, spelt and checked as
// handtrackd's configuration names their values (README, "Configuration"): the hand fitted, where
// the camera looks from, how it is turned, and the part forest of late fusion.

#include "handtrack/core/camera_roll.hpp"

#include <CLI/CLI.hpp>

#include <string>

namespace handtrack::tools {

// --hand: tracker.handedness ("auto", "right" or "left"); `hand` keeps its value unless given.
inline CLI::Option* add_hand_option(CLI::App& app, std::string& hand) {
  return app
      .add_option("--hand", hand,
                  "auto (default: both hands, the better fit chosen at every (re)start), right or left, as "
                  "handtrackd's tracker.handedness")
      ->check(CLI::IsMember({"right", "left", "auto"}));
}

// --arrangement: tracker.arrangement ("facing" or "head-mounted").
inline CLI::Option* add_arrangement_option(CLI::App& app, std::string& arrangement) {
  return app
      .add_option("--arrangement", arrangement,
                  "facing (default: a camera facing the user) or head-mounted (at the user's eyes): which side of "
                  "a hand, and which hand on which side of the image, auto handedness expects where the depth "
                  "leaves it open (handtrackd's tracker.arrangement)")
      ->check(CLI::IsMember({"facing", "head-mounted"}));
}

// --camera-roll: camera.roll (0, 90, 180, 270, or -90, -180 degrees); `degrees` keeps its value
// unless given, and parse_camera_roll() takes any value it lets through.
inline CLI::Option* add_camera_roll_option(CLI::App& app, std::string& degrees, const std::string& what) {
  return app
      .add_option("--camera-roll", degrees,
                  "degrees the camera is turned about its optical axis, as handtrack-synth's --roll: 0 (default), "
                  "90, 180 (upside down) or 270 (-90); each frame is tracked turned upright" + what +
                      " (handtrackd's camera.roll; docs/TRACKER.md, \"A camera mounted turned\")")
      ->check([](const std::string& v) {
        return parse_camera_roll(v) ? std::string() : std::string("one of ") + kCameraRollValues;
      });
}

// --forest: tracker.forest_model; `forest` stays empty unless given (then the shipped one).
inline CLI::Option* add_forest_option(CLI::App& app, std::string& forest) {
  return app
      .add_option("--forest", forest,
                  "part-classification forest for late fusion (default: the shipped one, $HANDTRACK_FOREST, data/ "
                  "or /usr/share/handtrack)")
      ->check(CLI::ExistingFile);
}

}  // namespace handtrack::tools
