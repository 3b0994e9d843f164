#pragma once
/// The `geometry:` section of a design file: link outlines, pins and layers, for collision checking and printed parts. One module of the design (see
/// docs/architecture.md "Design sections"): the struct and its validate() here, its loader and
/// writer hooks in lib/src/sections/geometry.cpp. A Design holds it as `design.get<Geometry>()`.

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

/// Physical link geometry (`geometry:`), for collision checking and printed parts. Defaults
/// follow the paper's resin-printed device in spirit (mm).
struct Geometry {
  static constexpr std::string_view kKey = "geometry";
  std::array<double, 4> link_width{4.0, 4.0, 4.0, 4.0};  ///< L1..L4: outline is a capsule this wide
  double link_thickness = 2.5;         ///< of every link plate
  double pin_diameter = 2.0;           ///< nominal pin at every joint (O_i, A_i, P)
  double boss_diameter = 5.0;          ///< rounded link end around each pin
  double tactor_diameter = 4.0;        ///< contact disk at P
  double tactor_height = 6.0;          ///< above the top link plane
  std::array<int, 4> layers{0, 0, 1, 1};  ///< plane of L1..L4, 0 nearest the base plate
  double layer_gap = 0.4;              ///< between planes (washers)
  double motor_shaft_diameter = 3.0;   ///< D-shaft of the motors
  double motor_shaft_flat = 0.5;       ///< depth of the shaft's flat
  double min_clearance = 0.3;          ///< a smaller gap between links counts as a collision
  /// Throws ValidationError naming the key ("link_width[2]", "pin_diameter").
  void validate() const;
};

}  // namespace fivebar
