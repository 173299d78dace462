// handtrack::draw: primitives put pixels where expected, the colour maps keep their promises, and
// the evaluator's error plot has the documented size, is a valid PNG and draws errors at the right
// height.
#include "handtrack/draw/canvas.hpp"
#include "handtrack/draw/colormap.hpp"
#include "handtrack/draw/plot.hpp"

#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <set>
#include <string>
#include <tuple>

namespace handtrack::draw {
namespace {
namespace fs = std::filesystem;

constexpr Rgb kBg{10, 20, 30};
constexpr Rgb kInk{250, 10, 10};

// Pixels of `c` that are not the background, as (x, y).
std::set<std::pair<int, int>> inked(const Canvas& c) {
  std::set<std::pair<int, int>> out;
  for (int y = 0; y < c.height(); ++y) {
    for (int x = 0; x < c.width(); ++x) {
      if (c.pixel(x, y) != kBg) out.insert({x, y});
    }
  }
  return out;
}

TEST(Canvas, StartsFilledAndClipsOutside) {
  Canvas c(7, 5, kBg);
  EXPECT_EQ(c.width(), 7);
  EXPECT_EQ(c.height(), 5);
  EXPECT_EQ(c.image().pixels.size(), 7U * 5U * 3U);
  EXPECT_TRUE(inked(c).empty());
  c.set_pixel(-1, 0, kInk);
  c.set_pixel(7, 4, kInk);
  c.set_pixel(0, 5, kInk);
  EXPECT_TRUE(inked(c).empty());
  c.set_pixel(6, 4, kInk);
  EXPECT_EQ(c.pixel(6, 4), kInk);
  EXPECT_EQ(inked(c).size(), 1U);
  EXPECT_EQ(c.pixel(100, 100), colours::kBlack);
  // Shapes far outside, or at non-finite positions, draw nothing and do not crash.
  c.line(-1e12, 3, 1e12, 3, kInk);
  c.fill_circle(std::nan(""), 2, 3, kInk);
  c.circle(2, std::numeric_limits<double>::infinity(), 3, kInk);
  c.fill_rect(-50, -50, 10, 10, kInk);
  EXPECT_EQ(c.pixel(0, 3), kInk);  // the clipped horizontal line still crosses the canvas
}

TEST(Canvas, RejectsAnImageOfTheWrongSize) {
  RgbImage bad{4, 4, 3, std::vector<uint8_t>(10)};
  EXPECT_THROW(Canvas{bad}, std::invalid_argument);
}

TEST(Canvas, LinesIncludeBothEndsAndNothingElse) {
  Canvas c(12, 12, kBg);
  c.line(1, 2, 6, 2, kInk);
  std::set<std::pair<int, int>> want;
  for (int x = 1; x <= 6; ++x) want.insert({x, 2});
  EXPECT_EQ(inked(c), want);

  Canvas d(12, 12, kBg);
  d.line(5, 5, 0, 0, kInk);  // backwards diagonal
  want.clear();
  for (int i = 0; i <= 5; ++i) want.insert({i, i});
  EXPECT_EQ(inked(d), want);

  Canvas v(12, 12, kBg);
  v.line(3.4, 9.6, 3.4, 1.2, kInk);  // end points round to the nearest pixel
  want.clear();
  for (int y = 1; y <= 10; ++y) want.insert({3, y});
  EXPECT_EQ(inked(v), want);

  // A steep line is 8-connected: one pixel per row.
  Canvas s(12, 12, kBg);
  s.line(1, 0, 4, 11, kInk);
  const auto px = inked(s);
  EXPECT_EQ(px.size(), 12U);
  for (int y = 0; y < 12; ++y) {
    int in_row = 0;
    for (const auto& p : px) in_row += p.second == y ? 1 : 0;
    EXPECT_EQ(in_row, 1) << "row " << y;
  }
}

TEST(Canvas, ThickLinesAreWider) {
  Canvas c(20, 20, kBg);
  c.line(2, 10, 17, 10, kInk, 3);
  for (int x = 2; x <= 17; ++x) {
    EXPECT_EQ(c.pixel(x, 9), kInk);
    EXPECT_EQ(c.pixel(x, 10), kInk);
    EXPECT_EQ(c.pixel(x, 11), kInk);
  }
  EXPECT_EQ(c.pixel(10, 7), kBg);
  EXPECT_EQ(c.pixel(10, 13), kBg);
}

TEST(Canvas, FilledCircleCoversExactlyTheDisc) {
  Canvas c(21, 21, kBg);
  c.fill_circle(10, 10, 3, kInk);
  for (int y = 0; y < 21; ++y) {
    for (int x = 0; x < 21; ++x) {
      const double d = std::hypot(x - 10, y - 10);
      EXPECT_EQ(c.pixel(x, y) == kInk, d <= 3.0) << x << "," << y;
    }
  }
  // Half transparency mixes with what is below.
  Canvas a(5, 5, Rgb{0, 0, 0});
  a.fill_circle(2, 2, 0.2, Rgb{200, 100, 50}, 0.5);
  EXPECT_EQ(a.pixel(2, 2), (Rgb{100, 50, 25}));
  EXPECT_EQ(a.pixel(1, 2), (Rgb{0, 0, 0}));
}

TEST(Canvas, CircleOutlineIsAClosedRing) {
  Canvas c(31, 31, kBg);
  const double r = 9.0;
  c.circle(15, 15, r, kInk);
  EXPECT_EQ(c.pixel(15, 15), kBg);
  EXPECT_EQ(c.pixel(24, 15), kInk);
  EXPECT_EQ(c.pixel(15, 6), kInk);
  for (const auto& [x, y] : inked(c)) EXPECT_LE(std::abs(std::hypot(x - 15, y - 15) - r), 0.5 + 1e-9);
  // Every direction meets the ring: a pixel lies within one pixel of each point on the circle.
  for (int k = 0; k < 360; ++k) {
    const double a = k * M_PI / 180.0;
    const int x = static_cast<int>(std::lround(15 + r * std::cos(a)));
    const int y = static_cast<int>(std::lround(15 + r * std::sin(a)));
    bool near = false;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) near = near || c.pixel(x + dx, y + dy) == kInk;
    }
    EXPECT_TRUE(near) << "gap at " << k << " degrees";
  }
}

TEST(Canvas, RectanglesOutlineAndFill) {
  Canvas c(10, 10, kBg);
  c.rect(2, 3, 5, 4, kInk);  // pixels x 2..6, y 3..6
  EXPECT_EQ(c.pixel(2, 3), kInk);
  EXPECT_EQ(c.pixel(6, 3), kInk);
  EXPECT_EQ(c.pixel(2, 6), kInk);
  EXPECT_EQ(c.pixel(6, 6), kInk);
  EXPECT_EQ(c.pixel(4, 3), kInk);
  EXPECT_EQ(c.pixel(4, 5), kBg);  // inside stays empty
  EXPECT_EQ(c.pixel(7, 3), kBg);
  EXPECT_EQ(c.pixel(2, 7), kBg);
  EXPECT_EQ(inked(c).size(), 14U);  // perimeter of a 5x4 rectangle

  Canvas f(10, 10, kBg);
  f.fill_rect(8, 8, 5, 5, kInk);  // clipped to 2x2
  EXPECT_EQ(inked(f).size(), 4U);
}

TEST(Canvas, BlitCopiesWithOffset) {
  Canvas small(2, 2, kInk);
  Canvas c(5, 5, kBg);
  c.blit(small, 4, -1);  // only (4, 0) lands on the canvas
  const std::set<std::pair<int, int>> want{{4, 0}};
  EXPECT_EQ(inked(c), want);
}

TEST(Font, GlyphsLandWhereExpected) {
  Canvas c(20, 12, kBg);
  EXPECT_EQ(c.text(2, 3, "-", kInk), 5);
  // '-' is the fourth row of the 5x7 cell, all five columns.
  std::set<std::pair<int, int>> want;
  for (int x = 2; x <= 6; ++x) want.insert({x, 6});
  EXPECT_EQ(inked(c), want);

  Canvas s(30, 30, kBg);
  EXPECT_EQ(s.text(1, 1, "-", kInk, 2), 10);
  want.clear();
  for (int x = 1; x <= 10; ++x) {
    want.insert({x, 7});
    want.insert({x, 8});
  }
  EXPECT_EQ(inked(s), want);

  // '|' is the middle column of all seven rows; the second glyph starts 6 pixels on.
  Canvas t(20, 12, kBg);
  t.text(0, 0, " |", kInk);
  want.clear();
  for (int y = 0; y < 7; ++y) want.insert({8, y});
  EXPECT_EQ(inked(t), want);
}

TEST(Font, MetricsAndUnknownCharacters) {
  EXPECT_EQ(text_width(""), 0);
  EXPECT_EQ(text_width("ab"), 11);
  EXPECT_EQ(text_width("ab", 3), 33);
  EXPECT_EQ(text_width("abc\nd"), 17);
  EXPECT_EQ(text_height("x"), 7);
  EXPECT_EQ(text_height("x\ny", 2), 32);
  // Every printable glyph draws something (except space), and non-ASCII draws as '?'.
  for (char ch = '!'; ch <= '~'; ++ch) {
    Canvas c(6, 8, kBg);
    c.text(0, 0, std::string(1, ch), kInk);
    EXPECT_FALSE(inked(c).empty()) << "glyph '" << ch << "' is blank";
  }
  Canvas q(6, 8, kBg), u(6, 8, kBg);
  q.text(0, 0, "?", kInk);
  u.text(0, 0, "\xC3", kInk);
  EXPECT_EQ(inked(q), inked(u));
  // Different letters look different.
  Canvas a(6, 8, kBg), b(6, 8, kBg);
  a.text(0, 0, "g", kInk);
  b.text(0, 0, "9", kInk);
  EXPECT_NE(inked(a), inked(b));
}

// A caption wider than its panel (handtrack-view's model caption on a 240-pixel portrait panel) is
// broken at spaces into lines that fit, every word kept; one that fits, and its own line breaks,
// stay as they are; a word wider than the panel is cut.
TEST(Font, WrapKeepsEveryLineWithinTheWidth) {
  const std::string caption = "model: tracking, right hand  conf 0.69  E 0.323\ntip error 17.8 mm (x = truth)";
  for (const int width : {238, 120, 60}) {
    for (const int scale : {1, 2}) {
      const std::string wrapped = wrap_text(caption, width * scale, scale);
      size_t start = 0;
      std::string words;
      while (start <= wrapped.size()) {
        const size_t end = std::min(wrapped.find('\n', start), wrapped.size());
        const std::string line = wrapped.substr(start, end - start);
        EXPECT_LE(text_width(line, scale), width * scale) << "'" << line << "' at " << width << " px";
        words += line + ' ';
        start = end + 1;
      }
      std::string expected = caption;
      std::replace(expected.begin(), expected.end(), '\n', ' ');
      const auto squeeze = [](std::string t) {
        t.erase(std::unique(t.begin(), t.end(), [](char a, char b) { return a == ' ' && b == ' '; }), t.end());
        while (!t.empty() && t.back() == ' ') t.pop_back();
        return t;
      };
      EXPECT_EQ(squeeze(words), squeeze(expected)) << width;
    }
  }
  EXPECT_EQ(wrap_text(caption, 400), caption);
  EXPECT_EQ(wrap_text("", 100), "");
  EXPECT_EQ(wrap_text("abcdefghij", 4 * kGlyphAdvance), "abcd\nefgh\nij");
}

TEST(Colormap, DepthGrayNearIsBrightAndNoMeasurementIsBlack) {
  const Rgb near = depth_gray(300, 300, 600);
  const Rgb mid = depth_gray(450, 300, 600);
  const Rgb far = depth_gray(600, 300, 600);
  EXPECT_EQ(near, colours::kWhite);
  EXPECT_GT(near.r, mid.r);
  EXPECT_GT(mid.r, far.r);
  EXPECT_GT(far.r, 0);  // far is still distinguishable from "no measurement"
  EXPECT_EQ(depth_gray(0, 300, 600), colours::kBlack);
  EXPECT_EQ(depth_gray(std::nan(""), 300, 600), colours::kBlack);
  EXPECT_EQ(depth_gray(5000, 300, 600), far);  // clamped
  EXPECT_EQ(depth_turbo(0, 300, 600), colours::kBlack);
  EXPECT_NE(depth_turbo(300, 300, 600), depth_turbo(600, 300, 600));
}

TEST(Colormap, TurboIsContinuousAndSpansHues) {
  Rgb prev = turbo(0.0);
  for (int i = 1; i <= 200; ++i) {
    const Rgb c = turbo(i / 200.0);
    EXPECT_LE(std::abs(c.r - prev.r) + std::abs(c.g - prev.g) + std::abs(c.b - prev.b), 30) << i;
    prev = c;
  }
  EXPECT_GT(turbo(0.1).b, turbo(0.1).r);  // blue end
  EXPECT_GT(turbo(0.9).r, turbo(0.9).b);  // red end
  EXPECT_EQ(turbo(-3.0), turbo(0.0));
  EXPECT_EQ(turbo(7.0), turbo(1.0));
}

TEST(Colormap, ThirteenDistinctPartColours) {
  std::set<std::tuple<int, int, int>> seen;
  for (int label = 0; label <= 12; ++label) {
    const Rgb c = part_colour(label);
    for (const auto& [r, g, b] : seen) {
      // Distinct enough to tell apart: at least 40 apart in the sum of channel differences.
      EXPECT_GE(std::abs(c.r - r) + std::abs(c.g - g) + std::abs(c.b - b), 40) << "label " << label;
    }
    seen.insert({c.r, c.g, c.b});
  }
  EXPECT_EQ(seen.size(), 13U);
  EXPECT_EQ(part_colour(13), part_colour(-1));  // out of range: one warning colour
  EXPECT_EQ(series_colour(0), series_colour(8));
  EXPECT_NE(series_colour(0), series_colour(1));
}

TEST(Colormap, MixAndShade) {
  EXPECT_EQ(mix(Rgb{0, 0, 0}, Rgb{200, 100, 50}, 0.5), (Rgb{100, 50, 25}));
  EXPECT_EQ(mix(Rgb{0, 0, 0}, Rgb{200, 100, 50}, 2.0), (Rgb{200, 100, 50}));
  EXPECT_EQ(shade(Rgb{200, 100, 50}, 0.5), (Rgb{100, 50, 25}));
  EXPECT_EQ(shade(Rgb{0, 0, 0}, 2.0), colours::kWhite);
}

// ---- the error plot ----

std::vector<double> constant(double mm, size_t n) { return std::vector<double>(n, mm); }

// Mean row of the pixels in `image` that have exactly the colour `c`; -1 if none.
double mean_row(const RgbImage& image, Rgb c, int y_from = 0, int y_to = -1) {
  const Canvas canvas(image);
  if (y_to < 0) y_to = canvas.height();
  double sum = 0.0;
  int n = 0;
  for (int y = y_from; y < y_to; ++y) {
    for (int x = 0; x < canvas.width(); ++x) {
      if (canvas.pixel(x, y) == c) {
        sum += y;
        ++n;
      }
    }
  }
  return n > 0 ? sum / n : -1.0;
}

TEST(ErrorPlot, HasTheDocumentedSize) {
  const std::vector<ErrorSeries> three{{"a", constant(10, 50)}, {"b", constant(20, 80)}, {"c", {}}};
  PlotOptions o;
  auto img = render_error_plot(three, o);
  EXPECT_EQ(img.width, o.width);
  EXPECT_EQ(img.height, 3 * o.panel_height);
  EXPECT_EQ(img.channels, 3);
  o.title = "fingertip error";
  o.width = 640;
  o.panel_height = 120;
  img = render_error_plot(three, o);
  EXPECT_EQ(img.width, 640);
  EXPECT_EQ(img.height, 3 * 120 + kPlotTitleHeightPx);
  o.overlay = true;
  img = render_error_plot(three, o);
  EXPECT_EQ(img.height, 120 + kPlotTitleHeightPx);
  // No series at all: one empty panel rather than an exception.
  img = render_error_plot({}, PlotOptions{});
  EXPECT_EQ(img.height, PlotOptions{}.panel_height);
  PlotOptions tiny;
  tiny.width = 50;
  EXPECT_THROW(render_error_plot(three, tiny), std::invalid_argument);
}

TEST(ErrorPlot, LargerErrorsAreDrawnHigher) {
  // One panel each; within its panel a 35 mm line must sit above (smaller y than) a 10 mm line.
  PlotOptions o;
  o.y_max_mm = 40;
  const Rgb line = series_colour(0);
  const auto low = render_error_plot({{"low", constant(10, 100)}}, o);
  const auto high = render_error_plot({{"high", constant(35, 100)}}, o);
  const double y_low = mean_row(low, line);
  const double y_high = mean_row(high, line);
  ASSERT_GT(y_low, 0);
  ASSERT_GT(y_high, 0);
  EXPECT_LT(y_high, y_low);
  // Linear in mm: 10, 20 and 30 mm are equally spaced.
  const double y10 = mean_row(render_error_plot({{"10", constant(10, 100)}}, o), line);
  const double y20 = mean_row(render_error_plot({{"20", constant(20, 100)}}, o), line);
  const double y30 = mean_row(render_error_plot({{"30", constant(30, 100)}}, o), line);
  EXPECT_GT(y10 - y20, 10.0);
  EXPECT_NEAR(y10 - y20, y20 - y30, 1.5);

  // Overlay: two series in their own colours, the larger error higher.
  o.overlay = true;
  const auto both = render_error_plot({{"low", constant(10, 100)}, {"high", constant(35, 100)}}, o);
  const double overlay_low = mean_row(both, series_colour(0), 22);
  const double overlay_high = mean_row(both, series_colour(1), 22);
  ASSERT_GT(overlay_low, 0);
  ASSERT_GT(overlay_high, 0);
  EXPECT_LT(overlay_high, overlay_low);
}

TEST(ErrorPlot, NotScoredFramesBreakTheLine) {
  PlotOptions o;
  o.y_max_mm = 40;
  const Rgb line = series_colour(0);
  std::vector<double> gappy(200, 20.0);
  for (size_t i = 50; i < 150; ++i) gappy[i] = std::numeric_limits<double>::quiet_NaN();
  const auto img = render_error_plot({{"gappy", gappy}}, o);
  const Canvas c(img);
  // The middle of the x range has no line pixels.
  int middle = 0, left = 0;
  for (int y = 0; y < c.height(); ++y) {
    middle += c.pixel(c.width() / 2, y) == line ? 1 : 0;
    for (int x = 60; x < 150; ++x) left += c.pixel(x, y) == line ? 1 : 0;
  }
  EXPECT_EQ(middle, 0);
  EXPECT_GT(left, 0);
  // All-NaN and infinite errors do not crash.
  EXPECT_NO_THROW(render_error_plot({{"none", std::vector<double>(10, std::nan(""))},
                                     {"inf", {1.0, std::numeric_limits<double>::infinity(), 500.0}}}));
}

TEST(ErrorPlot, WritesAValidPngOfTheExpectedSize) {
  const fs::path file = fs::temp_directory_path() / ("handtrack_plot_" + std::to_string(::getpid()) + ".png");
  std::vector<double> err(300);
  for (size_t i = 0; i < err.size(); ++i) err[i] = 15.0 + 10.0 * std::sin(0.05 * static_cast<double>(i));
  PlotOptions o;
  o.title = "pinch";
  write_error_plot(file, {{"pinch", err}, {"random", constant(22, 341)}}, o);

  png_image png;
  std::memset(&png, 0, sizeof png);
  png.version = PNG_IMAGE_VERSION;
  ASSERT_NE(png_image_begin_read_from_file(&png, file.c_str()), 0) << png.message;
  EXPECT_EQ(png.width, static_cast<png_uint_32>(o.width));
  EXPECT_EQ(png.height, static_cast<png_uint_32>(2 * o.panel_height + kPlotTitleHeightPx));
  EXPECT_NE(png.format & PNG_FORMAT_FLAG_COLOR, 0U);
  png.format = PNG_FORMAT_RGB;
  std::vector<uint8_t> pixels(PNG_IMAGE_SIZE(png));
  EXPECT_NE(png_image_finish_read(&png, nullptr, pixels.data(), 0, nullptr), 0) << png.message;
  png_image_free(&png);
  fs::remove(file);

  EXPECT_THROW(write_error_plot("/nonexistent-dir/x/plot.png", {{"a", {1.0}}}), std::runtime_error);
}

}  // namespace
}  // namespace handtrack::draw
