#include "segment_owner.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <string_view>

#include <pwd.h>
#include <sys/stat.h>
#include <unistd.h>

namespace handtrack::ipc::detail {

namespace {

// getpwnam_r/getpwuid_r with a fixed buffer: passwd entries are short, and a lookup that does not
// fit is treated as "no such user" rather than grown without bound.
constexpr std::size_t kPasswdBuffer = 4096;

bool uid_of_name(const std::string& name, uid_t* uid) {
  std::array<char, kPasswdBuffer> buffer{};
  passwd entry{};
  passwd* found = nullptr;
  if (::getpwnam_r(name.c_str(), &entry, buffer.data(), buffer.size(), &found) != 0 || found == nullptr) {
    return false;
  }
  *uid = found->pw_uid;
  return true;
}

std::string name_of_uid(uid_t uid) {
  std::array<char, kPasswdBuffer> buffer{};
  passwd entry{};
  passwd* found = nullptr;
  if (::getpwuid_r(uid, &entry, buffer.data(), buffer.size(), &found) != 0 || found == nullptr) return {};
  return found->pw_name;
}

// A HANDTRACK_TRUSTED_USERS entry: a numeric uid or a user name.
bool parse_user(std::string_view entry, uid_t* uid) {
  unsigned long value = 0;
  const auto [end, ec] = std::from_chars(entry.data(), entry.data() + entry.size(), value);
  if (ec == std::errc() && end == entry.data() + entry.size()) {
    *uid = static_cast<uid_t>(value);
    return static_cast<unsigned long>(*uid) == value;
  }
  return uid_of_name(std::string(entry), uid);
}

}  // namespace

std::string describe_user(uid_t uid) {
  const std::string name = name_of_uid(uid);
  const std::string number = "uid " + std::to_string(uid);
  return name.empty() ? number : "user " + name + " (" + number + ")";
}

TrustedOwners TrustedOwners::from_environment(std::string* error) {
  TrustedOwners owners;
  owners.uids_ = {0, ::geteuid()};
  uid_t service = 0;
  if (uid_of_name(kServiceUser, &service)) owners.uids_.push_back(service);
  if (const char* extra = std::getenv(kTrustedUsersVariable); extra != nullptr) {
    std::string_view rest(extra);
    while (!rest.empty()) {
      const std::size_t comma = rest.find(',');
      const std::string_view entry = rest.substr(0, comma);
      rest = comma == std::string_view::npos ? std::string_view() : rest.substr(comma + 1);
      if (entry.empty()) continue;
      uid_t uid = 0;
      if (parse_user(entry, &uid)) {
        owners.uids_.push_back(uid);
      } else if (error != nullptr && error->empty()) {
        *error = std::string(kTrustedUsersVariable) + ": no user '" + std::string(entry.substr(0, 64)) + "'";
      }
    }
  }
  return owners;
}

bool TrustedOwners::trusts(uid_t uid) const noexcept {
  return std::find(uids_.begin(), uids_.end(), uid) != uids_.end();
}

std::string TrustedOwners::describe() const {
  std::string list;
  std::vector<uid_t> seen;
  for (const uid_t uid : uids_) {
    if (std::find(seen.begin(), seen.end(), uid) != seen.end()) continue;
    seen.push_back(uid);
    const std::string name = name_of_uid(uid);
    list += (list.empty() ? "" : ", ") + (name.empty() ? "uid " + std::to_string(uid) : name);
  }
  return list;
}

bool owner_of(int fd, uid_t* uid) {
  struct stat st {};
  if (::fstat(fd, &st) != 0) return false;
  *uid = st.st_uid;
  return true;
}

std::string untrusted_reason(int fd, const TrustedOwners& trusted) {
  struct stat st {};
  if (::fstat(fd, &st) != 0) return "cannot see who owns it";
  if (!trusted.trusts(st.st_uid)) {
    return "it belongs to " + describe_user(st.st_uid) + ", not to a trusted owner (" + trusted.describe() +
           "; more in " + kTrustedUsersVariable + ")";
  }
  if ((st.st_mode & (S_IWGRP | S_IWOTH)) != 0) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
    return "other users may write it (mode " + std::string(mode) + "), so its poses could be anyone's";
  }
  return {};
}

}  // namespace handtrack::ipc::detail
