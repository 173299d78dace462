// The sequence directory of SPEC.md and PNG files: round trips, and bad input giving one clear
// error that names the file.
#include "handtrack/core/png_io.hpp"
#include "handtrack/core/sequence.hpp"

#include "forged_png.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace handtrack {
namespace {
namespace fs = std::filesystem;

class SequenceIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("handtrack_seq_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Writes a 2-frame 32x24 sequence; returns its camera.
  CameraIntrinsics write_small() {
    CameraIntrinsics cam;
    cam.width = 32;
    cam.height = 24;
    cam.fx = cam.fy = 30;
    cam.cx = 16;
    cam.cy = 12;
    cam.depth_scale_mm = 0.125;
    SequenceWriter w(dir_, cam);
    for (int f = 0; f < 2; ++f) {
      DepthImage d{cam, std::vector<float>(32 * 24, 0.0F)};
      for (size_t i = 0; i < d.depth_mm.size(); ++i) d.depth_mm[i] = static_cast<float>(300.0 + 0.125 * (i % 50) + f);
      w.write_depth(f, d);
      Fingertips tips;
      tips[kThumb] = Eigen::Vector3d(1.5, -2.25, 400.125);
      if (f == 1) tips[kLittle] = Eigen::Vector3d(-30, 10, 420);
      w.write_fingertips(f, tips);
      Joints joints;
      for (int j = 0; j < kNumJoints; ++j) joints[static_cast<size_t>(j)] = Eigen::Vector3d(j, -j, 400 + j);
      w.write_joints(f, joints);
      w.write_labels(f, Gray8Image{32, 24, 1, std::vector<uint8_t>(32 * 24, static_cast<uint8_t>(f + 3))});
    }
    return cam;
  }
  void write_text(const fs::path& file, const std::string& text) { std::ofstream(file) << text; }

  // Expects `fn` to throw a runtime_error whose message contains `needle` and the file name.
  template <typename Fn>
  void expect_error(Fn&& fn, const std::string& file, const std::string& needle) {
    try {
      fn();
      FAIL() << "no error for " << file;
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(file), std::string::npos) << what;
      EXPECT_NE(what.find(needle), std::string::npos) << what;
      EXPECT_EQ(what.find('\n'), std::string::npos) << "one line: " << what;
    }
  }

  fs::path dir_;
};

TEST_F(SequenceIo, RoundTripKeepsDepthGroundTruthJointsAndLabels) {
  const auto cam = write_small();
  const SequenceReader r(dir_);
  ASSERT_EQ(r.frame_count(), 2U);
  EXPECT_EQ(r.camera().width, 32);
  EXPECT_DOUBLE_EQ(r.camera().depth_scale_mm, 0.125);
  const DepthImage d = r.depth(1);
  for (size_t i = 0; i < d.depth_mm.size(); ++i) EXPECT_FLOAT_EQ(d.depth_mm[i], 300.0F + 0.125F * (i % 50) + 1.0F);
  const auto tips0 = r.fingertips(0);
  ASSERT_TRUE(tips0[kThumb].has_value());
  EXPECT_NEAR((*tips0[kThumb] - Eigen::Vector3d(1.5, -2.25, 400.125)).norm(), 0.0, 1e-3);
  EXPECT_FALSE(tips0[kLittle].has_value());  // empty cells = not annotated
  EXPECT_TRUE(r.fingertips(1)[kLittle].has_value());
  const auto joints = r.joints(1);
  ASSERT_TRUE(joints.has_value());
  EXPECT_NEAR((*joints)[20].z(), 420.0, 1e-9);
  const auto labels = r.labels(1);
  ASSERT_TRUE(labels.has_value());
  EXPECT_EQ(labels->pixels[100], 4);
  (void)cam;
}

// The CSV header of `hands` hands' fingertips as docs/SEQUENCES.md spells it out.
std::string fingertip_header(int hands) {
  std::string h = "frame";
  for (int hand = 0; hand < hands; ++hand) {
    for (const char* finger : {"thumb", "index", "middle", "ring", "little"}) {
      for (const char* axis : {"_x", "_y", "_z"}) h += std::string(",") + (hand == 1 ? "h1_" : "") + finger + axis;
    }
  }
  return h;
}

std::string first_line(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  return line;
}

TEST_F(SequenceIo, AOneHandSequenceKeepsSpecsColumnsAndNeedsNoHandJson) {
  write_small();
  EXPECT_EQ(first_line(dir_ / "groundtruth.csv"), fingertip_header(1));
  EXPECT_EQ(first_line(dir_ / "groundtruth.csv"),
            "frame,thumb_x,thumb_y,thumb_z,index_x,index_y,index_z,middle_x,middle_y,middle_z,ring_x,ring_y,ring_z,"
            "little_x,little_y,little_z");
  EXPECT_FALSE(fs::exists(dir_ / "hand.json"));
  const SequenceReader r(dir_);
  EXPECT_EQ(r.hand_count(), 1);
  EXPECT_TRUE(r.hands().empty());
  EXPECT_THROW((void)r.fingertips(0, 1), std::out_of_range);
}

// Two hands: hand.json names them, each CSV row holds hand 0's block then hand 1's (prefixed h1_);
// a hand without ground truth in a frame has empty cells there and reads back as not annotated.
TEST_F(SequenceIo, TwoHandRoundTripKeepsEachHandsBlock) {
  CameraIntrinsics cam;
  cam.width = 16;
  cam.height = 12;
  cam.cx = 8;
  cam.cy = 6;
  const auto joints_of = [](double offset) {
    Joints j;
    for (int k = 0; k < kNumJoints; ++k) j[static_cast<size_t>(k)] = Eigen::Vector3d(k + offset, -k, 400 + offset);
    return j;
  };
  {
    SequenceWriter w(dir_, cam);
    EXPECT_THROW(w.write_fingertips(0, Fingertips{}, 1), std::out_of_range) << "hand 1 before write_hands()";
    EXPECT_THROW(w.write_hands({"right", "up"}), std::invalid_argument);
    w.write_hands({"right", "left"}, {{"motion", "two_cross"}});
    for (int f = 0; f < 2; ++f) {
      w.write_depth(f, DepthImage{cam, std::vector<float>(16 * 12, 500.0F)});
      Fingertips right, left;
      right[kThumb] = Eigen::Vector3d(-100.5, 1, 350);
      right[kLittle] = Eigen::Vector3d(-60, 2, 352.25);
      left[kIndex] = Eigen::Vector3d(120, -3.5, 480);
      w.write_fingertips(f, right, 0);
      if (f == 0) w.write_fingertips(f, left, 1);  // frame 1: the left hand not annotated
      w.write_joints(f, joints_of(0), 0);
      if (f == 0) w.write_joints(f, joints_of(1000), 1);
    }
  }
  EXPECT_EQ(first_line(dir_ / "groundtruth.csv"), fingertip_header(2));
  EXPECT_NE(first_line(dir_ / "joints.csv").find(",little_tip_z,h1_wrist_x,h1_wrist_y,"), std::string::npos);
  EXPECT_EQ(read_hand_json(dir_ / "hand.json"), (std::vector<std::string>{"right", "left"}));

  const SequenceReader r(dir_);
  ASSERT_EQ(r.hand_count(), 2);
  EXPECT_EQ(r.hands(), (std::vector<std::string>{"right", "left"}));
  const auto right0 = r.fingertips(0);  // hand 0 by default, as for one hand
  ASSERT_TRUE(right0[kThumb].has_value());
  EXPECT_NEAR((*right0[kThumb] - Eigen::Vector3d(-100.5, 1, 350)).norm(), 0.0, 1e-3);
  EXPECT_FALSE(right0[kIndex].has_value());
  const auto left0 = r.fingertips(0, 1);
  ASSERT_TRUE(left0[kIndex].has_value());
  EXPECT_NEAR((*left0[kIndex] - Eigen::Vector3d(120, -3.5, 480)).norm(), 0.0, 1e-3);
  EXPECT_FALSE(left0[kThumb].has_value());
  for (const auto& tip : r.fingertips(1, 1)) EXPECT_FALSE(tip.has_value()) << "frame 1's left hand is not annotated";
  EXPECT_TRUE(r.fingertips(1, 0)[kLittle].has_value());
  ASSERT_TRUE(r.joints(0, 1).has_value());
  EXPECT_NEAR((*r.joints(0, 1))[20].x(), 1020.0, 1e-9);
  EXPECT_NEAR((*r.joints(1, 0))[20].x(), 20.0, 1e-9);
  EXPECT_FALSE(r.joints(1, 1).has_value());
  EXPECT_THROW((void)r.fingertips(0, 2), std::out_of_range);
}

TEST_F(SequenceIo, HandJsonAndTwoHandColumnsThatDisagreeNameTheFileAndField) {
  write_small();  // one hand's columns
  write_text(dir_ / "hand.json", R"({"hands":["right","left"]})");
  expect_error([&] { SequenceReader r(dir_); }, "groundtruth.csv", "expected 31 cells, found 16");
  // Two hands' columns without hand.json naming them.
  fs::remove(dir_ / "hand.json");
  fs::remove(dir_ / "joints.csv");
  write_text(dir_ / "groundtruth.csv", fingertip_header(2) + "\n0" + std::string(30, ',') + "\n");
  expect_error([&] { SequenceReader r(dir_); }, "groundtruth.csv", "2 hands' columns: hand.json must name them");
  write_text(dir_ / "hand.json", R"({"hands":["right","left"],"view":"palm"})");
  EXPECT_EQ(SequenceReader(dir_).hand_count(), 2);
  for (const char* bad : {R"({"hands":["right","middle"]})", R"({"hands":[]})", R"({"hands":"right"})",
                          R"({"hands":["left","right","left"]})", R"({"hands":[1]})"}) {
    write_text(dir_ / "hand.json", bad);
    expect_error([&] { SequenceReader r(dir_); }, "hand.json", "field 'hands' must list 1 to 2");
  }
  write_text(dir_ / "hand.json", R"({"view":"palm"})");
  expect_error([&] { SequenceReader r(dir_); }, "hand.json", "missing field 'hands'");
  write_text(dir_ / "hand.json", "{");
  expect_error([&] { SequenceReader r(dir_); }, "hand.json", "not valid JSON");
  // A player never reads it.
  EXPECT_EQ(SequenceReader(dir_, SequenceReader::Annotations::kIgnore).hand_count(), 1);
  // A hand's joints either all given or none.
  write_text(dir_ / "hand.json", R"({"hands":["right","left"]})");
  std::string row = "0";
  for (int k = 0; k < 2 * 3 * kNumJoints; ++k) row += k == 70 ? "," : ",1";
  write_text(dir_ / "joints.csv", row + "\n");
  expect_error([&] { SequenceReader r(dir_); }, "joints.csv", "frame 0: empty cell");
}

TEST_F(SequenceIo, MissingOrCorruptFilesGiveOneClearError) {
  write_small();
  fs::remove(dir_ / "depth" / "000001.png");
  {
    std::ofstream(dir_ / "depth" / "000001.png") << "this is not a png";
    const SequenceReader r(dir_);
    expect_error([&] { (void)r.depth(1); }, "000001.png", "not a readable PNG");
  }
  {
    // A truncated PNG: the header survives, the data does not.
    const auto good = dir_ / "depth" / "000000.png";
    std::ifstream in(good, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    std::ofstream(dir_ / "depth" / "000001.png", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    const SequenceReader r(dir_);
    expect_error([&] { (void)r.depth(1); }, "000001.png", "PNG");
  }
  {
    write_png_gray16(dir_ / "depth" / "000001.png", Gray16Image{16, 16, 1, std::vector<uint16_t>(256, 1)});
    const SequenceReader r(dir_);
    expect_error([&] { (void)r.depth(1); }, "000001.png", "camera.json says 32x24");
  }
  expect_error([&] { (void)read_png_gray16(dir_ / "nope.png"); }, "nope.png", "no such file");
  write_png_rgb(dir_ / "rgb.png", RgbImage{4, 4, 3, std::vector<uint8_t>(48, 9)});
  expect_error([&] { (void)read_png_gray16(dir_ / "rgb.png"); }, "rgb.png", "grayscale");
}

TEST_F(SequenceIo, BadCameraJsonNamesTheField) {
  write_small();
  const auto cam = dir_ / "camera.json";
  write_text(cam, R"({"width":320,"height":240,"fx":224.5,"cx":160,"cy":120})");
  expect_error([&] { SequenceReader r(dir_); }, "camera.json", "'fy'");
  write_text(cam, R"({"width":320,"height":240,"fx":"big","fy":1,"cx":160,"cy":120})");
  expect_error([&] { SequenceReader r(dir_); }, "camera.json", "'fx' must be a number");
  write_text(cam, R"({"width":0,"height":240,"fx":224.5,"fy":224.5,"cx":160,"cy":120})");
  expect_error([&] { SequenceReader r(dir_); }, "camera.json", "width");
  write_text(cam, R"({"width":320,"height":240,"fx":224.5,"fy":224.5,"cx":160,"cy":120,"depth_scale_mm":-1})");
  expect_error([&] { SequenceReader r(dir_); }, "camera.json", "depth_scale_mm");
  write_text(cam, "{ not json");
  expect_error([&] { SequenceReader r(dir_); }, "camera.json", "not valid JSON");
  fs::remove(cam);
  expect_error([&] { SequenceReader r(dir_); }, "camera.json", "cannot open");
  expect_error([&] { SequenceReader r(dir_ / "missing"); }, "missing", "not a directory");
}

TEST_F(SequenceIo, BadGroundTruthNamesTheLine) {
  write_small();
  write_text(dir_ / "groundtruth.csv", "frame,thumb_x\n0,1,2\n");
  expect_error([&] { SequenceReader r(dir_); }, "groundtruth.csv", "line 2");
  write_text(dir_ / "groundtruth.csv", "0,a,2,3,,,,,,,,,,,,\n");
  expect_error([&] { SequenceReader r(dir_); }, "groundtruth.csv", "'a' is not a number");
  // Found by fuzz_sequence_csv: a frame beyond int was converted (undefined behaviour).
  write_text(dir_ / "groundtruth.csv", "1e62,1,2,3,,,,,,,,,,,,\n");
  expect_error([&] { SequenceReader r(dir_); }, "groundtruth.csv", "line 1: bad frame");
}

// Hostile files (issue 13): the checks happen on the header, before a pixel is decoded.
TEST_F(SequenceIo, AHugeClaimedSizeIsRefusedFromTheHeader) {
  const auto cam = write_small();
  const auto bomb = dir_ / "depth" / "000001.png";
  test::write_png_claiming(bomb, 60000, 60000);
  const auto size = fs::file_size(bomb);
  EXPECT_LT(size, 200U);
  // Against camera.json (what every reader of a sequence does) and against the absolute cap.
  const SequenceReader r(dir_);
  expect_error([&] { (void)r.depth(1); }, "000001.png", "is 60000x60000 but camera.json says 32x24");
  expect_error([&] { (void)read_png_gray16(bomb); }, "000001.png", "claims 60000x60000 pixels; at most 8192");
  expect_error([&] { (void)read_png_gray8(bomb); }, "000001.png", "60000x60000");
  (void)cam;
}

TEST_F(SequenceIo, EightBitDepthIsRefusedNotReadAsMillimetres) {
  write_small();
  write_png_gray8(dir_ / "depth" / "000001.png", Gray8Image{32, 24, 1, std::vector<uint8_t>(32 * 24, 200)});
  const SequenceReader r(dir_);
  expect_error([&] { (void)r.depth(1); }, "000001.png", "8-bit PNG: depth frames must be 16-bit");
}

TEST_F(SequenceIo, HugeFrameNumberAndSlideShowFpsAreClearErrors) {
  write_small();
  write_png_gray16(dir_ / "depth" / "99999999999.png", Gray16Image{32, 24, 1, std::vector<uint16_t>(32 * 24, 500)});
  expect_error([&] { SequenceReader r(dir_); }, "99999999999.png", "frame number 99999999999 is too large");
  fs::remove(dir_ / "depth" / "99999999999.png");
  write_text(dir_ / "camera.json", R"({"width":32,"height":24,"fx":30,"fy":30,"cx":16,"cy":12,"fps":1e-6})");
  expect_error([&] { SequenceReader r(dir_); }, "camera.json", "fps must be in [1, 1000]");
}

TEST_F(SequenceIo, APlayerIgnoresAnnotationsItNeverUses) {
  write_small();
  write_text(dir_ / "groundtruth.csv", "garbage,not,csv\n\x01\x02");
  write_text(dir_ / "joints.csv", "0,a\n");
  expect_error([&] { SequenceReader r(dir_); }, "groundtruth.csv", "line");
  const SequenceReader player(dir_, SequenceReader::Annotations::kIgnore);
  EXPECT_EQ(player.frame_count(), 2U);
  EXPECT_FALSE(player.has_groundtruth());
  EXPECT_EQ(player.depth(0).width(), 32);
}

TEST(RealData, Sr305FrameLoadsWithItsDepthUnit) {
  const fs::path file = fs::path(HANDTRACK_SHARED_DATA_DIR) / "real-sr305/20210326-230536/110.png";
  if (!fs::exists(file)) GTEST_SKIP() << "shared data absent: " << file;
  CameraIntrinsics cam{Sr305Camera::kWidth, Sr305Camera::kHeight, Sr305Camera::kFx, Sr305Camera::kFy,
                       Sr305Camera::kCx,    Sr305Camera::kCy,     Sr305Camera::kDepthScaleMm, 30};
  const auto raw = read_png_gray16(file);
  ASSERT_EQ(raw.width, 640);
  const DepthImage d = DepthImage::from_raw(cam, raw.pixels);
  // The hand is at roughly 450-800 mm: a good share of the pixels must fall there.
  size_t in_range = 0;
  for (float v : d.depth_mm) in_range += (v > 400 && v < 900) ? 1 : 0;
  EXPECT_GT(in_range, d.depth_mm.size() / 20);
}

}  // namespace
}  // namespace handtrack
