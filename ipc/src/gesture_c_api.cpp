// Gestures of the C API (handtrack/client.h, handtrack_gesture*): strengths from a hand's joints,
// and start/end events with hysteresis, for each hand of a frame by its hand_id (docs/GESTURES.md).
#include <handtrack/client.h>

#include "hand_slots.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <new>

namespace {

// Joints (SPEC.md): 0 the wrist, then per finger (thumb..little) base, PIP, DIP, tip.
constexpr int kIndex = 1;
constexpr int kLittle = 4;
const float* joint(const handtrack_hand& p, int finger, int k) { return p.joints_mm[1 + 4 * finger + k]; }

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
float curl(const handtrack_hand& p, int finger) {
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

// The hysteresis of one hand.
struct HandGestures {
  uint32_t hand_id = 0;  // 0: free
  int32_t handedness = HANDTRACK_HANDEDNESS_UNKNOWN;
  bool active[HANDTRACK_NUM_GESTURES] = {};
};

// Hysteresis: on above HANDTRACK_GESTURE_ON, off below HANDTRACK_GESTURE_OFF or without a hand;
// in between nothing changes, so jitter around one threshold makes no burst of events.
void step(HandGestures& h, bool hand, handtrack_gesture_state& out) {
  out.hand_id = h.hand_id;
  out.handedness = h.handedness;
  out.present = hand ? 1 : 0;
  for (int g = 0; g < HANDTRACK_NUM_GESTURES; ++g) {
    bool& on = h.active[g];
    const bool was = on;
    if (!hand) {
      on = false;
    } else if (!on && out.strength[g] > HANDTRACK_GESTURE_ON) {
      on = true;
    } else if (on && out.strength[g] < HANDTRACK_GESTURE_OFF) {
      on = false;
    }
    out.active[g] = on ? 1 : 0;
    out.event[g] = on == was ? HANDTRACK_GESTURE_NONE : (on ? HANDTRACK_GESTURE_START : HANDTRACK_GESTURE_END);
  }
}

}  // namespace

// The hands of the last update, matched to the next frame's hands by hand_id.
struct handtrack_gestures {
  std::array<HandGestures, HANDTRACK_MAX_HANDS> hands;
};

extern "C" {

void handtrack_gesture_strengths(const handtrack_hand* hand, float out[HANDTRACK_NUM_GESTURES]) {
  if (out == nullptr) return;
  std::fill(out, out + HANDTRACK_NUM_GESTURES, 0.0F);
  if (hand == nullptr || hand->state == HANDTRACK_STATE_NO_HAND) return;
  const float pinch = distance(hand->fingertips_mm[0], hand->fingertips_mm[1]);
  out[HANDTRACK_GESTURE_PINCH] = unit((kPinchOpenMm - pinch) / (kPinchOpenMm - kPinchClosedMm));
  float others = 0.0F;  // middle..little
  for (int f = kIndex + 1; f <= kLittle; ++f) others += curl(*hand, f);
  others /= 3.0F;
  const float index = curl(*hand, kIndex);
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
  if (gestures != nullptr) gestures->hands.fill(HandGestures{});
}

int handtrack_gestures_update(handtrack_gestures* gestures, const handtrack_frame* frame,
                              handtrack_gesture_state out[HANDTRACK_GESTURE_MAX_STATES]) {
  using handtrack::ipc::detail::frame_has_hand;
  if (gestures == nullptr || frame == nullptr || out == nullptr) return HANDTRACK_ERR_INVALID_ARGUMENT;
  // The hands that left first (their states are then free for new hands), reported after the
  // frame's own hands.
  handtrack_gesture_state left[HANDTRACK_MAX_HANDS];
  int n_left = 0;
  for (HandGestures& h : gestures->hands) {
    if (h.hand_id == 0 || frame_has_hand(*frame, h.hand_id)) continue;
    handtrack_gesture_state& s = left[n_left++];
    std::fill(s.strength, s.strength + HANDTRACK_NUM_GESTURES, 0.0F);
    step(h, false, s);
    h = HandGestures{};
  }
  int n = 0;
  const uint32_t count = handtrack::ipc::detail::hand_count(*frame);
  for (uint32_t i = 0; i < count; ++i) {
    const handtrack_hand& hand = frame->hands[i];
    if (hand.hand_id == 0) continue;  // not a hand (a present hand never has id 0)
    HandGestures& mine = handtrack::ipc::detail::hand_state(gestures->hands, hand.hand_id);
    mine.handedness = hand.handedness;
    handtrack_gesture_state& s = out[n++];
    handtrack_gesture_strengths(&hand, s.strength);
    step(mine, hand.state != HANDTRACK_STATE_NO_HAND, s);
  }
  for (int k = 0; k < n_left; ++k) out[n++] = left[k];
  return n;
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
