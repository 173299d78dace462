#pragma once
// Rendering of one tracked frame into side-by-side panels (handtrack-view).

#include "handtrack/core/camera.hpp"
#include "handtrack/core/depth_input.hpp"
#include "handtrack/core/hand_model.hpp"
#include "handtrack/core/png_io.hpp"
#include "handtrack/core/sequence.hpp"
#include "handtrack/core/tracker.hpp"

#include <optional>
#include <string>
#include <vector>

namespace handtrack::view {

// One hand of the frame: what its tracker (a HandsTracker slot) segmented and fitted.
struct HandView {
  const DepthInput* input = nullptr;  // its preprocessing, in the frame's own image (unmirrored())
  const TrackerOutput* output = nullptr;
  const HandModel* model = nullptr;
  // A left hand (TrackerOutput::handedness): output->params pose the model in the mirrored frame
  // (Tracker), so its Gaussians are drawn mirrored back (x negated).
  bool mirrored_model = false;
  int slot = 0;  // its HandsTracker slot: its colour (kHandColours) when several hands are drawn
};

struct FrameView {
  const DepthImage* depth = nullptr;  // the frame as read, mm
  // The hands, in slot order. One hand is drawn as handtrack-view always drew it; several each in
  // their own colour with a caption by the hand. None: the frame's depth alone, "no hand".
  std::vector<HandView> hands;
  const Gray8Image* labels = nullptr;    // optional part labels (panel d)
  std::string labels_caption = "labels";
  // Annotated fingertips, drawn as crosses: one entry per ground-truth hand (empty: none).
  std::vector<Fingertips> truth_tips;
  std::string name;  // caption: what the frame is (file or "frame N")
};

struct RenderOptions {
  bool crop = false;       // zoom every panel onto the segmented hands
  int panel_height = 0;    // px; 0 = the image height (360 with crop)
};

// The panels side by side: (a) depth + hand masks, (b) quadtree Gaussians, (c) models + skeletons,
// (d) labels when given. Throws std::invalid_argument if the depth or a hand's pointer is null.
RgbImage render_frame(const FrameView& frame, const RenderOptions& options = {});

// The tracker's input of a left hand (of the mirrored frame) back in the frame's own image: mask,
// labels, depth and quadtree Gaussians flipped left to right, points and axes with x negated.
DepthInput unmirrored(const DepthInput& input);

// Mean distance between the tracked and the annotated fingertips, mm; nullopt if none annotated.
std::optional<double> fingertip_error_mm(const TrackerOutput& output, const Fingertips& truth);
// The smallest of fingertip_error_mm() over the ground-truth hands: the error against the hand
// the tracked one is nearest to (with two hands the tracker's hand k need not be the sequence's).
std::optional<double> nearest_fingertip_error_mm(const TrackerOutput& output, const std::vector<Fingertips>& truth);

}  // namespace handtrack::view
