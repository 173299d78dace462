#include "helper_channel.hpp"

#include "handtrack/common/clock.hpp"

#include <algorithm>
#include <cerrno>

#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

namespace handtrack::daemon::isolated {

Channel::~Channel() { close(); }

Channel& Channel::operator=(Channel&& other) noexcept {
  if (this != &other) {
    close();
    fd_ = other.fd_;
    other.fd_ = -1;
  }
  return *this;
}

void Channel::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

namespace {

Io send_all(int fd, const void* data, std::size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  while (bytes > 0) {
    const ssize_t n = ::send(fd, p, bytes, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return Io::kClosed;
    p += n;
    bytes -= static_cast<std::size_t>(n);
  }
  return Io::kOk;
}

}  // namespace

Io Channel::send(Kind kind, const void* a, std::size_t a_bytes, const void* b, std::size_t b_bytes) {
  if (fd_ < 0) return Io::kClosed;
  Header header;
  header.kind = static_cast<std::uint32_t>(kind);
  header.payload_bytes = static_cast<std::uint32_t>(a_bytes + b_bytes);
  Io io = send_all(fd_, &header, sizeof header);
  if (io == Io::kOk && a_bytes > 0) io = send_all(fd_, a, a_bytes);
  if (io == Io::kOk && b_bytes > 0) io = send_all(fd_, b, b_bytes);
  return io;
}

Io Channel::receive(void* out, std::size_t bytes, std::int64_t deadline_ns) {
  if (fd_ < 0) return Io::kClosed;
  auto* p = static_cast<unsigned char*>(out);
  while (bytes > 0) {
    int wait_ms = -1;
    if (deadline_ns >= 0) {
      const std::int64_t left = deadline_ns - monotonic_ns();
      if (left <= 0) return Io::kTimeout;
      wait_ms = static_cast<int>(std::min<std::int64_t>((left + 999'999) / 1'000'000, 60'000));
    }
    pollfd pfd{fd_, POLLIN, 0};
    const int ready = ::poll(&pfd, 1, wait_ms);
    if (ready < 0 && errno == EINTR) continue;
    if (ready < 0) return Io::kClosed;
    if (ready == 0) continue;  // the deadline is checked at the top
    const ssize_t n = ::read(fd_, p, bytes);
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (n <= 0) return Io::kClosed;
    p += n;
    bytes -= static_cast<std::size_t>(n);
  }
  return Io::kOk;
}

Io Channel::receive_header(Header* header, std::int64_t deadline_ns) {
  const Io io = receive(header, sizeof *header, deadline_ns);
  if (io != Io::kOk) return io;
  return header->magic == kMagic ? Io::kOk : Io::kBad;
}

Io Channel::receive_text(std::string* out, std::size_t bytes, std::int64_t deadline_ns) {
  if (bytes > kMaxText) return Io::kBad;
  out->assign(bytes, '\0');
  return bytes == 0 ? Io::kOk : receive(out->data(), bytes, deadline_ns);
}

}  // namespace handtrack::daemon::isolated
