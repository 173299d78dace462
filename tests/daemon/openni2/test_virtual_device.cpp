// Device loss and return for the live OpenNI2 source, without hardware: the real libOpenNI2
// loads handtrack's virtual driver (virtual_driver/virtual_depth_driver.cpp) and the test
// "unplugs" and "replugs" it by removing and creating its plug file.
//
// How OpenNI2 is made to load our driver (Debian's 2.2.0.33): OpenNI::initialize() reads
// /etc/openni2/OpenNI.ini (Repository= unset) and loads every lib*.so.0 (Debian's suffix) in "OpenNI2/Drivers"
// relative to the directory libOpenNI2.so.0 itself was loaded from (dladdr + realpath). There
// is no environment override. So main() below stages a private copy of the library:
//   $TMP/handtrack-oni2-XXXXXX/libOpenNI2.so.0                 (a copy, not a symlink)
//   $TMP/handtrack-oni2-XXXXXX/OpenNI2/Drivers/libhandtrack_virtual_depth.so.0 -> the built driver
// and runs the tests in a child process with LD_LIBRARY_PATH pointing there (only our driver is
// loaded: no real camera can interfere). Nothing under /etc or /usr is touched.
#include "handtrack/daemon/depth_source.hpp"
#include "virtual_stage.hpp"

#include <gtest/gtest.h>

#include <OniCAPI.h>

#include <dirent.h>
#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

namespace fs = std::filesystem;
using handtrack::daemon::DepthSource;
using handtrack::daemon::GrabStatus;
using handtrack::daemon::make_source;
using handtrack::daemon::RawFrame;
using handtrack::daemon::SourceOptions;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

namespace {

constexpr const char* kVirtualUri = "handtrack-virtual://depth0";

fs::path plug_file() { return fs::path(std::getenv(handtrack::test::kPlugFileEnv)); }
void plug() { std::ofstream(plug_file()) << "plugged\n"; }
void unplug() { fs::remove(plug_file()); }

int count_entries(const char* dir) {
  int n = 0;
  if (DIR* d = opendir(dir)) {
    while (const dirent* e = readdir(d)) {
      if (e->d_name[0] != '.') ++n;
    }
    closedir(d);
  }
  return n - (std::string(dir) == "/proc/self/fd" ? 1 : 0);  // the DIR's own descriptor
}
int thread_count() { return count_entries("/proc/self/task"); }
int fd_count() { return count_entries("/proc/self/fd"); }

// Thread exit shows in /proc a moment after join: wait briefly for a count to settle.
int settled(int (*count)(), int expected) {
  int n = count();
  for (int i = 0; i < 100 && n != expected; ++i) {
    std::this_thread::sleep_for(10ms);
    n = count();
  }
  return n;
}

// Opens, polling like the pipeline does, until `deadline`.
bool open_within(DepthSource& source, std::chrono::milliseconds deadline, std::string* why) {
  const auto end = Clock::now() + deadline;
  do {
    if (source.open(why)) return true;
    std::this_thread::sleep_for(20ms);
  } while (Clock::now() < end);
  return false;
}

int frames_within(DepthSource& source, int wanted, std::chrono::milliseconds deadline, RawFrame& frame) {
  int got = 0;
  const auto end = Clock::now() + deadline;
  while (got < wanted && Clock::now() < end) {
    if (source.grab(frame, 100ms) == GrabStatus::kFrame) ++got;
  }
  return got;
}

class VirtualDevice : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string problem = handtrack::test::staged_openni2_problem();
    ASSERT_TRUE(problem.empty()) << problem;
    plug();
  }
  void TearDown() override { plug(); }
};

TEST_F(VirtualDevice, StreamsDepthFramesWithIntrinsicsFromTheDevice) {
  auto source = make_source("openni2", SourceOptions{});
  EXPECT_TRUE(source->is_live());
  std::string why;
  ASSERT_TRUE(source->open(&why)) << why;
  const auto cam = source->camera();
  EXPECT_EQ(cam.width, 320);
  EXPECT_EQ(cam.height, 240);
  EXPECT_DOUBLE_EQ(cam.fps, 60.0);
  EXPECT_DOUBLE_EQ(cam.depth_scale_mm, 1.0);
  // The virtual sensor reports 58 x 45 degrees: f = (w/2) / tan(fov/2).
  EXPECT_NEAR(cam.fx, 160.0 / std::tan(29.0 * M_PI / 180.0), 0.05);
  EXPECT_NEAR(cam.fy, 120.0 / std::tan(22.5 * M_PI / 180.0), 0.05);
  EXPECT_DOUBLE_EQ(cam.cx, 160.0);
  EXPECT_DOUBLE_EQ(cam.cy, 120.0);

  RawFrame frame;
  const auto t0 = Clock::now();
  uint64_t previous = 0;
  for (int i = 0; i < 30; ++i) {
    ASSERT_EQ(source->grab(frame, 500ms), GrabStatus::kFrame) << i;
    ASSERT_EQ(frame.depth_raw.size(), 320u * 240u);
    EXPECT_GT(frame.frame_number, previous);
    previous = frame.frame_number;
    // The wall and the disc in front of it, unmirrored.
    EXPECT_EQ(*std::max_element(frame.depth_raw.begin(), frame.depth_raw.end()), 1800);
    EXPECT_EQ(*std::min_element(frame.depth_raw.begin(), frame.depth_raw.end()), 600);
    EXPECT_GT(frame.capture_ns, 0);
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  // 0.5 s at 60 fps; the bound only tells a stalled stream from a busy machine.
  EXPECT_LT(seconds, 2.0) << "30 frames at 60 fps";
  // The buffer is filled in place once it has the frame's size.
  const uint16_t* data = frame.depth_raw.data();
  ASSERT_EQ(source->grab(frame, 500ms), GrabStatus::kFrame);
  EXPECT_EQ(frame.depth_raw.data(), data);
}

TEST_F(VirtualDevice, FallsBackTo640x480At30WhenTheModeIsNotOffered) {
  SourceOptions options;
  options.width = 1280;
  options.height = 1024;
  options.fps = 30;
  auto source = make_source(std::string("openni2:") + kVirtualUri, options);
  std::string why;
  ASSERT_TRUE(source->open(&why)) << why;
  EXPECT_EQ(source->camera().width, 640);
  EXPECT_EQ(source->camera().height, 480);
  EXPECT_DOUBLE_EQ(source->camera().fps, 30.0);
  RawFrame frame;
  ASSERT_EQ(source->grab(frame, 500ms), GrabStatus::kFrame);
  EXPECT_EQ(frame.depth_raw.size(), 640u * 480u);
}

TEST_F(VirtualDevice, UnknownUriWaitsForThatDevice) {
  auto source = make_source("openni2:handtrack-virtual://no-such-camera", SourceOptions{});
  std::string why;
  EXPECT_FALSE(source->open(&why));
  EXPECT_NE(why.find("waiting for a device"), std::string::npos) << why;
  EXPECT_NE(why.find("no-such-camera"), std::string::npos) << why;
  RawFrame frame;
  EXPECT_EQ(source->grab(frame, 10ms), GrabStatus::kDisconnected);
}

TEST_F(VirtualDevice, WaitsForADeviceToBePluggedIn) {
  unplug();
  auto source = make_source("openni2", SourceOptions{});
  std::string why;
  // No device at all: refused, repeatedly, with the reason.
  for (int i = 0; i < 3; ++i) {
    EXPECT_FALSE(source->open(&why));
    EXPECT_NE(why.find("waiting for a device"), std::string::npos) << why;
    std::this_thread::sleep_for(30ms);
  }
  plug();
  ASSERT_TRUE(open_within(*source, 2s, &why)) << why;
  RawFrame frame;
  EXPECT_EQ(frames_within(*source, 5, 1s, frame), 5);
}

TEST_F(VirtualDevice, GrabReturnsPromptlyWhenUnpluggedDuringALongWait) {
  auto source = make_source("openni2", SourceOptions{});
  std::string why;
  ASSERT_TRUE(source->open(&why)) << why;
  RawFrame frame;
  ASSERT_EQ(frames_within(*source, 3, 1s, frame), 3);
  std::thread puller([] {
    std::this_thread::sleep_for(100ms);
    unplug();
  });
  // A grab with a 10 s timeout must not sit out the timeout (nor block for ever in readFrame).
  const auto t0 = Clock::now();
  GrabStatus s = GrabStatus::kFrame;
  while (s == GrabStatus::kFrame && Clock::now() - t0 < 5s) s = source->grab(frame, 10s);
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - t0).count();
  puller.join();
  EXPECT_EQ(s, GrabStatus::kDisconnected);
  // Against the 10 s timeout it must not sit out; 3 s leaves room for a busy machine.
  EXPECT_LT(ms, 3000) << "grab took " << ms << " ms to notice the unplug";
  std::printf("unplug noticed %lld ms after the grab started (unplug at ~100 ms)\n", static_cast<long long>(ms));
}

TEST_F(VirtualDevice, UnplugReplugCyclesLeakNoThreadsOrDescriptors) {
  const int threads_before = thread_count();
  const int fds_before = fd_count();
  {
    auto source = make_source("openni2", SourceOptions{});
    std::string why;
    ASSERT_TRUE(source->open(&why)) << why;
    RawFrame frame;
    ASSERT_EQ(frames_within(*source, 5, 1s, frame), 5);
    const int threads_open = thread_count();
    const int fds_open = fd_count();
    std::printf("threads: %d before, %d while open; fds: %d before, %d while open\n", threads_before,
                threads_open, fds_before, fds_open);

    constexpr int kCycles = 5;
    for (int cycle = 0; cycle < kCycles; ++cycle) {
      SCOPED_TRACE("cycle " + std::to_string(cycle));
      // Unplug: grab reports the loss within a bounded time, each call within about its timeout.
      unplug();
      const auto t0 = Clock::now();
      GrabStatus s = GrabStatus::kFrame;
      int64_t longest_ms = 0;
      while (s != GrabStatus::kDisconnected && Clock::now() - t0 < 3s) {
        const auto g0 = Clock::now();
        s = source->grab(frame, 200ms);
        longest_ms = std::max<int64_t>(
            longest_ms, std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - g0).count());
      }
      const auto lost_ms = std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - t0).count();
      ASSERT_EQ(s, GrabStatus::kDisconnected);
      // Bounds that tell a hang from a busy machine (a grab that ignored its 200 ms timeout would
      // block until the 3 s loop ends), not latency figures.
      EXPECT_LT(lost_ms, 2000);
      EXPECT_LE(longest_ms, 1000);
      source->close();

      // While unplugged: open() refuses with the reason, and keeps refusing.
      for (int i = 0; i < 3; ++i) {
        EXPECT_FALSE(source->open(&why));
        EXPECT_NE(why.find("waiting for a device"), std::string::npos) << why;
        std::this_thread::sleep_for(20ms);
      }

      // Replug: open succeeds again and frames resume.
      plug();
      const auto r0 = Clock::now();
      ASSERT_TRUE(open_within(*source, 2s, &why)) << why;
      EXPECT_EQ(frames_within(*source, 5, 1s, frame), 5);
      const auto resumed_ms = std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - r0).count();
      std::printf("cycle %d: loss reported after %lld ms, frames resumed %lld ms after replug\n", cycle,
                  static_cast<long long>(lost_ms), static_cast<long long>(resumed_ms));

      // Steady state: each cycle leaves the same threads and descriptors as the first open.
      EXPECT_EQ(settled(thread_count, threads_open), threads_open);
      EXPECT_EQ(settled(fd_count, fds_open), fds_open);
    }
  }
  // Source gone: OpenNI2 shut down, its and the driver's threads joined, nothing left open.
  EXPECT_EQ(settled(thread_count, threads_before), threads_before);
  EXPECT_EQ(settled(fd_count, fds_before), fds_before);
}

TEST_F(VirtualDevice, ASilentCameraIsReopened) {
  // The device stays listed but sends nothing (a hung sensor, or a driver that missed an unplug):
  // after 3 s of silence grab() reports it lost so that the pipeline reopens it.
  const fs::path stall_file = std::getenv(handtrack::test::kStallFileEnv);
  auto source = make_source("openni2", SourceOptions{});
  std::string why;
  ASSERT_TRUE(source->open(&why)) << why;
  RawFrame frame;
  ASSERT_EQ(frames_within(*source, 3, 1s, frame), 3);
  std::ofstream(stall_file) << "stalled\n";
  const auto t0 = Clock::now();
  GrabStatus s = GrabStatus::kFrame;
  while (s != GrabStatus::kDisconnected && Clock::now() - t0 < 6s) s = source->grab(frame, 200ms);
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_EQ(s, GrabStatus::kDisconnected);
  EXPECT_GT(seconds, 2.5);
  EXPECT_LT(seconds, 4.0);
  fs::remove(stall_file);
  source->close();
  ASSERT_TRUE(open_within(*source, 1s, &why)) << why;
  EXPECT_EQ(frames_within(*source, 5, 1s, frame), 5);
}

TEST_F(VirtualDevice, TwoSourcesShareOneOpenNI2Runtime) {
  // The runtime is process-wide: a second source (e.g. while the pipeline rebuilds) neither
  // re-initializes OpenNI2 nor shuts it down under the first.
  auto first = make_source("openni2", SourceOptions{});
  std::string why;
  ASSERT_TRUE(first->open(&why)) << why;
  {
    auto second = make_source(std::string("openni2:") + kVirtualUri, SourceOptions{});
    ASSERT_TRUE(second->open(&why)) << why;
    RawFrame frame;
    EXPECT_EQ(frames_within(*second, 3, 1s, frame), 3);
  }
  RawFrame frame;
  EXPECT_EQ(frames_within(*first, 3, 1s, frame), 3);
}

}  // namespace

int main(int argc, char** argv) {
  if (const int status = handtrack::test::run_in_staged_openni2(argc, argv); status >= 0) return status;
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
