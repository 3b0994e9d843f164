#pragma once
// Log-log work-precision plots (private; cairo stays in work_precision_plot.cpp): error against
// run time, one series per method or precision, its fitted order in the legend.

#include <string>
#include <utility>
#include <vector>

namespace fivebar::plot {

struct PlotSeries {
  std::string label;                             ///< legend text (with the fitted order)
  std::vector<std::pair<double, double>> points; ///< (x, y); points with x <= 0 or y <= 0 are not drawn
  bool line = true;                              ///< join the points (false: markers only)
};

struct PlotSpec {
  std::string title;
  std::string x_label;  ///< with unit, e.g. "run time (s)"
  std::string y_label;  ///< with unit, e.g. "error |A - A_exact| (mm²)"
  std::vector<PlotSeries> series;
  std::string footnote;  ///< small text under the plot (may be empty)
};

/// The plot as an SVG document.
std::string render_svg(const PlotSpec& spec);
/// The plot as PNG bytes.
std::string render_png(const PlotSpec& spec);

}  // namespace fivebar::plot
