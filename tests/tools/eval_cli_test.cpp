// handtrack-eval on sequences it cannot score (issue 13): one clear line and a failing exit code,
// never a table of `nan`s with exit 0. And the benchmark's groups: sequences pooled by the view,
// motion and hand their hand.json names, frames without a pose counted as misses. And two hands
// (issue 14): a sequence whose hand.json names two is scored per hand.
#include "handtrack/core/sequence.hpp"
#include "handtrack/synth/synthetic_camera.hpp"

#include <nlohmann/json.hpp>

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

namespace fs = std::filesystem;

namespace {

class EvalCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("handtrack-eval-test-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    // Four frames of empty depth (nothing in the working volume: no hand), each annotated.
    handtrack::CameraIntrinsics cam;
    handtrack::SequenceWriter writer(dir_ / "seq", cam);
    for (int f = 0; f < 4; ++f) {
      writer.write_depth(f, handtrack::DepthImage{cam, std::vector<float>(static_cast<size_t>(cam.width) * cam.height, 0.0F)});
      handtrack::Fingertips tips;
      tips[0] = Eigen::Vector3d(0, 0, 400);
      writer.write_fingertips(f, tips);
    }
    writer.flush();
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs handtrack-eval on the sequences (default: the empty one); returns the exit code, stderr in
  // *err.
  int eval(std::string* err, const std::string& args = "") const {
    const fs::path out = dir_ / "stdout.txt", errf = dir_ / "stderr.txt";
    const std::string cmd = std::string("'") + HANDTRACK_EVAL_EXE + "' " +
                            (args.empty() ? "'" + (dir_ / "seq").string() + "'" : args) + " >'" + out.string() +
                            "' 2>'" + errf.string() + "' </dev/null";
    const int status = std::system(cmd.c_str());
    std::ifstream in(errf);
    std::stringstream text;
    text << in.rdbuf();
    *err = text.str();
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }

  fs::path dir_;
};

TEST_F(EvalCli, NoScorableFrameIsAnErrorNotNan) {
  std::string err;
  EXPECT_NE(eval(&err), 0);
  EXPECT_NE(err.find("handtrack-eval: error: no frame could be scored"), std::string::npos) << err;
  EXPECT_EQ(err.find("nan"), std::string::npos) << err;
}

TEST_F(EvalCli, AnEmptyGroundTruthFileIsNotCalledMissing) {
  std::ofstream(dir_ / "seq" / "groundtruth.csv", std::ios::trunc).flush();
  std::string err;
  EXPECT_NE(eval(&err), 0);
  EXPECT_NE(err.find("groundtruth.csv: no annotated frame in it"), std::string::npos) << err;
  fs::remove(dir_ / "seq" / "groundtruth.csv");
  EXPECT_NE(eval(&err), 0);
  EXPECT_NE(err.find("no groundtruth.csv"), std::string::npos) << err;
}

// Two rendered sequences and the empty one, each with a hand.json naming its view and motion: the
// JSON pools them per view, motion and hand, and the empty one's frames are all misses.
TEST_F(EvalCli, GroupsSequencesByTheViewMotionAndHandTheirHandJsonNames) {
  const auto describe = [](const fs::path& seq, const std::string& hand, const std::string& view,
                           const std::string& motion) {
    std::ofstream(seq / "hand.json") << nlohmann::json{{"hands", {hand}}, {"view", view}, {"motion", motion}}.dump();
  };
  for (const char* motion : {"pinch", "adbadd"}) {
    handtrack::synth::SynthOptions o;
    o.motion = motion;
    o.frames = 6;
    handtrack::synth::SyntheticCamera cam(o);
    handtrack::SequenceWriter writer(dir_ / motion, cam.camera());
    for (int f = 0; f < o.frames; ++f) {
      const auto frame = cam.render(f);
      writer.write_depth(f, frame.depth);
      writer.write_fingertips(f, frame.fingertips);
    }
    writer.flush();
    describe(dir_ / motion, "right", "palm", motion);
  }
  describe(dir_ / "seq", "left", "head-mounted", "pinch");
  const fs::path json = dir_ / "eval.json";
  std::string err;
  ASSERT_EQ(eval(&err, "'" + (dir_ / "pinch").string() + "' '" + (dir_ / "adbadd").string() + "' '" +
                           (dir_ / "seq").string() + "' --json '" + json.string() + "'"),
            0)
      << err;
  std::ifstream in(json);
  const auto j = nlohmann::json::parse(in);
  const auto& g = j.at("groups");
  EXPECT_EQ(g.at("view").at("palm").at("frames").get<int>(), 12);
  EXPECT_EQ(g.at("view").at("head-mounted").at("frames_without_pose").get<int>(), 4);
  EXPECT_DOUBLE_EQ(g.at("view").at("head-mounted").at("pct_frames_without_pose").get<double>(), 100.0);
  EXPECT_EQ(g.at("motion").at("pinch").at("frames").get<int>(), 10);
  EXPECT_EQ(g.at("hand").at("left").at("frames").get<int>(), 4);
  EXPECT_LT(g.at("view").at("palm").at("mean_fingertip_error_mm").get<double>(), 30.0);
  EXPECT_EQ(j.at("sequences").at(2).at("view"), "head-mounted");
  EXPECT_DOUBLE_EQ(j.at("overall").at("pct_frames_without_pose").get<double>(), 100.0 * 4 / 16);
}

// A rendered two-hand sequence (hand.json: right, left) is tracked with HandsTracker and scored per
// hand beside the one-hand keys; a one-hand sequence is scored per hand only with --max-hands 2.
TEST_F(EvalCli, ATwoHandSequenceIsScoredPerHandAndAOneHandOneOnlyWhenAsked) {
  handtrack::synth::SynthOptions o;
  o.motion = "two_apart";
  o.frames = 8;
  handtrack::synth::SyntheticCamera cam(o);
  {
    handtrack::SequenceWriter writer(dir_ / "pair", cam.camera());
    writer.write_hands({"right", "left"}, {{"motion", o.motion}});
    for (int f = 0; f < o.frames; ++f) {
      const auto frame = cam.render(f);
      writer.write_depth(f, frame.depth);
      for (int h = 0; h < frame.hand_count; ++h) writer.write_fingertips(f, frame.hands[static_cast<size_t>(h)].fingertips, h);
    }
  }
  const fs::path json = dir_ / "eval.json", tips = dir_ / "tips.csv";
  const std::string pair = "'" + (dir_ / "pair").string() + "'", empty = "'" + (dir_ / "seq").string() + "'";
  std::string err;
  ASSERT_EQ(eval(&err, pair + " " + empty + " --json '" + json.string() + "' --tips-csv '" + tips.string() + "'"), 0)
      << err;
  {
    std::ifstream in(json);
    const auto j = nlohmann::json::parse(in);
    const auto& seq = j.at("sequences").at(0);
    EXPECT_EQ(seq.at("frames"), 8);
    EXPECT_TRUE(seq.contains("mean_fingertip_error_mm") && seq.contains("pct_frames_below_mm"));
    const auto& hands = seq.at("hands");
    ASSERT_EQ(hands.size(), 2U);
    for (size_t k = 0; k < 2; ++k) {
      SCOPED_TRACE("hand " + std::to_string(k));
      EXPECT_EQ(hands.at(k).at("hand"), k);
      EXPECT_EQ(hands.at(k).at("side"), k == 0 ? "right" : "left");
      EXPECT_EQ(hands.at(k).at("frames"), 8);
      EXPECT_LE(hands.at(k).at("misses").get<int>(), 2);
      EXPECT_LT(hands.at(k).at("mean_fingertip_error_mm").get<double>(), 30.0);
      EXPECT_TRUE(hands.at(k).contains("identity_swaps_per_1000_frames"));
      EXPECT_TRUE(hands.at(k).at("handedness").contains("pct_frames_correct"));
    }
    EXPECT_TRUE(seq.contains("phantom_frames"));
    EXPECT_EQ(j.at("overall").at("hands").size(), 2U);
    EXPECT_FALSE(j.at("sequences").at(1).contains("hands")) << "a one-hand sequence stays one-hand";
  }
  std::ifstream tips_in(tips);
  std::stringstream tips_text;
  tips_text << tips_in.rdbuf();
  EXPECT_NE(tips_text.str().find("\npair/h1,7,"), std::string::npos) << "a --tips-csv row per hand and frame";

  // --max-hands 2: the empty one-hand sequence through HandsTracker, its hand missed in every frame.
  ASSERT_EQ(eval(&err, pair + " " + empty + " --max-hands 2 --json '" + json.string() + "'"), 0) << err;
  std::ifstream in(json);
  const auto j = nlohmann::json::parse(in);
  const auto& one = j.at("sequences").at(1);
  ASSERT_EQ(one.at("hands").size(), 1U);
  EXPECT_EQ(one.at("hands").at(0).at("misses"), 4);
  EXPECT_EQ(one.at("frames_without_pose"), 4);
  EXPECT_EQ(eval(&err, pair + " --max-hands 3"), 1);
  EXPECT_NE(err.find("--max-hands"), std::string::npos) << err;
}

}  // namespace
