#include "tracked_hands.hpp"

#include <stdexcept>
#include <string>

namespace handtrack::view {
namespace {

DepthInput input_in_frame(const DepthInput& input, Handedness hand) {
  return hand == Handedness::kLeft ? unmirrored(input) : input;
}

}  // namespace

std::vector<TrackedHand> tracked_hands(HandsTracker& tracker, const HandsOutput& out) {
  const HandsInputs& inputs = tracker.last_inputs();
  std::vector<TrackedHand> hands;
  for (int k = 0; k < out.count; ++k) {
    const TrackerOutput& output = out.hands[static_cast<size_t>(k)];
    const int s = out.slot[static_cast<size_t>(k)];
    const DepthInput* input = inputs.has(s) ? inputs.slot(s).get(output.handedness) : nullptr;
    if (input == nullptr) {
      throw std::runtime_error("the tracker preprocessed no input for hand #" + std::to_string(output.hand_id) +
                               " it reports");
    }
    hands.push_back({s, output, input_in_frame(*input, output.handedness), &tracker.slot_tracker(s).model()});
  }
  if (!hands.empty()) return hands;
  // No hand: what the first slot with an input segmented (its right hand's, else its left's).
  for (int s = 0; s < tracker.max_hands(); ++s) {
    if (!inputs.has(s)) continue;
    for (const Handedness side : {Handedness::kRight, Handedness::kLeft}) {
      if (const DepthInput* input = inputs.slot(s).get(side)) {
        hands.push_back({s, TrackerOutput{}, input_in_frame(*input, side), &tracker.slot_tracker(s).model()});
        return hands;
      }
    }
  }
  return hands;
}

std::vector<HandView> hand_views(const std::vector<TrackedHand>& hands) {
  std::vector<HandView> views;
  for (const TrackedHand& h : hands) {
    views.push_back({&h.input, &h.output, h.model, h.output.handedness == Handedness::kLeft, h.slot});
  }
  return views;
}

}  // namespace handtrack::view
