// ipc_test_reader: a reader process for the multi-process tests.
//
//   ipc_test_reader --name N --mode latest|next|wait-latest|unchecked
//                   [--reads K] [--duration-s S] [--epochs E] [--until-stopped] [--timeout-ms T]
//
// Checks every accepted record with is_whole_test_record() (a torn record fails) and that its
// epoch is the mapped segment's, and, on its own, that every hand of the frame carries the frame's
// number (hands_of_one_frame: a "mixed" frame has hands of different frames). Prints event lines
// while running:
//   dead LATENCY_NS        the reader got HANDTRACK_ERR_WRITER_DEAD; now - last heartbeat
//   stopped                HANDTRACK_ERR_WRITER_STOPPED
//   epoch E                first record of a new epoch
//   missed N               a read reported N skipped records
// and at the end (K reads done, S seconds over, E epochs seen, stopped, or SIGTERM) one line
//   summary reads=.. torn=.. mixed=.. distinct=.. missed=.. dead=.. stopped=.. epochs=.. max_dead_ns=..
// Mode "unchecked" copies the newest slot WITHOUT the seqlock check: the negative control that
// shows the checker does see torn records when nothing prevents them.
#include <handtrack/ipc/pose_ring_reader.hpp>
#include <handtrack/ipc/pose_ring_shm.hpp>

#include "../test_pattern.hpp"

#include <boost/interprocess/mapped_region.hpp>
#include <boost/interprocess/shared_memory_object.hpp>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_term(int) { g_stop = 1; }

std::int64_t now_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_MONOTONIC, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

struct Tally {
  std::uint64_t reads = 0, torn = 0, mixed = 0, distinct = 0, missed = 0, dead = 0, stopped = 0, epochs = 0;
  std::int64_t max_dead_ns = 0;
  std::uint64_t last_frame = UINT64_MAX;
  std::uint64_t last_epoch = 0;
};

void print_summary(const Tally& t) {
  std::printf("summary reads=%llu torn=%llu mixed=%llu distinct=%llu missed=%llu dead=%llu stopped=%llu "
              "epochs=%llu max_dead_ns=%lld\n",
              static_cast<unsigned long long>(t.reads), static_cast<unsigned long long>(t.torn),
              static_cast<unsigned long long>(t.mixed),
              static_cast<unsigned long long>(t.distinct), static_cast<unsigned long long>(t.missed),
              static_cast<unsigned long long>(t.dead), static_cast<unsigned long long>(t.stopped),
              static_cast<unsigned long long>(t.epochs), static_cast<long long>(t.max_dead_ns));
  std::fflush(stdout);
}

// The negative control: a reader without the seqlock. Copies the newest slot word by word.
int run_unchecked(const std::string& name, std::uint64_t reads, double duration_s) {
  namespace bip = boost::interprocess;
  namespace shm = handtrack::ipc::shm;
  bip::shared_memory_object object(bip::open_only, name.c_str(), bip::read_only);
  bip::mapped_region region(object, bip::read_only);
  if (shm::validate_segment(region.get_address(), region.get_size(), nullptr) != HANDTRACK_OK) {
    return 1;
  }
  const auto* header = static_cast<const shm::Header*>(region.get_address());
  const auto* slots = reinterpret_cast<const shm::Slot*>(
      static_cast<const unsigned char*>(region.get_address()) + sizeof(shm::Header));
  Tally t;
  const std::int64_t end = now_ns() + static_cast<std::int64_t>(duration_s * 1e9);
  while (!g_stop && t.reads < reads && now_ns() < end) {
    const std::uint64_t head = header->head.load(std::memory_order_acquire);
    if (head == 0) continue;
    const shm::Slot& slot = slots[(head - 1) % header->capacity];
    handtrack::ipc::FrameRecord record;
    std::uint64_t words[shm::kRecordWords];
    for (std::size_t k = 0; k < shm::kRecordWords; ++k) {
      words[k] = slot.words[k].load(std::memory_order_relaxed);
    }
    std::memcpy(&record, words, sizeof record);
    ++t.reads;
    if (!handtrack::ipc::test::hands_of_one_frame(record)) ++t.mixed;
    if (!handtrack::ipc::test::is_whole_test_record(record) && ++t.torn >= 100) break;
  }
  print_summary(t);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string name, mode = "latest";
  std::uint64_t reads = UINT64_MAX, epochs = UINT64_MAX;
  double duration_s = 1e9;
  bool until_stopped = false;
  long timeout_ms = 50;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) std::exit(2);
      return argv[++i];
    };
    if (arg == "--name") name = value();
    else if (arg == "--mode") mode = value();
    else if (arg == "--reads") reads = std::stoull(value());
    else if (arg == "--duration-s") duration_s = std::stod(value());
    else if (arg == "--epochs") epochs = std::stoull(value());
    else if (arg == "--until-stopped") until_stopped = true;
    else if (arg == "--timeout-ms") timeout_ms = std::stol(value());
    else {
      std::fprintf(stderr, "ipc_test_reader: unknown argument %s\n", arg.c_str());
      return 2;
    }
  }
  std::signal(SIGTERM, on_term);
  if (mode == "unchecked") return run_unchecked(name, reads, duration_s);

  handtrack::ipc::PoseRingReader reader;
  handtrack::ipc::Status status = reader.open(name);
  if (status != HANDTRACK_OK) {
    std::fprintf(stderr, "ipc_test_reader: open: %s\n", reader.error_detail().c_str());
    return 1;
  }
  std::printf("open %llu\n", static_cast<unsigned long long>(reader.epoch()));
  std::fflush(stdout);
  Tally t;
  const std::int64_t end = now_ns() + static_cast<std::int64_t>(duration_s * 1e9);
  handtrack::ipc::FrameRecord record;
  handtrack::ipc::Status previous = HANDTRACK_OK;
  const auto timeout = std::chrono::milliseconds(timeout_ms);
  while (!g_stop && t.reads < reads && t.epochs < epochs && now_ns() < end) {
    if (mode == "latest") status = reader.latest(record);
    else if (mode == "next") status = reader.wait_next(record, timeout);
    else if (mode == "wait-latest") status = reader.wait_latest(record, timeout);
    else return 2;

    if (status == HANDTRACK_OK) {
      ++t.reads;
      if (!handtrack::ipc::test::is_whole_test_record(record) || record.epoch != reader.epoch()) {
        ++t.torn;
        std::printf("torn frame=%llu\n", static_cast<unsigned long long>(record.frame));
      }
      if (!handtrack::ipc::test::hands_of_one_frame(record)) {
        ++t.mixed;
        std::printf("mixed frame=%llu\n", static_cast<unsigned long long>(record.frame));
      }
      if (record.epoch != t.last_epoch) {
        t.last_epoch = record.epoch;
        ++t.epochs;
        std::printf("epoch %llu\n", static_cast<unsigned long long>(record.epoch));
        std::fflush(stdout);
      }
      if (record.frame != t.last_frame) ++t.distinct;
      t.last_frame = record.frame;
      if (reader.missed() > 0 && mode == "next") {
        t.missed += reader.missed();
        std::printf("missed %llu\n", static_cast<unsigned long long>(reader.missed()));
        std::fflush(stdout);
      }
    } else if (status == HANDTRACK_ERR_WRITER_DEAD && previous != HANDTRACK_ERR_WRITER_DEAD) {
      // The first report of this death (later waits repeat it at their timeout).
      handtrack::ipc::WriterStatus ws;
      reader.writer_status(ws);
      const std::int64_t latency = now_ns() - ws.heartbeat_ns;
      ++t.dead;
      t.max_dead_ns = std::max(t.max_dead_ns, latency);
      std::printf("dead %lld\n", static_cast<long long>(latency));
      std::fflush(stdout);
    } else if (status == HANDTRACK_ERR_WRITER_STOPPED && previous != HANDTRACK_ERR_WRITER_STOPPED) {
      ++t.stopped;
      std::printf("stopped\n");
      std::fflush(stdout);
      if (until_stopped) break;
    } else if (status < 0 && status != HANDTRACK_ERR_BUSY && status != HANDTRACK_ERR_WRITER_DEAD &&
               status != HANDTRACK_ERR_WRITER_STOPPED) {
      std::fprintf(stderr, "ipc_test_reader: status %d: %s\n", static_cast<int>(status),
                   reader.error_detail().c_str());
      return 1;
    }
    previous = status;
  }
  print_summary(t);
  return 0;
}
