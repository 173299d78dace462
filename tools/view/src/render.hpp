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

namespace handtrack::view {

struct FrameView {
  const DepthImage* depth = nullptr;     // the frame as read, mm
  const DepthInput* input = nullptr;     // the tracker's preprocessing of it (Tracker::last_input())
  const TrackerOutput* output = nullptr;
  const HandModel* model = nullptr;
  // A left hand (TrackerOutput::handedness): output->params pose the model in the mirrored frame
  // (Tracker), so its Gaussians are drawn mirrored back (x negated); `input` must be in the
  // frame's own image (unmirrored()).
  bool mirrored_model = false;
  const Gray8Image* labels = nullptr;    // optional part labels (panel d)
  std::string labels_caption = "labels";
  const Fingertips* truth_tips = nullptr;  // optional annotated fingertips, drawn as crosses
  std::string name;                        // caption: what the frame is (file or "frame N")
};

struct RenderOptions {
  bool crop = false;       // zoom every panel onto the segmented hand
  int panel_height = 0;    // px; 0 = the image height (360 with crop)
};

// The panels side by side: (a) depth + hand mask, (b) quadtree Gaussians, (c) model + skeleton,
// (d) labels when given. Throws std::invalid_argument if a required pointer is null.
RgbImage render_frame(const FrameView& frame, const RenderOptions& options = {});

// The tracker's input of a left hand (of the mirrored frame) back in the frame's own image: mask,
// labels, depth and quadtree Gaussians flipped left to right, points and axes with x negated.
DepthInput unmirrored(const DepthInput& input);

// Mean distance between the tracked and the annotated fingertips, mm; nullopt if none annotated.
std::optional<double> fingertip_error_mm(const TrackerOutput& output, const Fingertips& truth);

}  // namespace handtrack::view
