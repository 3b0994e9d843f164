// The `coverage` product: does each mechanism, and the shared region of both, reach every point of
// the station's target ellipse, with margin, on its assembly side and with LCI >= min_lci?
// Passes when every station is covered.

#include <string>
#include <vector>

#include "fivebar/coverage/coverage.hpp"
#include "fivebar/coverage/report.hpp"
#include "fivebar/workspace/station.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {

namespace {

std::string yes_no(bool v) { return v ? "yes" : "**no**"; }

void add_row(md::Table& t, const std::string& label, const CoverageResult& r) {
  t.row({label, r.covered ? "✓ covered" : "✗ **not covered**", md::fixed(r.margin_mm, 3),
         md::fixed(100.0 * r.covered_fraction, 2) + " %", md::pair(r.worst_point.x(), r.worst_point.y(), 2),
         md::fixed(r.min_lci, 4), md::pair(r.min_lci_point.x(), r.min_lci_point.y(), 2),
         md::fixed(r.min_force_capability, 4), yes_no(r.assembly_ok), yes_no(r.lci_ok)});
}

std::string station_markdown(const Station& s, const StationCoverage& c, const Json* workspace) {
  const Ellipse& e = s.target;
  std::string out = "### Station " + md::code(s.name) + "\n\n";
  out += "Target: centre " + md::pair(e.center.x(), e.center.y(), 2) + " mm, full axes " + md::fixed(e.axes.x(), 2) +
         " × " + md::fixed(e.axes.y(), 2) + " mm, rotated " + md::fixed(angle_deg(e.angle), 1) + "°.\n\n";
  md::Table t({"region", "verdict", "margin (mm)", "covered", "worst point (mm)", "min LCI", "at (mm)",
               "min force cap. (N/N·mm)", "assembly side", "LCI ≥ min_lci"},
              "llrrcrcrcc");
  if (c.lower) add_row(t, "lower", *c.lower);
  if (c.upper) add_row(t, "upper", *c.upper);
  if (c.shared) add_row(t, "shared", *c.shared);
  out += t.str() + "\n";
  std::vector<std::pair<std::string, const CoverageResult*>> parts;
  if (c.lower) parts.emplace_back("lower", &*c.lower);
  if (c.upper) parts.emplace_back("upper", &*c.upper);
  if (c.shared) parts.emplace_back("shared", &*c.shared);
  for (const auto& [name, r] : parts) {
    out += "- " + name + ": " + (r->reason.empty() ? std::string() : "✗ " + r->reason + ". ") + "Decided by " +
           r->method + ".\n";
  }
  out += "\n";
  if (workspace != nullptr) {
    for (const auto& st : workspace->at("stations")) {
      if (st.at("station") != s.name) continue;
      for (const auto& f : st.at("files")) {
        const std::string file = f.get<std::string>();
        if (file.size() > 4 && file.ends_with(".png")) out += "Picture: [" + file + "](" + file + ").\n\n";
      }
    }
  }
  return out;
}

constexpr const char* kPreamble =
    "A region *covers* the target when the whole filled ellipse lies inside it, the tactor stays on the "
    "design's assembly side over the ellipse, and the LCI there is at least the design's `min_lci`. The "
    "*margin* is the signed distance from the ellipse to the region's boundary (negative: the ellipse "
    "sticks out by that much), decided in double precision and, within rounding of zero, exactly by CGAL "
    "against a polygon provably around the ellipse; *covered* is the fraction of the ellipse's area "
    "inside the region. *min LCI* and *min force cap.* (1/σmax(J), the smallest tactor force per unit "
    "motor torque) are taken over the filled ellipse. The *shared* row asks whether both tactors reach "
    "every point.\n\n";

}  // namespace

Product coverage_product() {
  Product p;
  p.name = "coverage";
  p.checks_designs = true;  // re-run on a proposed design (check_design())
  p.title = "Target coverage";
  p.unavailable = without_mechanisms;
  p.after = {"workspace"};  // links to the workspace pictures, when built
  p.build = [](Context& ctx) {
    Built b;
    Json stations = Json::array();
    std::string markdown = kPreamble;
    std::vector<std::string> failed;
    std::size_t total = 0;
    double worst_margin = 0.0;
    bool first = true;
    for (const Station& s : ctx.design.stations) {
      if (s.mechanisms().empty()) continue;
      ctx.say("coverage: station " + s.name);
      const StationCoverage c = station_coverage(s);
      stations.push_back(to_json(c, s.name));
      markdown += station_markdown(s, c, ctx.result_of("workspace"));
      for (const auto* r : {&c.lower, &c.upper}) {
        if (!r->has_value()) continue;
        ++total;
        if (first || (*r)->margin_mm < worst_margin) worst_margin = (*r)->margin_mm;
        first = false;
      }
      if (c.lower && !c.lower->covered) failed.push_back(s.name + "/lower");
      if (c.upper && !c.upper->covered) failed.push_back(s.name + "/upper");
    }
    b.result = {{"stations", stations}};
    b.markdown = markdown;
    b.passed = failed.empty();
    if (b.passed) {
      b.check = "all " + std::to_string(total) + " mechanisms cover their target (smallest margin " +
                md::fixed(worst_margin, 3) + " mm)";
    } else {
      std::string list;
      for (const auto& f : failed) list += (list.empty() ? "" : ", ") + f;
      b.check = std::to_string(failed.size()) + " of " + std::to_string(total) + " mechanisms do not cover their target: " + list;
    }
    return b;
  };
  return p;
}

}  // namespace fivebar::products
