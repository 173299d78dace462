// handtrack-cat: print frames (every hand of each) from handtrackd's shared memory, one JSON object
// a line.
//
// The objects are clients/json/pose_json.hpp's (SPEC.md "handtrack-cat"), as handtrack-ws sends.
#include <handtrack/client.hpp>

#include "pose_json.hpp"

#include "handtrack/common/cli.hpp"

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>

namespace {

using handtrack::json::format_frame;
using handtrack::json::format_status;
using handtrack::json::Line;

int fail(const std::string& message) { return handtrack::report_error("handtrack-cat", message, 1); }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Print hand poses from handtrackd's shared memory, one JSON object per frame (its hands) a line."};
  std::string shm_name = HANDTRACK_DEFAULT_SHM_NAME;
  std::uint64_t count = 0;
  double timeout_s = -1;
  bool latest_only = false;
  bool status_only = false;
  bool smooth = false;
  bool from_start = false;
  app.add_option("--shm-name", shm_name, "shared-memory object name")->capture_default_str();
  app.add_option("--count", count, "stop after N frames (0: never)")->check(CLI::NonNegativeNumber);
  app.add_option("--timeout", timeout_s,
                 "give up (exit 1) when no frame arrives for S seconds, including waiting for "
                 "the daemon to appear (default: wait forever)")
      ->check(CLI::PositiveNumber);
  app.add_flag("--latest", latest_only, "print only the newest frame when several are waiting");
  app.add_flag("--status", status_only, "print the daemon's status and statistics once and exit");
  app.add_flag("--from-start", from_start,
               "begin with the oldest frame still in the ring instead of the next new one");
  app.add_flag("--smooth", smooth,
               "smooth each hand's joints, fingertips and palm with the client library's One Euro filter (its defaults; "
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
  handtrack_frame frame{};
  handtrack::PoseFilter filter;
  std::uint64_t printed = 0;
  int last_trouble = HANDTRACK_OK;
  deadline = Clock::now() + timeout;
  while (count == 0 || printed < count) {
    const auto wait_for = has_timeout ? std::max(deadline - Clock::now(), Clock::duration::zero())
                                      : std::chrono::duration_cast<Clock::duration>(std::chrono::seconds(1));
    const int st = latest_only ? client.wait_latest(frame, wait_for) : client.wait_next(frame, wait_for);
    if (st == HANDTRACK_OK) {
      last_trouble = HANDTRACK_OK;
      if (smooth) filter.apply(frame);
      format_frame(frame, client.missed(), line);
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
      std::snprintf(message, sizeof message, "no frame within %g s on '/%s'%s%s%s", timeout_s,
                    shm_name.c_str(), last_trouble != HANDTRACK_OK ? " (" : "",
                    last_trouble != HANDTRACK_OK ? handtrack_strerror(last_trouble) : "",
                    last_trouble != HANDTRACK_OK ? ")" : "");
      return fail(message);
    }
  }
  return 0;
}
