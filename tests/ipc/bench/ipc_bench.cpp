// Google Benchmark: what a client pays to read, and what the writer pays to publish.
//   BM_ReadLatest      PoseRingReader::latest() of a 1336-byte frame record, two hands (target: <= 100 ns median)
//   BM_CReadLatest     the same through the C API (handtrack_latest)
//   BM_TryNextNothing  polling for a record that is not there yet
//   BM_Publish         PoseRingWriter::publish() including the FUTEX_WAKE system call
#include <handtrack/client.h>
#include <handtrack/ipc/pose_ring_reader.hpp>
#include <handtrack/ipc/pose_ring_writer.hpp>

#include "../test_pattern.hpp"

#include <benchmark/benchmark.h>

#include <string>

#include <unistd.h>

namespace {

using handtrack::ipc::FrameRecord;
using handtrack::ipc::PoseRingReader;
using handtrack::ipc::PoseRingWriter;

struct Ring {
  std::string name = "ht_bench_" + std::to_string(::getpid());
  PoseRingWriter writer;
  Ring() : writer(make_options(name)) {
    for (std::uint64_t f = 0; f < 10; ++f) writer.publish(handtrack::ipc::test::make_test_record(f));
  }
  ~Ring() { PoseRingWriter::remove(name); }
  static PoseRingWriter::Options make_options(const std::string& n) {
    PoseRingWriter::Options o;
    o.name = n;
    o.replace_live_writer = true;
    return o;
  }
};

void BM_ReadLatest(benchmark::State& state) {
  Ring ring;
  PoseRingReader reader;
  if (reader.open(ring.name) != HANDTRACK_OK) state.SkipWithError("open failed");
  FrameRecord out;
  for (auto _ : state) {
    benchmark::DoNotOptimize(reader.latest(out));
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_ReadLatest);

void BM_CReadLatest(benchmark::State& state) {
  Ring ring;
  handtrack_client* client = nullptr;
  if (handtrack_open(ring.name.c_str(), &client) != HANDTRACK_OK) state.SkipWithError("open failed");
  handtrack_frame out;
  for (auto _ : state) {
    benchmark::DoNotOptimize(handtrack_latest(client, &out));
    benchmark::ClobberMemory();
  }
  handtrack_close(client);
}
BENCHMARK(BM_CReadLatest);

void BM_TryNextNothing(benchmark::State& state) {
  Ring ring;
  PoseRingReader reader;
  if (reader.open(ring.name) != HANDTRACK_OK) state.SkipWithError("open failed");
  FrameRecord out;
  for (auto _ : state) benchmark::DoNotOptimize(reader.try_next(out));
}
BENCHMARK(BM_TryNextNothing);

void BM_Publish(benchmark::State& state) {
  Ring ring;
  const FrameRecord record = handtrack::ipc::test::make_test_record(1);
  for (auto _ : state) ring.writer.publish(record);
}
BENCHMARK(BM_Publish);

}  // namespace

BENCHMARK_MAIN();
