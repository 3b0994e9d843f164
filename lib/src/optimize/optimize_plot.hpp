#pragma once
// Pictures of an optimisation (lib/src/optimize/optimize_plot.cpp): the hypervolume against the
// evaluations, and the front in parallel coordinates. Private to lib.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "fivebar/rendered_plot.hpp"

namespace fivebar::detail {

/// Normalised hypervolume of the front after each round against the evaluations so far.
RenderedPlot hypervolume_plot(const std::vector<std::pair<std::uint64_t, double>>& curve, const std::string& title);

/// One polyline per front point across the axes (variables, then objectives), each axis scaled
/// to [lo, hi]; `chosen` (index into rows, or -1) drawn bold, `reference` (the design as given,
/// may be empty) dashed; the other lines coloured by their value on axis `colour_axis`.
struct ParallelAxis {
  std::string label;
  double lo = 0.0, hi = 1.0;
};
RenderedPlot parallel_coordinates_plot(const std::vector<ParallelAxis>& axes, const std::vector<std::vector<double>>& rows,
                                       int chosen, const std::vector<double>& reference, const std::string& title,
                                       std::size_t colour_axis);

}  // namespace fivebar::detail
