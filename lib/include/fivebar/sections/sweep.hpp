#pragma once
/// The `sweep:` section of a design file: a link-dimension sweep of one station. One module of the design (see
/// docs/architecture.md "Design sections"): the struct and its validate() here, its loader and
/// writer hooks in lib/src/sections/sweep.cpp. A Design holds it as `design.get<SweepSettings>()`.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fivebar/design.hpp"

namespace fivebar {

/// One swept design variable (`sweep.vary`): NAME = LO:HI:N, in file units (mm).
struct SweepVariable {
  std::string name;  ///< one of sweep_variable_names()
  double lo = 0.0;
  double hi = 0.0;
  int n = 1;  ///< grid points (grid sampling); ignored by random / sobol
};

/// A link-dimension sweep (`sweep:`) over one station.
struct SweepSettings {
  static constexpr std::string_view kKey = "sweep";
  std::string station;
  std::string mechanism;             ///< "lower", "upper" or empty: every mechanism and shared
  std::vector<SweepVariable> vary;
  std::string sample = "grid";       ///< grid | random | sobol
  std::uint64_t count = 0;           ///< random / sobol designs (0: the grid's size)
  std::uint64_t seed = 1;
  std::vector<std::string> objectives{"margin", "min_lci"};  ///< see sweep_objective_names()
  /// Grid spacing (mm) of the per-design collision fraction (see collision_fraction()), computed
  /// for covered designs when the design has `geometry:` and the station both mechanisms; 0: off.
  /// Never finer than 1/24 of the ellipse's larger axis (sweep_collision_spacing()).
  double collision_spacing_mm = 2.0;
  /// Rules that need no design (names, ranges, counts); the design checks the station.
  void validate() const;
};
/// L1 L2 L3 L4, L12 (L1 = L2), L34 (L3 = L4), spacing (base spacing), upper_height (y of the
/// upper bases), ellipse_a, ellipse_b (full axes of the target).
const std::vector<std::string>& sweep_variable_names();
/// margin (max), min_lci (max), force (max), footprint (min: bounding-box area of the linkage),
/// collision (min: fraction of tactor-position pairs in the ellipse whose mechanisms collide).
const std::vector<std::string>& sweep_objective_names();
}  // namespace fivebar
