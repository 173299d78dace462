// handtrack-cat against a real writer process: the JSON lines carry the SPEC fields with the
// values the writer published; bad input and a missing daemon fail with one line on stderr.
#include <handtrack/ipc/pose_ring_writer.hpp>

#include "test_pattern.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstdio>
#include <sstream>
#include <string>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

namespace {

struct Result {
  int exit_code = -1;
  std::string out, err;
};

Result run(const std::string& args) {
  const std::string err_path = "/tmp/ht_cat_err_" + std::to_string(::getpid());
  const std::string command = std::string(HANDTRACK_CAT) + " " + args + " 2>" + err_path;
  Result r;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) r.out.append(buffer, n);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (FILE* f = std::fopen(err_path.c_str(), "r")) {
    for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;) r.err.append(buffer, n);
    std::fclose(f);
  }
  std::remove(err_path.c_str());
  return r;
}

int count_lines(const std::string& s) {
  int n = 0;
  for (char c : s) n += c == '\n';
  return n;
}

}  // namespace

TEST(HandtrackCat, PrintsOneJsonObjectPerFrameWithItsHandsAndTheSpecFields) {
  const std::string name = "ht_cat_" + std::to_string(::getpid());
  handtrack::ipc::PoseRingWriter::remove(name);
  const pid_t writer = ::fork();
  if (writer == 0) {
    ::execl(IPC_TEST_WRITER, IPC_TEST_WRITER, "--name", name.c_str(), "--rate-hz", "200",
            static_cast<char*>(nullptr));
    ::_exit(127);
  }
  const Result r = run("--shm-name " + name + " --count 5 --timeout 5");
  ::kill(writer, SIGTERM);
  ::waitpid(writer, nullptr, 0);
  const Result status = run("--shm-name " + name + " --status");
  handtrack::ipc::PoseRingWriter::remove(name);

  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_EQ(count_lines(r.out), 5) << r.out;
  std::istringstream lines(r.out);
  std::uint64_t previous_frame = 0;
  bool first = true;
  for (std::string line; std::getline(lines, line);) {
    const auto j = nlohmann::json::parse(line);
    const std::uint64_t frame = j.at("frame").get<std::uint64_t>();
    const handtrack::ipc::FrameRecord expected = handtrack::ipc::test::make_test_record(frame);
    EXPECT_GT(j.at("epoch").get<std::uint64_t>(), 0U);
    EXPECT_EQ(j.at("capture_ns").get<std::int64_t>(), expected.capture_ns);
    EXPECT_GT(j.at("publish_ns").get<std::int64_t>(), 0);
    EXPECT_FLOAT_EQ(j.at("timings_ms").at("optimize").get<float>(), expected.optimize_ms);
    const auto& hands = j.at("hands");
    ASSERT_EQ(hands.size(), 2U) << "every hand of the frame, in one object";
    const char* states[] = {"no_hand", "tracking", "recovering"};
    for (std::size_t k = 0; k < hands.size(); ++k) {
      SCOPED_TRACE("hand " + std::to_string(k));
      const auto& h = hands[k];
      const handtrack::ipc::HandRecord& e = expected.hands[k];
      EXPECT_EQ(h.at("hand_id").get<std::uint32_t>(), e.hand_id);
      EXPECT_EQ(h.at("handedness"), k == 0 ? "right" : "left");
      EXPECT_FLOAT_EQ(h.at("handedness_confidence").get<float>(), e.handedness_confidence);
      EXPECT_EQ(h.at("state"), states[e.state]);
      EXPECT_FLOAT_EQ(h.at("confidence").get<float>(), e.confidence);
      EXPECT_FLOAT_EQ(h.at("energy").get<float>(), e.energy);
      EXPECT_FLOAT_EQ(h.at("optimize_ms").get<float>(), e.optimize_ms);
      ASSERT_EQ(h.at("params").size(), 26U);
      EXPECT_EQ(h.at("params")[0].get<double>(), static_cast<double>(frame)) << "the hand is of this frame";
      EXPECT_EQ(h.at("params")[3].get<double>(), e.params[3]);
      EXPECT_EQ(h.at("params")[25].get<double>(), e.params[25]);  // exact round trip
      ASSERT_EQ(h.at("joints").size(), 21U);
      ASSERT_EQ(h.at("joints")[20].size(), 3U);
      EXPECT_EQ(h.at("joints")[20][2].get<float>(), e.joints_mm[20][2]);
      ASSERT_EQ(h.at("fingertips").size(), 5U);
      EXPECT_EQ(h.at("fingertips")[4][0].get<float>(), e.fingertips_mm[4][0]);
      EXPECT_EQ(h.at("pinch").at("distance_mm").get<float>(), e.pinch_distance_mm);
      EXPECT_EQ(h.at("pinch").at("strength").get<float>(), e.pinch_strength);
      EXPECT_EQ(h.at("palm").at("normal")[2].get<float>(), e.palm_normal[2]);
      EXPECT_EQ(h.at("hand_scale").at("width").get<float>(), e.hand_scale[1]);
    }
    EXPECT_TRUE(j.at("missed").is_number_unsigned());
    if (!first) {
      EXPECT_EQ(frame, previous_frame + 1 + j.at("missed").get<std::uint64_t>());
    }
    first = false;
    previous_frame = frame;
  }
  ASSERT_EQ(status.exit_code, 0) << status.err;
  const auto s = nlohmann::json::parse(status.out);
  EXPECT_EQ(s.at("device_state"), "stopped");
  EXPECT_EQ(s.at("alive"), false);
}

TEST(HandtrackCat, MissingDaemonAndBadArgumentsFailWithOneLine) {
  const Result missing = run("--shm-name ht_cat_missing_" + std::to_string(::getpid()) + " --timeout 0.2");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_EQ(count_lines(missing.err), 1) << missing.err;
  EXPECT_NE(missing.err.find("handtrack-cat: error: no handtrack shared memory"), std::string::npos) << missing.err;

  const Result bad = run("--count banana");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_EQ(count_lines(bad.err), 1) << bad.err;
  EXPECT_NE(bad.err.find("--count"), std::string::npos) << bad.err;

  const Result help = run("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--timeout"), std::string::npos);
}
