#pragma once
// Service tests run programs as other users (forked as root, then setuid): the service user, a
// group member, a stranger, a squatter. Numeric ids that are unlikely to exist: the tests must
// not depend on (or touch) /etc/passwd.
#include <filesystem>
#include <string>
#include <system_error>

#include <stdlib.h>
#include <sys/stat.h>

namespace handtrack::test {

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

}  // namespace handtrack::test
