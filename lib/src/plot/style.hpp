#pragma once
// The house style of every picture (private to lib/src/): one palette, one tick rule, one tick
// label. The cairo pictures and the hand-written SVG animations take their colours from here, so
// the upper mechanism is the same blue and the lower the same red in every file a run writes
// (as the paper's Fig. 4: lower red, upper blue).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "fivebar/colour.hpp"

namespace fivebar::style {

using fivebar::Rgb;
using fivebar::viridis;

inline constexpr Rgb kUpper{0.16, 0.38, 0.78};     ///< upper mechanism: fills, paths, lines
inline constexpr Rgb kLower{0.82, 0.18, 0.16};     ///< lower mechanism
inline constexpr Rgb kUpperInk{0.05, 0.18, 0.58};  ///< upper mechanism's outlines and labels
inline constexpr Rgb kLowerInk{0.60, 0.06, 0.06};  ///< lower mechanism's outlines and labels
inline constexpr Rgb kMoved{0.95, 0.55, 0.05};     ///< a target the priority rule moved
inline constexpr Rgb kShared{0.33, 0.10, 0.42};    ///< what both mechanisms share
inline constexpr Rgb kTarget{0.0, 0.48, 0.24};     ///< the target ellipse
inline constexpr Rgb kSimulated{0.10, 0.54, 0.23}; ///< the simulated tactor
inline constexpr Rgb kGood{0.10, 0.50, 0.20};      ///< a verdict that passed
inline constexpr Rgb kBad{0.75, 0.10, 0.10};       ///< a verdict that failed, an unstable cell
inline constexpr Rgb kInk{0.12, 0.12, 0.12};       ///< text and frames
inline constexpr Rgb kGrey{0.55, 0.55, 0.55};      ///< ticks, secondary text
inline constexpr Rgb kGridLine{0.88, 0.88, 0.90};  ///< grid lines
inline constexpr Rgb kNoData{0.88, 0.88, 0.88};    ///< cells without a value
inline constexpr Rgb kWhite{1.0, 1.0, 1.0};        ///< page and halos
/// Series of a chart with many lines: Tableau 10 (distinguishable, colour-blind friendlier).
inline constexpr Rgb kSeries[10] = {{0.122, 0.467, 0.706}, {1.000, 0.498, 0.055}, {0.173, 0.627, 0.173},
                                    {0.839, 0.153, 0.157}, {0.580, 0.404, 0.741}, {0.549, 0.337, 0.294},
                                    {0.890, 0.467, 0.761}, {0.498, 0.498, 0.498}, {0.737, 0.741, 0.133},
                                    {0.090, 0.745, 0.812}};

/// The mechanism's colour by name ("upper" is blue, any other red).
inline Rgb mechanism_colour(const std::string& mechanism) { return mechanism == "upper" ? kUpper : kLower; }

/// The colour scaled towards black (f = 0.55: the darker line of the same series).
inline Rgb darker(const Rgb& c, double f = 0.55) { return {f * c.r, f * c.g, f * c.b}; }

/// "#rrggbb" for SVG and HTML written by hand.
inline std::string hex(const Rgb& c) {
  const auto byte = [](double v) { return static_cast<int>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); };
  char buf[8];
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", byte(c.r), byte(c.g), byte(c.b));
  return buf;
}

/// The tick step of an axis: 1, 2 or 5 times a power of ten, the smallest giving at most
/// `intervals` intervals over `span` (1 for an empty or non-finite span).
inline double tick_step(double span, double intervals = 6.0) {
  if (!(span > 0.0) || !std::isfinite(span) || !(intervals > 0.0)) return 1.0;
  const double raw = span / intervals;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10.0 * p;
}

/// A tick label: four significant digits, no "-0".
inline std::string tick_label(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", std::fabs(v) < 1e-12 ? 0.0 : v);
  return buf;
}

}  // namespace fivebar::style
