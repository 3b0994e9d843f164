#pragma once
/// Coverage results with units at the edges, shared by `fivebar coverage --json` and the
/// `coverage` product of `fivebar run` (so both print the same document).

#include <string_view>

#include "fivebar/coverage.hpp"
#include "fivebar/json.hpp"

namespace fivebar {

/// {covered, inside, margin_mm, covered_fraction, worst_point_mm [x, y], min_lci,
///  min_lci_point_mm [x, y], min_force_capability (N per N*mm), lci_ok, assembly_ok, method,
///  reason}, in that order and nothing else.
Json to_json(const CoverageResult& result);
/// {"lower": {...}, "upper": {...}, "shared": {...}} with the parts the station has.
Json to_json(const StationCoverage& station);


}  // namespace fivebar
