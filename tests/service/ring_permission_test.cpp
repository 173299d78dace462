// The pose ring of a daemon running as its own user is readable by that user's group only, as
// under handtrackd.service (User=/Group=handtrack): a process with the group as a supplementary
// group (what `usermod -aG handtrack USER` gives after a new login) reads poses; a process
// outside the group is refused with HANDTRACK_ERR_PERMISSION. The real handtrackd runs as a
// separate uid/gid (set in a forked child as root), so this is the mode and ownership the daemon
// itself gives the segment, not one the test set. Skips when not root.
#include "../daemon/child_process.hpp"
#include "other_user.hpp"

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
    handtrack_frame frame;
    const int read = handtrack_wait_next(client, &frame, 5'000'000'000LL);
    handtrack_close(client);
    ::_exit(read == HANDTRACK_OK ? kReadOk : 92);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

TEST(ServiceRing, GroupMembersReadPosesOthersAreRefused) {
  if (::geteuid() != 0) GTEST_SKIP() << "needs root to run the daemon and the readers as other users";
  const std::string name = "htsvc_perm_" + std::to_string(::getpid());
  const std::string path = "/dev/shm/" + name;
  ::unlink(path.c_str());
  const handtrack::test::ReachableCopy copy;
  ASSERT_TRUE(copy.ok()) << "cannot copy handtrackd and its configuration to /tmp";
  // kDaemonUid stands for the service user "handtrack", which readers (root here) trust by name.
  ::setenv("HANDTRACK_TRUSTED_USERS", std::to_string(kDaemonUid).c_str(), 1);

  const handtrack::test::TempDir logs("perm");
  ::chmod(logs.path().c_str(), 0777);
  handtrack::test::Child daemon({copy.daemon(), "--config", copy.config(), "--source", "synthetic:pinch",
                                 "--shm-name", name, "--log-level", "warn"},
                                logs / "out", logs / "err", {}, handtrack::test::Identity{kDaemonUid, kDaemonGid});

  // Wait (as root) until the daemon publishes.
  bool publishing = false;
  for (int i = 0; i < 150 && !publishing; ++i) {
    handtrack_client* client = nullptr;
    if (handtrack_open(name.c_str(), &client) == HANDTRACK_OK) {
      handtrack_frame frame;
      publishing = handtrack_wait_next(client, &frame, 2'000'000'000LL) == HANDTRACK_OK;
      handtrack_close(client);
    }
    if (!publishing) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    ASSERT_FALSE(daemon.wait(std::chrono::milliseconds(0))) << "handtrackd exited:\n" << daemon.err();
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

  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait(std::chrono::seconds(10)), 0) << daemon.err();
  // The stopped daemon leaves its segment (state "stopped"); the test cleans up its own.
  EXPECT_EQ(::access(path.c_str(), F_OK), 0);
  ::unlink(path.c_str());
}
