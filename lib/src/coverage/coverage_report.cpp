// Coverage results as JSON, and the --ellipse text form (fivebar/coverage/report.hpp).
#include "fivebar/format.hpp"
#include "fivebar/coverage/report.hpp"

#include <charconv>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "fivebar/error.hpp"

namespace fivebar {

Json to_json(const CoverageResult& r) {
  Json j;
  j["covered"] = r.covered;
  j["inside"] = r.inside;
  j["decided"] = r.decided;
  j["margin_mm"] = r.margin_mm;
  j["margin_error_mm"] = r.margin_error_mm;
  j["covered_fraction"] = r.covered_fraction;
  j["worst_point_mm"] = {r.worst_point.x(), r.worst_point.y()};
  j["min_lci"] = r.min_lci;
  j["min_lci_point_mm"] = {r.min_lci_point.x(), r.min_lci_point.y()};
  j["min_force_capability"] = r.min_force_capability;
  j["lci_ok"] = r.lci_ok;
  j["assembly_ok"] = r.assembly_ok;
  j["assembly_crossing_mm"] =
      r.assembly_crossing ? Json{r.assembly_crossing->x(), r.assembly_crossing->y()} : Json(nullptr);
  j["method"] = r.method;
  j["reason"] = r.reason;
  return j;
}

Json to_json(const StationCoverage& s, std::string_view station) {
  Json j = Json::object();
  j["station"] = station;
  j["mechanisms"] = Json::array();
  for (const auto& [name, r] : {std::pair{"lower", &s.lower}, std::pair{"upper", &s.upper}}) {
    if (!r->has_value()) continue;
    Json m = {{"mechanism", name}};
    m.update(to_json(**r));
    j["mechanisms"].push_back(std::move(m));
  }
  j["shared"] = s.shared ? to_json(*s.shared) : Json(nullptr);
  return j;
}


}  // namespace fivebar
