#pragma once
// The per-frame error plot of the evaluator, like the paper's Fig. 6: fingertip error in mm over
// the frame index, with gridlines at the paper's thresholds (15, 20, 25, 30 mm).

#include "handtrack/draw/canvas.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace handtrack::draw {

struct ErrorSeries {
  std::string name;
  std::vector<double> error_mm;  // per frame, NaN = not scored
};

struct PlotOptions {
  std::string title;                                   // drawn above the panels when not empty
  int width = 1000;                                    // image width, px
  int panel_height = 200;                              // height of one panel, px
  double y_max_mm = 0.0;  // top of the y axis; 0 = automatic: the largest error rounded up to 10, in [40, 60]
  std::vector<double> gridlines_mm = {15, 20, 25, 30}; // the paper's thresholds (Sec. 7)
  bool overlay = false;  // false: one panel per series, stacked; true: all in one panel with a legend
};

// Height of the title strip when PlotOptions::title is not empty.
inline constexpr int kPlotTitleHeightPx = 28;

// The plot as an image: options.width wide and options.panel_height * panels (+ kPlotTitleHeightPx
// with a title) tall, where panels = series.size() (at least 1), or 1 with overlay. A series' panel
// shows its name, its mean error and the fraction of scored frames below each gridline. Errors above
// the axis are drawn as a mark on the top edge; NaN frames break the line. Throws
// std::invalid_argument for a width below 200 or a panel height below 80.
RgbImage render_error_plot(const std::vector<ErrorSeries>& series, const PlotOptions& options = {});
// render_error_plot() written as an RGB PNG; throws std::runtime_error naming the file on failure.
void write_error_plot(const std::filesystem::path& png, const std::vector<ErrorSeries>& series,
                      const PlotOptions& options = {});

}  // namespace handtrack::draw
