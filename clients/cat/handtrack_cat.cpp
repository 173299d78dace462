// handtrack-cat: print poses from handtrackd's shared memory, one JSON object a line.
//
// Fields (SPEC.md, "handtrack-cat"): frame, epoch, state, capture_ns, publish_ns, confidence,
// energy, params (26), joints (21 x [x,y,z] mm), fingertips (5 x [x,y,z] mm, thumb..little),
// pinch {distance_mm, strength}, missed; plus timings_ms, palm and hand_scale.
// Numbers are printed with std::to_chars (shortest text that reads back to the same float or
// double); a non-finite value is printed as null (JSON has no NaN).
#include <handtrack/client.hpp>

#include "handtrack/common/cli.hpp"

#include <charconv>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>

namespace {

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

void format_pose(const handtrack_pose& p, std::uint64_t missed, Line& out) {
  out.text().clear();
  out.raw("{");
  out.key("frame"), out.number(p.frame), out.raw(",");
  out.key("epoch"), out.number(p.epoch), out.raw(",");
  out.key("state"), out.raw("\""), out.raw(handtrack_state_name(p.state)), out.raw("\",");
  out.key("capture_ns"), out.number(p.capture_ns), out.raw(",");
  out.key("publish_ns"), out.number(p.publish_ns), out.raw(",");
  out.key("confidence"), out.number(p.confidence), out.raw(",");
  out.key("energy"), out.number(p.energy), out.raw(",");
  out.key("params"), out.array(p.params, HANDTRACK_NUM_PARAMS), out.raw(",");
  out.key("joints"), out.points<float, HANDTRACK_NUM_JOINTS>(p.joints_mm), out.raw(",");
  out.key("fingertips"), out.points<float, HANDTRACK_NUM_FINGERTIPS>(p.fingertips_mm), out.raw(",");
  out.raw("\"pinch\":{");
  out.key("distance_mm"), out.number(p.pinch_distance_mm), out.raw(",");
  out.key("strength"), out.number(p.pinch_strength), out.raw("},");
  out.raw("\"timings_ms\":{");
  out.key("grab"), out.number(p.grab_ms), out.raw(",");
  out.key("preprocess"), out.number(p.preprocess_ms), out.raw(",");
  out.key("optimize"), out.number(p.optimize_ms), out.raw(",");
  out.key("publish"), out.number(p.publish_ms), out.raw("},");
  out.raw("\"palm\":{");
  out.key("center_mm"), out.array(p.palm_center_mm, 3), out.raw(",");
  out.key("normal"), out.array(p.palm_normal, 3), out.raw("},");
  out.raw("\"hand_scale\":{");
  out.key("length"), out.number(p.hand_scale[0]), out.raw(",");
  out.key("width"), out.number(p.hand_scale[1]), out.raw(",");
  out.key("sigma"), out.number(p.hand_scale[2]), out.raw("},");
  out.key("missed"), out.number(missed);
  out.raw("}\n");
}

void format_status(const handtrack_writer_status& s, Line& out) {
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

int fail(const std::string& message) { return handtrack::report_error("handtrack-cat", message, 1); }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Print hand poses from handtrackd's shared memory, one JSON object a line."};
  std::string shm_name = HANDTRACK_DEFAULT_SHM_NAME;
  std::uint64_t count = 0;
  double timeout_s = -1;
  bool latest_only = false;
  bool status_only = false;
  bool smooth = false;
  bool from_start = false;
  app.add_option("--shm-name", shm_name, "shared-memory object name")->capture_default_str();
  app.add_option("--count", count, "stop after N poses (0: never)")->check(CLI::NonNegativeNumber);
  app.add_option("--timeout", timeout_s,
                 "give up (exit 1) when no pose arrives for S seconds, including waiting for "
                 "the daemon to appear (default: wait forever)")
      ->check(CLI::PositiveNumber);
  app.add_flag("--latest", latest_only, "print only the newest pose when several are waiting");
  app.add_flag("--status", status_only, "print the daemon's status and statistics once and exit");
  app.add_flag("--from-start", from_start,
               "begin with the oldest pose still in the ring instead of the next new one");
  app.add_flag("--smooth", smooth,
               "smooth joints, fingertips and palm with the client library's One Euro filter (its defaults; "
               "docs/FILTER.md)");
  if (const auto exit_code = handtrack::parse_command_line(app, argc, argv, "handtrack-cat", 1)) return *exit_code;
  std::signal(SIGPIPE, SIG_IGN);  // a closed pipe (| head) ends us through fwrite's error

  using Clock = std::chrono::steady_clock;
  const bool has_timeout = timeout_s > 0;
  const auto timeout = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));

  handtrack::Client client;
  auto deadline = Clock::now() + timeout;
  for (;;) {
    const int st = client.open(shm_name);
    if (st == HANDTRACK_OK) break;
    const bool transient = st == HANDTRACK_ERR_NOT_FOUND || st == HANDTRACK_ERR_NOT_READY;
    if (!transient || !has_timeout || Clock::now() >= deadline) {
      return fail(handtrack::Client::describe(st));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }

  Line line;
  if (status_only) {
    handtrack_writer_status status{};
    if (const int st = client.writer_status(status); st != HANDTRACK_OK) {
      return fail(handtrack::Client::describe(st));
    }
    format_status(status, line);
    std::fwrite(line.text().data(), 1, line.text().size(), stdout);
    return std::fflush(stdout) == 0 ? 0 : 1;
  }

  if (from_start) client.rewind();
  handtrack_pose pose{};
  handtrack::PoseFilter filter;
  std::uint64_t printed = 0;
  int last_trouble = HANDTRACK_OK;
  deadline = Clock::now() + timeout;
  while (count == 0 || printed < count) {
    const auto wait_for = has_timeout ? std::max(deadline - Clock::now(), Clock::duration::zero())
                                      : std::chrono::duration_cast<Clock::duration>(std::chrono::seconds(1));
    const int st = latest_only ? client.wait_latest(pose, wait_for) : client.wait_next(pose, wait_for);
    if (st == HANDTRACK_OK) {
      last_trouble = HANDTRACK_OK;
      if (smooth) filter.apply(pose);
      format_pose(pose, client.missed(), line);
      if (std::fwrite(line.text().data(), 1, line.text().size(), stdout) != line.text().size() ||
          std::fflush(stdout) != 0) {
        return 0;  // the reader of our output went away
      }
      ++printed;
      deadline = Clock::now() + timeout;
      continue;
    }
    if (st == HANDTRACK_ERR_WRITER_DEAD || st == HANDTRACK_ERR_WRITER_STOPPED) {
      if (st != last_trouble && !has_timeout) {  // with --timeout the exit line says it
        std::fprintf(stderr, "handtrack-cat: %s; waiting for it to come back\n", handtrack_strerror(st));
      }
      last_trouble = st;
    } else if (st != HANDTRACK_TIMEOUT) {
      return fail(handtrack::Client::describe(st));
    }
    if (has_timeout && Clock::now() >= deadline) {
      char message[160];
      std::snprintf(message, sizeof message, "no pose within %g s on '/%s'%s%s%s", timeout_s,
                    shm_name.c_str(), last_trouble != HANDTRACK_OK ? " (" : "",
                    last_trouble != HANDTRACK_OK ? handtrack_strerror(last_trouble) : "",
                    last_trouble != HANDTRACK_OK ? ")" : "");
      return fail(message);
    }
  }
  return 0;
}
