// handtrack-view end to end: it renders a sequence frame (from handtrack-synth when that program is
// built, otherwise from a sequence written here) and a single depth PNG to a valid PNG with one
// panel per view, and it fails cleanly (exit 1, one line on stderr naming the problem) on a
// missing file, a corrupt PNG, a bad camera.json and a frame out of range.
#include "handtrack/core/camera.hpp"
#include "handtrack/core/png_io.hpp"
#include "handtrack/core/sequence.hpp"

#include <gtest/gtest.h>
#include <png.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

namespace handtrack {
namespace {
namespace fs = std::filesystem;

struct ProcessResult {
  int exit_code = -1;
  std::string err;
};

struct PngSize {
  int width = 0;
  int height = 0;
};

// Reads `file` completely as RGB; nullopt unless it is a valid PNG.
std::optional<PngSize> read_png_size(const fs::path& file) {
  png_image png;
  std::memset(&png, 0, sizeof png);
  png.version = PNG_IMAGE_VERSION;
  if (png_image_begin_read_from_file(&png, file.c_str()) == 0) return std::nullopt;
  png.format = PNG_FORMAT_RGB;
  std::vector<uint8_t> pixels(PNG_IMAGE_SIZE(png));
  const bool ok = png_image_finish_read(&png, nullptr, pixels.data(), 0, nullptr) != 0;
  const PngSize size{static_cast<int>(png.width), static_cast<int>(png.height)};
  png_image_free(&png);
  if (!ok) return std::nullopt;
  return size;
}

int count_lines(const std::string& text) {
  int n = 0;
  for (char c : text) n += c == '\n' ? 1 : 0;
  return n;
}

class ViewCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("handtrack_view_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs `exe args` with stdout discarded and stderr captured.
  ProcessResult run(const std::string& exe, const std::string& args) const {
    const fs::path err = dir_ / "stderr.txt";
    const std::string cmd = "'" + exe + "' " + args + " >/dev/null 2>'" + err.string() + "'";
    const int status = std::system(cmd.c_str());
    ProcessResult r;
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::ifstream in(err);
    std::stringstream text;
    text << in.rdbuf();
    r.err = text.str();
    return r;
  }
  ProcessResult view(const std::string& args) const { return run(HANDTRACK_VIEW_EXE, args); }

  // A 320x240 depth image of a crude open hand (palm disc and five finger bars) at 400 mm in front
  // of a wall at 900 mm.
  static DepthImage hand_depth(const CameraIntrinsics& cam) {
    DepthImage d{cam, std::vector<float>(static_cast<size_t>(cam.width) * cam.height, 900.0F)};
    const double palm_u = 160, palm_v = 150, palm_r = 28;
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        const bool palm = std::hypot(u - palm_u, v - palm_v) < palm_r;
        bool finger = false;
        for (int f = 0; f < 4; ++f) {
          const double fu = palm_u - 21 + 14 * f;
          finger = finger || (std::abs(u - fu) < 5 && v > palm_v - 80 + (f == 0 || f == 3 ? 12 : 0) && v < palm_v);
        }
        finger = finger || (std::abs(v - (palm_v + 5)) < 5 && u > palm_u - 65 && u < palm_u);
        if (palm || finger) d.at(u, v) = 400.0F;
      }
    }
    return d;
  }
  static CameraIntrinsics camera() {
    CameraIntrinsics cam;  // the SPEC.md example: 320x240, fx 224.502, fy 230.494
    cam.depth_scale_mm = 0.125;
    return cam;
  }
  // Writes the hand as a 16-bit PNG (0.125 mm units); returns its path.
  fs::path write_hand_png() const {
    const fs::path file = dir_ / "hand.png";
    const auto raw = hand_depth(camera()).to_raw();
    write_png_gray16(file, Gray16Image{320, 240, 1, raw});
    return file;
  }
  // A sequence of `frames` frames: from handtrack-synth if built, else the static hand written here.
  fs::path make_sequence(int frames) const {
    const fs::path seq = dir_ / "seq";
#ifdef HANDTRACK_VIEW_SYNTH_EXE
    if (fs::exists(HANDTRACK_VIEW_SYNTH_EXE)) {
      const ProcessResult r = run(HANDTRACK_VIEW_SYNTH_EXE,
                        "--motion pinch --frames " + std::to_string(frames) + " --out '" + seq.string() + "'");
      if (r.exit_code == 0) return seq;
      ADD_FAILURE() << "handtrack-synth failed: " << r.err;
    }
#endif
    SequenceWriter writer(seq, camera());
    Gray8Image labels{320, 240, 1, std::vector<uint8_t>(320 * 240, 0)};
    const DepthImage d = hand_depth(camera());
    for (size_t i = 0; i < d.depth_mm.size(); ++i) labels.pixels[i] = d.depth_mm[i] < 500.0F ? kPalm : 0;
    for (int f = 0; f < frames; ++f) {
      writer.write_depth(f, d);
      writer.write_labels(f, labels);
    }
    return seq;
  }
  // Exit 1 and exactly one line on stderr that mentions `needle`.
  static void expect_clean_failure(const ProcessResult& r, const std::string& needle) {
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_EQ(count_lines(r.err), 1) << r.err;
    EXPECT_NE(r.err.find("handtrack-view"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(needle), std::string::npos) << "expected '" << needle << "' in: " << r.err;
  }

  fs::path dir_;
};

TEST_F(ViewCli, HelpExitsZero) {
  const ProcessResult r = view("--help");
  EXPECT_EQ(r.exit_code, 0);
}

TEST_F(ViewCli, RendersATrackedSequenceFrameWithLabels) {
  const fs::path seq = make_sequence(6);
  const fs::path out = dir_ / "frame.png";
  const ProcessResult r = view("--seq '" + seq.string() + "' --frame 5 --out '" + out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto size = read_png_size(out);
  ASSERT_TRUE(size) << "not a valid PNG: " << out;
  // Four panels (depth, quadtree, model, labels), each as large as the 320x240 image, plus captions.
  const CameraIntrinsics cam = SequenceReader(seq).camera();
  EXPECT_GE(size->width, 4 * cam.width);
  EXPECT_LT(size->width, 4 * cam.width + 100);
  EXPECT_GT(size->height, cam.height);
  EXPECT_LT(size->height, cam.height + 100);
}

TEST_F(ViewCli, EveryKthFrameOfASequence) {
  const fs::path seq = make_sequence(5);
  const ProcessResult r = view("--seq '" + seq.string() + "' --every 2 --crop --out '" + (dir_ / "out.png").string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (int f : {0, 2, 4}) {
    char name[32];
    std::snprintf(name, sizeof name, "out_%06d.png", f);
    EXPECT_TRUE(read_png_size(dir_ / name)) << name;
  }
  EXPECT_FALSE(fs::exists(dir_ / "out_000001.png"));
}

TEST_F(ViewCli, RendersASingleDepthPng) {
  const fs::path depth = write_hand_png();
  const fs::path out = dir_ / "single.png";
  ProcessResult r = view("--depth '" + depth.string() + "' --fx 224.502 --fy 230.494 --depth-scale 0.125 --out '" +
               out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto size = read_png_size(out);
  ASSERT_TRUE(size);
  EXPECT_GE(size->width, 3 * 320);  // three panels without labels
  EXPECT_LT(size->width, 4 * 320);

  // The same with camera.json, and a label image as a fourth panel.
  write_camera_json(dir_ / "camera.json", camera());
  write_png_gray8(dir_ / "labels.png", Gray8Image{320, 240, 1, std::vector<uint8_t>(320 * 240, 1)});
  r = view("--depth '" + depth.string() + "' --camera '" + (dir_ / "camera.json").string() + "' --labels '" +
           (dir_ / "labels.png").string() + "' --out '" + out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  size = read_png_size(out);
  ASSERT_TRUE(size);
  EXPECT_GE(size->width, 4 * 320);
}

TEST_F(ViewCli, MissingFilesFailCleanly) {
  const std::string out = " --out '" + (dir_ / "x.png").string() + "'";
  expect_clean_failure(view("--depth '" + (dir_ / "nope.png").string() + "' --fx 200" + out), "nope.png");
  expect_clean_failure(view("--seq '" + (dir_ / "noseq").string() + "' --frame 0" + out), "noseq");
  EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

TEST_F(ViewCli, CorruptPngFailsCleanly) {
  const fs::path bad = dir_ / "corrupt.png";
  {
    std::ofstream f(bad, std::ios::binary);
    f << "\x89PNG\r\n\x1a\n this is not really a PNG file";
  }
  expect_clean_failure(view("--depth '" + bad.string() + "' --fx 200 --out '" + (dir_ / "x.png").string() + "'"),
                       "corrupt.png");
  // A corrupt frame inside a sequence.
  const fs::path seq = make_sequence(2);
  fs::copy_file(bad, seq / "depth" / "000001.png", fs::copy_options::overwrite_existing);
  expect_clean_failure(view("--seq '" + seq.string() + "' --frame 1 --out '" + (dir_ / "x.png").string() + "'"),
                       "000001.png");
}

TEST_F(ViewCli, BadCameraJsonFailsCleanly) {
  const fs::path depth = write_hand_png();
  {
    std::ofstream f(dir_ / "camera.json");
    f << "{\"width\": 320, \"height\": ";
  }
  expect_clean_failure(view("--depth '" + depth.string() + "' --camera '" + (dir_ / "camera.json").string() +
                            "' --out '" + (dir_ / "x.png").string() + "'"),
                       "camera.json");
  // A camera of the wrong size for the image.
  CameraIntrinsics wrong = camera();
  wrong.width = 640;
  wrong.height = 480;
  write_camera_json(dir_ / "camera.json", wrong);
  expect_clean_failure(view("--depth '" + depth.string() + "' --camera '" + (dir_ / "camera.json").string() +
                            "' --out '" + (dir_ / "x.png").string() + "'"),
                       "640x480");
}

TEST_F(ViewCli, FrameOutOfRangeFailsCleanly) {
  const fs::path seq = make_sequence(3);
  expect_clean_failure(view("--seq '" + seq.string() + "' --frame 3 --out '" + (dir_ / "x.png").string() + "'"),
                       "out of range");
}

TEST_F(ViewCli, UsageErrorsAreOneLine) {
  for (const std::string args : {"", "--out x.png", "--seq a --depth b --out x.png", "--frame -3 --out x.png",
                                 "--bogus"}) {
    const ProcessResult r = view(args);
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_NE(r.exit_code, 1) << args << ": usage errors are not input errors";
    EXPECT_EQ(count_lines(r.err), 1) << args << ": " << r.err;
  }
  // --depth without any intrinsics.
  const fs::path depth = write_hand_png();
  const ProcessResult r = view("--depth '" + depth.string() + "' --out '" + (dir_ / "x.png").string() + "'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(count_lines(r.err), 1) << r.err;
  EXPECT_NE(r.err.find("--fx"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace handtrack
