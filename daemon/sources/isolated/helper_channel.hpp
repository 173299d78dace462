#pragma once
// The conversation between handtrackd and its source helper (handtrack-source-helper), the
// process that runs a third-party camera driver so that a driver fault cannot take the daemon
// down (docs/SECURITY.md). One AF_UNIX stream socket; the daemon asks, the helper answers:
//
//   daemon -> helper   kOpen  {OpenRequest, spec text}   helper -> kOpened {CameraReply} | kStatus
//   daemon -> helper   kGrab  {GrabRequest}              helper -> kFrame {FrameReply, pixels} | kStatus
//   daemon -> helper   kClose {}                         helper closes the source and exits
//
// Every message is a Header and `payload_bytes` of payload. The daemon trusts nothing it reads:
// sizes are bounded before anything is allocated, a frame must have the size the helper opened
// with, and a helper that does not answer within its deadline is killed.
//
// Thread roles: thread-bound: a Channel is used by one thread (the grab thread, or the helper's
// main thread).
#include <cstddef>
#include <cstdint>
#include <string>

namespace handtrack::daemon::isolated {

inline constexpr std::uint32_t kMagic = 0x48545348;  // "HSTH" in memory order
inline constexpr std::uint32_t kMaxText = 4096;      // spec and error texts
inline constexpr int kMaxSide = 8192;                // frame width and height

enum class Kind : std::uint32_t { kOpen = 1, kOpened, kGrab, kFrame, kStatus, kClose };

struct Header {
  std::uint32_t magic = kMagic;
  std::uint32_t kind = 0;
  std::uint32_t payload_bytes = 0;
  std::uint32_t reserved = 0;
};

struct OpenRequest {  // followed by the source spec (oni:FILE, openni2:URI)
  std::int32_t loop = 0;
  std::int32_t as_fast_as_possible = 0;
  std::int32_t width = 0;
  std::int32_t height = 0;
  std::int32_t fps = 0;
  std::int32_t log_level = 0;  // see GrabRequest
};

struct CameraReply {
  std::int32_t width = 0;
  std::int32_t height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0, depth_scale_mm = 0, fps = 0;
};

struct GrabRequest {
  std::int64_t timeout_ms = 0;
  // The daemon's log level now (a spdlog::level::level_enum), as in every request: the helper logs
  // at it, and a SIGHUP that changes daemon.log_level reaches the helper with its next grab.
  std::int32_t log_level = 0;
  std::int32_t reserved = 0;
};

struct FrameReply {  // followed by width * height uint16 pixels, row-major
  std::uint64_t frame_number = 0;
  std::int64_t capture_ns = 0;
  std::int32_t width = 0;
  std::int32_t height = 0;
};

struct StatusReply {  // followed by last_error() text
  std::int32_t status = 0;  // GrabStatus, or -1: open() failed
  std::int32_t reserved = 0;
};

enum class Io { kOk, kTimeout, kClosed, kBad };

class Channel {
 public:
  Channel() = default;
  explicit Channel(int fd) : fd_(fd) {}
  ~Channel();
  Channel(Channel&& other) noexcept : fd_(other.fd_) { other.fd_ = -1; }
  Channel& operator=(Channel&& other) noexcept;
  Channel(const Channel&) = delete;
  Channel& operator=(const Channel&) = delete;

  [[nodiscard]] bool is_open() const { return fd_ >= 0; }
  void close();

  // Sends a message whose payload is `a` then `b` (either may be empty). kClosed when the peer is
  // gone; never raises SIGPIPE.
  Io send(Kind kind, const void* a, std::size_t a_bytes, const void* b = nullptr, std::size_t b_bytes = 0);
  // Reads the next header, waiting until `deadline_ns` (CLOCK_MONOTONIC; < 0: for ever). kBad for
  // a wrong magic.
  Io receive_header(Header* header, std::int64_t deadline_ns);
  // Reads exactly `bytes` of payload into `out`.
  Io receive(void* out, std::size_t bytes, std::int64_t deadline_ns);
  // Reads a text payload of `bytes` (at most kMaxText, else kBad).
  Io receive_text(std::string* out, std::size_t bytes, std::int64_t deadline_ns);

 private:
  int fd_ = -1;
};

}  // namespace handtrack::daemon::isolated
