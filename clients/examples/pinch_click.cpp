// pinch_click: an HCI example. Turns live poses into pinch-to-click events, one JSON object a
// line on stdout:
//   {"event":"pinch_start","frame":812,"position_mm":[12.5,-30.1,402.7],"distance_mm":11.2,"strength":0.86}
//   {"event":"pinch_end","frame":851,"position_mm":[...],"distance_mm":34.0,"strength":0.12,"duration_ms":650.0,"reason":"released"}
// position_mm is the midpoint of the thumb and index fingertips (camera frame, mm): where the
// "click" happens. Start/end come from the client library's gestures (handtrack::Gestures, with
// hysteresis; docs/GESTURES.md); losing the hand ends a pinch (reason "hand_lost", not "released").
//   Usage: pinch_click [--shm-name NAME] [--events N] [--timeout S]
//   --events N: exit 0 after N events; --timeout S: exit 1 when no pose arrives for S seconds.
#include <handtrack/client.hpp>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

// duration_ms < 0 and reason == nullptr for pinch_start.
void print_event(const char* event, const handtrack_pose& pose, float strength, double duration_ms,
                 const char* reason) {
  float mid[3];
  for (int k = 0; k < 3; ++k) mid[k] = 0.5F * (pose.fingertips_mm[0][k] + pose.fingertips_mm[1][k]);
  std::printf("{\"event\":\"%s\",\"frame\":%llu,\"position_mm\":[%.1f,%.1f,%.1f],"
              "\"distance_mm\":%.1f,\"strength\":%.3f",
              event, static_cast<unsigned long long>(pose.frame), static_cast<double>(mid[0]),
              static_cast<double>(mid[1]), static_cast<double>(mid[2]),
              static_cast<double>(pose.pinch_distance_mm), static_cast<double>(strength));
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
  handtrack_pose pose{};
  long events = 0;
  std::int64_t start_ns = 0;
  auto last_pose = std::chrono::steady_clock::now();
  while (max_events == 0 || events < max_events) {
    const int status = client.wait_next(pose, std::chrono::milliseconds(500));
    const auto now = std::chrono::steady_clock::now();
    if (status != HANDTRACK_OK) {
      if (status < 0 && status != HANDTRACK_ERR_WRITER_DEAD && status != HANDTRACK_ERR_WRITER_STOPPED) {
        std::fprintf(stderr, "pinch_click: %s\n", handtrack::Client::describe(status).c_str());
        return 1;
      }
      if (timeout_s > 0.0 && std::chrono::duration<double>(now - last_pose).count() > timeout_s) {
        std::fprintf(stderr, "pinch_click: no pose for %.1f s\n", timeout_s);
        return 1;
      }
      continue;
    }
    last_pose = now;
    // recovering still has a hand (the tracker restarts on it); only no_hand ends a pinch.
    const handtrack_gesture_state& g = gestures.update(pose);
    const float strength = g.strength[HANDTRACK_GESTURE_PINCH];
    switch (g.event[HANDTRACK_GESTURE_PINCH]) {
      case HANDTRACK_GESTURE_START:
        start_ns = pose.capture_ns;
        print_event("pinch_start", pose, strength, -1.0, nullptr);
        ++events;
        break;
      case HANDTRACK_GESTURE_END:
        print_event("pinch_end", pose, strength, static_cast<double>(pose.capture_ns - start_ns) / 1e6,
                    pose.state != HANDTRACK_STATE_NO_HAND ? "released" : "hand_lost");
        ++events;
        break;
      default:
        break;
    }
  }
  return 0;
}
