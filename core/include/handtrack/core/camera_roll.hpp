#pragma once
// A camera mounted turned about its optical axis (ours, not in the paper): upside down under a
// shelf or a monitor's bezel, or on its side. The tracker is taught and tuned on hands whose
// forearm enters from the image's bottom edge; from another edge it reads the forest both ways and
// keeps the surer reading (docs/FOREST.md, "A hand from another image edge"), which on real depth
// is a coin toss more often (real SR305 hands upside down: 66 % of frames the right hand, against
// 98.6 % as recorded; docs/TRACKER.md, "A camera mounted turned"). A user who knows how the camera
// is mounted says so, and each frame is turned upright before it is tracked and every pose turned
// back into the camera's own frame after.
//
// The roll phi is the camera's turn about its optical axis as handtrack-synth's --roll gives it:
// camera-frame points turn by R_z(phi), so at phi = 90 a forearm that entered from the image's
// bottom enters from its left (x right, y down, z forward). Upright:
//
//   p_upright = R_z(-phi) p_camera,   p_camera = R_z(phi) p_upright
//
// For phi a multiple of 90 deg both are exact (components swapped and negated) and the image turns
// pixel for pixel: the principal point goes where its pixel goes, at phi = 180 to
// ((W - 1) - cx, (H - 1) - cy) (pixel centres at integer u, v), and at 90 and 270 width and height
// and fx and fy swap. The pose parameters' wrist position and global rotation turn with the points
// (camera_R_hand = R_z(phi) upright_R_hand); a left hand's parameters are those of the right-hand
// model in the mirrored image (Tracker), where the same turn is R_z(-phi) (mirroring x reverses the
// sense of a turn about z).

#include "handtrack/core/camera.hpp"
#include "handtrack/core/hands_tracker.hpp"

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace handtrack {

enum class CameraRoll : uint8_t { k0, k90, k180, k270 };

// 0, 90, 180 or 270 (degrees, -90 and -180 too, as handtrack-synth's --roll names them); nullopt for
// any other number or text.
std::optional<CameraRoll> parse_camera_roll(const std::string& degrees);
std::optional<CameraRoll> camera_roll_from_degrees(int degrees);
int degrees(CameraRoll roll);  // 0, 90, 180, 270
// What the two functions above take, for messages.
inline constexpr const char* kCameraRollValues = "0, 90, 180, 270 (or -90, -180)";
// The turn back: R_z(-phi).
CameraRoll inverse(CameraRoll roll);

// The camera's intrinsics as an upright camera has them.
CameraIntrinsics upright_camera(const CameraIntrinsics& camera, CameraRoll roll);

// The image the camera took (`camera.width` x `camera.height` pixels, row-major) turned upright into
// *upright (resized; no allocation once it has the size; empty when `pixels` is not of the camera's
// size). Ground-truth labels and any other per-pixel data go the same way as the depth.
template <typename T>
void turn_upright(const std::vector<T>& pixels, const CameraIntrinsics& camera, CameraRoll roll,
                  std::vector<T>* upright);
void turn_upright(const DepthImage& image, CameraRoll roll, DepthImage* upright);
// The frame as the tracker sees it: `image` itself when the camera is upright, else `image` turned
// upright into *scratch.
const DepthImage& upright_frame(const DepthImage& image, CameraRoll roll, DepthImage* scratch);

// p_camera = R_z(phi) p_upright and p_upright = R_z(-phi) p_camera, exactly.
Eigen::Vector3d turn_to_camera(CameraRoll roll, const Eigen::Vector3d& upright_p);
Eigen::Vector3d turn_to_upright(CameraRoll roll, const Eigen::Vector3d& camera_p);

// A pose tracked in the upright image, in the camera's own frame: joints, fingertips, palm centre
// and normal, and the wrist position and global rotation of its parameters.
void turn_to_camera(CameraRoll roll, TrackerOutput* output);
void turn_to_camera(CameraRoll roll, HandsOutput* output);

}  // namespace handtrack
