// Gestures of the C API (handtrack/client.h, handtrack_gesture*): strengths from a pose's joints,
// and start/end events with hysteresis (docs/GESTURES.md).
#include <handtrack/client.h>

#include <algorithm>
#include <cmath>
#include <new>

namespace {

// Joints (SPEC.md): 0 the wrist, then per finger (thumb..little) base, PIP, DIP, tip.
constexpr int kIndex = 1;
constexpr int kLittle = 4;
const float* joint(const handtrack_pose& p, int finger, int k) { return p.joints_mm[1 + 4 * finger + k]; }

float distance(const float* a, const float* b) {
  const float dx = a[0] - b[0];
  const float dy = a[1] - b[1];
  const float dz = a[2] - b[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

float unit(float x) { return std::isfinite(x) ? std::clamp(x, 0.0F, 1.0F) : 0.0F; }

// How curled a finger is, 0 (straight) .. 1 (curled into the palm): its reach (base to tip) over
// its length along the bones. A straight finger reaches 1.0 of its length; curled into a fist, a
// finger reaches about 0.45 of it (the synthetic fists: 0.40-0.50).
constexpr float kStraightReach = 0.95F;
constexpr float kCurledReach = 0.50F;
float curl(const handtrack_pose& p, int finger) {
  const float length = distance(joint(p, finger, 0), joint(p, finger, 1)) +
                       distance(joint(p, finger, 1), joint(p, finger, 2)) +
                       distance(joint(p, finger, 2), joint(p, finger, 3));
  if (!(length > 0.0F)) return 0.0F;
  const float reach = distance(joint(p, finger, 0), joint(p, finger, 3)) / length;
  return unit((kStraightReach - reach) / (kStraightReach - kCurledReach));
}

// Thumb and index tips (centres of the tip spheres) this far apart touch, and this far apart are
// fully open.
constexpr float kPinchClosedMm = 20.0F;
constexpr float kPinchOpenMm = 60.0F;

}  // namespace

struct handtrack_gestures {
  bool active[HANDTRACK_NUM_GESTURES] = {};
};

extern "C" {

void handtrack_gesture_strengths(const handtrack_pose* pose, float out[HANDTRACK_NUM_GESTURES]) {
  if (out == nullptr) return;
  std::fill(out, out + HANDTRACK_NUM_GESTURES, 0.0F);
  if (pose == nullptr || pose->state == HANDTRACK_STATE_NO_HAND) return;
  const float pinch = distance(pose->fingertips_mm[0], pose->fingertips_mm[1]);
  out[HANDTRACK_GESTURE_PINCH] = unit((kPinchOpenMm - pinch) / (kPinchOpenMm - kPinchClosedMm));
  float others = 0.0F;  // middle..little
  for (int f = kIndex + 1; f <= kLittle; ++f) others += curl(*pose, f);
  others /= 3.0F;
  const float index = curl(*pose, kIndex);
  out[HANDTRACK_GESTURE_GRAB] = unit(0.25F * index + 0.75F * others);
  out[HANDTRACK_GESTURE_POINT] = unit(std::min(1.0F - index, others));
}

int handtrack_gestures_new(handtrack_gestures** out) {
  if (out == nullptr) return HANDTRACK_ERR_INVALID_ARGUMENT;
  *out = new (std::nothrow) handtrack_gestures;
  return *out != nullptr ? HANDTRACK_OK : HANDTRACK_ERR_SYSTEM;
}

void handtrack_gestures_free(handtrack_gestures* gestures) { delete gestures; }

void handtrack_gestures_reset(handtrack_gestures* gestures) {
  if (gestures != nullptr) *gestures = handtrack_gestures{};
}

int handtrack_gestures_update(handtrack_gestures* gestures, const handtrack_pose* pose, handtrack_gesture_state* out) {
  if (gestures == nullptr || pose == nullptr || out == nullptr) return HANDTRACK_ERR_INVALID_ARGUMENT;
  handtrack_gesture_strengths(pose, out->strength);
  const bool hand = pose->state != HANDTRACK_STATE_NO_HAND;
  for (int g = 0; g < HANDTRACK_NUM_GESTURES; ++g) {
    bool& on = gestures->active[g];
    const bool was = on;
    // Hysteresis: on above HANDTRACK_GESTURE_ON, off below HANDTRACK_GESTURE_OFF or without a
    // hand; in between nothing changes, so jitter around one threshold makes no burst of events.
    if (!hand) {
      on = false;
    } else if (!on && out->strength[g] > HANDTRACK_GESTURE_ON) {
      on = true;
    } else if (on && out->strength[g] < HANDTRACK_GESTURE_OFF) {
      on = false;
    }
    out->active[g] = on ? 1 : 0;
    out->event[g] = on == was ? HANDTRACK_GESTURE_NONE : (on ? HANDTRACK_GESTURE_START : HANDTRACK_GESTURE_END);
  }
  return HANDTRACK_OK;
}

const char* handtrack_gesture_name(int gesture) {
  switch (gesture) {
    case HANDTRACK_GESTURE_PINCH: return "pinch";
    case HANDTRACK_GESTURE_GRAB: return "grab";
    case HANDTRACK_GESTURE_POINT: return "point";
    default: return "unknown";
  }
}

}  // extern "C"
