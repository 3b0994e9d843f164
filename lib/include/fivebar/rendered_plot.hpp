#pragma once
/// A picture in the two formats every plot of fivebar is written in: SVG for the browser and
/// print, PNG for everything else. Both come from the same drawing (lib/src/plot/canvas.hpp).

#include <string>

namespace fivebar {

/// An image in two formats, as bytes (written by the caller, atomically).
struct RenderedPlot {
  std::string svg;
  std::string png;
};

}  // namespace fivebar
