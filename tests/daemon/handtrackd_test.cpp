// The real handtrackd binary, driven like a user or systemd would: poses read by the real
// handtrack-cat and compared with ground truth (seq: and synthetic: sources), the sd_notify
// protocol on a NOTIFY_SOCKET this test listens on (READY, watchdog pings that stop when the
// optimizer stalls, STATUS), clean SIGTERM, SIGHUP reload, --record, and bad input of every kind.
#include "child_process.hpp"
#include "handtrack/core/png_io.hpp"
#include "handtrack/core/sequence.hpp"
#include "source_frames.hpp"
#include "forged_png.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/socket.h>
#include <sys/un.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <regex>
#include <thread>

namespace handtrack::test {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using nlohmann::json;

const std::string kDaemon = HANDTRACKD_EXE;
// handtrackd built for tests with fault-injecting sources (faulty_handtrackd.cpp).
const std::string kFaultyDaemon = HANDTRACKD_FAULTY_EXE;
const std::string kCat = HANDTRACK_CAT_EXE;
const std::string kSynth = HANDTRACK_SYNTH_EXE;
constexpr double kMaxMeanFingertipErrorMm = 40.0;

struct Run {
  int code = -1;
  std::string out, err;
};

Run run(const std::vector<std::string>& argv, const TempDir& dir, const std::string& tag,
        std::chrono::milliseconds timeout = 30s, const std::vector<std::string>& env = {}) {
  Child child(argv, dir / (tag + ".out"), dir / (tag + ".err"), env);
  const auto code = child.wait(timeout);
  return {code.value_or(-1), child.out(), child.err()};
}

// Mean fingertip error (mm) of the cat's JSON lines (one hand each) against `truth(frame)`. A
// frame without a hand is a miss and fails the test.
template <typename Truth>
double mean_fingertip_error(const std::vector<json>& poses, Truth truth) {
  double sum = 0.0;
  int frames = 0;
  for (const auto& p : poses) {
    const Fingertips tips = truth(p.at("frame").get<int>());
    const json& hands = p.at("hands");
    EXPECT_EQ(hands.size(), 1U) << "frame " << p.at("frame") << ": the hand is missed";
    if (hands.empty()) continue;
    double frame_sum = 0.0;
    int n = 0;
    for (int f = 0; f < kNumFingers; ++f) {
      if (!tips[static_cast<size_t>(f)]) continue;
      const auto& t = hands[0].at("fingertips").at(static_cast<size_t>(f));
      const Eigen::Vector3d got(t.at(0).get<double>(), t.at(1).get<double>(), t.at(2).get<double>());
      frame_sum += (got - *tips[static_cast<size_t>(f)]).norm();
      ++n;
    }
    if (n == 0) continue;
    sum += frame_sum / n;
    ++frames;
  }
  return frames > 0 ? sum / frames : 1e9;
}

std::vector<json> parse_lines(const std::string& text) {
  std::vector<json> out;
  for (const auto& line : lines_of(text)) out.push_back(json::parse(line));
  return out;
}

// The numbers of handtrackd's last line ("stopped: N frames captured, M published ...").
struct Summary {
  int captured = -1, published = -1, dropped = -1, skipped = -1, empty = -1, source_errors = -1;
};
Summary summary_of(const std::string& err) {
  static const std::regex re(
      R"((\d+) frames captured, (\d+) published in [0-9.]+ s \([0-9.]+ fps\), (\d+) dropped, (\d+) skipped, (\d+) empty, (\d+) source errors)");
  std::smatch m;
  Summary s;
  if (std::regex_search(err, m, re)) {
    s = {std::stoi(m[1]), std::stoi(m[2]), std::stoi(m[3]), std::stoi(m[4]), std::stoi(m[5]), std::stoi(m[6])};
  }
  return s;
}

json cat_status(const std::string& shm, const TempDir& dir) {
  const auto r = run({kCat, "--shm-name", shm, "--status"}, dir, "status", 10s);
  return r.code == 0 ? json::parse(r.out) : json{};
}

class Handtrackd : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    scratch_ = new TempDir("suite");
    pinch_ = scratch_->path() / "pinch";
    const auto r = run({kSynth, "--motion", "pinch", "--frames", "60", "--out", pinch_.string()}, *scratch_, "synth",
                       120s);
    ASSERT_EQ(r.code, 0) << r.err;
  }
  static void TearDownTestSuite() {
    delete scratch_;
    scratch_ = nullptr;
  }
  void SetUp() override {
    std::ofstream(dir_ / "empty.toml") << "# no overrides: built-in defaults\n";
  }
  // handtrackd with a hermetic (empty) config unless the arguments name one.
  std::vector<std::string> daemon_args(std::vector<std::string> args, const std::string& exe = kDaemon) const {
    if (std::find(args.begin(), args.end(), "--config") == args.end()) {
      args.insert(args.begin(), {"--config", (dir_ / "empty.toml").string()});
    }
    args.insert(args.begin(), exe);
    return args;
  }
  // A copy of the pinch sequence to damage.
  fs::path copy_of_pinch(const std::string& name) const {
    const auto to = dir_ / name;
    fs::copy(pinch_, to, fs::copy_options::recursive);
    return to;
  }

  static inline TempDir* scratch_ = nullptr;
  static inline fs::path pinch_;
  TempDir dir_{::testing::UnitTest::GetInstance()->current_test_info()->name()};
};

TEST_F(Handtrackd, HelpExitsZero) {
  const auto r = run({kDaemon, "--help"}, dir_, "help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.out.find("--source"), std::string::npos);
  EXPECT_NE(r.out.find("--shm-name"), std::string::npos);
}

TEST_F(Handtrackd, SeqSourceFingertipsMatchGroundTruth) {
  ShmName shm("seq");
  // --from-start: the daemon plays the 60 frames in well under the cat's 50 ms poll for the ring,
  // so a cat that only waited for new poses could attach after most of them.
  Child cat({kCat, "--shm-name", shm.str(), "--count", "40", "--timeout", "30", "--from-start"}, dir_ / "cat.out",
            dir_ / "cat.err");
  const auto r = run(daemon_args({"--source", "seq:" + pinch_.string(), "--fast", "--shm-name", shm.str()}), dir_,
                     "daemon", 60s);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("60 frames captured, 60 published"), std::string::npos) << r.err;
  ASSERT_EQ(cat.wait(30s), 0) << cat.err();
  const auto poses = parse_lines(cat.out());
  ASSERT_EQ(poses.size(), 40U);
  const SequenceReader truth(pinch_);
  const double error = mean_fingertip_error(poses, [&](int frame) { return truth.fingertips(static_cast<size_t>(frame)); });
  std::printf("seq: mean fingertip error over %zu poses: %.1f mm\n", poses.size(), error);
  EXPECT_LT(error, kMaxMeanFingertipErrorMm);
  for (const auto& p : poses) {
    for (const json& hand : p.at("hands")) {
      EXPECT_EQ(hand.at("params").size(), 26U);
      EXPECT_EQ(hand.at("joints").size(), 21U);
    }
    EXPECT_GT(p.at("publish_ns").get<int64_t>(), p.at("capture_ns").get<int64_t>());
  }
  ASSERT_EQ(poses.back().at("hands").size(), 1U);
  EXPECT_EQ(poses.back().at("hands")[0].at("state"), "tracking");
  // The daemon exited at the end of the recording: the ring says so.
  EXPECT_EQ(cat_status(shm.str(), dir_).value("device_state", ""), "stopped");
}

// A camera mounted upside down (camera.roll = 180): the pinch rendered through a camera turned
// half round, its ground truth in that camera's frame. The daemon tracks each frame turned upright
// and publishes the poses turned back, so they meet the truth where the camera saw it (published in
// the upright image's frame they would be hundreds of mm off: x and y negated).
TEST_F(Handtrackd, ACameraMountedUpsideDownPublishesPosesInItsOwnFrame) {
  const fs::path upside_down = dir_ / "pinch-upside-down";
  const auto synth = run({kSynth, "--motion", "pinch", "--frames", "60", "--roll", "180", "--out", upside_down.string()},
                         dir_, "synth", 120s);
  ASSERT_EQ(synth.code, 0) << synth.err;
  std::ofstream(dir_ / "roll.toml") << "[camera]\nroll = 180\n";
  ShmName shm("roll");
  Child cat({kCat, "--shm-name", shm.str(), "--count", "40", "--timeout", "30", "--from-start"}, dir_ / "cat.out",
            dir_ / "cat.err");
  const auto r = run(daemon_args({"--config", (dir_ / "roll.toml").string(), "--source", "seq:" + upside_down.string(),
                                  "--fast", "--shm-name", shm.str()}),
                     dir_, "daemon", 60s);
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_EQ(cat.wait(30s), 0) << cat.err();
  const auto poses = parse_lines(cat.out());
  ASSERT_EQ(poses.size(), 40U);
  const SequenceReader truth(upside_down);
  const double error = mean_fingertip_error(poses, [&](int frame) { return truth.fingertips(static_cast<size_t>(frame)); });
  std::printf("camera upside down: mean fingertip error over %zu poses: %.1f mm\n", poses.size(), error);
  EXPECT_LT(error, kMaxMeanFingertipErrorMm);
  ASSERT_EQ(poses.back().at("hands").size(), 1U);
  EXPECT_EQ(poses.back().at("hands")[0].at("handedness"), "right");
}

TEST_F(Handtrackd, SyntheticSourceFingertipsMatchGroundTruth) {
  ShmName shm("synthetic");
  Child cat({kCat, "--shm-name", shm.str(), "--count", "60", "--timeout", "30", "--from-start"}, dir_ / "cat.out",
            dir_ / "cat.err");
  const auto r = run(daemon_args({"--source", "synthetic:pinch", "--fast", "--frames", "90", "--shm-name", shm.str()}),
                     dir_, "daemon", 60s);
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_EQ(cat.wait(30s), 0) << cat.err();
  const auto poses = parse_lines(cat.out());
  ASSERT_EQ(poses.size(), 60U);
  synth::SyntheticCamera camera(daemon::synthetic_source_options("pinch"));
  const double error = mean_fingertip_error(poses, [&](int frame) { return camera.render(frame).fingertips; });
  std::printf("synthetic: mean fingertip error over %zu poses: %.1f mm\n", poses.size(), error);
  EXPECT_LT(error, kMaxMeanFingertipErrorMm);
  ASSERT_EQ(poses.back().at("hands").size(), 1U);
  const json& last = poses.back().at("hands")[0];
  EXPECT_GE(last.at("pinch").at("strength").get<double>(), 0.0);
  EXPECT_GT(last.at("confidence").get<double>(), 0.0);
  EXPECT_NEAR(last.at("hand_scale").at("length").get<double>(), 1.0, 1e-6);
}

// ABI version 2 end to end: handtrack-cat prints one object per frame with its hands, each with its
// id and handedness; the synthetic camera renders a right hand, and it keeps its id while in view.
TEST_F(Handtrackd, CatPrintsEachFramesHandsWithIdAndHandedness) {
  ShmName shm("hands");
  Child cat({kCat, "--shm-name", shm.str(), "--count", "30", "--timeout", "30", "--from-start"}, dir_ / "cat.out",
            dir_ / "cat.err");
  const auto r = run(daemon_args({"--source", "synthetic:pinch", "--fast", "--frames", "40", "--shm-name", shm.str()}),
                     dir_, "daemon", 60s);
  ASSERT_EQ(r.code, 0) << r.err;
  ASSERT_EQ(cat.wait(30s), 0) << cat.err();
  const std::string text = cat.out();
  EXPECT_NE(text.find("\"hands\":[{\"hand_id\":"), std::string::npos) << text.substr(0, 400);
  const auto frames = parse_lines(text);
  ASSERT_EQ(frames.size(), 30U);
  std::uint32_t id = 0;
  int right = 0;
  for (const auto& f : frames) {
    for (const char* field : {"frame", "epoch", "capture_ns", "publish_ns", "missed", "hands"}) {
      EXPECT_TRUE(f.contains(field)) << field << " missing in " << f.dump();
    }
    ASSERT_EQ(f.at("hands").size(), 1U) << "one hand in view: " << f.dump();
    const json& hand = f.at("hands")[0];
    const auto hand_id = hand.at("hand_id").get<std::uint32_t>();
    EXPECT_NE(hand_id, 0U);
    if (id != 0) {
      EXPECT_EQ(hand_id, id) << "the hand keeps its id while it stays in view";
    }
    id = hand_id;
    right += hand.at("handedness") == "right";
    const auto confidence = hand.at("handedness_confidence").get<double>();
    EXPECT_TRUE(confidence >= 0.0 && confidence <= 1.0) << confidence;
  }
  EXPECT_EQ(frames.back().at("hands")[0].at("handedness"), "right") << "the synthetic camera renders a right hand";
  EXPECT_GE(right, 27) << "of 30 frames seen as a right hand";
}

// Two hands end to end (issue 14): `frames` of a two_apart scene (a right and a left hand) as
// handtrack-cat prints them: every frame has both hands, one left and one right, each with its own
// id that it keeps; the right hand is the one on the image's left (negative x), as the scene
// places it.
void expect_both_hands_kept(const std::vector<json>& frames) {
  std::uint32_t right_id = 0;
  std::uint32_t left_id = 0;
  size_t both_sides = 0;
  for (const auto& f : frames) {
    ASSERT_EQ(f.at("hands").size(), 2U) << "two hands in view: " << f.dump().substr(0, 300);
    std::uint32_t ids[2] = {};
    double x[2] = {};
    std::string side[2];
    for (int k = 0; k < 2; ++k) {
      const json& hand = f.at("hands")[static_cast<size_t>(k)];
      ids[k] = hand.at("hand_id").get<std::uint32_t>();
      side[k] = hand.at("handedness").get<std::string>();
      x[k] = hand.at("joints")[0][0].get<double>();  // the wrist
    }
    EXPECT_NE(ids[0], ids[1]);
    const int r_index = x[0] < x[1] ? 0 : 1;  // the hand on the image's left is the right hand
    both_sides += side[r_index] == "right" && side[1 - r_index] == "left" ? 1 : 0;
    if (right_id != 0) {
      EXPECT_EQ(ids[r_index], right_id) << "the right hand keeps its id";
      EXPECT_EQ(ids[1 - r_index], left_id) << "the left hand keeps its id";
    }
    right_id = ids[r_index];
    left_id = ids[1 - r_index];
  }
  EXPECT_GE(both_sides + 2, frames.size()) << "frames with each hand's side right";
}

// The synthetic two-hand scene through handtrackd (the second hand on the side threads), recorded
// with --record, and the recording played back through the seq: source: both times both hands.
TEST_F(Handtrackd, TwoHandsLiveAndFromTheirRecording) {
  const auto recorded = dir_ / "two_hands";
  for (const bool replay : {false, true}) {
    ShmName shm(replay ? "two-replay" : "two");
    Child cat({kCat, "--shm-name", shm.str(), "--count", "40", "--timeout", "30", "--from-start"}, dir_ / "cat.out",
              dir_ / "cat.err");
    const auto args = replay ? daemon_args({"--source", "seq:" + recorded.string(), "--fast", "--shm-name", shm.str()})
                             : daemon_args({"--source", "synthetic:two_apart", "--fast", "--frames", "50", "--record",
                                            recorded.string(), "--shm-name", shm.str()});
    const auto r = run(args, dir_, replay ? "replay" : "live", 60s);
    ASSERT_EQ(r.code, 0) << r.err;
    ASSERT_EQ(cat.wait(30s), 0) << cat.err();
    const auto frames = parse_lines(cat.out());
    ASSERT_EQ(frames.size(), 40U) << (replay ? "replayed" : "live");
    expect_both_hands_kept(frames);
  }
  EXPECT_EQ(SequenceReader(recorded).frame_count(), 50U);
}

// ---- sd_notify -------------------------------------------------------------------------------

class NotifyListener {
 public:
  explicit NotifyListener(const fs::path& path) : path_(path) {
    fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", path.c_str());
    fs::remove(path);
    bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    timeval tv{0, 20000};
    setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    thread_ = std::thread([this] {
      char buffer[4096];
      while (!done_) {
        const ssize_t n = recv(fd_, buffer, sizeof buffer - 1, 0);
        if (n <= 0) continue;
        const std::string text(buffer, static_cast<size_t>(n));
        std::lock_guard lock(mutex_);
        for (const auto& line : lines_of(text)) messages_.push_back({Clock::now(), line});
      }
    });
  }
  ~NotifyListener() {
    done_ = true;
    thread_.join();
    close(fd_);
    fs::remove(path_);
  }
  NotifyListener(const NotifyListener&) = delete;
  NotifyListener& operator=(const NotifyListener&) = delete;

  struct Message {
    Clock::time_point when;
    std::string text;
  };
  std::vector<Message> messages() {
    std::lock_guard lock(mutex_);
    return messages_;
  }
  std::string env() const { return "NOTIFY_SOCKET=" + path_.string(); }

 private:
  fs::path path_;
  int fd_ = -1;
  std::atomic<bool> done_{false};
  std::thread thread_;
  std::mutex mutex_;
  std::vector<Message> messages_;
};

std::vector<Clock::time_point> times_of(const std::vector<NotifyListener::Message>& m, const std::string& prefix) {
  std::vector<Clock::time_point> out;
  for (const auto& x : m) {
    if (x.text.rfind(prefix, 0) == 0) out.push_back(x.when);
  }
  return out;
}

bool any_starts(const std::vector<NotifyListener::Message>& m, const std::string& prefix, const std::string& contains = "") {
  return std::any_of(m.begin(), m.end(), [&](const auto& x) {
    return x.text.rfind(prefix, 0) == 0 && x.text.find(contains) != std::string::npos;
  });
}

// The daemon runs 3.5 s from READY=1. Timed from its start instead, the test failed once in the
// suite (2026-11-30; not seen again in the runs since, alone, beside CPU hogs and beside the
// mutants test; which expectation failed was not kept): under load the start, the forest loaded and the pool
// allocated, eats into those seconds, and it is not what the watchdog is about. The daemon's log
// now goes with each expectation.
TEST_F(Handtrackd, NotifiesReadyStatusAndWatchdogWhileProgressing) {
  ShmName shm("notify");
  NotifyListener listener(dir_ / "notify.sock");
  Child d(daemon_args({"--source", "synthetic:pinch", "--shm-name", shm.str()}), dir_ / "d.out", dir_ / "d.err",
          {listener.env(), "WATCHDOG_USEC=1000000"});
  const auto give_up = Clock::now() + 30s;
  std::vector<Clock::time_point> ready;
  while ((ready = times_of(listener.messages(), "READY=1")).empty() && Clock::now() < give_up) {
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_FALSE(ready.empty()) << "no READY=1 within 30 s\n" << d.err();
  std::this_thread::sleep_until(ready.front() + 3500ms);
  const auto end = Clock::now();
  d.signal(SIGTERM);
  ASSERT_EQ(d.wait(10s), 0) << d.err();
  const auto m = listener.messages();
  ASSERT_FALSE(m.empty());
  EXPECT_EQ(m.front().text, "READY=1");
  EXPECT_TRUE(any_starts(m, "STATUS=", "fps")) << "no STATUS= with the frame rate";
  EXPECT_TRUE(any_starts(m, "STOPPING=1"));
  const auto pings = times_of(m, "WATCHDOG=1");
  // WatchdogSec = 1 s: a ping every 0.5 s while the pipeline makes progress (7 in 3.5 s).
  EXPECT_GE(pings.size(), 5U) << d.err();
  ASSERT_FALSE(pings.empty());
  EXPECT_LT(end - pings.back(), 1200ms) << "pings stopped although the pipeline was progressing\n" << d.err();
}

TEST_F(Handtrackd, WatchdogPingsStopWhenTheSourceHangs) {
  ShmName shm("stall");
  NotifyListener listener(dir_ / "notify.sock");
  // The source's grab() stops returning after 20 frames, for 8 s (a hung camera driver); the
  // daemon notices within half the watchdog interval and says so with STATUS=stalled. From then
  // on: 2 s without a single ping.
  Child d(daemon_args({"--source", "hang-after:20:8", "--shm-name", shm.str()}, kFaultyDaemon), dir_ / "d.out",
          dir_ / "d.err", {listener.env(), "WATCHDOG_USEC=1000000"});
  const auto deadline = Clock::now() + 30s;
  std::optional<Clock::time_point> stalled_at;
  while (!stalled_at && Clock::now() < deadline) {
    std::this_thread::sleep_for(20ms);
    for (const auto& m : listener.messages()) {
      if (m.text.rfind("STATUS=stalled", 0) == 0) stalled_at = m.when;
    }
  }
  ASSERT_TRUE(stalled_at) << "no STATUS=stalled within 30 s\n" << d.err();
  std::this_thread::sleep_for(2s);
  const auto status = cat_status(shm.str(), dir_);
  d.signal(SIGTERM);
  // The grab thread comes back when the hang ends (8 s after it began): then the daemon stops.
  ASSERT_EQ(d.wait(15s), 0) << "a stalled daemon must still stop cleanly\n" << d.err();
  const auto m = listener.messages();
  const auto pings = times_of(m, "WATCHDOG=1");
  ASSERT_FALSE(pings.empty()) << "no ping before the stall";
  EXPECT_LT(pings.front(), *stalled_at);
  EXPECT_LE(pings.back(), *stalled_at) << "watchdog pings went on while the source was hanging";
  EXPECT_TRUE(any_starts(m, "STATUS=stalled", "grab busy on frame 20")) << "no STATUS=stalled naming the grab stage";
  EXPECT_NE(d.err().find("pipeline stalled (grab busy on frame 20"), std::string::npos) << d.err();
  // The ring's heartbeat stops too: clients see a dead writer, not a live one without poses.
  EXPECT_EQ(status.value("alive", true), false) << status.dump();
}

TEST_F(Handtrackd, SigtermStopsCleanlyAndMarksTheRingStopped) {
  ShmName shm("sigterm");
  Child d(daemon_args({"--source", "synthetic", "--shm-name", shm.str()}), dir_ / "d.out", dir_ / "d.err");
  const auto cat = run({kCat, "--shm-name", shm.str(), "--count", "10", "--timeout", "20"}, dir_, "cat", 30s);
  ASSERT_EQ(cat.code, 0) << cat.err;
  const auto live = cat_status(shm.str(), dir_);
  EXPECT_EQ(live.value("device_state", ""), "streaming");
  EXPECT_EQ(live.value("alive", false), true);
  d.signal(SIGTERM);
  const auto t0 = Clock::now();
  ASSERT_EQ(d.wait(5s), 0) << d.err();
  EXPECT_LT(Clock::now() - t0, 2s);
  EXPECT_NE(d.err().find("SIGTERM: stopping"), std::string::npos);
  const auto stopped = cat_status(shm.str(), dir_);
  EXPECT_EQ(stopped.value("device_state", ""), "stopped");
  EXPECT_EQ(stopped.value("alive", true), false);
}

TEST_F(Handtrackd, SighupReloadsLiveFieldsAndRefusesBadValues) {
  ShmName shm("sighup");
  const auto config = dir_ / "handtrackd.toml";
  std::ofstream(config) << "[tracker]\nparticles = 2\n";
  Child d(daemon_args({"--config", config.string(), "--source", "synthetic:pinch", "--shm-name", shm.str()}),
          dir_ / "d.out", dir_ / "d.err");
  ASSERT_EQ(run({kCat, "--shm-name", shm.str(), "--count", "5", "--timeout", "20"}, dir_, "cat1", 30s).code, 0);
  std::ofstream(config) << "[daemon]\nlog_level = \"debug\"\nring_capacity = 64\n[tracker]\nparticles = 1\n";
  d.signal(SIGHUP);
  std::this_thread::sleep_for(1500ms);
  std::ofstream(config) << "[tracker]\nparticles = 0\n";
  d.signal(SIGHUP);
  // Still tracking after the refused reload.
  ASSERT_EQ(run({kCat, "--shm-name", shm.str(), "--count", "5", "--timeout", "20"}, dir_, "cat2", 30s).code, 0);
  d.signal(SIGTERM);
  ASSERT_EQ(d.wait(10s), 0);
  const auto err = d.err();
  EXPECT_NE(err.find("SIGHUP: configuration reloaded"), std::string::npos) << err;
  EXPECT_NE(err.find("tracker parameters reloaded (1 particles"), std::string::npos) << err;
  EXPECT_NE(err.find("daemon.ring_capacity changed but only take effect after a restart"), std::string::npos) << err;
  EXPECT_NE(err.find("debug:"), std::string::npos) << "the new log level was not applied\n" << err;
  EXPECT_NE(err.find("reload refused"), std::string::npos) << err;
  EXPECT_NE(err.find("tracker.particles = 0 is out of range"), std::string::npos) << err;
}

TEST_F(Handtrackd, RecordWritesASequenceDirectory) {
  ShmName shm("record");
  const auto out = dir_ / "recorded";
  const auto r = run(daemon_args({"--source", "synthetic:pinch", "--fast", "--frames", "30", "--record", out.string(),
                                  "--shm-name", shm.str()}),
                     dir_, "daemon", 60s);
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("30 recorded"), std::string::npos) << r.err;
  const SequenceReader recorded(out);
  ASSERT_EQ(recorded.frame_count(), 30U);
  synth::SyntheticCamera camera(daemon::synthetic_source_options("pinch"));
  for (const size_t i : {size_t{0}, size_t{29}}) {
    const auto got = recorded.depth(i);
    const auto want = camera.render(recorded.frame_number(i)).depth;
    ASSERT_EQ(got.depth_mm.size(), want.depth_mm.size());
    double worst = 0.0;
    for (size_t k = 0; k < got.depth_mm.size(); ++k) {
      worst = std::max(worst, std::abs(double{got.depth_mm[k]} - double{want.depth_mm[k]}));
    }
    EXPECT_LE(worst, 0.5) << "frame " << i;  // raw = mm rounded to 1 mm units
  }
}

// ---- bad input -------------------------------------------------------------------------------

// One line on stderr, naming what it must, and a non-zero exit; no shared memory left behind.
void expect_one_line_error(const Run& r, const std::vector<std::string>& names) {
  EXPECT_NE(r.code, 0);
  EXPECT_NE(r.code, -1) << "did not exit";
  const auto lines = lines_of(r.err);
  EXPECT_EQ(lines.size(), 1U) << r.err;
  for (const auto& n : names) EXPECT_NE(r.err.find(n), std::string::npos) << "'" << n << "' missing in: " << r.err;
}

TEST_F(Handtrackd, MissingSequenceDirectoryIsAClearError) {
  ShmName shm("missing");
  const auto r = run(daemon_args({"--source", "seq:" + (dir_ / "nothing").string(), "--shm-name", shm.str()}), dir_, "d");
  expect_one_line_error(r, {(dir_ / "nothing").string()});
  EXPECT_FALSE(fs::exists("/dev/shm/" + shm.str())) << "a failed start leaves no ring behind";
}

TEST_F(Handtrackd, CorruptOrWrongCameraJsonIsAClearError) {
  ShmName shm("camjson");
  const auto seq = copy_of_pinch("seq");
  std::ofstream(seq / "camera.json") << "{\"width\": 320, \"height\": ";
  expect_one_line_error(run(daemon_args({"--source", "seq:" + seq.string(), "--shm-name", shm.str()}), dir_, "d1"),
                        {"camera.json"});
  std::ofstream(seq / "camera.json")
      << R"({"width":-320,"height":240,"fx":224.5,"fy":230.5,"cx":160,"cy":120,"depth_scale_mm":1,"fps":60})";
  expect_one_line_error(run(daemon_args({"--source", "seq:" + seq.string(), "--shm-name", shm.str()}), dir_, "d2"),
                        {"camera.json", "width"});
}

TEST_F(Handtrackd, CorruptPngFramesAreSkippedAndCounted) {
  ShmName shm("png");
  const auto seq = copy_of_pinch("seq");
  std::ofstream(seq / "depth" / "000010.png") << "this is not a PNG";
  {
    const auto png = read_text(seq / "depth" / "000020.png");
    std::ofstream(seq / "depth" / "000020.png", std::ios::binary) << png.substr(0, png.size() / 2);  // truncated
  }
  const auto r = run(daemon_args({"--source", "seq:" + seq.string(), "--fast", "--shm-name", shm.str()}), dir_, "d", 60s);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("bad frame skipped"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("000010.png"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("58 frames captured, 58 published"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("2 source errors"), std::string::npos) << r.err;
}

// Hostile sequence files (issue 13): a frame whose header claims 60000 x 60000 pixels (a 177-byte
// memory bomb) and an 8-bit frame are skipped and counted with their reason, read from the header
// without allocating; a garbage groundtruth.csv is not even opened (handtrackd never scores).
TEST_F(Handtrackd, HostileSequenceFilesAreSkippedWithTheirReason) {
  ShmName shm("hostile");
  const auto seq = copy_of_pinch("hostile");
  test::write_png_claiming(seq / "depth" / "000010.png", 60000, 60000);
  write_png_gray8(seq / "depth" / "000020.png", Gray8Image{320, 240, 1, std::vector<uint8_t>(320 * 240, 200)});
  std::ofstream(seq / "groundtruth.csv") << "\x01garbage,\n1,2\n";
  const auto r = run(daemon_args({"--source", "seq:" + seq.string(), "--fast", "--shm-name", shm.str()}), dir_, "d", 60s);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("is 60000x60000 but camera.json says 320x240"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("58 frames captured, 58 published"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("2 source errors"), std::string::npos) << r.err;
}

TEST_F(Handtrackd, ResolutionChangeInASequenceIsSkippedAndCounted) {
  ShmName shm("resolution");
  const auto seq = dir_ / "mixed";
  const auto camera = synth::default_camera(320, 240);
  {
    SequenceWriter writer(seq, camera);
    synth::SyntheticCamera small(daemon::synthetic_source_options("pinch"));
    for (int i = 0; i < 20; ++i) writer.write_depth(i, small.render(i).depth);
  }
  Gray16Image big{640, 480, 1, std::vector<uint16_t>(640 * 480, 400)};
  for (int i = 10; i < 15; ++i) write_png_gray16(frame_file(seq / "depth", i), big);
  const auto r = run(daemon_args({"--source", "seq:" + seq.string(), "--fast", "--shm-name", shm.str()}), dir_, "d", 60s);
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.err.find("is 640x480 but camera.json says 320x240"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("15 frames captured, 15 published"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("5 source errors"), std::string::npos) << r.err;
}

TEST_F(Handtrackd, AllZeroAndAllMaxRangeFramesAreNoHand) {
  ShmName shm("empty");
  const auto seq = dir_ / "blank";
  constexpr int kFrames = 30;
  {
    SequenceWriter writer(seq, synth::default_camera(320, 240));
    Gray16Image zero{320, 240, 1, std::vector<uint16_t>(320 * 240, 0)};
    Gray16Image far{320, 240, 1, std::vector<uint16_t>(320 * 240, 65535)};
    for (int i = 0; i < kFrames; ++i) writer.write_depth_raw(i, i % 2 == 0 ? zero : far);
  }
  Child cat({kCat, "--shm-name", shm.str(), "--count", "10", "--timeout", "20"}, dir_ / "cat.out", dir_ / "cat.err");
  // Paced at 60 fps, so the cat has attached before most frames come.
  const auto r = run(daemon_args({"--source", "seq:" + seq.string(), "--shm-name", shm.str()}), dir_, "d", 60s);
  EXPECT_EQ(r.code, 0) << r.err;
  const auto s = summary_of(r.err);
  EXPECT_EQ(s.captured, kFrames) << r.err;
  EXPECT_GT(s.published, 0);
  EXPECT_EQ(s.empty, s.published) << "every published frame without depth counts as empty\n" << r.err;
  EXPECT_EQ(s.published + s.dropped, kFrames) << r.err;
  ASSERT_EQ(cat.wait(20s), 0) << cat.err();
  for (const auto& p : parse_lines(cat.out())) EXPECT_TRUE(p.at("hands").empty()) << p.dump();
}

// The real OpenNI2 recording (head and shoulders at ~1.5 m, a shoulder reaching to ~550 mm, no
// hand in the working volume): every frame is read through OpenNI2 and published as "no hand".
TEST_F(Handtrackd, RealOniRecordingWithoutAHandIsNoHand) {
  const fs::path oni = fs::path(HANDTRACK_SHARED_DATA_DIR) / "oni" / "head-and-shoulders-640x480.oni";
  if (!fs::exists(oni)) GTEST_SKIP() << "shared data absent: " << oni;
  ShmName shm("oni");
  // From the ring's start (the cat may attach after the first frames went out), and every frame
  // of the recording (--fast: OpenNI2's player hands out each frame in turn; at the recording's
  // own 30 fps it skips a frame when the machine is busy: 23 of 24 were seen in a CI run).
  Child cat({kCat, "--shm-name", shm.str(), "--count", "10", "--timeout", "20", "--from-start"}, dir_ / "cat.out",
            dir_ / "cat.err");
  const auto r =
      run(daemon_args({"--source", "oni:" + oni.string(), "--fast", "--shm-name", shm.str()}), dir_, "d", 60s);
  EXPECT_EQ(r.code, 0) << r.err;
  const auto s = summary_of(r.err);
  EXPECT_EQ(s.captured, 24) << r.err;
  EXPECT_EQ(s.published + s.dropped, 24) << r.err;
  ASSERT_EQ(cat.wait(20s), 0) << cat.err();
  const auto poses = parse_lines(cat.out());
  EXPECT_EQ(poses.size(), 10U);
  for (const auto& p : poses) EXPECT_TRUE(p.at("hands").empty()) << p.dump();
}

struct BadConfig {
  const char* toml;
  std::vector<std::string> names;  // besides the file name
};

TEST_F(Handtrackd, BadConfigValuesAreRefusedWithFileFieldAndRange) {
  const std::vector<BadConfig> cases = {
      {"[tracker]\nparticles = 0\n", {"tracker.particles", "1..64"}},
      {"[tracker.energy]\nw_c = -1.0\n", {"tracker.energy.w_c", "0.0..1000.0"}},
      {"[tracker.optimizer]\niterations = 100000\n", {"tracker.optimizer.iterations", "1..1000"}},
      {"[tracker.input]\nnear_mm = 700.0\n", {"tracker.input.near_mm", "tracker.input.far_mm"}},
      {"[tracker.input]\nquadtree_threshold_mm = \"twenty\"\n", {"tracker.input.quadtree_threshold_mm", "number"}},
      {"[pipeline]\nrealtime_priority = 120\n", {"pipeline.realtime_priority", "0..99"}},
      {"[daemon]\nlog_level = \"loud\"\n", {"daemon.log_level", "trace, debug"}},
      {"[daemon]\nshm_name = \"a/b\"\n", {"daemon.shm_name", "without '/'"}},
      {"[tracker]\nparticels = 2\n", {"unknown field", "tracker.particels"}},
      {"[tracker\nparticles = 2\n", {":1:", "TOML syntax error"}},
  };
  int i = 0;
  for (const auto& c : cases) {
    const auto file = dir_ / ("bad" + std::to_string(i++) + ".toml");
    std::ofstream(file) << c.toml;
    auto names = c.names;
    names.push_back(file.string());
    SCOPED_TRACE(c.toml);
    expect_one_line_error(run(daemon_args({"--config", file.string(), "--source", "synthetic"}), dir_, "d"), names);
  }
  expect_one_line_error(run(daemon_args({"--particles", "0", "--source", "synthetic"}), dir_, "cli"),
                        {"tracker.particles", "1..64"});
}

TEST_F(Handtrackd, UnreadableOrMissingConfigIsAClearError) {
  expect_one_line_error(run(daemon_args({"--config", (dir_ / "nope.toml").string()}), dir_, "missing"),
                        {"nope.toml", "no such file"});
  expect_one_line_error(run(daemon_args({"--config", dir_.path().string()}), dir_, "dir"), {"is a directory"});
  const auto garbage = dir_ / "garbage.toml";
  std::ofstream(garbage, std::ios::binary) << std::string("\x89PNG\r\n\x1a\n\0\0\xff\xfe", 12);
  expect_one_line_error(run(daemon_args({"--config", garbage.string()}), dir_, "garbage"), {"garbage.toml"});
  if (geteuid() != 0) {  // root reads any file
    const auto locked = dir_ / "locked.toml";
    std::ofstream(locked) << "[tracker]\nparticles = 2\n";
    fs::permissions(locked, fs::perms::none);
    expect_one_line_error(run(daemon_args({"--config", locked.string()}), dir_, "locked"), {"locked.toml", "cannot read"});
  }
}

TEST_F(Handtrackd, UnknownSourceIsAClearError) {
  expect_one_line_error(run(daemon_args({"--source", "webcam"}), dir_, "d1"), {"webcam", "unknown source"});
  expect_one_line_error(run(daemon_args({"--source", "synthetic:juggle"}), dir_, "d2"), {"juggle", "unknown motion"});
}

// A 10 MB string in the configuration (issue 13) is named in one line, not echoed whole.
TEST_F(Handtrackd, AHugeConfigStringIsNotEchoedWhole) {
  const auto config = dir_ / "huge.toml";
  std::ofstream(config) << "[daemon]\nsource = \"" << std::string(10'000'000, 'x') << "\"\n";
  const auto r = run(daemon_args({"--config", config.string()}), dir_, "d", 60s);
  expect_one_line_error(r, {"huge.toml: daemon.source", "characters left out"});
  EXPECT_LT(r.err.size(), 2000U);
}

}  // namespace
}  // namespace handtrack::test
