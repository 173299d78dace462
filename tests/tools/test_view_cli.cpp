// handtrack-view end to end: it renders a sequence frame (from handtrack-synth when that program is
// built, otherwise from a sequence written here) and a single depth PNG to a valid PNG with one
// panel per view, and it fails cleanly (exit 1, one line on stderr naming the problem) on a
// missing file, a corrupt PNG, a bad camera.json and a frame out of range. Of a two-hand sequence
// it draws both fitted hands, each in its own colour, and with --max-hands 1 only one.
#include "hand_colours.hpp"  // tools/view/src

#include "handtrack/core/camera.hpp"
#include "handtrack/core/png_io.hpp"
#include "handtrack/core/sequence.hpp"

#include <gtest/gtest.h>
#include <png.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
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

struct RgbPng {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> pixels;  // RGB, row after row
  [[nodiscard]] draw::Rgb at(int x, int y) const {
    const size_t i = 3 * (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x));
    return {pixels[i], pixels[i + 1], pixels[i + 2]};
  }
};

// Reads `file` completely as RGB; nullopt unless it is a valid PNG.
std::optional<RgbPng> read_png_rgb(const fs::path& file) {
  png_image png;
  std::memset(&png, 0, sizeof png);
  png.version = PNG_IMAGE_VERSION;
  if (png_image_begin_read_from_file(&png, file.c_str()) == 0) return std::nullopt;
  png.format = PNG_FORMAT_RGB;
  RgbPng out{static_cast<int>(png.width), static_cast<int>(png.height), std::vector<uint8_t>(PNG_IMAGE_SIZE(png))};
  const bool ok = png_image_finish_read(&png, nullptr, out.pixels.data(), 0, nullptr) != 0;
  png_image_free(&png);
  if (!ok) return std::nullopt;
  return out;
}

// The size of `file`, read completely; nullopt unless it is a valid PNG.
std::optional<PngSize> read_png_size(const fs::path& file) {
  const auto png = read_png_rgb(file);
  if (!png) return std::nullopt;
  return PngSize{png->width, png->height};
}

// Whether `pixel` is `colour` as handtrack-view draws a hand in it: the colour itself, blended over
// the gray depth, or shaded toward black or white. All of these keep the colour's chroma (its
// difference from its own gray level) up to a positive factor, so the two chroma vectors point the
// same way; gray, and the other colours of the panel (the other hand's, the ground-truth cyan), do
// not.
bool of_colour(draw::Rgb pixel, draw::Rgb colour) {
  const auto chroma = [](draw::Rgb c) {
    const double mean = (c.r + c.g + c.b) / 3.0;
    return std::array<double, 3>{c.r - mean, c.g - mean, c.b - mean};
  };
  const auto p = chroma(pixel);
  const auto c = chroma(colour);
  const double dot = p[0] * c[0] + p[1] * c[1] + p[2] * c[2];
  const double p_norm = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
  const double c_norm = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  constexpr double kMinChroma = 30.0;  // below: near gray, the hue is noise (8-bit rounding)
  constexpr double kMinCosine = 0.97;  // about 14 degrees between the chroma vectors
  return p_norm >= kMinChroma && dot >= kMinCosine * p_norm * c_norm;
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

// --camera-roll: the frame is drawn as the tracker sees it, turned upright. A quarter turn makes the
// 320x240 image 240 wide and 320 high, so each panel is too (and its caption a line longer).
TEST_F(ViewCli, ACameraTurnedIsDrawnUpright) {
  const fs::path seq = make_sequence(6);
  const fs::path out = dir_ / "turned.png";
  const ProcessResult r = view("--seq '" + seq.string() + "' --frame 5 --camera-roll 90 --out '" + out.string() + "'");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto size = read_png_size(out);
  ASSERT_TRUE(size) << "not a valid PNG: " << out;
  const CameraIntrinsics cam = SequenceReader(seq).camera();
  EXPECT_GE(size->width, 4 * cam.height);
  EXPECT_LT(size->width, 4 * cam.width);
  EXPECT_GT(size->height, cam.width);
  EXPECT_LT(size->height, cam.width + 120);
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

// --hand fixes the hand fitted, as handtrackd's tracker.handedness does: a right hand fitted as
// the left one is another pose, so the two pictures differ (with --hand ignored, both would be
// auto's, the same to the pixel: tracking is deterministic).
TEST_F(ViewCli, HandChoosesTheHandFitted) {
  const fs::path seq = make_sequence(6);
  const auto render = [&](const std::string& hand) {
    const fs::path out = dir_ / (hand + ".png");
    const ProcessResult r = view("--seq '" + seq.string() + "' --frame 5 --hand " + hand + " --out '" + out.string() + "'");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return read_png_rgb(out);
  };
  const auto right = render("right");
  const auto left = render("left");
  ASSERT_TRUE(right && left);
  ASSERT_EQ(right->pixels.size(), left->pixels.size());
  EXPECT_NE(right->pixels, left->pixels);
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
                                 "--bogus", "--arrangement sideways --out x.png", "--hand both --out x.png",
                                 "--camera-roll 45 --out x.png"}) {
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

// Two hands side by side (handtrack-synth's two_apart: the palms ~200 mm apart, one in each half
// of the image): the model panel shows both fitted models, each in its own colour, one in the left
// half and the other in the right; with --max-hands 1 it shows one hand only.
TEST_F(ViewCli, DrawsBothHandsOfATwoHandSequence) {
#ifndef HANDTRACK_VIEW_SYNTH_EXE
  GTEST_SKIP() << "needs handtrack-synth for a two-hand sequence";
#else
  const fs::path seq = dir_ / "two";
  const ProcessResult synth =
      run(HANDTRACK_VIEW_SYNTH_EXE, "--motion two_apart --frames 30 --out '" + seq.string() + "'");
  ASSERT_EQ(synth.exit_code, 0) << synth.err;
  ASSERT_EQ(SequenceReader(seq).hand_count(), 2);
  const int image_width = SequenceReader(seq).camera().width;

  // Pixels of each hand's colour in the left and the right half of the model panel (c), the third
  // of four (depth, quadtree, model, labels), each as wide as the image, with equal gaps.
  struct Halves {
    std::array<int, view::kHandColours.size()> left{};
    std::array<int, view::kHandColours.size()> right{};
  };
  const auto model_panel_halves = [&](const std::string& extra_args) {
    const fs::path out = dir_ / "two.png";
    const ProcessResult r =
        view("--seq '" + seq.string() + "' --frame 29 " + extra_args + " --out '" + out.string() + "'");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    const auto png = read_png_rgb(out);
    Halves h;
    if (!png) {
      ADD_FAILURE() << "not a valid PNG: " << out;
      return h;
    }
    const int gaps = png->width - 4 * image_width;
    EXPECT_TRUE(gaps > 0 && gaps % 5 == 0) << "not four panels of " << image_width << " px: " << png->width;
    const int gap = gaps / 5;
    const int x0 = gap + 2 * (image_width + gap);
    for (int y = 0; y < png->height; ++y) {
      for (int x = x0; x < x0 + image_width; ++x) {
        for (size_t k = 0; k < view::kHandColours.size(); ++k) {
          if (!of_colour(png->at(x, y), view::kHandColours[k])) continue;
          ++(x < x0 + image_width / 2 ? h.left : h.right)[k];
        }
      }
    }
    return h;
  };
  // A fitted hand is ~3000 px of its colour here, measured: its model's Gaussians ~1550, skeleton and
  // fingertips ~1050, the outline of its segmented pixels and its label ~400 (so without the model
  // ~1450). It is drawn in a half when its colour has more than kDrawnPx pixels there and the other
  // half less than a tenth of that.
  constexpr int kDrawnPx = 2000;
  const auto drawn_in = [](const Halves& h, size_t k) {
    if (h.left[k] > kDrawnPx && h.right[k] * 10 < h.left[k]) return -1;
    if (h.right[k] > kDrawnPx && h.left[k] * 10 < h.right[k]) return +1;
    return 0;
  };

  const Halves two = model_panel_halves("");  // --max-hands 2, the default
  EXPECT_NE(drawn_in(two, 0), 0) << "hand colour 0: left " << two.left[0] << " px, right " << two.right[0] << " px";
  EXPECT_NE(drawn_in(two, 1), 0) << "hand colour 1: left " << two.left[1] << " px, right " << two.right[1] << " px";
  EXPECT_EQ(drawn_in(two, 0), -drawn_in(two, 1)) << "the two hands are not in opposite halves";

  // One hand, by part colours: neither hand colour as a whole hand in a half of its own.
  const Halves one = model_panel_halves("--max-hands 1");
  EXPECT_FALSE(drawn_in(one, 0) != 0 && drawn_in(one, 0) == -drawn_in(one, 1))
      << "--max-hands 1 drew two hands: " << one.left[0] << "/" << one.right[0] << ", " << one.left[1] << "/"
      << one.right[1];
#endif
}

}  // namespace
}  // namespace handtrack
