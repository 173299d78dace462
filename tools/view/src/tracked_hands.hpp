#pragma once
// What handtrack-view shows of a HandsTracker frame: each reported hand with the input its slot
// fitted, in the frame's own image.

#include "render.hpp"

#include "handtrack/core/hands_tracker.hpp"

#include <vector>

namespace handtrack::view {

struct TrackedHand {
  int slot = 0;           // HandsTracker slot
  TrackerOutput output;   // state kNoHand: the frame has no hand; this is what slot `slot` segmented
  DepthInput input;       // the slot's input of output.handedness, unmirrored() for a left hand
  const HandModel* model = nullptr;
};

// The hands of `out` (the frame tracker.track() just returned), in slot order. A frame without
// hands gives the input of the first slot that had one (no hand fitted to it), as a Tracker alone
// shows it; nothing when no slot had an input. Throws std::runtime_error if a reported hand's
// input is missing (a HandsTracker bug).
std::vector<TrackedHand> tracked_hands(HandsTracker& tracker, const HandsOutput& out);

// The hands as render_frame() draws them (pointing into `hands`, which must outlive the views).
std::vector<HandView> hand_views(const std::vector<TrackedHand>& hands);

}  // namespace handtrack::view
