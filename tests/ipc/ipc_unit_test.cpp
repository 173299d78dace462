// In-process tests of the pose ring: layout validation, round trips, missed counts, waiting,
// liveness, restarts. Threads appear only where a test is about in-process concurrency (this
// file is also built with TSan); the cross-process behaviour is in ipc_process_test.cpp.
#include <handtrack/client.h>
#include <handtrack/ipc/pose_ring_reader.hpp>
#include <handtrack/ipc/pose_ring_shm.hpp>
#include <handtrack/ipc/pose_ring_writer.hpp>

#include "test_pattern.hpp"

#include <boost/interprocess/mapped_region.hpp>
#include <boost/interprocess/shared_memory_object.hpp>
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <sys/stat.h>
#include <unistd.h>

namespace bip = boost::interprocess;
using namespace std::chrono_literals;
using handtrack::ipc::DeviceState;
using handtrack::ipc::FrameRecord;
using handtrack::ipc::PoseRingReader;
using handtrack::ipc::PoseRingWriter;
using handtrack::ipc::Status;
using handtrack::ipc::test::hands_of_one_frame;
using handtrack::ipc::test::is_whole_test_record;
using handtrack::ipc::test::make_test_record;
namespace shm = handtrack::ipc::shm;

#if defined(__SANITIZE_THREAD__)
#define HT_UNDER_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define HT_UNDER_TSAN 1
#endif
#endif
#ifdef HT_UNDER_TSAN
constexpr bool kUnderTsan = true;
#else
constexpr bool kUnderTsan = false;
#endif

namespace {

// A name no other test (or concurrent ctest job) uses; removed when the guard goes.
struct ShmName {
  std::string value;
  ShmName() {
    static int counter = 0;
    value = "ht_unit_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
    PoseRingWriter::remove(value);
  }
  ~ShmName() { PoseRingWriter::remove(value); }
  ShmName(const ShmName&) = delete;
  ShmName& operator=(const ShmName&) = delete;
};

PoseRingWriter::Options options_for(const ShmName& name, std::uint32_t capacity = 8,
                                    std::chrono::milliseconds period = 100ms) {
  PoseRingWriter::Options o;
  o.name = name.value;
  o.capacity = capacity;
  o.heartbeat_period = period;
  return o;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// A correct segment image in ordinary memory, to corrupt field by field.
std::vector<std::uint64_t> valid_image(std::uint32_t capacity) {
  std::vector<std::uint64_t> words(shm::segment_size(capacity) / 8, 0);
  auto* h = new (words.data()) shm::Header();
  h->abi_version = HANDTRACK_ABI_VERSION;
  h->endian_marker = shm::kEndianMarker;
  h->header_size = sizeof(shm::Header);
  h->record_size = sizeof(FrameRecord);
  h->slot_size = sizeof(shm::Slot);
  h->capacity = capacity;
  h->total_size = shm::segment_size(capacity);
  h->epoch = 7;
  h->heartbeat_period_ns = 100'000'000;
  h->magic.store(shm::kMagic, std::memory_order_release);
  return words;
}

shm::Header& header_of(std::vector<std::uint64_t>& image) {
  return *reinterpret_cast<shm::Header*>(image.data());
}

}  // namespace

TEST(IpcValidate, AcceptsAValidImageAndRejectsEachCorruption) {
  auto image = valid_image(4);
  const std::size_t size = image.size() * 8;
  std::string detail;
  ASSERT_EQ(shm::validate_segment(image.data(), size, &detail), HANDTRACK_OK) << detail;

  auto expect = [&](auto corrupt, Status wanted, const char* needle, std::size_t map_size = 0) {
    auto bad = valid_image(4);
    corrupt(header_of(bad));
    std::string why;
    EXPECT_EQ(shm::validate_segment(bad.data(), map_size != 0 ? map_size : size, &why), wanted);
    EXPECT_NE(why.find(needle), std::string::npos) << why;
  };
  expect([](shm::Header& h) { h.magic.store(0x1234, std::memory_order_relaxed); },
         HANDTRACK_ERR_BAD_MAGIC, "magic is 0x0000000000001234");
  expect([](shm::Header& h) { h.magic.store(__builtin_bswap64(shm::kMagic), std::memory_order_relaxed); },
         HANDTRACK_ERR_BAD_ENDIANNESS, "byte order");
  expect([](shm::Header& h) { h.magic.store(0, std::memory_order_relaxed); },
         HANDTRACK_ERR_NOT_READY, "not initialized");
  expect([](shm::Header& h) { h.endian_marker = 0x04030201; }, HANDTRACK_ERR_BAD_ENDIANNESS,
         "0x04030201");
  expect([](shm::Header& h) { h.abi_version = 3; }, HANDTRACK_ERR_BAD_VERSION,
         "segment has ABI version 3, this client reads version 2: rebuild the client against the installed handtrack");
  expect([](shm::Header& h) { h.abi_version = 1; }, HANDTRACK_ERR_BAD_VERSION,
         "segment has ABI version 1, this client reads version 2: the running handtrackd is older than this client");
  expect([](shm::Header& h) { h.record_size = 600; }, HANDTRACK_ERR_BAD_RECORD_SIZE,
         "record size is 600");
  expect([](shm::Header& h) { h.slot_size = 704; }, HANDTRACK_ERR_BAD_LAYOUT, "slot size is 704");
  expect([](shm::Header& h) { h.capacity = 0; }, HANDTRACK_ERR_BAD_LAYOUT, "capacity is 0");
  expect([](shm::Header& h) { h.capacity = 5; }, HANDTRACK_ERR_BAD_LAYOUT, "total size");
  expect([](shm::Header& h) { h.heartbeat_period_ns = 0; }, HANDTRACK_ERR_BAD_LAYOUT,
         "heartbeat period");
  expect([](shm::Header&) {}, HANDTRACK_ERR_TRUNCATED, "truncated", size - 1);
  expect([](shm::Header&) {}, HANDTRACK_ERR_TRUNCATED, "smaller than the 256-byte header", 100);
}

TEST(IpcRing, PublishedRecordReadsBackWithEpochAndPublishTime) {
  ShmName name;
  PoseRingWriter writer(options_for(name));
  PoseRingReader reader;
  ASSERT_EQ(reader.open(name.value), HANDTRACK_OK) << reader.error_detail();
  FrameRecord out{};
  EXPECT_EQ(reader.latest(out), HANDTRACK_NO_RECORD);

  const FrameRecord in = make_test_record(42);
  const auto before = std::chrono::steady_clock::now().time_since_epoch().count();
  writer.publish(in);
  ASSERT_EQ(reader.latest(out), HANDTRACK_OK);
  EXPECT_TRUE(is_whole_test_record(out));
  EXPECT_EQ(out.frame, 42U);
  EXPECT_EQ(out.epoch, writer.epoch());
  EXPECT_EQ(out.epoch, reader.epoch());
  EXPECT_GE(out.publish_ns, before);  // steady_clock is CLOCK_MONOTONIC on Linux
  EXPECT_EQ(std::memcmp(out.hands, in.hands, sizeof in.hands), 0);
}

// A frame's hand_count says how many hands[] are real: 0 for a frame without a hand, and never
// more than the record holds, even from a writer that says otherwise (readers loop up to it).
TEST(IpcRing, HandCountIsReadBackAndNeverExceedsTheRecord) {
  ShmName name;
  PoseRingWriter writer(options_for(name));
  PoseRingReader reader;
  ASSERT_EQ(reader.open(name.value), HANDTRACK_OK) << reader.error_detail();
  FrameRecord in{};
  in.frame = 1;
  writer.publish(in);
  FrameRecord out{};
  ASSERT_EQ(reader.wait_next(out, 0ms), HANDTRACK_OK);
  EXPECT_EQ(out.hand_count, 0U);
  in.frame = 2;
  in.hand_count = 7;
  writer.publish(in);
  ASSERT_EQ(reader.wait_next(out, 0ms), HANDTRACK_OK);
  EXPECT_EQ(out.hand_count, handtrack::ipc::kMaxHands);
}

TEST(IpcRing, InOrderReaderCountsOverwrittenRecordsAsMissed) {
  ShmName name;
  PoseRingWriter writer(options_for(name, 8));
  PoseRingReader reader;
  ASSERT_EQ(reader.open(name.value), HANDTRACK_OK);
  FrameRecord out{};
  for (std::uint64_t f = 0; f < 3; ++f) writer.publish(make_test_record(f));
  for (std::uint64_t f = 0; f < 3; ++f) {
    ASSERT_EQ(reader.wait_next(out, 0ns), HANDTRACK_OK);
    EXPECT_EQ(out.frame, f);
    EXPECT_EQ(reader.missed(), 0U);
  }
  EXPECT_EQ(reader.wait_next(out, 0ns), HANDTRACK_TIMEOUT);
  // 20 more into 8 slots: records 3..15 are gone; the oldest safe one is head - capacity + 1 = 16.
  for (std::uint64_t f = 3; f < 23; ++f) writer.publish(make_test_record(f));
  ASSERT_EQ(reader.wait_next(out, 0ns), HANDTRACK_OK);
  EXPECT_EQ(out.frame, 16U);
  EXPECT_EQ(reader.missed(), 13U);
  for (std::uint64_t f = 17; f < 23; ++f) {
    ASSERT_EQ(reader.wait_next(out, 0ns), HANDTRACK_OK);
    EXPECT_EQ(out.frame, f);
    EXPECT_EQ(reader.missed(), 0U);
  }
  EXPECT_EQ(reader.missed_total(), 13U);
}

TEST(IpcRing, LatestSkipsToTheNewestAndCountsTheSkipped) {
  ShmName name;
  PoseRingWriter writer(options_for(name, 8));
  PoseRingReader reader;
  ASSERT_EQ(reader.open(name.value), HANDTRACK_OK);
  FrameRecord out{};
  for (std::uint64_t f = 0; f < 5; ++f) writer.publish(make_test_record(f));
  ASSERT_EQ(reader.latest(out), HANDTRACK_OK);
  EXPECT_EQ(out.frame, 4U);
  EXPECT_EQ(reader.missed(), 4U);
  ASSERT_EQ(reader.latest(out), HANDTRACK_OK);  // the same record again: nothing missed
  EXPECT_EQ(reader.missed(), 0U);
  EXPECT_EQ(reader.wait_latest(out, 0ns), HANDTRACK_TIMEOUT);  // nothing newer
  writer.publish(make_test_record(5));
  writer.publish(make_test_record(6));
  ASSERT_EQ(reader.wait_latest(out, 0ns), HANDTRACK_OK);
  EXPECT_EQ(out.frame, 6U);
  EXPECT_EQ(reader.missed(), 1U);
}

TEST(IpcRing, OpenStartsAfterTheNewestRecordPresent) {
  ShmName name;
  PoseRingWriter writer(options_for(name));
  writer.publish(make_test_record(1));
  PoseRingReader reader;
  ASSERT_EQ(reader.open(name.value), HANDTRACK_OK);
  FrameRecord out{};
  EXPECT_EQ(reader.wait_next(out, 0ns), HANDTRACK_TIMEOUT);
  writer.publish(make_test_record(2));
  ASSERT_EQ(reader.wait_next(out, 0ns), HANDTRACK_OK);
  EXPECT_EQ(out.frame, 2U);
}

TEST(IpcWait, TimesOutAfterTheTimeoutWhileTheWriterIsAlive) {
  ShmName name;
  PoseRingWriter writer(options_for(name));
  PoseRingReader reader;
  ASSERT_EQ(reader.open(name.value), HANDTRACK_OK);
  FrameRecord out{};
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(reader.wait_next(out, 30ms), HANDTRACK_TIMEOUT);
  const double waited = seconds_since(t0);
  EXPECT_GE(waited, 0.030);
  EXPECT_LT(waited, 0.5);
}

TEST(IpcWait, WakesWhenAnotherThreadPublishes) {
  ShmName name;
  PoseRingWriter writer(options_for(name));
  PoseRingReader reader;
  ASSERT_EQ(reader.open(name.value), HANDTRACK_OK);
  // The clock starts before the publisher does: it publishes no sooner than 50 ms after t0, so a
  // reader that waited for it waited at least that long (started after the thread, t0 could come
  // late by however long this thread was descheduled: 44.95 ms once).
  const auto t0 = std::chrono::steady_clock::now();
  std::thread publisher([&] {
    std::this_thread::sleep_for(50ms);
    writer.publish(make_test_record(9));
  });
  FrameRecord out{};
  const Status status = reader.wait_next(out, 5s);
  const double waited = seconds_since(t0);
  publisher.join();
  ASSERT_EQ(status, HANDTRACK_OK);
  EXPECT_EQ(out.frame, 9U);
  EXPECT_GE(waited, 0.050);
  EXPECT_LT(waited, 1.0);  // woken by the futex, not by the 5 s timeout
}

TEST(IpcLiveness, StoppedWriterIsReportedAtOnceThenWaitedOut) {
  ShmName name;
  PoseRingWriter writer(options_for(name));
  PoseRingReader reader;
  ASSERT_EQ(reader.open(name.value), HANDTRACK_OK);
  writer.mark_stopped();
  FrameRecord out{};
  auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(reader.wait_next(out, 2s), HANDTRACK_ERR_WRITER_STOPPED);
  EXPECT_LT(seconds_since(t0), 0.5);
  t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(reader.wait_next(out, 40ms), HANDTRACK_ERR_WRITER_STOPPED);  // no busy loop
  EXPECT_GE(seconds_since(t0), 0.040);
  handtrack::ipc::WriterStatus status{};
  ASSERT_EQ(reader.writer_status(status), HANDTRACK_OK);
  EXPECT_EQ(status.device_state, HANDTRACK_DEVICE_STOPPED);
  EXPECT_EQ(status.alive, 0);
}

TEST(IpcLiveness, SilentWriterIsReportedDeadWithinThreeHeartbeatPeriods) {
  ShmName name;
  constexpr auto kPeriod = 20ms;
  PoseRingWriter writer(options_for(name, 8, kPeriod));
  PoseRingReader reader;
  ASSERT_EQ(reader.open(name.value), HANDTRACK_OK);
  writer.publish(make_test_record(0));  // the last sign of life
  const auto last_beat = std::chrono::steady_clock::now();
  FrameRecord out{};
  ASSERT_EQ(reader.wait_next(out, 0ns), HANDTRACK_OK);
  EXPECT_EQ(reader.wait_next(out, 2s), HANDTRACK_ERR_WRITER_DEAD);
  const double after = seconds_since(last_beat);
  EXPECT_GE(after, 2.5 * 0.020 - 0.002);  // not before the heartbeat is 2.5 periods old
  EXPECT_LE(after, 3 * 0.020);           // and within 3 periods
  handtrack::ipc::WriterStatus status{};
  ASSERT_EQ(reader.writer_status(status), HANDTRACK_OK);
  EXPECT_EQ(status.alive, 0);
  // It comes back to life: the next wait sees records again.
  writer.heartbeat();
  writer.publish(make_test_record(1));
  ASSERT_EQ(reader.wait_next(out, 1s), HANDTRACK_OK);
  EXPECT_EQ(out.frame, 1U);
}

TEST(IpcLiveness, HeartbeatsKeepAnIdleWriterAlive) {
  ShmName name;
  PoseRingWriter writer(options_for(name, 8, 20ms));
  PoseRingReader reader;
  ASSERT_EQ(reader.open(name.value), HANDTRACK_OK);
  std::atomic<bool> done{false};
  std::thread beater([&] {
    while (!done.load()) {
      writer.heartbeat();
      std::this_thread::sleep_for(10ms);
    }
  });
  FrameRecord out{};
  const Status status = reader.wait_next(out, 250ms);
  done = true;
  beater.join();
  EXPECT_EQ(status, HANDTRACK_TIMEOUT);
}

TEST(IpcLiveness, StatsAndStateReachTheReader) {
  ShmName name;
  PoseRingWriter writer(options_for(name));
  PoseRingReader reader;
  ASSERT_EQ(reader.open(name.value), HANDTRACK_OK);
  handtrack::ipc::RingStats stats{};
  stats.fps = 59.5F;
  stats.optimize_ms = 12.25F;
  stats.latency_p99_ms = 30.0F;
  stats.frames_dropped = 3;
  stats.frames_skipped = 4;
  stats.frames_captured = 1000;
  writer.set_stats(stats);
  writer.set_device_state(DeviceState::kWaitingForDevice);
  writer.publish(make_test_record(0));
  writer.publish(make_test_record(1));
  handtrack::ipc::WriterStatus status{};
  ASSERT_EQ(reader.writer_status(status), HANDTRACK_OK);
  EXPECT_EQ(status.device_state, HANDTRACK_DEVICE_WAITING_FOR_DEVICE);
  EXPECT_EQ(status.alive, 1);
  EXPECT_EQ(status.writer_pid, ::getpid());
  EXPECT_EQ(status.capacity, 8U);
  EXPECT_EQ(status.epoch, writer.epoch());
  EXPECT_EQ(status.records_published, 2U);
  EXPECT_EQ(status.heartbeat_period_ns, 100'000'000);
  EXPECT_LT(status.heartbeat_age_ns, 100'000'000);
  EXPECT_EQ(std::memcmp(&status.stats, &stats, sizeof stats), 0);
}

TEST(IpcRestart, NewWriterGetsALargerEpochAndReadersFollowIt) {
  ShmName name;
  PoseRingReader reader;
  std::uint64_t first_epoch = 0;
  {
    PoseRingWriter first(options_for(name));
    first_epoch = first.epoch();
    first.publish(make_test_record(1));
    ASSERT_EQ(reader.open(name.value), HANDTRACK_OK);
  }  // stopped
  PoseRingWriter second(options_for(name));
  EXPECT_GT(second.epoch(), first_epoch);
  ASSERT_TRUE(second.replaced_epoch().has_value());
  EXPECT_EQ(*second.replaced_epoch(), first_epoch);
  second.publish(make_test_record(100));
  FrameRecord out{};
  ASSERT_EQ(reader.wait_next(out, 1s), HANDTRACK_OK);  // reattached on its own
  EXPECT_EQ(out.frame, 100U);
  EXPECT_EQ(out.epoch, second.epoch());
  EXPECT_EQ(reader.epoch(), second.epoch());
}

TEST(IpcRestart, WaitingReaderIsWokenByTheReplacingWriter) {
  ShmName name;
  auto first = std::make_unique<PoseRingWriter>(options_for(name, 8, 1000ms));
  PoseRingReader reader;
  ASSERT_EQ(reader.open(name.value), HANDTRACK_OK);
  std::uint64_t second_epoch = 0;
  std::thread restarter([&] {
    std::this_thread::sleep_for(30ms);
    PoseRingWriter::Options o = options_for(name);
    o.replace_live_writer = true;  // `first` still looks alive: heartbeat fresh, our own pid
    PoseRingWriter second(o);
    second_epoch = second.epoch();
    second.publish(make_test_record(5));
    std::this_thread::sleep_for(300ms);
  });
  FrameRecord out{};
  const auto t0 = std::chrono::steady_clock::now();
  const Status status = reader.wait_next(out, 3s);
  const double waited = seconds_since(t0);
  restarter.join();
  ASSERT_EQ(status, HANDTRACK_OK);
  EXPECT_EQ(out.frame, 5U);
  EXPECT_EQ(out.epoch, second_epoch);
  EXPECT_LT(waited, 0.3);  // well before the 1 s heartbeat period could expire
}

TEST(IpcOwnership, LiveWriterIsNotReplacedUnlessAsked) {
  ShmName name;
  PoseRingWriter first(options_for(name));
  try {
    PoseRingWriter second(options_for(name));
    FAIL() << "a second writer took over a live segment";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("live writer"), std::string::npos) << e.what();
  }
  PoseRingWriter::Options o = options_for(name);
  o.replace_live_writer = true;
  PoseRingWriter third(o);
  EXPECT_GT(third.epoch(), first.epoch());
}

TEST(IpcOwnership, GarbageUnderTheNameIsReplaced) {
  ShmName name;
  {
    bip::shared_memory_object garbage(bip::create_only, name.value.c_str(), bip::read_write);
    garbage.truncate(4096);
    bip::mapped_region region(garbage, bip::read_write);
    std::memset(region.get_address(), 0xAB, region.get_size());
  }
  PoseRingWriter writer(options_for(name));
  EXPECT_FALSE(writer.replaced_epoch().has_value());
  writer.publish(make_test_record(3));
  PoseRingReader reader;
  ASSERT_EQ(reader.open(name.value), HANDTRACK_OK) << reader.error_detail();
  FrameRecord out{};
  ASSERT_EQ(reader.latest(out), HANDTRACK_OK);
  EXPECT_EQ(out.frame, 3U);
}

TEST(IpcOwnership, SegmentIsGroupReadableAndFullyReserved) {
  ShmName name;
  PoseRingWriter writer(options_for(name, 64));
  struct stat st {};
  ASSERT_EQ(::stat(("/dev/shm/" + name.value).c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640U);
  EXPECT_EQ(static_cast<std::uint64_t>(st.st_size), shm::segment_size(64));
  // posix_fallocate: the pages are allocated now, not on first touch.
  EXPECT_GE(static_cast<std::uint64_t>(st.st_blocks) * 512, shm::segment_size(64));
}

TEST(IpcOwnership, InvalidOptionsAreRefusedWithTheReason) {
  ShmName name;
  auto message_for = [&](PoseRingWriter::Options o) -> std::string {
    try {
      PoseRingWriter w(o);
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(message_for(options_for(name, 1)).find("capacity 1"), std::string::npos);
  EXPECT_NE(message_for(options_for(name, 8, 0ms)).find("heartbeat period"), std::string::npos);
  PoseRingWriter::Options slash = options_for(name);
  slash.name = "a/b";
  EXPECT_NE(message_for(slash).find("invalid name"), std::string::npos);
}

TEST(IpcOpen, CorruptOrMissingSegmentsAreRefusedWithAClearError) {
  ShmName name;
  PoseRingReader reader;
  EXPECT_EQ(reader.open(name.value), HANDTRACK_ERR_NOT_FOUND);
  EXPECT_NE(reader.error_detail().find(name.value), std::string::npos);
  EXPECT_EQ(reader.open(""), HANDTRACK_ERR_INVALID_ARGUMENT);

  struct Case {
    const char* what;
    void (*corrupt)(shm::Header&);
    Status status;
    const char* needle;
  };
  const Case cases[] = {
      {"magic", [](shm::Header& h) { h.magic.store(42, std::memory_order_relaxed); },
       HANDTRACK_ERR_BAD_MAGIC, "not a handtrack segment"},
      // A v2 client meeting a newer segment (what a v1 client meets on a v2 daemon's segment), and
      // an older one: refused, and the message names both versions and what to do.
      {"newer version", [](shm::Header& h) { h.abi_version = 3; }, HANDTRACK_ERR_BAD_VERSION,
       "has ABI version 3, this client reads version 2: rebuild the client against the installed handtrack"},
      {"older version", [](shm::Header& h) { h.abi_version = 1; }, HANDTRACK_ERR_BAD_VERSION,
       "has ABI version 1, this client reads version 2: the running handtrackd is older than this client; "
       "upgrade and restart it"},
      {"record size", [](shm::Header& h) { h.record_size = 512; }, HANDTRACK_ERR_BAD_RECORD_SIZE,
       "record size is 512"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    PoseRingWriter writer(options_for(name));
    {
      bip::shared_memory_object object(bip::open_only, name.value.c_str(), bip::read_write);
      bip::mapped_region region(object, bip::read_write);
      c.corrupt(*static_cast<shm::Header*>(region.get_address()));
    }
    EXPECT_EQ(reader.open(name.value), c.status);
    EXPECT_NE(reader.error_detail().find(c.needle), std::string::npos) << reader.error_detail();
    // The C API says the same.
    handtrack_client* client = nullptr;
    EXPECT_EQ(handtrack_open(name.value.c_str(), &client), c.status);
    EXPECT_EQ(client, nullptr);
    EXPECT_NE(std::string(handtrack_error_detail()).find(c.needle), std::string::npos);
    EXPECT_GT(std::strlen(handtrack_strerror(c.status)), 10U);
    PoseRingWriter::remove(name.value);
  }
  {
    SCOPED_TRACE("truncated");
    PoseRingWriter writer(options_for(name, 64));
    {
      bip::shared_memory_object object(bip::open_only, name.value.c_str(), bip::read_write);
      object.truncate(static_cast<bip::offset_t>(shm::segment_size(64) - sizeof(shm::Slot) * 10));
    }
    EXPECT_EQ(reader.open(name.value), HANDTRACK_ERR_TRUNCATED);
    EXPECT_NE(reader.error_detail().find("truncated"), std::string::npos) << reader.error_detail();
    handtrack_client* client = nullptr;
    EXPECT_EQ(handtrack_open(name.value.c_str(), &client), HANDTRACK_ERR_TRUNCATED);
  }
}

TEST(IpcCApi, ReadsRecordsAndReportsMissed) {
  ShmName name;
  PoseRingWriter writer(options_for(name, 4));
  handtrack_client* client = nullptr;
  ASSERT_EQ(handtrack_open(name.value.c_str(), &client), HANDTRACK_OK);
  handtrack_frame frame{};
  EXPECT_EQ(handtrack_latest(client, &frame), HANDTRACK_NO_RECORD);
  for (std::uint64_t f = 0; f < 10; ++f) writer.publish(make_test_record(f));
  ASSERT_EQ(handtrack_wait_next(client, &frame, 0), HANDTRACK_OK);
  EXPECT_EQ(frame.frame, 7U);  // 10 published into 4 slots: oldest safe is 10 - 4 + 1
  EXPECT_EQ(handtrack_missed(client), 7U);
  ASSERT_EQ(handtrack_latest(client, &frame), HANDTRACK_OK);
  EXPECT_EQ(frame.frame, 9U);
  EXPECT_TRUE(is_whole_test_record(frame));
  EXPECT_EQ(handtrack_missed(client), 1U);
  EXPECT_EQ(handtrack_missed_total(client), 8U);
  handtrack_writer_status status{};
  ASSERT_EQ(handtrack_writer_status_get(client, &status), HANDTRACK_OK);
  EXPECT_EQ(status.records_published, 10U);
  // Both hands of frame 9 (test_pattern.hpp): hand 1 right recovering, hand 2 left tracking.
  ASSERT_EQ(frame.hand_count, 2U);
  EXPECT_EQ(frame.hands[0].hand_id, 1U);
  EXPECT_STREQ(handtrack_handedness_name(frame.hands[0].handedness), "right");
  EXPECT_STREQ(handtrack_state_name(frame.hands[0].state), "recovering");
  EXPECT_EQ(frame.hands[1].hand_id, 2U);
  EXPECT_STREQ(handtrack_handedness_name(frame.hands[1].handedness), "left");
  EXPECT_STREQ(handtrack_state_name(frame.hands[1].state), "tracking");
  EXPECT_STREQ(handtrack_handedness_name(HANDTRACK_HANDEDNESS_UNKNOWN), "unknown");
  EXPECT_STREQ(handtrack_device_state_name(status.device_state), "starting");
  EXPECT_EQ(handtrack_wait_next(nullptr, &frame, 0), HANDTRACK_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(handtrack_open(name.value.c_str(), nullptr), HANDTRACK_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(handtrack_frame_size(), sizeof(handtrack_frame));
  EXPECT_EQ(handtrack_hand_size(), sizeof(handtrack_hand));
  EXPECT_EQ(handtrack_abi_version(), 2U);
  handtrack_close(client);
  handtrack_close(nullptr);
}

// In-process concurrency (the part TSan checks): a writer thread at full speed into a 2-slot ring
// (every publish overwrites the slot a reader most likely copies) and reader threads that check
// every record they accept, and that its hands are all of its frame.
TEST(IpcConcurrency, ReaderThreadsNeverAcceptATornRecord) {
  ShmName name;
  PoseRingWriter writer(options_for(name, 2));
  std::atomic<bool> stop{false};
  std::thread publisher([&] {
    for (std::uint64_t f = 0; !stop.load(std::memory_order_relaxed); ++f) {
      writer.publish(make_test_record(f));
    }
  });
  constexpr int kReaders = 2;
  constexpr std::uint64_t kReadsEach = kUnderTsan ? 20'000 : 100'000;  // TSan: ~20x slower
  std::vector<std::thread> readers;
  std::vector<std::uint64_t> torn(kReaders, 0), mixed(kReaders, 0), accepted(kReaders, 0), distinct(kReaders, 0);
  for (int r = 0; r < kReaders; ++r) {
    readers.emplace_back([&, r] {
      PoseRingReader reader;
      if (reader.open(name.value) != HANDTRACK_OK) return;
      FrameRecord out{};
      std::uint64_t last = UINT64_MAX;
      const auto end = std::chrono::steady_clock::now() + 20s;
      while (accepted[r] < kReadsEach && std::chrono::steady_clock::now() < end) {
        const Status s = (r == 0) ? reader.latest(out) : reader.wait_next(out, 10ms);
        if (s != HANDTRACK_OK) continue;
        ++accepted[r];
        if (!is_whole_test_record(out)) ++torn[r];
        if (!hands_of_one_frame(out)) ++mixed[r];
        if (out.frame != last) ++distinct[r];
        last = out.frame;
      }
    });
  }
  for (auto& t : readers) t.join();
  stop = true;
  publisher.join();
  for (int r = 0; r < kReaders; ++r) {
    EXPECT_EQ(accepted[r], kReadsEach) << "reader " << r;
    EXPECT_EQ(torn[r], 0U) << "reader " << r;
    EXPECT_EQ(mixed[r], 0U) << "reader " << r;
    // The readers really raced the writer (latest() may run in bursts while the writer is off-CPU).
    EXPECT_GT(distinct[r], 10U) << "reader " << r;
  }
}
