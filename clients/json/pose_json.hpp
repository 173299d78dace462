#pragma once
// One frame (or the writer status) as one line of JSON: what handtrack-cat prints and handtrack-ws
// sends (SPEC.md "handtrack-cat", ABI version 2): frame, epoch, capture_ns, publish_ns, missed,
// timings_ms, and hands: a list (empty when no hand is seen) of objects with hand_id, handedness
// ("left"/"right"), handedness_confidence, state, confidence, energy, optimize_ms, params (26),
// joints (21 x [x,y,z] mm), fingertips (5 x [x,y,z] mm, thumb..little), pinch {distance_mm,
// strength}, palm and hand_scale.
// Numbers are printed with std::to_chars (shortest text that reads back to the same float or
// double); a non-finite value is printed as null (JSON has no NaN). No allocation once a Line's
// text has grown to a frame's size.
//
// Thread roles: reentrant: a Line belongs to one thread at a time.
#include <handtrack/client.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <type_traits>

namespace handtrack::json {

class Line {
 public:
  void raw(const char* s) { text_ += s; }
  void key(const char* k) {
    text_ += '"';
    text_ += k;
    text_ += "\":";
  }
  template <typename T>
  void number(T value) {
    if constexpr (std::is_floating_point_v<T>) {
      if (!std::isfinite(value)) {
        text_ += "null";
        return;
      }
    }
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
    text_.append(buffer, result.ptr);
  }
  template <typename T>
  void array(const T* values, int n) {
    text_ += '[';
    for (int i = 0; i < n; ++i) {
      if (i > 0) text_ += ',';
      number(values[i]);
    }
    text_ += ']';
  }
  template <typename T, int N>
  void points(const T (*rows)[3]) {
    text_ += '[';
    for (int i = 0; i < N; ++i) {
      if (i > 0) text_ += ',';
      array(rows[i], 3);
    }
    text_ += ']';
  }
  std::string& text() { return text_; }

 private:
  std::string text_;
};

inline void format_hand(const handtrack_hand& h, Line& out) {
  out.raw("{");
  out.key("hand_id"), out.number(h.hand_id), out.raw(",");
  out.key("handedness"), out.raw("\""), out.raw(handtrack_handedness_name(h.handedness)), out.raw("\",");
  out.key("handedness_confidence"), out.number(h.handedness_confidence), out.raw(",");
  out.key("state"), out.raw("\""), out.raw(handtrack_state_name(h.state)), out.raw("\",");
  out.key("confidence"), out.number(h.confidence), out.raw(",");
  out.key("energy"), out.number(h.energy), out.raw(",");
  out.key("optimize_ms"), out.number(h.optimize_ms), out.raw(",");
  out.key("params"), out.array(h.params, HANDTRACK_NUM_PARAMS), out.raw(",");
  out.key("joints"), out.points<float, HANDTRACK_NUM_JOINTS>(h.joints_mm), out.raw(",");
  out.key("fingertips"), out.points<float, HANDTRACK_NUM_FINGERTIPS>(h.fingertips_mm), out.raw(",");
  out.raw("\"pinch\":{");
  out.key("distance_mm"), out.number(h.pinch_distance_mm), out.raw(",");
  out.key("strength"), out.number(h.pinch_strength), out.raw("},");
  out.raw("\"palm\":{");
  out.key("center_mm"), out.array(h.palm_center_mm, 3), out.raw(",");
  out.key("normal"), out.array(h.palm_normal, 3), out.raw("},");
  out.raw("\"hand_scale\":{");
  out.key("length"), out.number(h.hand_scale[0]), out.raw(",");
  out.key("width"), out.number(h.hand_scale[1]), out.raw(",");
  out.key("sigma"), out.number(h.hand_scale[2]), out.raw("}}");
}

inline void format_frame(const handtrack_frame& f, std::uint64_t missed, Line& out) {
  out.text().clear();
  out.raw("{");
  out.key("frame"), out.number(f.frame), out.raw(",");
  out.key("epoch"), out.number(f.epoch), out.raw(",");
  out.key("capture_ns"), out.number(f.capture_ns), out.raw(",");
  out.key("publish_ns"), out.number(f.publish_ns), out.raw(",");
  out.raw("\"timings_ms\":{");
  out.key("grab"), out.number(f.grab_ms), out.raw(",");
  out.key("preprocess"), out.number(f.preprocess_ms), out.raw(",");
  out.key("optimize"), out.number(f.optimize_ms), out.raw(",");
  out.key("publish"), out.number(f.publish_ms), out.raw("},");
  out.key("hands"), out.raw("[");
  const std::uint32_t count = f.hand_count < HANDTRACK_MAX_HANDS ? f.hand_count : HANDTRACK_MAX_HANDS;
  for (std::uint32_t i = 0; i < count; ++i) {
    if (i > 0) out.raw(",");
    format_hand(f.hands[i], out);
  }
  out.raw("],");
  out.key("missed"), out.number(missed);
  out.raw("}\n");
}

inline void format_status(const handtrack_writer_status& s, Line& out) {
  out.text().clear();
  out.raw("{\"device_state\":\""), out.raw(handtrack_device_state_name(s.device_state)), out.raw("\",");
  out.key("alive"), out.raw(s.alive != 0 ? "true," : "false,");
  out.key("writer_pid"), out.number(s.writer_pid), out.raw(",");
  out.key("epoch"), out.number(s.epoch), out.raw(",");
  out.key("capacity"), out.number(s.capacity), out.raw(",");
  out.key("records_published"), out.number(s.records_published), out.raw(",");
  out.key("heartbeat_age_ms"), out.number(static_cast<double>(s.heartbeat_age_ns) / 1e6), out.raw(",");
  out.key("heartbeat_period_ms"), out.number(static_cast<double>(s.heartbeat_period_ns) / 1e6), out.raw(",");
  out.raw("\"stats\":{");
  out.key("fps"), out.number(s.stats.fps), out.raw(",");
  out.key("grab_ms"), out.number(s.stats.grab_ms), out.raw(",");
  out.key("preprocess_ms"), out.number(s.stats.preprocess_ms), out.raw(",");
  out.key("optimize_ms"), out.number(s.stats.optimize_ms), out.raw(",");
  out.key("publish_ms"), out.number(s.stats.publish_ms), out.raw(",");
  out.key("latency_p50_ms"), out.number(s.stats.latency_p50_ms), out.raw(",");
  out.key("latency_p99_ms"), out.number(s.stats.latency_p99_ms), out.raw(",");
  out.key("frames_captured"), out.number(s.stats.frames_captured), out.raw(",");
  out.key("frames_dropped"), out.number(s.stats.frames_dropped), out.raw(",");
  out.key("frames_skipped"), out.number(s.stats.frames_skipped), out.raw(",");
  out.key("source_errors"), out.number(s.stats.source_errors), out.raw("}}\n");
}

}  // namespace handtrack::json
