// pinch_click: an HCI example. Turns live hands into pinch-to-click events, each hand (up to
// HANDTRACK_MAX_HANDS) on its own, one JSON object a line on stdout:
//   {"event":"pinch_start","hand_id":3,"handedness":"right","frame":812,"position_mm":[12.5,-30.1,402.7],"distance_mm":11.2,"strength":0.86}
//   {"event":"pinch_end","hand_id":3,"handedness":"right","frame":851,"position_mm":[...],"distance_mm":34.0,"strength":0.12,"duration_ms":650.0,"reason":"released"}
// position_mm is the midpoint of the hand's thumb and index fingertips (camera frame, mm): where the
// "click" happens. Start/end come from the client library's gestures (handtrack::Gestures, with
// hysteresis, per hand_id; docs/GESTURES.md); a hand that leaves ends its pinch (reason
// "hand_lost", not "released", at the last place it was seen).
//   Usage: pinch_click [--shm-name NAME] [--events N] [--timeout S]
//   --events N: exit 0 after N events; --timeout S: exit 1 when no frame arrives for S seconds.
#include <handtrack/client.hpp>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

// What pinch_click remembers of a hand between frames: where its pinch is and when it began.
struct PinchingHand {
  std::uint32_t hand_id = 0;  // 0: free entry
  float position_mm[3] = {};
  float distance_mm = 0.0F;
  std::int64_t start_ns = 0;
};

// The entry of `hand_id`, or a free one for it (there are enough: a frame's hands plus the ones
// that left in it).
PinchingHand& entry(PinchingHand (&hands)[HANDTRACK_GESTURE_MAX_STATES], std::uint32_t hand_id) {
  PinchingHand* free_entry = nullptr;
  for (PinchingHand& h : hands) {
    if (h.hand_id == hand_id) return h;
    if (h.hand_id == 0 && free_entry == nullptr) free_entry = &h;
  }
  *free_entry = PinchingHand{};
  free_entry->hand_id = hand_id;
  return *free_entry;
}

// duration_ms < 0 and reason == nullptr for pinch_start.
void print_event(const char* event, const handtrack_gesture_state& g, std::uint64_t frame, const PinchingHand& h,
                 double duration_ms, const char* reason) {
  std::printf("{\"event\":\"%s\",\"hand_id\":%u,\"handedness\":\"%s\",\"frame\":%llu,"
              "\"position_mm\":[%.1f,%.1f,%.1f],\"distance_mm\":%.1f,\"strength\":%.3f",
              event, static_cast<unsigned>(g.hand_id), handtrack_handedness_name(g.handedness),
              static_cast<unsigned long long>(frame), static_cast<double>(h.position_mm[0]),
              static_cast<double>(h.position_mm[1]), static_cast<double>(h.position_mm[2]),
              static_cast<double>(h.distance_mm), static_cast<double>(g.strength[HANDTRACK_GESTURE_PINCH]));
  if (duration_ms >= 0.0) std::printf(",\"duration_ms\":%.1f", duration_ms);
  if (reason != nullptr) std::printf(",\"reason\":\"%s\"", reason);
  std::printf("}\n");
  std::fflush(stdout);  // events are for other programs: one line as soon as it happens
}

int usage() {
  std::fprintf(stderr, "usage: pinch_click [--shm-name NAME] [--events N] [--timeout S]\n");
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  std::string name = HANDTRACK_DEFAULT_SHM_NAME;
  long max_events = 0;  // 0: for ever
  double timeout_s = 0.0;  // 0: wait for ever
  for (int i = 1; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (std::strcmp(argv[i], "--shm-name") == 0 && has_value) {
      name = argv[++i];
    } else if (std::strcmp(argv[i], "--events") == 0 && has_value) {
      max_events = std::strtol(argv[++i], nullptr, 10);
    } else if (std::strcmp(argv[i], "--timeout") == 0 && has_value) {
      timeout_s = std::strtod(argv[++i], nullptr);
    } else {
      return usage();
    }
  }
  if (max_events < 0 || timeout_s < 0.0) return usage();

  handtrack::Client client;
  if (const int status = client.open(name); status != HANDTRACK_OK) {
    std::fprintf(stderr, "pinch_click: %s\n", handtrack::Client::describe(status).c_str());
    return 1;
  }
  handtrack::Gestures gestures;
  PinchingHand pinching[HANDTRACK_GESTURE_MAX_STATES];
  handtrack_frame frame{};
  long events = 0;
  auto last_frame = std::chrono::steady_clock::now();
  while (max_events == 0 || events < max_events) {
    const int status = client.wait_next(frame, std::chrono::milliseconds(500));
    const auto now = std::chrono::steady_clock::now();
    if (status != HANDTRACK_OK) {
      if (status < 0 && status != HANDTRACK_ERR_WRITER_DEAD && status != HANDTRACK_ERR_WRITER_STOPPED) {
        std::fprintf(stderr, "pinch_click: %s\n", handtrack::Client::describe(status).c_str());
        return 1;
      }
      if (timeout_s > 0.0 && std::chrono::duration<double>(now - last_frame).count() > timeout_s) {
        std::fprintf(stderr, "pinch_click: no frame for %.1f s\n", timeout_s);
        return 1;
      }
      continue;
    }
    last_frame = now;
    // The frame's hands come first, in its order (g.present), then the hands that left.
    const handtrack::Hands hands = handtrack::hands(frame);
    for (const handtrack_gesture_state& g : gestures.update(frame)) {
      PinchingHand& h = entry(pinching, g.hand_id);
      if (g.present != 0) {
        for (const handtrack_hand& hand : hands) {
          if (hand.hand_id != g.hand_id) continue;
          for (int k = 0; k < 3; ++k) h.position_mm[k] = 0.5F * (hand.fingertips_mm[0][k] + hand.fingertips_mm[1][k]);
          h.distance_mm = hand.pinch_distance_mm;
        }
      }
      switch (g.event[HANDTRACK_GESTURE_PINCH]) {
        case HANDTRACK_GESTURE_START:
          h.start_ns = frame.capture_ns;
          print_event("pinch_start", g, frame.frame, h, -1.0, nullptr);
          ++events;
          break;
        case HANDTRACK_GESTURE_END:
          print_event("pinch_end", g, frame.frame, h, static_cast<double>(frame.capture_ns - h.start_ns) / 1e6,
                      g.present != 0 ? "released" : "hand_lost");
          ++events;
          break;
        default:
          break;
      }
      if (g.present == 0) h = PinchingHand{};  // gone: its id is never seen again
    }
  }
  return 0;
}
