#pragma once
// Who may own the pose ring (SPEC.md "Shared memory", docs/SECURITY.md). POSIX shared-memory
// names live in one directory that every local user may create names in (/dev/shm, mode 1777),
// so a name alone proves nothing: any user can create "/handtrack" before the daemon does and
// fill it with poses of their choosing. Both sides therefore look at the object's owner:
// - a reader accepts a segment only from a trusted owner (TrustedOwners) and only when no other
//   user may write it (mode without group/other write bits);
// - the writer never maps for writing, and never flags, an object that another user owns.
//
// Thread roles: thread-safe: TrustedOwners is immutable once built; the functions are reentrant.
#include <sys/types.h>

#include <string>
#include <vector>

namespace handtrack::ipc::detail {

// The service user handtrackd runs as under systemd (systemd/handtrack.sysusers).
inline constexpr const char* kServiceUser = "handtrack";
// Extra trusted owners for readers: comma-separated user names or numeric uids.
inline constexpr const char* kTrustedUsersVariable = "HANDTRACK_TRUSTED_USERS";

// "user nobody (uid 65534)", or "uid 46101" for a uid without a passwd entry.
std::string describe_user(uid_t uid);

// The owners a reader trusts: root, the reader's own effective user, the service user when it
// exists, and everyone named in $HANDTRACK_TRUSTED_USERS.
class TrustedOwners {
 public:
  // Reads the environment and the user database. An entry of HANDTRACK_TRUSTED_USERS that names
  // no user makes *error say so (and the set is built without it).
  static TrustedOwners from_environment(std::string* error);

  [[nodiscard]] bool trusts(uid_t uid) const noexcept;
  // For messages: "root, handtrack, your own user".
  [[nodiscard]] std::string describe() const;

 private:
  std::vector<uid_t> uids_;
};

// Empty when the object behind `fd` may be read as a pose ring: its owner is trusted and only
// its owner may write it. Otherwise one sentence saying who owns it and why it is refused.
std::string untrusted_reason(int fd, const TrustedOwners& trusted);

// The owner of the object behind `fd`; false when fstat fails.
bool owner_of(int fd, uid_t* uid);

}  // namespace handtrack::ipc::detail
