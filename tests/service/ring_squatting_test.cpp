// Another local user takes the ring's name before the daemon does (SPEC.md "Shared memory",
// docs/SECURITY.md): /dev/shm lets anyone create any name. Three squats, each made by a real
// process of another uid: garbage bytes, a stopped handtrack segment full of fake poses, and a
// live-looking fake writer that keeps publishing and heartbeating. In every case
// - a client (root included) refuses the segment and names its owner: no fake pose is ever read;
// - handtrackd as root removes it without writing into it, and clients then read its real poses;
// - handtrackd as a user who may not remove it (the service user) fails with one line naming the
//   owner.
// Needs root (to be the other users); skips otherwise.
#include "../daemon/child_process.hpp"
#include "other_user.hpp"

#include <handtrack/client.h>
#include <handtrack/ipc/pose_ring_writer.hpp>

#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>
#include <vector>

namespace {

using handtrack::test::Child;
using handtrack::test::Identity;
using handtrack::test::TempDir;
using namespace std::chrono_literals;

constexpr Identity kSquatter{46110, 46110};
constexpr Identity kServiceUser{46111, 46111};  // stands for "handtrack"; not the squatter
// The squatter's poses start at this frame number; a real daemon's frames count from 0.
constexpr std::uint64_t kFakeFrame = 900'000;

enum class Squat { kGarbage, kStoppedFake, kLiveFake };

std::string squat_name(const ::testing::TestParamInfo<Squat>& param) {
  switch (param.param) {
    case Squat::kGarbage: return "Garbage";
    case Squat::kStoppedFake: return "StoppedFake";
    case Squat::kLiveFake: return "LiveFake";
  }
  return "?";
}

// The squatter: a forked process of another uid that creates `name` (mode 0644: readable by all,
// as a real ring would be) and, for a live fake, keeps publishing until killed. Returns once the
// object is in place.
class Squatter {
 public:
  Squatter(const std::string& name, Squat squat) {
    int ready[2];
    if (::pipe(ready) != 0) return;
    pid_ = ::fork();
    if (pid_ == 0) {
      ::close(ready[0]);
      if (::setgroups(0, nullptr) != 0 || ::setgid(kSquatter.gid) != 0 || ::setuid(kSquatter.uid) != 0) ::_exit(90);
      run(name, squat, ready[1]);
      ::_exit(0);
    }
    ::close(ready[1]);
    char byte = 0;
    ok_ = pid_ > 0 && ::read(ready[0], &byte, 1) == 1;
    ::close(ready[0]);
  }
  ~Squatter() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  Squatter(const Squatter&) = delete;
  Squatter& operator=(const Squatter&) = delete;
  [[nodiscard]] bool ok() const { return ok_; }

 private:
  static void run(const std::string& name, Squat squat, int ready) {
    if (squat == Squat::kGarbage) {
      const int fd = ::shm_open(("/" + name).c_str(), O_CREAT | O_EXCL | O_RDWR, 0644);
      const std::vector<unsigned char> junk(64 * 1024, 0xAB);
      if (fd < 0 || ::write(fd, junk.data(), junk.size()) != static_cast<ssize_t>(junk.size())) ::_exit(91);
      ::fchmod(fd, 0644);
      ::close(fd);
      (void)!::write(ready, "r", 1);
      return;
    }
    handtrack::ipc::PoseRingWriter fake(
        handtrack::ipc::PoseRingWriter::Options{.name = name, .capacity = 64, .mode = 0644});
    fake.set_device_state(handtrack::ipc::DeviceState::kStreaming);
    handtrack::ipc::FrameRecord frame{};
    frame.hand_count = 1;
    frame.hands[0].hand_id = 1;
    frame.hands[0].state = HANDTRACK_STATE_TRACKING;
    frame.hands[0].confidence = 0.99F;
    for (std::uint64_t i = 0; i < 32; ++i) {
      frame.frame = kFakeFrame + i;
      fake.publish(frame);
    }
    if (squat == Squat::kStoppedFake) {
      fake.mark_stopped();
      (void)!::write(ready, "r", 1);
      return;
    }
    (void)!::write(ready, "r", 1);
    for (std::uint64_t i = 32;; ++i) {  // until SIGKILL
      frame.frame = kFakeFrame + i;
      fake.publish(frame);
      std::this_thread::sleep_for(5ms);
    }
  }

  pid_t pid_ = -1;
  bool ok_ = false;
};

// Opens `name` as this (root) process: the status, and the detail on failure.
struct OpenResult {
  int status = HANDTRACK_OK;
  std::string detail;
};
OpenResult open_as_root(const std::string& name) {
  handtrack_client* client = nullptr;
  OpenResult r;
  r.status = handtrack_open(name.c_str(), &client);
  if (r.status != HANDTRACK_OK) r.detail = handtrack_error_detail();
  handtrack_close(client);
  return r;
}

class Squatting : public ::testing::TestWithParam<Squat> {
 protected:
  void SetUp() override {
    if (::geteuid() != 0) GTEST_SKIP() << "needs root to be the squatter and the service user";
    ::shm_unlink(("/" + name_).c_str());
    squatter_.emplace(name_, GetParam());
    ASSERT_TRUE(squatter_->ok()) << "the squatter could not create /" << name_;
    struct stat st {};
    ASSERT_EQ(::stat(("/dev/shm/" + name_).c_str(), &st), 0);
    ASSERT_EQ(st.st_uid, kSquatter.uid);
  }
  void TearDown() override {
    squatter_.reset();
    ::shm_unlink(("/" + name_).c_str());
  }

  const std::string name_ = "htsvc_squat_" + std::to_string(::getpid());
  std::optional<Squatter> squatter_;
};

TEST_P(Squatting, ClientsRefuseItAndNameTheOwner) {
  const OpenResult r = open_as_root(name_);
  EXPECT_EQ(r.status, HANDTRACK_ERR_UNTRUSTED_OWNER) << r.detail;
  EXPECT_NE(r.detail.find("uid 46110"), std::string::npos) << r.detail;
}

TEST_P(Squatting, RootDaemonReplacesItWithoutTrustingIt) {
  const TempDir dir("squat-root");
  Child daemon({HANDTRACKD, "--config", std::string(HANDTRACK_SOURCE_DIR) + "/data/handtrackd.toml", "--source",
                "synthetic:pinch", "--shm-name", name_, "--log-level", "warn"},
               dir / "out", dir / "err");
  // Poll until the name holds the daemon's segment: the squatter's is refused, so open() fails
  // until the daemon has replaced it.
  handtrack_client* client = nullptr;
  for (int i = 0; i < 200 && handtrack_open(name_.c_str(), &client) != HANDTRACK_OK; ++i) {
    ASSERT_FALSE(daemon.wait(0ms)) << "handtrackd exited:\n" << daemon.err();
    std::this_thread::sleep_for(50ms);
  }
  ASSERT_NE(client, nullptr) << "no trusted segment within 10 s: " << handtrack_error_detail() << "\n" << daemon.err();
  handtrack_writer_status status{};
  ASSERT_EQ(handtrack_writer_status_get(client, &status), HANDTRACK_OK);
  EXPECT_EQ(status.writer_pid, daemon.pid());
  for (int i = 0; i < 20; ++i) {
    handtrack_frame frame{};
    ASSERT_EQ(handtrack_wait_next(client, &frame, 5'000'000'000LL), HANDTRACK_OK) << handtrack_error_detail();
    ASSERT_LT(frame.frame, kFakeFrame) << "a fake frame was read";
  }
  handtrack_close(client);
  daemon.signal(SIGTERM);
  ASSERT_EQ(daemon.wait(10s), 0) << daemon.err();
  EXPECT_NE(daemon.err().find("uid 46110"), std::string::npos) << "the log names whose object was removed:\n"
                                                               << daemon.err();
}

TEST_P(Squatting, ServiceUserDaemonFailsNamingTheOwner) {
  const handtrack::test::ReachableCopy copy;
  ASSERT_TRUE(copy.ok());
  const TempDir dir("squat-service");
  ::chmod(dir.path().c_str(), 0777);
  Child daemon({copy.daemon(), "--config", copy.config(), "--source", "synthetic:pinch", "--shm-name", name_},
               dir / "out", dir / "err", {}, kServiceUser);
  const auto code = daemon.wait(20s);
  ASSERT_TRUE(code.has_value()) << "handtrackd did not give up:\n" << daemon.err();
  EXPECT_EQ(*code, 1) << daemon.err();
  const auto lines = handtrack::test::lines_of(daemon.err());
  ASSERT_EQ(lines.size(), 1U) << daemon.err();
  EXPECT_NE(lines[0].find("uid 46110"), std::string::npos) << lines[0];
  EXPECT_NE(lines[0].find("may not remove"), std::string::npos) << lines[0];
  EXPECT_EQ(open_as_root(name_).status, HANDTRACK_ERR_UNTRUSTED_OWNER) << "the squat is still refused";
}

INSTANTIATE_TEST_SUITE_P(AnotherUser, Squatting,
                         ::testing::Values(Squat::kGarbage, Squat::kStoppedFake, Squat::kLiveFake),
                         squat_name);

}  // namespace
