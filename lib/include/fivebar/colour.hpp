#pragma once
/// Colours of the pictures: one colour type and the one colour map every heat map uses
/// (lib/src/plot/style.hpp holds the rest of the house style, privately).

namespace fivebar {

/// A colour as r, g, b in [0, 1].
struct Rgb {
  double r = 0.0, g = 0.0, b = 0.0;
};

/// Colour of `value` in [0, 1] on matplotlib's viridis map (perceptually uniform, readable in grey
/// and by colour-blind readers): linear between the map's values at 0, 0.1, ..., 1; clamped
/// outside [0, 1], and NaN is the low end.
Rgb viridis(double value);

}  // namespace fivebar
