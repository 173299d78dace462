// Header validation: everything a reader checks before it trusts a segment's offsets.
#include <handtrack/ipc/pose_ring_shm.hpp>

#include <cinttypes>
#include <cstdarg>
#include <cstdio>

namespace handtrack::ipc::shm {
namespace {

Status fail(std::string* detail, Status status, const char* format, ...)
    __attribute__((format(printf, 3, 4)));

Status fail(std::string* detail, Status status, const char* format, ...) {
  if (detail != nullptr) {
    char buffer[256];
    va_list args;
    va_start(args, format);
    std::vsnprintf(buffer, sizeof buffer, format, args);
    va_end(args);
    detail->assign(buffer);
  }
  return status;
}

constexpr std::uint64_t byteswap64(std::uint64_t v) { return __builtin_bswap64(v); }

}  // namespace

Status validate_segment(const void* base, std::size_t mapped_size, std::string* detail) noexcept {
  if (detail != nullptr) detail->clear();
  if (base == nullptr) return fail(detail, HANDTRACK_ERR_INVALID_ARGUMENT, "no memory to validate");
  if (mapped_size == 0) {
    return fail(detail, HANDTRACK_ERR_NOT_READY, "segment is empty (writer still creating it)");
  }
  if (mapped_size < sizeof(Header)) {
    return fail(detail, HANDTRACK_ERR_TRUNCATED,
                "segment is %zu bytes, smaller than the %zu-byte header", mapped_size,
                sizeof(Header));
  }
  const auto* h = static_cast<const Header*>(base);
  // SYNC: acquire; pairs with the writer's release store of the magic, after which the identity
  // fields below are immutable.
  const std::uint64_t magic = h->magic.load(std::memory_order_acquire);
  if (magic == 0) {
    return fail(detail, HANDTRACK_ERR_NOT_READY, "segment header not initialized yet (magic is 0)");
  }
  if (magic == byteswap64(kMagic)) {
    return fail(detail, HANDTRACK_ERR_BAD_ENDIANNESS,
                "segment was written by a machine of the other byte order");
  }
  if (magic != kMagic) {
    return fail(detail, HANDTRACK_ERR_BAD_MAGIC,
                "magic is 0x%016" PRIx64 ", expected 0x%016" PRIx64 " (not a handtrack segment)",
                magic, kMagic);
  }
  if (h->endian_marker != kEndianMarker) {
    return fail(detail, HANDTRACK_ERR_BAD_ENDIANNESS,
                "endianness marker is 0x%08" PRIx32 ", expected 0x%08" PRIx32, h->endian_marker,
                kEndianMarker);
  }
  if (h->abi_version != kAbiVersion) {
    // Say which side to update: the one with the older version.
    return fail(detail, HANDTRACK_ERR_BAD_VERSION,
                "segment has ABI version %" PRIu32 ", this client reads version %" PRIu32 ": %s",
                h->abi_version, kAbiVersion,
                h->abi_version > kAbiVersion
                    ? "rebuild the client against the installed handtrack"
                    : "the running handtrackd is older than this client; upgrade and restart it");
  }
  if (h->record_size != sizeof(FrameRecord)) {
    return fail(detail, HANDTRACK_ERR_BAD_RECORD_SIZE,
                "segment record size is %" PRIu32 " bytes, this client expects %zu",
                h->record_size, sizeof(FrameRecord));
  }
  if (h->header_size != sizeof(Header)) {
    return fail(detail, HANDTRACK_ERR_BAD_LAYOUT, "header size is %" PRIu32 ", expected %zu",
                h->header_size, sizeof(Header));
  }
  if (h->slot_size != sizeof(Slot)) {
    return fail(detail, HANDTRACK_ERR_BAD_LAYOUT, "slot size is %" PRIu32 ", expected %zu",
                h->slot_size, sizeof(Slot));
  }
  if (h->capacity < 2 || h->capacity > kMaxCapacity) {
    return fail(detail, HANDTRACK_ERR_BAD_LAYOUT,
                "capacity is %" PRIu32 ", outside 2..%" PRIu32, h->capacity, kMaxCapacity);
  }
  const std::uint64_t expected_total = segment_size(h->capacity);
  if (h->total_size != expected_total) {
    return fail(detail, HANDTRACK_ERR_BAD_LAYOUT,
                "total size is %" PRIu64 " bytes, but %" PRIu32 " slots need %" PRIu64,
                h->total_size, h->capacity, expected_total);
  }
  if (h->heartbeat_period_ns < kMinHeartbeatPeriodNs ||
      h->heartbeat_period_ns > kMaxHeartbeatPeriodNs) {
    return fail(detail, HANDTRACK_ERR_BAD_LAYOUT,
                "heartbeat period is %" PRId64 " ns, outside 1 ms..1 h", h->heartbeat_period_ns);
  }
  if (mapped_size < expected_total) {
    return fail(detail, HANDTRACK_ERR_TRUNCATED,
                "segment is %zu bytes, but its header says %" PRIu64 " (truncated)", mapped_size,
                expected_total);
  }
  return HANDTRACK_OK;
}

}  // namespace handtrack::ipc::shm
