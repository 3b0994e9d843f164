// Coverage results as JSON, and the --ellipse text form (fivebar/coverage_report.hpp).
#include "fivebar/format.hpp"
#include "fivebar/coverage_report.hpp"

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
  j["margin_mm"] = r.margin_mm;
  j["covered_fraction"] = r.covered_fraction;
  j["worst_point_mm"] = {r.worst_point.x(), r.worst_point.y()};
  j["min_lci"] = r.min_lci;
  j["min_lci_point_mm"] = {r.min_lci_point.x(), r.min_lci_point.y()};
  j["min_force_capability"] = r.min_force_capability;
  j["lci_ok"] = r.lci_ok;
  j["assembly_ok"] = r.assembly_ok;
  j["method"] = r.method;
  j["reason"] = r.reason;
  return j;
}

Json to_json(const StationCoverage& s) {
  Json j = Json::object();
  if (s.lower) j["lower"] = to_json(*s.lower);
  if (s.upper) j["upper"] = to_json(*s.upper);
  if (s.shared) j["shared"] = to_json(*s.shared);
  return j;
}

Ellipse parse_ellipse(std::string_view text, std::string_view option) {
  const std::string form = "CX,CY,AX,AY,ANGLE: centre (mm), full axis lengths (mm), rotation (deg)";
  auto fail = [&](const std::string& why) -> Ellipse {
    throw InputError(std::string(option) + " '" + std::string(text) + "': " + why + " (expected " + form + ")");
  };
  std::vector<double> v;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    std::string_view part = text.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
    while (!part.empty() && (part.front() == ' ' || part.front() == '\t')) part.remove_prefix(1);
    while (!part.empty() && (part.back() == ' ' || part.back() == '\t')) part.remove_suffix(1);
    if (!part.empty() && part.front() == '+') part.remove_prefix(1);
    double x = 0.0;
    const auto [end, ec] = std::from_chars(part.data(), part.data() + part.size(), x);
    if (part.empty() || ec != std::errc() || end != part.data() + part.size() || !std::isfinite(x)) {
      return fail("value " + std::to_string(v.size() + 1) + " '" + std::string(part) + "' is not a finite number");
    }
    v.push_back(x);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  if (v.size() != 5) return fail("got " + std::to_string(v.size()) + " numbers, need 5");
  if (!(v[2] > 0.0) || !(v[3] > 0.0)) return fail("axis lengths must be > 0");
  Ellipse e;
  e.center = {v[0], v[1]};
  e.axes = {v[2], v[3]};
  e.angle = format::rad_from_deg(v[4]);
  try {
    e.validate();
  } catch (const InputError& err) {
    return fail(err.what());
  }
  return e;
}

}  // namespace fivebar
