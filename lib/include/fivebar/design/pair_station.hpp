#pragma once
/// The station of a two-tactor study (collision, patterns, simulate, replay, animate) and the
/// geometry it needs, chosen in one place for every front end (the CLI, the Python module).

#include <string>

#include "fivebar/design.hpp"
#include "fivebar/sections/geometry.hpp"

namespace fivebar {

/// `station` (empty: the design's only station), which must have both mechanisms. InputError naming
/// the design's stations when the name is unknown or none is given among several, and the missing
/// mechanism otherwise.
const Station& pair_station(const Design& design, const std::string& station);

/// The design's `geometry:` section (link widths, pins, planes); InputError when it has none.
const Geometry& require_geometry(const Design& design);

}  // namespace fivebar
