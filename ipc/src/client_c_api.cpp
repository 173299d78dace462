// The C API (handtrack/client.h) over PoseRingReader. No exception crosses this boundary.
#include <handtrack/client.h>
#include <handtrack/ipc/pose_ring_reader.hpp>

#include <chrono>
#include <cstdio>
#include <new>
#include <string>

struct handtrack_client {
  handtrack::ipc::PoseRingReader reader;
};

namespace {

thread_local char g_detail[320] = "";

void set_detail(const std::string& text) {
  std::snprintf(g_detail, sizeof g_detail, "%s", text.c_str());
}

int remember(handtrack_client* client, int status) {
  if (status < 0) {
    const std::string& d = client->reader.error_detail();
    set_detail(d.empty() ? handtrack_strerror(status) : d);
  }
  return status;
}

}  // namespace

extern "C" {

int handtrack_open(const char* shm_name, handtrack_client** out) {
  if (out == nullptr) {
    set_detail("handtrack_open: out is NULL");
    return HANDTRACK_ERR_INVALID_ARGUMENT;
  }
  *out = nullptr;
  try {
    auto* client = new handtrack_client;
    const int status =
        client->reader.open(shm_name != nullptr ? shm_name : HANDTRACK_DEFAULT_SHM_NAME);
    if (status != HANDTRACK_OK) {
      set_detail(client->reader.error_detail());
      delete client;
      return status;
    }
    *out = client;
    return HANDTRACK_OK;
  } catch (...) {
    set_detail("handtrack_open: out of memory");
    return HANDTRACK_ERR_SYSTEM;
  }
}

void handtrack_close(handtrack_client* client) { delete client; }

int handtrack_latest(handtrack_client* client, handtrack_frame* out) {
  if (client == nullptr || out == nullptr) return HANDTRACK_ERR_INVALID_ARGUMENT;
  return remember(client, client->reader.latest(*out));
}

int handtrack_wait_next(handtrack_client* client, handtrack_frame* out, int64_t timeout_ns) {
  if (client == nullptr || out == nullptr) return HANDTRACK_ERR_INVALID_ARGUMENT;
  return remember(client, client->reader.wait_next(*out, std::chrono::nanoseconds(timeout_ns)));
}

int handtrack_wait_latest(handtrack_client* client, handtrack_frame* out, int64_t timeout_ns) {
  if (client == nullptr || out == nullptr) return HANDTRACK_ERR_INVALID_ARGUMENT;
  return remember(client, client->reader.wait_latest(*out, std::chrono::nanoseconds(timeout_ns)));
}

int handtrack_rewind(handtrack_client* client) {
  if (client == nullptr || !client->reader.is_open()) return HANDTRACK_ERR_INVALID_ARGUMENT;
  client->reader.rewind();
  return HANDTRACK_OK;
}

uint64_t handtrack_missed(const handtrack_client* client) {
  return client != nullptr ? client->reader.missed() : 0;
}

uint64_t handtrack_missed_total(const handtrack_client* client) {
  return client != nullptr ? client->reader.missed_total() : 0;
}

int handtrack_writer_status_get(handtrack_client* client, handtrack_writer_status* out) {
  if (client == nullptr || out == nullptr) return HANDTRACK_ERR_INVALID_ARGUMENT;
  return remember(client, client->reader.writer_status(*out));
}

const char* handtrack_strerror(int status) {
  switch (status) {
    case HANDTRACK_OK: return "success";
    case HANDTRACK_TIMEOUT: return "no new frame within the timeout";
    case HANDTRACK_NO_RECORD: return "the daemon has not published any frame yet";
    case HANDTRACK_ERR_INVALID_ARGUMENT: return "invalid argument";
    case HANDTRACK_ERR_NOT_FOUND: return "no handtrack shared memory with that name (is handtrackd running?)";
    case HANDTRACK_ERR_PERMISSION: return "permission denied opening the handtrack shared memory (is this user in the daemon's group?)";
    case HANDTRACK_ERR_NOT_READY: return "the handtrack shared memory is still being initialized";
    case HANDTRACK_ERR_BAD_MAGIC: return "not a handtrack shared-memory segment (wrong magic)";
    case HANDTRACK_ERR_BAD_ENDIANNESS: return "the segment was written with the other byte order";
    case HANDTRACK_ERR_BAD_VERSION: return "the daemon uses a different ABI version than this client library (see handtrack_error_detail)";
    case HANDTRACK_ERR_BAD_RECORD_SIZE: return "the daemon's frame record size differs from this client library's";
    case HANDTRACK_ERR_BAD_LAYOUT: return "the segment header is inconsistent (sizes or capacity)";
    case HANDTRACK_ERR_TRUNCATED: return "the shared-memory segment is smaller than its header says (truncated)";
    case HANDTRACK_ERR_WRITER_DEAD: return "the daemon is not alive (heartbeat stale)";
    case HANDTRACK_ERR_WRITER_STOPPED: return "the daemon has stopped";
    case HANDTRACK_ERR_BUSY: return "the record was overwritten during every read attempt";
    case HANDTRACK_ERR_SYSTEM: return "system error (see handtrack_error_detail)";
    case HANDTRACK_ERR_UNTRUSTED_OWNER: return "the shared memory belongs to an untrusted user or others may write it (see handtrack_error_detail)";
    default: return "unknown handtrack status";
  }
}

const char* handtrack_error_detail(void) { return g_detail; }

const char* handtrack_state_name(int32_t tracking_state) {
  switch (tracking_state) {
    case HANDTRACK_STATE_NO_HAND: return "no_hand";
    case HANDTRACK_STATE_TRACKING: return "tracking";
    case HANDTRACK_STATE_RECOVERING: return "recovering";
    default: return "unknown";
  }
}

const char* handtrack_handedness_name(int32_t handedness) {
  switch (handedness) {
    case HANDTRACK_HANDEDNESS_LEFT: return "left";
    case HANDTRACK_HANDEDNESS_RIGHT: return "right";
    default: return "unknown";
  }
}

const char* handtrack_device_state_name(int32_t device_state) {
  switch (device_state) {
    case HANDTRACK_DEVICE_STOPPED: return "stopped";
    case HANDTRACK_DEVICE_STARTING: return "starting";
    case HANDTRACK_DEVICE_WAITING_FOR_DEVICE: return "waiting_for_device";
    case HANDTRACK_DEVICE_STREAMING: return "streaming";
    case HANDTRACK_DEVICE_ERROR: return "error";
    default: return "unknown";
  }
}

uint32_t handtrack_abi_version(void) { return HANDTRACK_ABI_VERSION; }
size_t handtrack_frame_size(void) { return sizeof(handtrack_frame); }
size_t handtrack_hand_size(void) { return sizeof(handtrack_hand); }
size_t handtrack_writer_status_size(void) { return sizeof(handtrack_writer_status); }

}  // extern "C"
