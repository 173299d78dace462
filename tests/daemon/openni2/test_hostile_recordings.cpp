// Hostile .oni recordings through the real handtrackd: OpenNI2's file driver runs in
// handtrack-source-helper (daemon/sources/isolated), so a recording that crashes or hangs it
// must never take the daemon down.
// - 240 mutants of the real recording (200 single-byte changes, half of them in the first 4 KiB
//   where the headers are, and 40 truncations), four daemons at a time: no death by signal, no
//   hang; a refused file gives exit 1 and one error line naming it; where the source failed while
//   streaming, the daemon stays alive, its ring says "error", and the log says why.
// - A helper killed by SIGSEGV while streaming (what a driver fault looks like): the same.
// - The helper's own log lines follow the daemon's format and level.
// Skips without the recording (../shared/data, only in the project workspace).
#include "../child_process.hpp"

#include "handtrack/client.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace {

namespace fs = std::filesystem;
using handtrack::test::Child;
using handtrack::test::ShmName;
using handtrack::test::TempDir;
using namespace std::chrono_literals;

const fs::path kRecording = fs::path(HANDTRACK_SHARED_DATA_DIR) / "oni" / "head-and-shoulders-640x480.oni";

#define SKIP_WITHOUT_RECORDING()                                                                  \
  if (!fs::exists(kRecording)) GTEST_SKIP() << "real recording " << kRecording << " is absent " \
                                               "(only in the project workspace); skipping"

std::vector<char> read_bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const fs::path& file, const std::vector<char>& bytes, std::size_t length) {
  std::ofstream(file, std::ios::binary | std::ios::trunc).write(bytes.data(), static_cast<std::streamsize>(length));
}

// The device state in the ring named `name`, or -1 when it cannot be read.
int ring_state(const std::string& name) {
  handtrack_client* client = nullptr;
  if (handtrack_open(name.c_str(), &client) != HANDTRACK_OK) return -1;
  handtrack_writer_status status{};
  const int rc = handtrack_writer_status_get(client, &status);
  handtrack_close(client);
  return rc == HANDTRACK_OK ? status.device_state : -1;
}

enum class Outcome { kPlayed, kRefused, kHelperDiedOpening, kFailedWhileStreaming };

struct PlayResult {
  Outcome outcome = Outcome::kPlayed;
  std::string problem;  // empty: the daemon behaved
};

// Plays `file` through handtrackd as fast as possible (at most 100 frames: a corrupt frame count
// must not make a long run) and judges what the daemon did. The recording's bytes are under test,
// not the tracker nor the pipeline: the tracker runs depth-only (loading the 26 MB part forest was
// half of each run) and the pipeline holds 4 frames (the default's 14 frames of 640x480 buffers,
// touched for the first time as the recording's 24 frames pass, were half of what was left: 0.55
// -> 0.29 s a play).
PlayResult play(const fs::path& file, const TempDir& dir, const std::string& shm) {
  const fs::path config = dir / "small.toml";
  if (!fs::exists(config)) {
    std::ofstream(config) << "[tracker]\nenergy_mode = \"depth-only\"\n[pipeline]\npool_frames = 4\nqueue_capacity = 1\n";
  }
  Child daemon({HANDTRACKD_EXE, "--config", config.string(), "--source", "oni:" + file.string(), "--fast", "--frames",
                "100", "--shm-name", shm, "--log-level", "warn"},
               dir / "out", dir / "err");
  PlayResult run;
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  std::optional<int> code;
  while (!(code = daemon.wait(20ms))) {
    if (ring_state(shm) == HANDTRACK_DEVICE_ERROR) {
      run.outcome = Outcome::kFailedWhileStreaming;
      std::this_thread::sleep_for(300ms);  // still alive a moment later, and still saying so
      if (daemon.wait(0ms)) {
        run.problem = "exited after its source failed";
      } else if (ring_state(shm) != HANDTRACK_DEVICE_ERROR) {
        run.problem = "the ring stopped saying error";
      }
      daemon.signal(SIGTERM);
      code = daemon.wait(10s);
      if (!code) return {run.outcome, "did not stop on SIGTERM"};
      if (*code != 0 && run.problem.empty()) run.problem = "exit " + std::to_string(*code) + " after SIGTERM";
      const std::string err = daemon.err();
      if (run.problem.empty() && err.find("error: oni:" + file.string() + ": the source helper") == std::string::npos) {
        run.problem = "no error line naming the recording and the helper:\n" + err;
      }
      return run;
    }
    if (std::chrono::steady_clock::now() > deadline) return {run.outcome, "hung for 30 s:\n" + daemon.err()};
  }
  if (*code >= 128) return {run.outcome, "died by signal " + std::to_string(*code - 128) + ":\n" + daemon.err()};
  if (*code == 0) return run;
  run.outcome = Outcome::kRefused;
  const auto lines = handtrack::test::lines_of(daemon.err());
  const bool clear = *code == 1 && !lines.empty() &&
                     lines.back().rfind("handtrackd: error: oni:" + file.string() + ": ", 0) == 0;
  if (!clear) run.problem = "exit " + std::to_string(*code) + " without one clear error line:\n" + daemon.err();
  if (clear && lines.back().find("the source helper") != std::string::npos) run.outcome = Outcome::kHelperDiedOpening;
  return run;
}

// One mutant of the recording: a byte changed, or the file cut short.
struct Mutation {
  std::size_t at = 0;      // the byte changed, or the length cut to
  char value = 0;
  bool truncation = false;
  [[nodiscard]] std::string describe() const {
    return truncation ? "truncated to " + std::to_string(at) + " bytes"
                      : "byte " + std::to_string(at) + " = " + std::to_string(static_cast<unsigned char>(value));
  }
};

TEST(HostileRecordings, MutantsNeverTakeTheDaemonDown) {
  SKIP_WITHOUT_RECORDING();
  const std::vector<char> original = read_bytes(kRecording);
  ASSERT_GT(original.size(), 65536U);
  constexpr int kByteMutants = 200;
  constexpr int kTruncations = 40;
  std::mt19937_64 rng(20261124);
  std::vector<Mutation> mutations;
  for (int i = 0; i < kByteMutants; ++i) {
    const std::size_t span = i % 2 == 0 ? 4096 : original.size();
    const std::size_t at = std::uniform_int_distribution<std::size_t>(0, span - 1)(rng);
    mutations.push_back({at, static_cast<char>(std::uniform_int_distribution<int>(0, 255)(rng)), false});
  }
  for (int i = 0; i < kTruncations; ++i) {
    mutations.push_back({std::uniform_int_distribution<std::size_t>(0, original.size() - 1)(rng), 0, true});
  }

  // Four daemons play mutants at once, each with its own file and ring: a play waits on OpenNI2
  // starting and shutting down its drivers in the helper, and the waits overlap.
  constexpr int kPlayers = 4;
  std::mutex mutex;
  std::map<Outcome, int> outcomes;
  std::vector<std::string> failures;
  std::atomic<std::size_t> next{0};
  const auto player = [&](int p) {
    const TempDir dir("oni-mutants-" + std::to_string(p));
    const ShmName shm("oni-mutants-" + std::to_string(p));
    const fs::path mutant = dir / "mutant.oni";
    std::vector<char> bytes = original;
    for (std::size_t i; (i = next++) < mutations.size();) {
      const Mutation& m = mutations[i];
      if (m.truncation) {
        write_bytes(mutant, original, m.at);
      } else {
        bytes[m.at] = m.value;
        write_bytes(mutant, bytes, bytes.size());
        bytes[m.at] = original[m.at];
      }
      const PlayResult run = play(mutant, dir, shm.str());
      const std::lock_guard lock(mutex);
      ++outcomes[run.outcome];
      if (!run.problem.empty()) failures.push_back("mutant " + std::to_string(i) + " (" + m.describe() + "): " + run.problem);
      if (failures.size() >= 5) next = mutations.size();
    }
  };
  std::vector<std::thread> players;
  for (int p = 0; p < kPlayers; ++p) players.emplace_back(player, p);
  for (auto& t : players) t.join();
  for (const auto& f : failures) ADD_FAILURE() << f;
  std::cout << mutations.size() << " mutants: " << outcomes[Outcome::kPlayed] << " played, "
            << outcomes[Outcome::kRefused] << " refused by OpenNI2 with an error line, "
            << outcomes[Outcome::kHelperDiedOpening] << " killed the helper while opening (exit 1, error line), "
            << outcomes[Outcome::kFailedWhileStreaming]
            << " failed while streaming (daemon alive, ring state error)\n";
}

// The helper's lines (OpenNI2 starting, the recording opened) reach the daemon's stderr in the
// daemon's format and obey its --log-level: none on stdout, none below the level.
TEST(OniThroughHandtrackd, TheHelperLogsLikeTheDaemonAtItsLevel) {
  SKIP_WITHOUT_RECORDING();
  const TempDir dir("oni-helper-log");
  const ShmName shm("oni-helper-log");
  for (const std::string level : {"info", "warn"}) {
    SCOPED_TRACE(level);
    Child daemon({HANDTRACKD_EXE, "--config", std::string(HANDTRACK_SOURCE_DIR) + "/data/handtrackd.toml", "--source",
                  "oni:" + kRecording.string(), "--fast", "--frames", "5", "--shm-name", shm.str(), "--log-level", level},
                 dir / "out", dir / "err");
    ASSERT_EQ(daemon.wait(30s), 0) << daemon.err();
    EXPECT_EQ(daemon.out(), "");
    const bool helper_line = daemon.err().find("handtrackd: info: OpenNI2 ") != std::string::npos;
    EXPECT_EQ(helper_line, level == "info") << daemon.err();
  }
}

// The helper's pid: the daemon's only child.
pid_t helper_of(pid_t daemon) {
  std::ifstream children("/proc/" + std::to_string(daemon) + "/task/" + std::to_string(daemon) + "/children");
  pid_t pid = 0;
  children >> pid;
  return pid;
}

TEST(HostileRecordings, AHelperKilledWhileStreamingLeavesTheDaemonAliveSayingError) {
  SKIP_WITHOUT_RECORDING();
  const TempDir dir("oni-helper-crash");
  const ShmName shm("oni-helper-crash");
  Child daemon({HANDTRACKD_EXE, "--config", std::string(HANDTRACK_SOURCE_DIR) + "/data/handtrackd.toml", "--source",
                "oni:" + kRecording.string(), "--loop", "--shm-name", shm.str(), "--log-level", "warn"},
               dir / "out", dir / "err");
  handtrack_client* client = nullptr;
  for (int i = 0; i < 200 && handtrack_open(shm.str().c_str(), &client) != HANDTRACK_OK; ++i) {
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_NE(client, nullptr) << daemon.err();
  handtrack_frame frame{};
  ASSERT_EQ(handtrack_wait_next(client, &frame, 10'000'000'000LL), HANDTRACK_OK) << daemon.err();
  const pid_t helper = helper_of(daemon.pid());
  ASSERT_GT(helper, 0) << "no helper process under the daemon";
  ASSERT_EQ(::kill(helper, SIGSEGV), 0);

  handtrack_writer_status status{};
  for (int i = 0; i < 100; ++i) {
    ASSERT_EQ(handtrack_writer_status_get(client, &status), HANDTRACK_OK);
    if (status.device_state == HANDTRACK_DEVICE_ERROR) break;
    std::this_thread::sleep_for(20ms);
  }
  EXPECT_EQ(status.device_state, HANDTRACK_DEVICE_ERROR);
  std::this_thread::sleep_for(500ms);  // several heartbeats: still alive, still saying error
  ASSERT_EQ(handtrack_writer_status_get(client, &status), HANDTRACK_OK);
  EXPECT_EQ(status.alive, 1);
  EXPECT_EQ(status.device_state, HANDTRACK_DEVICE_ERROR);
  EXPECT_FALSE(daemon.wait(0ms).has_value()) << daemon.err();
  handtrack_close(client);

  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait(10s), 0);
  const std::string err = daemon.err();
  EXPECT_NE(err.find("error: oni:" + kRecording.string() + ": the source helper (pid " + std::to_string(helper) +
                     ") was killed by signal 11"),
            std::string::npos)
      << err;
}

}  // namespace
