#pragma once
/// The `print:` section of a design file: resin printing clearances and minimums. One module of the design (see
/// docs/architecture.md "Design sections"): the struct and its validate() here, its loader and
/// writer hooks in lib/src/sections/print.cpp. A Design holds it as `design.get<PrintSettings>()`.

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

/// Resin printing (`print:`): clearances and minimums of the printer and material.
struct PrintSettings {
  static constexpr std::string_view kKey = "print";
  double pin_clearance = 0.15;  ///< radial, mm (Tough 2000 guides: 0.1 - 0.25)
  double min_wall = 0.8;        ///< the printer's minimum wall, mm
  int fn = 96;                  ///< OpenSCAD $fn for printed circles
  double layer_height = 0.05;   ///< mm
  std::string material = "Formlabs Tough 2000";
  /// Density of the cured resin, g/cm^3, for the parts' mass properties. An assumption to
  /// replace: a value typical of cured photopolymer resins; the paper (Tough 2000) gives none.
  double density_g_cm3 = 1.15;
  void validate() const;
};

}  // namespace fivebar
