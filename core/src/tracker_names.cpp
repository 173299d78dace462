// The names of the tracker's modes and states, as the configuration and the outputs spell them
// (tracker.hpp), and the camera's roll in degrees (camera_roll.hpp). Apart from the tracker, in
// handtrack::core_files: handtrackd's configuration parser uses them, and the fuzz tree builds that
// parser without the tracker (tests/fuzz).
#include "handtrack/core/camera_roll.hpp"
#include "handtrack/core/tracker.hpp"

#include <charconv>
#include <initializer_list>
#include <string>

namespace handtrack {

namespace {
// The value among `values` whose to_string() is `text`.
template <typename Enum>
bool parse_name(const std::string& text, std::initializer_list<Enum> values, Enum* out) {
  for (Enum v : values) {
    if (text == to_string(v)) {
      *out = v;
      return true;
    }
  }
  return false;
}
}  // namespace

const char* to_string(EnergyMode mode) {
  return mode == EnergyMode::kLateFusion ? "late-fusion" : "depth-only";
}

bool parse_energy_mode(const std::string& text, EnergyMode* mode) {
  return parse_name(text, {EnergyMode::kLateFusion, EnergyMode::kDepthOnly}, mode);
}

const char* to_string(TrackingState state) {
  switch (state) {
    case TrackingState::kNoHand: return "no_hand";
    case TrackingState::kTracking: return "tracking";
    case TrackingState::kRecovering: return "recovering";
  }
  return "?";
}

const char* to_string(Handedness hand) { return hand == Handedness::kLeft ? "left" : "right"; }

const char* to_string(HandednessMode mode) {
  switch (mode) {
    case HandednessMode::kRight: return "right";
    case HandednessMode::kLeft: return "left";
    case HandednessMode::kAuto: return "auto";
  }
  return "?";
}

bool parse_handedness_mode(const std::string& text, HandednessMode* mode) {
  return parse_name(text, {HandednessMode::kAuto, HandednessMode::kLeft, HandednessMode::kRight}, mode);
}

const char* to_string(CameraArrangement arrangement) {
  return arrangement == CameraArrangement::kHeadMounted ? "head-mounted" : "facing";
}

bool parse_camera_arrangement(const std::string& text, CameraArrangement* arrangement) {
  return parse_name(text, {CameraArrangement::kFacing, CameraArrangement::kHeadMounted}, arrangement);
}

std::optional<CameraRoll> parse_camera_roll(const std::string& degrees) {
  int value = 0;
  const char* end = degrees.data() + degrees.size();
  const auto [rest, error] = std::from_chars(degrees.data(), end, value);
  if (error != std::errc{} || rest != end) return std::nullopt;
  return camera_roll_from_degrees(value);
}

std::optional<CameraRoll> camera_roll_from_degrees(int degrees) {
  switch (degrees) {
    case 0: return CameraRoll::k0;
    case 90: return CameraRoll::k90;
    case 180:
    case -180: return CameraRoll::k180;
    case 270:
    case -90: return CameraRoll::k270;
    default: return std::nullopt;
  }
}

int degrees(CameraRoll roll) { return 90 * static_cast<int>(roll); }

CameraRoll inverse(CameraRoll roll) { return static_cast<CameraRoll>((4 - static_cast<int>(roll)) % 4); }

}  // namespace handtrack
