#pragma once
// A time-series chart on a cairo page (private to lib/src/): frame, grid, ticks, rotated y label,
// clipped lines and a legend along the top. The simulation and identification pictures draw
// their signals with it.

#include <cairo.h>

#include <string>
#include <utility>
#include <vector>

#include "plot/style.hpp"

namespace fivebar::plot {

using style::Rgb;

/// One signal: (t, value) points, its colour, width and dash, and its legend label.
struct Line {
  std::vector<std::pair<double, double>> points;
  Rgb colour;
  double width = 1.0;
  bool dashed = false;
  std::string label;
};

/// A line of at most ~3000 points from samples y(t) (every k-th sample; time from t.front());
/// empty when the sizes differ.
Line decimated_line(const std::vector<double>& t, const std::vector<double>& y, Rgb colour, double width,
                    bool dashed, std::string label);

struct ChartLayout {
  double x = 0.0, y = 0.0, w = 0.0, h = 0.0;  ///< the frame on the page (pixels)
  std::string title;
  std::string y_label;
  double t_end = 1.0;          ///< the time axis spans [0, t_end] s
  bool include_zero = false;   ///< the value axis always shows 0 (currents, forces)
  double y_label_gap = 44.0;   ///< pixels from the frame to the rotated y label
};

/// Draws the chart; lines without points are left out of the legend.
void time_chart(cairo_t* cr, const ChartLayout& layout, const std::vector<Line>& lines);

}  // namespace fivebar::plot
