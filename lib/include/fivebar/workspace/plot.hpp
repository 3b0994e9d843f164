#pragma once
/// The picture of a station's workspace (drawn with cairo behind lib/src/plot/), as SVG and PNG
/// from the same drawing. Left panel: both mechanisms' exact regions (lower red, upper blue,
/// translucent, as the paper's Fig. 4), the shared region hatched, the assembly-restricted
/// boundaries dashed, the target ellipse, the base joints and each linkage in its pose at the
/// ellipse centre. Right panel: heat map of the working-mode LCI (the smaller of the mechanisms'
/// where all of them reach) with a colour bar, the target and the shared boundary. Axes in mm,
/// equal scale, a legend and a title naming the station.

#include <string>

#include "fivebar/colour.hpp"  // Rgb and viridis(), the heat maps' colour map
#include "fivebar/workspace/station.hpp"

namespace fivebar {

struct PlotOptions {
  int width_px = 1600;   ///< PNG size; the SVG has the same size in points
  int height_px = 1000;
  std::string title;     ///< empty: "Station <name>: reachable workspace"
  std::string subtitle;  ///< e.g. the design name; may be empty
  /// Throws InputError when a size is outside [200, 8000] px.
  void validate() const;
};

/// The picture as an SVG document.
std::string station_svg(const StationWorkspace& workspace, const PlotOptions& options = {});
/// The same picture as PNG bytes (width_px x height_px, ARGB).
std::string station_png(const StationWorkspace& workspace, const PlotOptions& options = {});

}  // namespace fivebar
