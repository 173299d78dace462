#include "handtrack/draw/plot.hpp"

#include "handtrack/draw/colormap.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace handtrack::draw {
namespace {

// Panel layout, px.
constexpr int kLeftMargin = 44;    // y tick labels
constexpr int kRightMargin = 14;
constexpr int kCaptionHeight = 24; // series name and statistics above the axes
constexpr int kBottomMargin = 20;  // x tick labels
constexpr int kCaptionScale = 2;
// Automatic y range: at least up to 40 mm (above the paper's highest threshold, 30 mm), at most
// 60 mm so that a lost frame does not flatten the interesting range; taller errors are clipped
// (and marked).
constexpr double kAutoYMinMm = 40.0;
constexpr double kAutoYMaxMm = 60.0;

constexpr Rgb kPlotBackground{255, 255, 255};
constexpr Rgb kAxes{60, 60, 60};
constexpr Rgb kGrid{205, 205, 205};
constexpr Rgb kText{30, 30, 30};
constexpr Rgb kClipMark{200, 0, 0};

std::string format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

// 1, 2 or 5 times a power of ten, so that `span` holds about `wanted` steps.
double nice_step(double span, int wanted) {
  const double raw = std::max(span / std::max(1, wanted), 1e-9);
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * power >= raw) return m * power;
  }
  return 10.0 * power;
}

double auto_y_max(const std::vector<ErrorSeries>& series) {
  double top = 0.0;
  for (const auto& s : series) {
    for (double e : s.error_mm) {
      if (std::isfinite(e)) top = std::max(top, e);
    }
  }
  return std::clamp(std::ceil(top / 10.0) * 10.0, kAutoYMinMm, kAutoYMaxMm);
}

struct Axes {
  int x0, y0, x1, y1;  // plot area, inclusive pixel bounds; y0 is the top
  double frames;       // x axis spans frame 0 .. frames - 1
  double y_max;
  [[nodiscard]] double x(double frame) const {
    return x0 + (frames > 1 ? frame / (frames - 1) : 0.5) * (x1 - x0);
  }
  [[nodiscard]] double y(double mm) const { return y1 - std::clamp(mm / y_max, 0.0, 1.0) * (y1 - y0); }
};

void draw_axes(Canvas& c, const Axes& a, const PlotOptions& options, bool frame_label) {
  // Horizontal gridlines at the thresholds, labelled; 0 and the top of the axis labelled too.
  for (double g : options.gridlines_mm) {
    if (!(g > 0.0) || g > a.y_max) continue;
    const int y = static_cast<int>(std::lround(a.y(g)));
    for (int x = a.x0; x <= a.x1; x += 4) c.line(x, y, std::min(x + 1, a.x1), y, kGrid);
  }
  // Tick labels: 0 and the top first, then the gridlines, each skipped if it would overlap one
  // already drawn (close gridlines on a short panel).
  std::vector<int> label_rows;
  const auto label_at = [&](double mm) {
    const int y = static_cast<int>(std::lround(a.y(mm)));
    c.line(a.x0 - 3, y, a.x0, y, kAxes);
    for (int other : label_rows) {
      if (std::abs(other - y) < kLineAdvance) return;
    }
    label_rows.push_back(y);
    const std::string label = format("%.0f", mm);
    c.text(a.x0 - 6 - text_width(label), y - kGlyphHeight / 2, label, kText);
  };
  label_at(0.0);
  label_at(a.y_max);
  for (double g : options.gridlines_mm) {
    if (g > 0.0 && g < a.y_max) label_at(g);
  }
  c.text(4, a.y0 - 2, "mm", kText);
  // x ticks every "nice" number of frames.
  const double last = std::max(0.0, a.frames - 1);
  const double step = nice_step(std::max(last, 1.0), std::max(2, (a.x1 - a.x0) / 70));
  for (double f = 0.0; f <= last + 1e-9; f += step) {
    const int x = static_cast<int>(std::lround(a.x(f)));
    c.line(x, a.y1, x, a.y1 + 3, kAxes);
    const std::string label = format("%.0f", f);
    c.text(x - text_width(label) / 2, a.y1 + 6, label, kText);
  }
  if (frame_label) c.text(4, a.y1 + 6, "frame", kText);
  c.rect(a.x0, a.y0, a.x1 - a.x0 + 1, a.y1 - a.y0 + 1, kAxes);
}

void draw_series(Canvas& c, const Axes& a, const ErrorSeries& s, Rgb colour) {
  const auto n = s.error_mm.size();
  for (size_t i = 0; i < n; ++i) {
    const double e = s.error_mm[i];
    if (!std::isfinite(e)) continue;
    const double x = a.x(static_cast<double>(i));
    const double y = a.y(e);
    const bool prev = i > 0 && std::isfinite(s.error_mm[i - 1]);
    const bool next = i + 1 < n && std::isfinite(s.error_mm[i + 1]);
    if (prev) {
      c.line(a.x(static_cast<double>(i - 1)), a.y(s.error_mm[i - 1]), x, y, colour);
    } else if (!next) {
      c.fill_circle(x, y, 1.0, colour);  // an isolated scored frame
    }
    if (e > a.y_max) c.line(x, a.y0 - 4, x, a.y0 - 1, kClipMark);  // clipped: a mark above the axes
  }
}

struct Stats {
  int scored = 0;
  double mean = 0.0;
};

Stats stats(const ErrorSeries& s) {
  Stats out;
  for (double e : s.error_mm) {
    if (!std::isfinite(e)) continue;
    ++out.scored;
    out.mean += e;
  }
  if (out.scored > 0) out.mean /= out.scored;
  return out;
}

std::string caption(const ErrorSeries& s, const PlotOptions& options) {
  const Stats st = stats(s);
  std::string text = s.name.empty() ? std::string("(unnamed)") : s.name;
  if (st.scored == 0) return text + "  no scored frames";
  text += format("  mean %.1f mm", st.mean);
  for (double g : options.gridlines_mm) {
    int below = 0;
    for (double e : s.error_mm) below += std::isfinite(e) && e < g ? 1 : 0;
    text += format("  <%.0f:", g) + format(" %.0f%%", 100.0 * below / st.scored);
  }
  return text;
}

Axes panel_axes(int top, const PlotOptions& options, double frames, double y_max) {
  return {kLeftMargin, top + kCaptionHeight, options.width - 1 - kRightMargin,
          top + options.panel_height - 1 - kBottomMargin, std::max(frames, 1.0), y_max};
}

}  // namespace

RgbImage render_error_plot(const std::vector<ErrorSeries>& series, const PlotOptions& options) {
  if (options.width < 200) throw std::invalid_argument("error plot: width must be at least 200 px");
  if (options.panel_height < 80) throw std::invalid_argument("error plot: panel height must be at least 80 px");
  const int panels = options.overlay ? 1 : std::max<int>(1, static_cast<int>(series.size()));
  const int title_px = options.title.empty() ? 0 : kPlotTitleHeightPx;
  Canvas c(options.width, title_px + panels * options.panel_height, kPlotBackground);
  const double y_max =
      options.y_max_mm > 0.0 && std::isfinite(options.y_max_mm) ? options.y_max_mm : auto_y_max(series);

  if (!options.title.empty()) {
    c.text(kLeftMargin, (kPlotTitleHeightPx - kGlyphHeight * kCaptionScale) / 2, options.title, kText,
           kCaptionScale);
  }
  if (series.empty()) {
    const Axes a = panel_axes(title_px, options, 1.0, y_max);
    draw_axes(c, a, options, true);
    c.text(a.x0, title_px + 4, "no series", kText, kCaptionScale);
    return c.image();
  }
  if (options.overlay) {
    size_t frames = 0;
    for (const auto& s : series) frames = std::max(frames, s.error_mm.size());
    const Axes a = panel_axes(title_px, options, static_cast<double>(frames), y_max);
    draw_axes(c, a, options, true);
    // Legend: a colour swatch and the name with the mean error, left to right.
    int x = a.x0;
    for (size_t i = 0; i < series.size(); ++i) {
      const Rgb colour = series_colour(static_cast<int>(i));
      const Stats st = stats(series[i]);
      const std::string label =
          (series[i].name.empty() ? std::string("(unnamed)") : series[i].name) +
          (st.scored > 0 ? format(" %.1f mm", st.mean) : std::string(" -"));
      c.fill_rect(x, title_px + 6, 12, 12, colour);
      x += 16;
      x += c.text(x, title_px + 8, label, kText) + 14;
    }
    for (size_t i = 0; i < series.size(); ++i) draw_series(c, a, series[i], series_colour(static_cast<int>(i)));
    return c.image();
  }
  for (size_t i = 0; i < series.size(); ++i) {
    const int top = title_px + static_cast<int>(i) * options.panel_height;
    const Axes a = panel_axes(top, options, static_cast<double>(series[i].error_mm.size()), y_max);
    draw_axes(c, a, options, i + 1 == series.size());
    c.text(a.x0, top + (kCaptionHeight - kGlyphHeight * kCaptionScale) / 2, caption(series[i], options), kText,
           kCaptionScale);
    draw_series(c, a, series[i], series_colour(0));
  }
  return c.image();
}

void write_error_plot(const std::filesystem::path& png, const std::vector<ErrorSeries>& series,
                      const PlotOptions& options) {
  write_png_rgb(png, render_error_plot(series, options));
}

}  // namespace handtrack::draw
