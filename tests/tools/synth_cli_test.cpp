// handtrack-synth as a user runs it: bad arguments give one clear line and a non-zero exit; a run
// writes a sequence directory that SequenceReader accepts and whose ground truth is consistent.

#include "handtrack/core/sequence.hpp"

#include <nlohmann/json.hpp>
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#ifndef HANDTRACK_SYNTH_EXE
#error "HANDTRACK_SYNTH_EXE must name the handtrack-synth binary"
#endif

namespace fs = std::filesystem;

namespace {

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The pixels the first frame of `reader` labels as the hand.
std::ptrdiff_t hand_pixels(const handtrack::SequenceReader& reader) {
  const auto labels = reader.labels(0);
  return labels ? std::count_if(labels->pixels.begin(), labels->pixels.end(), [](uint8_t l) { return l != 0; }) : 0;
}

// Pixels of the first frame with a depth beyond `beyond_mm`.
std::ptrdiff_t pixels_beyond(const handtrack::SequenceReader& reader, float beyond_mm) {
  const auto depth = reader.depth(0).depth_mm;
  return std::count_if(depth.begin(), depth.end(), [&](float d) { return d > beyond_mm; });
}

class SynthCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("handtrack-synth-test-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  RunResult run(const std::string& args) const {
    const fs::path out = dir_ / "stdout.txt", err = dir_ / "stderr.txt";
    const std::string cmd = std::string("'") + HANDTRACK_SYNTH_EXE + "' " + args + " >'" + out.string() + "' 2>'" +
                            err.string() + "' </dev/null";
    const int status = std::system(cmd.c_str());
    RunResult r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    r.out = slurp(out);
    r.err = slurp(err);
    return r;
  }

  void expect_one_line_error(const std::string& args, const std::string& mentions) const {
    SCOPED_TRACE(args);
    const RunResult r = run(args);
    EXPECT_NE(r.exit_code, 0);
    EXPECT_LT(r.exit_code, 128) << "crashed";
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "stderr: " << r.err;
    EXPECT_NE(r.err.find(mentions), std::string::npos) << "stderr: " << r.err;
    EXPECT_TRUE(r.out.empty()) << r.out;
  }

  // One frame of a pinch, as rendered plainly and with the options `changed_by`: the two sequences.
  std::pair<handtrack::SequenceReader, handtrack::SequenceReader> plain_and(const std::string& changed_by) const {
    const std::string args = "--motion pinch --frames 1 --seed 3 --no-noise --background none ";
    const fs::path plain = dir_ / "plain", changed = dir_ / "changed";
    const RunResult a = run(args + "--out '" + plain.string() + "'");
    EXPECT_EQ(a.exit_code, 0) << a.err;
    const RunResult b = run(args + changed_by + " --out '" + changed.string() + "'");
    EXPECT_EQ(b.exit_code, 0) << b.err;
    return {handtrack::SequenceReader(plain), handtrack::SequenceReader(changed)};
  }

  fs::path dir_;
};

TEST_F(SynthCli, BadArgumentsGiveOneClearLine) {
  const std::string out = "--out '" + (dir_ / "seq").string() + "'";
  expect_one_line_error("--motion moonwalk --frames 5 " + out, "moonwalk");
  expect_one_line_error("--motion pinch --frames 0 " + out, "--frames");
  expect_one_line_error("--motion pinch --frames many " + out, "--frames");
  expect_one_line_error("--motion pinch --frames 5 --background wall " + out, "--background");
  expect_one_line_error("--motion pinch --frames 5 --hand both " + out, "--hand");
  expect_one_line_error("--motion pinch --frames 5 --subject-scale 3,1 " + out, "--subject-scale");
  expect_one_line_error("--motion pinch --frames 5 --subject-scale 1.0 " + out, "--subject-scale");
  expect_one_line_error("--motion pinch --frames 5 --width 0 " + out, "--width");
  expect_one_line_error("--motion pinch --frames 5 --fov 170 " + out, "--fov");
  expect_one_line_error("--motion pinch --frames 5 --depth-offset 400 " + out, "--depth-offset");
  expect_one_line_error("--motion two_apart --frames 5 --depth-offset 50 " + out, "depth offset");
  expect_one_line_error("--motion two_apart --frames 5 --arm shoulder " + out, "upper arm");
  expect_one_line_error("--motion two_apart --frames 5 --arm none " + out, "without its arm");
  expect_one_line_error("--motion pinch --frames 5 --arm elbow " + out, "--arm");
  expect_one_line_error("--motion pinch --frames 5", "--out");
  expect_one_line_error("--frames 5 " + out, "--motion");
  expect_one_line_error("--motion pinch --bogus " + out, "bogus");
  EXPECT_FALSE(fs::exists(dir_ / "seq" / "depth"));
}

TEST_F(SynthCli, HelpAndListMotions) {
  const RunResult help = run("--help");
  EXPECT_EQ(help.exit_code, 0);
  EXPECT_NE(help.out.find("--motion"), std::string::npos);
  EXPECT_NE(help.out.find("--subject-scale"), std::string::npos);
  const RunResult list = run("--list-motions");
  EXPECT_EQ(list.exit_code, 0);
  for (const char* m : {"adbadd", "fingercount", "fingerwave", "flexex1", "pinch", "random", "tigergrasp", "two_apart",
                        "two_clap", "two_cross", "two_pinch", "two_reach"}) {
    EXPECT_NE(list.out.find(m), std::string::npos) << m;
  }
}

TEST_F(SynthCli, Writes640x480SequenceWithConsistentGroundTruth) {
  const fs::path seq = dir_ / "seq";
  const RunResult r = run("--motion fingerwave --frames 12 --width 640 --height 480 --seed 5 --subject-scale 1.08,0.94 "
                    "--out '" + seq.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << "stderr is not a terminal: no progress expected, got " << r.err;

  const handtrack::SequenceReader reader(seq);
  EXPECT_EQ(reader.frame_count(), 12u);
  EXPECT_EQ(reader.camera().width, 640);
  EXPECT_EQ(reader.camera().height, 480);
  EXPECT_NEAR(reader.camera().fx, 449.004, 1e-6);
  EXPECT_NEAR(reader.camera().fps, 60.0, 1e-9);
  ASSERT_TRUE(reader.has_groundtruth());

  EXPECT_EQ(nlohmann::json::parse(slurp(seq / "hand.json")), nlohmann::json::parse(R"({"hands":["right"],"view":"palm","motion":"fingerwave"})"));
  const auto subject = nlohmann::json::parse(slurp(seq / "subject.json"));
  EXPECT_DOUBLE_EQ(subject.at("length_scale").get<double>(), 1.08);
  EXPECT_DOUBLE_EQ(subject.at("width_scale").get<double>(), 0.94);
  const auto middle_bones = subject.at("fingers").at("middle").at("bone_lengths_mm");
  EXPECT_NEAR(middle_bones[0].get<double>(), 46 * 1.08, 1e-9);

  std::array<double, 15> first_lengths{};
  for (size_t i = 0; i < reader.frame_count(); ++i) {
    const auto depth = reader.depth(i);
    const auto labels = reader.labels(i);
    ASSERT_TRUE(labels.has_value());
    EXPECT_EQ(labels->width, 640);
    const auto joints = reader.joints(i);
    ASSERT_TRUE(joints.has_value());
    const auto tips = reader.fingertips(i);
    for (int f = 0; f < handtrack::kNumFingers; ++f) {
      ASSERT_TRUE(tips[static_cast<size_t>(f)].has_value());
      EXPECT_LT((*tips[static_cast<size_t>(f)] - (*joints)[static_cast<size_t>(handtrack::fingertip_joint(f))]).norm(),
                1e-6);
      for (int b = 0; b < 3; ++b) {
        const double len = ((*joints)[static_cast<size_t>(handtrack::joint_index(f, b + 1))] -
                            (*joints)[static_cast<size_t>(handtrack::joint_index(f, b))])
                               .norm();
        const auto k = static_cast<size_t>(3 * f + b);
        if (i == 0) first_lengths[k] = len;
        EXPECT_NEAR(len, first_lengths[k], 0.01) << "bone length changes (csv has 3 decimals)";
        EXPECT_NEAR(len, subject.at("fingers").at(std::string(handtrack::kFingerNames[static_cast<size_t>(f)]))
                             .at("bone_lengths_mm")[static_cast<size_t>(b)].get<double>(), 0.01);
      }
    }
    // Some hand in every frame: labelled pixels with depth.
    size_t hand = 0;
    for (size_t p = 0; p < labels->pixels.size(); ++p) hand += (labels->pixels[p] != 0 && depth.depth_mm[p] > 0);
    EXPECT_GT(hand, 5000u);
  }

  // A second run into the same directory is refused without --force, accepted with it.
  const std::string again = "--motion pinch --frames 3 --out '" + seq.string() + "'";
  expect_one_line_error(again, "--force");
  const RunResult forced = run(again + " --force --no-noise --background none");
  EXPECT_EQ(forced.exit_code, 0) << forced.err;
  EXPECT_EQ(handtrack::SequenceReader(seq).frame_count(), 3u);
}

// --fov: another camera's lens. The focal lengths follow from the field of view, and the same
// hand at the same place covers fewer pixels through a wider lens, by the square of the focal
// lengths' ratio.
TEST_F(SynthCli, AWiderFieldOfViewShowsTheSameHandSmaller) {
  const auto [a, b] = plain_and("--fov 87");
  const double fx = 160.0 / std::tan(43.5 * M_PI / 180.0);
  EXPECT_NEAR(b.camera().fx, fx, 1e-6);
  EXPECT_NEAR(b.camera().fy / b.camera().fx, a.camera().fy / a.camera().fx, 1e-9);
  EXPECT_EQ(b.camera().width, 320);
  const double ratio = static_cast<double>(hand_pixels(b)) / static_cast<double>(hand_pixels(a));
  const double expected = (fx / a.camera().fx) * (fx / a.camera().fx);
  EXPECT_NEAR(ratio, expected, 0.05) << hand_pixels(b) << " against " << hand_pixels(a) << " pixels";
  // The tips are where the scene puts them, whatever the lens.
  EXPECT_LT((*a.fingertips(0)[1] - *b.fingertips(0)[1]).norm(), 1e-6);
}

// --depth-offset: the whole hand moves along the ray through its palm centre, so every fingertip
// moves by the same vector, whose depth is the offset, and the hand covers fewer pixels.
TEST_F(SynthCli, ADepthOffsetMovesTheHandAlongItsRay) {
  const auto [a, b] = plain_and("--depth-offset 100");
  const auto tips_a = a.fingertips(0);
  const auto tips_b = b.fingertips(0);
  const Eigen::Vector3d moved = *tips_b[0] - *tips_a[0];
  EXPECT_NEAR(moved.z(), 100.0, 0.01);
  for (size_t f = 1; f < tips_a.size(); ++f) EXPECT_LT((*tips_b[f] - *tips_a[f] - moved).norm(), 0.01) << f;
  EXPECT_LT(hand_pixels(b), hand_pixels(a) * 3 / 4);
}

// --arm shoulder: the arm goes on past the elbow, back to the shoulder: more of the image has
// depth, none of it the hand's, some of it beyond the working volume (600 mm) as the arm reaches
// back.
TEST_F(SynthCli, AnUpperArmGoesOnFromTheElbowToTheShoulder) {
  const auto [a, b] = plain_and("--arm shoulder");
  EXPECT_GT(pixels_beyond(b, 0.0F), pixels_beyond(a, 0.0F) + 1000);
  EXPECT_GT(pixels_beyond(b, 600.0F), pixels_beyond(a, 600.0F) + 100);
  EXPECT_EQ(hand_pixels(b), hand_pixels(a));
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "changed" / "subject.json")).at("arm"), "shoulder");
}

// --arm none: the hand alone, cut at the wrist: the forearm's pixels are gone, the hand's all there
// (with the forearm gone, a few of the wrist's come out from behind it), and subject.json says so.
TEST_F(SynthCli, AHandWithoutItsArmIsCutAtTheWrist) {
  const auto [a, b] = plain_and("--arm none");
  EXPECT_LT(pixels_beyond(b, 0.0F), pixels_beyond(a, 0.0F) - 1000);
  EXPECT_GE(hand_pixels(b), hand_pixels(a));
  EXPECT_LT(hand_pixels(b), hand_pixels(a) + hand_pixels(a) / 20);
  EXPECT_EQ(pixels_beyond(b, 0.0F), hand_pixels(b)) << "nothing but the hand has depth";
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "plain" / "subject.json")).at("arm"), "forearm");
  EXPECT_EQ(nlohmann::json::parse(slurp(dir_ / "changed" / "subject.json")).at("arm"), "none");
}

// --proportions varied: subject.json says so and gives each hand's proportions, which its bone
// lengths follow; the size stays the seed's. Anything but mean or varied is one clear error.
TEST_F(SynthCli, VariedProportionsAndAPalmArchAreWrittenDown) {
  const fs::path mean = dir_ / "mean", varied = dir_ / "varied";
  const std::string args = "--motion adbadd --frames 2 --seed 4 --no-noise --background none ";
  ASSERT_EQ(run(args + "--out '" + mean.string() + "'").exit_code, 0);
  const RunResult r = run(args + "--proportions varied --out '" + varied.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto m = nlohmann::json::parse(slurp(mean / "subject.json"));
  const auto v = nlohmann::json::parse(slurp(varied / "subject.json"));
  EXPECT_EQ(m.at("proportions"), "mean");
  EXPECT_EQ(v.at("proportions"), "varied");
  EXPECT_EQ(v.at("length_scale"), m.at("length_scale"));
  const double ring = v.at("finger_length_scales").at(3).get<double>();
  EXPECT_NE(ring, 1.0);
  EXPECT_NEAR(v.at("fingers").at("ring").at("bone_lengths_mm")[0].get<double>(),
              m.at("fingers").at("ring").at("bone_lengths_mm")[0].get<double>() * ring, 1e-9);
  expect_one_line_error(args + "--proportions thin --out '" + (dir_ / "x").string() + "'", "--proportions");

  // An arched palm is written down with the knuckles it moved; the default is flat.
  const fs::path arched = dir_ / "arched";
  const RunResult a = run(args + "--palm-arch 8 --out '" + arched.string() + "'");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const auto j = nlohmann::json::parse(slurp(arched / "subject.json"));
  EXPECT_EQ(m.at("palm_arch_mm"), 0.0);
  EXPECT_EQ(j.at("palm_arch_mm"), 8.0);
  EXPECT_GT(j.at("fingers").at("little").at("base_mm")[2].get<double>(), 8.0);
  expect_one_line_error(args + "--palm-arch 30 --out '" + (dir_ / "x").string() + "'", "--palm-arch");
  EXPECT_EQ(j.at("palm_arch_shape"), "bent");
  const fs::path back = dir_ / "back";
  const RunResult b = run(args + "--palm-arch 8 --palm-arch-shape back --out '" + back.string() + "'");
  ASSERT_EQ(b.exit_code, 0) << b.err;
  const auto jb = nlohmann::json::parse(slurp(back / "subject.json"));
  EXPECT_EQ(jb.at("palm_arch_shape"), "back");
  EXPECT_EQ(jb.at("fingers").at("little").at("base_mm"), m.at("fingers").at("little").at("base_mm"));
  expect_one_line_error(args + "--palm-arch 8 --palm-arch-shape cupped --out '" + (dir_ / "x").string() + "'",
                        "--palm-arch-shape");
}

// A two-hand motion writes both hands (docs/SEQUENCES.md): hand.json names them, each CSV row holds
// hand 0's block then hand 1's (h1_...), and each hand's tips are its joints' tips. --hand and
// --view, which it has no use for, are refused.
TEST_F(SynthCli, ATwoHandMotionWritesBothHandsGroundTruth) {
  const fs::path seq = dir_ / "pair";
  const std::string out = "--out '" + seq.string() + "'";
  expect_one_line_error("--motion two_cross --frames 3 --hand left " + out, "--hand does not apply");
  expect_one_line_error("--motion two_cross --frames 3 --view back " + out, "--view does not apply");
  const RunResult r = run("--motion two_cross --frames 5 --seed 3 " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(nlohmann::json::parse(slurp(seq / "hand.json")),
            nlohmann::json::parse(R"({"hands":["right","left"],"motion":"two_cross"})"));
  const std::string header = slurp(seq / "groundtruth.csv").substr(0, slurp(seq / "groundtruth.csv").find('\n'));
  EXPECT_NE(header.find(",little_z,h1_thumb_x,h1_thumb_y,h1_thumb_z,"), std::string::npos) << header;
  EXPECT_NE(slurp(seq / "poses.csv").find(",little_flex3,h1_tx,h1_ty,"), std::string::npos);
  const auto subject = nlohmann::json::parse(slurp(seq / "subject.json"));
  ASSERT_EQ(subject.at("hands").size(), 2U);
  EXPECT_EQ(subject.at("hands").at(1).at("hand"), "left");

  const handtrack::SequenceReader reader(seq);
  ASSERT_EQ(reader.hand_count(), 2);
  for (size_t i = 0; i < reader.frame_count(); ++i) {
    for (int h = 0; h < 2; ++h) {
      const auto joints = reader.joints(i, h);
      ASSERT_TRUE(joints.has_value());
      const auto tips = reader.fingertips(i, h);
      for (int f = 0; f < handtrack::kNumFingers; ++f) {
        ASSERT_TRUE(tips[static_cast<size_t>(f)].has_value());
        EXPECT_LT((*tips[static_cast<size_t>(f)] - (*joints)[static_cast<size_t>(handtrack::fingertip_joint(f))]).norm(),
                  1e-6);
      }
    }
    // The right hand nearer (two_cross), and the hands apart.
    EXPECT_LT((*reader.joints(i, 0))[0].z(), (*reader.joints(i, 1))[0].z());
  }
}

}  // namespace
