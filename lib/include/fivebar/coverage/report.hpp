#pragma once
/// Coverage results with units at the edges, shared by `fivebar coverage --json` and the
/// `coverage` product of `fivebar run` (so both print the same document).

#include <string_view>

#include "fivebar/coverage/coverage.hpp"
#include "fivebar/json.hpp"

namespace fivebar {

/// {covered, inside, margin_mm, covered_fraction, worst_point_mm [x, y], min_lci,
///  min_lci_point_mm [x, y], min_force_capability (N per N*mm), lci_ok, assembly_ok, method,
///  reason}, in that order and nothing else.
Json to_json(const CoverageResult& result);
/// A station record in the shape every command uses (docs/conventions.md "JSON documents"):
/// {"station": name, "mechanisms": [{"mechanism": "lower", <result>}, {"mechanism": "upper", ...}]
/// with the mechanisms the station has, "shared": <result> or null}.
Json to_json(const StationCoverage& station, std::string_view station_name);


}  // namespace fivebar
