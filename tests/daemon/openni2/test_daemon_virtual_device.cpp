// The real handtrackd on `--source openni2` against the virtual OpenNI2 camera: the device
// states it publishes in the shared-memory header (read with the C client API) follow the
// camera being plugged in, pulled and plugged in again, frames resume after each return, and the
// daemon's threads and descriptors stay flat over the cycles; a log level changed by SIGHUP reaches
// the source helper that runs the camera. The daemon is driven only through its command line,
// configuration file, signals and environment (LD_LIBRARY_PATH to the staged OpenNI2, see
// virtual_stage.hpp).
#include "virtual_stage.hpp"

#include "handtrack/client.h"

#include <gtest/gtest.h>

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

namespace {

int count_entries(const std::string& dir) {
  int n = 0;
  if (DIR* d = opendir(dir.c_str())) {
    while (const dirent* e = readdir(d)) {
      if (e->d_name[0] != '.') ++n;
    }
    closedir(d);
  }
  return n;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// handtrackd with `config` as its configuration file (stage/handtrackd.toml), at --log-level
// `level` (none when empty: the file's).
class Daemon {
 public:
  Daemon(const std::string& stage, const std::string& shm, const std::string& config = "",
         const std::string& level = "info")
      : stage_(stage), log_(fs::path(stage) / "handtrackd.log") {
    const std::string config_file = stage + "/handtrackd.toml";
    std::ofstream(config_file) << config;
    pid_ = fork();
    if (pid_ == 0) {
      const int fd = ::open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      if (fd >= 0) {
        dup2(fd, STDOUT_FILENO);
        dup2(fd, STDERR_FILENO);
        ::close(fd);
      }
      setenv("LD_LIBRARY_PATH", stage.c_str(), 1);
      setenv(handtrack::test::kPlugFileEnv, (stage + "/plugged").c_str(), 1);
      unsetenv("NOTIFY_SOCKET");
      std::vector<const char*> argv = {HANDTRACKD_BINARY, "--source", "openni2", "--shm-name", shm.c_str(),
                                       "--config", config_file.c_str()};
      if (!level.empty()) argv.insert(argv.end(), {"--log-level", level.c_str()});
      argv.push_back(nullptr);
      execv(HANDTRACKD_BINARY, const_cast<char* const*>(argv.data()));
      _exit(127);
    }
  }
  ~Daemon() {
    if (pid_ > 0 && !reaped_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  [[nodiscard]] pid_t pid() const { return pid_; }
  [[nodiscard]] std::string log() const { return read_file(log_); }
  // Waits for `text` in the log.
  bool logged(const std::string& text, std::chrono::milliseconds within) const {
    const auto end = Clock::now() + within;
    for (;;) {
      if (log().find(text) != std::string::npos) return true;
      if (Clock::now() >= end) return false;
      std::this_thread::sleep_for(20ms);
    }
  }
  [[nodiscard]] bool running() {
    if (reaped_) return false;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      reaped_ = true;
      status_ = status;
      return false;
    }
    return true;
  }
  // SIGTERM, then the exit status (-1 if it had to be killed after `patience`).
  int stop(std::chrono::milliseconds patience) {
    if (!running()) return WIFEXITED(status_) ? WEXITSTATUS(status_) : -1;
    kill(pid_, SIGTERM);
    const auto end = Clock::now() + patience;
    while (Clock::now() < end) {
      if (!running()) return WIFEXITED(status_) ? WEXITSTATUS(status_) : -1;
      std::this_thread::sleep_for(20ms);
    }
    return -1;
  }

 private:
  std::string stage_;
  fs::path log_;
  pid_t pid_ = -1;
  bool reaped_ = false;
  int status_ = 0;
};

class VirtualDeviceDaemon : public ::testing::Test {
 protected:
  void SetUp() override {
    stage_ = handtrack::test::stage_openni2();
    shm_ = "handtrack-oni2-test-" + std::to_string(getpid());
  }
  void TearDown() override {
    if (client_) handtrack_close(client_);
    shm_unlink(("/" + shm_).c_str());
    std::error_code ec;
    fs::remove_all(stage_, ec);
  }
  void plug() { std::ofstream(stage_ + "/plugged") << "plugged\n"; }
  void unplug() { fs::remove(stage_ + "/plugged"); }

  bool connect(Daemon& d, std::chrono::milliseconds within) {
    const auto end = Clock::now() + within;
    while (Clock::now() < end && d.running()) {
      if (handtrack_open(shm_.c_str(), &client_) == HANDTRACK_OK) return true;
      std::this_thread::sleep_for(50ms);
    }
    return false;
  }
  handtrack_writer_status status() {
    handtrack_writer_status s{};
    EXPECT_EQ(handtrack_writer_status_get(client_, &s), HANDTRACK_OK);
    return s;
  }
  // Waits for the published device state; returns the time it took, or -1.
  int64_t wait_state(int32_t wanted, std::chrono::milliseconds within) {
    const auto t0 = Clock::now();
    while (Clock::now() - t0 < within) {
      if (status().device_state == wanted) {
        return std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - t0).count();
      }
      std::this_thread::sleep_for(10ms);
    }
    return -1;
  }
  // Waits until at least `more` further frames were captured (stats refresh about once a second).
  bool frames_grow(uint64_t more, std::chrono::milliseconds within) {
    const uint64_t start = status().stats.frames_captured;
    const auto end = Clock::now() + within;
    while (Clock::now() < end) {
      if (status().stats.frames_captured >= start + more) return true;
      std::this_thread::sleep_for(50ms);
    }
    return false;
  }

  std::string stage_;
  std::string shm_;
  handtrack_client* client_ = nullptr;
};

TEST_F(VirtualDeviceDaemon, PublishesDeviceStatesAcrossUnplugAndReplug) {
  unplug();  // the daemon starts with no camera
  Daemon daemon(stage_, shm_);
  ASSERT_TRUE(connect(daemon, 20s)) << "handtrackd never created its ring\n" << daemon.log();

  const char* waiting = "waiting_for_device";
  ASSERT_GE(wait_state(HANDTRACK_DEVICE_WAITING_FOR_DEVICE, 10s), 0)
      << "state " << handtrack_device_state_name(status().device_state) << ", want " << waiting << "\n"
      << daemon.log();
  EXPECT_TRUE(status().alive);

  int daemon_threads = -1;
  int daemon_fds = -1;
  constexpr int kCycles = 3;
  for (int cycle = 0; cycle < kCycles; ++cycle) {
    SCOPED_TRACE("cycle " + std::to_string(cycle));
    plug();
    const int64_t up_ms = wait_state(HANDTRACK_DEVICE_STREAMING, 10s);
    ASSERT_GE(up_ms, 0) << daemon.log();
    ASSERT_TRUE(frames_grow(30, 8s)) << "frames did not resume\n" << daemon.log();

    // Steady state while streaming: the same threads and descriptors every cycle.
    const std::string proc = "/proc/" + std::to_string(daemon.pid());
    int threads = count_entries(proc + "/task");
    int fds = count_entries(proc + "/fd");
    for (int i = 0; i < 50 && cycle > 0 && (threads != daemon_threads || fds != daemon_fds); ++i) {
      std::this_thread::sleep_for(20ms);
      threads = count_entries(proc + "/task");
      fds = count_entries(proc + "/fd");
    }
    if (cycle == 0) {
      daemon_threads = threads;
      daemon_fds = fds;
    }
    EXPECT_EQ(threads, daemon_threads);
    EXPECT_EQ(fds, daemon_fds);

    unplug();
    const int64_t down_ms = wait_state(HANDTRACK_DEVICE_WAITING_FOR_DEVICE, 5s);
    ASSERT_GE(down_ms, 0) << "unplug not published\n" << daemon.log();
    EXPECT_TRUE(daemon.running());
    EXPECT_TRUE(status().alive) << "the daemon stays up (heartbeat) while the camera is away";
    std::printf("cycle %d: streaming %lld ms after plug-in, waiting_for_device %lld ms after unplug; "
                "daemon threads %d, fds %d\n",
                cycle, static_cast<long long>(up_ms), static_cast<long long>(down_ms), threads, fds);
  }

  EXPECT_EQ(daemon.stop(10s), 0) << daemon.log();
  const std::string log = daemon.log();
  EXPECT_NE(log.find("handtrack-virtual://depth0"), std::string::npos) << log;
}

// The camera runs in the source helper (a process of its own); a SIGHUP that raises
// daemon.log_level from warn to info reaches the helper already running: its OpenNI2 line when the
// camera is pulled ("device disconnected") appears, where before the reload its start-up lines did
// not.
TEST_F(VirtualDeviceDaemon, ASighupLogLevelReachesTheRunningHelper) {
  const std::string at_warn = "[daemon]\nlog_level = \"warn\"\n";
  plug();
  Daemon daemon(stage_, shm_, at_warn, "");
  ASSERT_TRUE(connect(daemon, 20s)) << "handtrackd never created its ring\n" << daemon.log();
  ASSERT_GE(wait_state(HANDTRACK_DEVICE_STREAMING, 10s), 0) << daemon.log();
  ASSERT_TRUE(frames_grow(5, 8s)) << daemon.log();
  EXPECT_EQ(daemon.log().find("info: OpenNI2"), std::string::npos) << "the helper logs below warn\n" << daemon.log();

  std::ofstream(stage_ + "/handtrackd.toml") << "[daemon]\nlog_level = \"info\"\n";
  ASSERT_EQ(kill(daemon.pid(), SIGHUP), 0);
  ASSERT_TRUE(daemon.logged("SIGHUP: configuration reloaded", 10s)) << daemon.log();
  ASSERT_TRUE(frames_grow(5, 8s)) << "the helper's grabs carry the new level\n" << daemon.log();
  unplug();
  ASSERT_GE(wait_state(HANDTRACK_DEVICE_WAITING_FOR_DEVICE, 5s), 0) << daemon.log();
  EXPECT_TRUE(daemon.logged("info: OpenNI2: device disconnected", 5s)) << daemon.log();
  EXPECT_EQ(daemon.stop(10s), 0) << daemon.log();
}

}  // namespace
