// PinchDetector: thumb-index pinch start/end from a stream of poses, with hysteresis, for
// "pinch to click" (pinch_click.cpp). Header-only, no dependency but <cmath>.
//
// A pinch starts when the hand is tracked and the pinch is clearly closed:
//     strength > start_strength (0.8)  or  distance < start_distance_mm (15 mm),
// and ends only when it is clearly open again (or the hand is lost):
//     strength < end_strength (0.5)  and  distance > end_distance_mm (30 mm).
// Between the two bands nothing changes, so tracking jitter of a few mm around one threshold
// does not turn into a burst of clicks.
#pragma once

#include <cmath>

namespace handtrack::examples {

struct PinchThresholds {
  float start_strength = 0.8F;
  float start_distance_mm = 15.0F;
  float end_strength = 0.5F;
  float end_distance_mm = 30.0F;
};

enum class PinchEvent { kNone, kStart, kEnd };

class PinchDetector {
 public:
  explicit PinchDetector(PinchThresholds thresholds = {}) : t_(thresholds) {}

  // One pose: `tracked` is false when there is no hand; non-finite values count as no hand.
  PinchEvent update(bool tracked, float distance_mm, float strength) {
    const bool valid = tracked && std::isfinite(distance_mm) && std::isfinite(strength);
    if (!pinching_) {
      if (valid && (strength > t_.start_strength || distance_mm < t_.start_distance_mm)) {
        pinching_ = true;
        return PinchEvent::kStart;
      }
      return PinchEvent::kNone;
    }
    if (!valid || (strength < t_.end_strength && distance_mm > t_.end_distance_mm)) {
      pinching_ = false;
      return PinchEvent::kEnd;
    }
    return PinchEvent::kNone;
  }

  [[nodiscard]] bool pinching() const { return pinching_; }

 private:
  PinchThresholds t_;
  bool pinching_ = false;
};

}  // namespace handtrack::examples
