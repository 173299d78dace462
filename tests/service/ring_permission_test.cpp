// The pose ring of a daemon running as its own user is readable by that user's group only, as
// under handtrackd.service (User=/Group=handtrack): a process with the group as a supplementary
// group (what `usermod -aG handtrack USER` gives after a new login) reads poses; a process
// outside the group is refused with HANDTRACK_ERR_PERMISSION. The real handtrackd runs as a
// separate uid/gid (set in a forked child as root), so this is the mode and ownership the daemon
// itself gives the segment, not one the test set. Skips when not root.
#include <handtrack/client.h>

#include <gtest/gtest.h>

#include <fcntl.h>
#include <grp.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

namespace {

// Numeric ids unlikely to exist: the test must not depend on (or touch) /etc/passwd.
constexpr uid_t kDaemonUid = 46101;
constexpr gid_t kDaemonGid = 46100;   // stands for group "handtrack"
constexpr uid_t kReaderUid = 46102;
constexpr gid_t kReaderGid = 46103;   // the reader's own primary group

constexpr int kReadOk = 10;
constexpr int kRefused = 20;

// Opens the ring as uid kReaderUid with primary group kReaderGid and the given supplementary
// groups, reads one new pose; exit code kReadOk, kRefused (HANDTRACK_ERR_PERMISSION) or other.
int read_as(const std::string& name, const std::vector<gid_t>& supplementary) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::setgroups(supplementary.size(), supplementary.data()) != 0 || ::setgid(kReaderGid) != 0 ||
        ::setuid(kReaderUid) != 0) {
      ::_exit(90);
    }
    handtrack_client* client = nullptr;
    const int status = handtrack_open(name.c_str(), &client);
    if (status == HANDTRACK_ERR_PERMISSION) ::_exit(kRefused);
    if (status != HANDTRACK_OK) ::_exit(91);
    handtrack_pose pose;
    const int read = handtrack_wait_next(client, &pose, 5'000'000'000LL);
    handtrack_close(client);
    ::_exit(read == HANDTRACK_OK ? kReadOk : 92);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// What the daemon's user runs, copied to a fresh directory under /tmp that every user may enter:
// the checkout (and so the build tree) may sit in a directory the service user cannot reach
// (root's home, any mode-0700 directory), and exec() of a binary there fails for it.
class ReachableCopy {
 public:
  ReachableCopy() {
    char pattern[] = "/tmp/handtrack-svc-XXXXXX";
    if (::mkdtemp(pattern) == nullptr) return;
    dir_ = pattern;
    std::error_code ec;
    std::filesystem::permissions(dir_, std::filesystem::perms(0755), ec);
    std::filesystem::copy_file(HANDTRACKD, dir_ / "handtrackd", ec);
    if (!ec) std::filesystem::copy_file(std::string(HANDTRACK_SOURCE_DIR) + "/data/handtrackd.toml",
                                        dir_ / "handtrackd.toml", ec);
    ok_ = !ec;
  }
  ~ReachableCopy() {
    std::error_code ec;
    if (!dir_.empty()) std::filesystem::remove_all(dir_, ec);
  }
  ReachableCopy(const ReachableCopy&) = delete;
  ReachableCopy& operator=(const ReachableCopy&) = delete;
  [[nodiscard]] bool ok() const { return ok_; }
  [[nodiscard]] std::string daemon() const { return (dir_ / "handtrackd").string(); }
  [[nodiscard]] std::string config() const { return (dir_ / "handtrackd.toml").string(); }

 private:
  std::filesystem::path dir_;
  bool ok_ = false;
};

}  // namespace

TEST(ServiceRing, GroupMembersReadPosesOthersAreRefused) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to run the daemon and the readers as other users";
  const std::string name = "htsvc_perm_" + std::to_string(::getpid());
  const std::string path = "/dev/shm/" + name;
  ::unlink(path.c_str());
  const ReachableCopy copy;
  ASSERT_TRUE(copy.ok()) << "cannot copy handtrackd and its configuration to /tmp";

  const pid_t daemon = ::fork();
  if (daemon == 0) {
    if (::setgroups(0, nullptr) != 0 || ::setgid(kDaemonGid) != 0 || ::setuid(kDaemonUid) != 0) ::_exit(90);
    const int devnull = ::open("/dev/null", O_WRONLY);
    ::dup2(devnull, STDOUT_FILENO);
    const std::string exe = copy.daemon();
    const std::string config = copy.config();
    ::execl(exe.c_str(), exe.c_str(), "--config", config.c_str(), "--source", "synthetic:pinch",
            "--shm-name", name.c_str(), "--log-level", "warn", static_cast<char*>(nullptr));
    ::_exit(91);
  }
  ASSERT_GT(daemon, 0);

  // Wait (as root) until the daemon publishes.
  bool publishing = false;
  for (int i = 0; i < 150 && !publishing; ++i) {
    handtrack_client* client = nullptr;
    if (handtrack_open(name.c_str(), &client) == HANDTRACK_OK) {
      handtrack_pose pose;
      publishing = handtrack_wait_next(client, &pose, 2'000'000'000LL) == HANDTRACK_OK;
      handtrack_close(client);
    }
    if (!publishing) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    int status = 0;
    if (::waitpid(daemon, &status, WNOHANG) == daemon) FAIL() << "handtrackd exited with status " << status;
  }
  ASSERT_TRUE(publishing) << "handtrackd (uid " << kDaemonUid << ") did not publish within 15 s";

  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0640U) << "the ring is rw for the daemon, r for its group, nothing for others";
  EXPECT_EQ(st.st_uid, kDaemonUid);
  EXPECT_EQ(st.st_gid, kDaemonGid);

  EXPECT_EQ(read_as(name, {kDaemonGid}), kReadOk) << "a member of the daemon's group reads poses";
  EXPECT_EQ(read_as(name, {}), kRefused) << "a process outside the group is refused";
  EXPECT_EQ(read_as(name, {kReaderGid + 1}), kRefused) << "other supplementary groups do not help";

  ::kill(daemon, SIGTERM);
  int status = 0;
  ASSERT_EQ(::waitpid(daemon, &status, 0), daemon);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
  // The stopped daemon leaves its segment (state "stopped"); the test cleans up its own.
  EXPECT_EQ(::access(path.c_str(), F_OK), 0);
  ::unlink(path.c_str());
}
