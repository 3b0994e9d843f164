// The `report` product: the quick accuracy report (work-precision of areas, coverage numbers,
// restricted regions and FK/IK) and the stability catalogue of every mechanism; its section of
// summary.md states how accurate each main number is.

#include <cmath>

#include "fivebar/report.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"
#include "report/format.hpp"

namespace fivebar::products {

namespace {

using report_fmt::sci;
using report_fmt::with_error_digits;

const WorkSeries* find(const std::vector<WorkSeries>& list, const std::string& method) {
  for (const WorkSeries& s : list)
    if (s.method == method && !s.points.empty()) return &s;
  return nullptr;
}

/// "value ± error" with the digits the error leaves.
std::string pm(double value, double error) { return with_error_digits(value, error) + " ± " + sci(error); }

struct Numbers {
  Json json;
  std::vector<std::string> row;
};

Numbers numbers(const MechanismAccuracy& m) {
  Numbers n;
  n.json["station"] = m.station;
  n.json["mechanism"] = m.mechanism;
  // Exact area: its double rounding is the only error; the closed form checks it where it exists.
  std::string area = md::fixed(m.exact_area_mm2, 6) + " (exact region";
  Json area_j = {{"value_mm2", m.exact_area_mm2}, {"method", "exact CGAL region"}};
  if (m.quad_area_mm2) {
    const double d = std::fabs(m.exact_area_mm2 - *m.quad_area_mm2);
    area += "; closed form agrees to " + sci(d) + ")";
    area_j["error_mm2"] = d;
  } else {
    area += ")";
    area_j["error_mm2"] = nullptr;
  }
  n.json["workspace_area"] = area_j;
  n.row = {md::code(m.station + "/" + m.mechanism) + (m.mirror_of.empty() ? "" : " (mirror image of " + md::code(m.mirror_of) + ")"),
           area};
  n.json["mirror_of"] = m.mirror_of.empty() ? Json(nullptr) : Json(m.mirror_of);
  for (const char* method : {"assembly-restricted area", "LCI-restricted area"}) {
    const WorkSeries* s = find(m.restricted, method);
    if (!s) {
      n.row.push_back("—");
      continue;
    }
    const WorkPoint& p = s->points.back();
    n.row.push_back(pm(p.value, p.error) + " (h = " + md::fixed(p.resolution, 3) + " mm)");
    n.json[std::string(method) == "LCI-restricted area" ? "lci_restricted_area" : "assembly_restricted_area"] = {
        {"value_mm2", p.value}, {"error_mm2", p.error}, {"h_mm", p.resolution},
        {"reference_h_mm", m.reference_spacing_mm}};
  }
  // Coverage margin: coverage()'s value; its error against the quad margin where there is one.
  if (m.margin_quad_mm) {
    const double e = std::fabs(m.margin_mm - *m.margin_quad_mm);
    n.row.push_back(pm(m.margin_mm, std::max(e, 1e-300)) + " (vs quad)");
    n.json["coverage_margin"] = {{"value_mm", m.margin_mm}, {"error_mm", e}, {"reference", "quad"}};
  } else {
    n.row.push_back(md::fixed(m.margin_mm, 6) + " (joint limits: no quad reference)");
    n.json["coverage_margin"] = {{"value_mm", m.margin_mm}, {"error_mm", nullptr}, {"reference", nullptr}};
  }
  const double le = std::fabs(m.min_lci - m.min_lci_reference);
  n.row.push_back(pm(m.min_lci, std::max(le, 1e-300)) + " (vs refined)");
  n.json["min_lci"] = {{"value", m.min_lci}, {"error", le}, {"reference", m.min_lci_reference}};
  return n;
}

const PrecisionCell* cell(const PrecisionStudy& s, const std::string& method, std::size_t stratum) {
  for (const PrecisionMethod& m : s.methods)
    if (m.name == method && stratum < m.cells.size()) return &m.cells[stratum];
  return nullptr;
}

std::string max_err(const PrecisionCell* c) {
  if (!c || c->samples == 0) return "—";
  std::string s = sci(c->max_error_mm);
  if (c->failed > 0) s += " (" + std::to_string(c->failed) + " no solution)";
  return s;
}

}  // namespace

Product report_product() {
  Product p;
  p.name = "report";
  p.title = "Accuracy and numerical stability";
  p.cost_s = 4.0;  // scheduler hint only (Product::cost_s): the showcase's report, measured
  p.unavailable = without_mechanisms;
  p.build = [](Context& ctx) {
    Built b;
    AccuracyOptions ao;
    ao.quick = true;
    ao.progress = ctx.progress;
    ctx.say("report: quick accuracy report");
    const AccuracyReport acc = accuracy_report(ctx.design, ao);
    ctx.say("report: stability catalogue");
    StabilityOptions so;
    so.progress = ctx.progress;
    const StabilityReport stab = stability_report(ctx.design, so);

    const auto plots = write_accuracy_plots(acc, ctx.dir / "report");
    for (const auto& f : plots) ctx.record(std::filesystem::path("report") / f);
    ctx.write_file("report/accuracy.json", to_json(acc).dump(2) + "\n");
    ctx.write_file("report/stability.json", to_json(stab).dump(2) + "\n");

    std::string out =
        "How accurate the numbers of this summary are, and whether the computations stay sound on extreme "
        "cases (`fivebar report accuracy --quick` and `fivebar report stability`; run them for the full "
        "tables). Errors are measured, not estimated: against the exact CGAL region, a 16× finer grid, or "
        "a `__float128` reimplementation of the kinematics and closed forms.\n\n";
    md::Table t({"mechanism", "workspace area (mm²)", "assembly-restricted area (mm²)", "LCI-restricted area (mm²)",
                 "coverage margin (mm)", "min LCI over the target"},
                "llllll");
    Json mechs = Json::array();
    for (const MechanismAccuracy& m : acc.mechanisms) {
      Numbers n = numbers(m);
      t.row(n.row);
      mechs.push_back(n.json);
    }
    out += "**Accuracy of the main numbers**\n\n" + t.str() + "\n";
    if (!acc.mechanisms.empty()) {
      const MechanismAccuracy& m0 = acc.mechanisms.front();
      out += "The LCI-restricted region is LCI ≥ " + md::fixed(m0.lci_threshold, 2) +
             (m0.lci_threshold_from_design ? " (the design's min_lci)" : " (illustrative: the design sets no min_lci)") +
             "; restricted areas are marching squares at the finest quick spacing against the same on a grid 16× "
             "finer. Min LCI: coverage()'s value against a refined local minimum.\n\n";
    }
    md::Table k({"|sin| (conditioning)", "FK fk() max error (mm)", "IK ik() max error (mm)",
                 "FK in float max error (mm)", "IK in float max error (mm)"},
                "lrrrr");
    for (std::size_t i = 0; i < acc.fk.strata.size(); ++i) {
      k.row({report_fmt::range(acc.fk.strata[i][0], acc.fk.strata[i][1]), max_err(cell(acc.fk, "fk()", i)),
             max_err(cell(acc.ik, "ik()", i)), max_err(cell(acc.fk, "float", i)), max_err(cell(acc.ik, "float", i))});
    }
    out += "**Kinematics against `__float128`**, by |sin| of the angle that conditions the problem (FK: between "
           "the distal links; IK: the elbows); errors grow like eps·L/|sin|:\n\n" +
           k.str() + "\n";
    out += "**Stability catalogue**: " + std::to_string(stab.cases.size()) + " cases (singularity distances 1e-1 … "
           "1e-16 and 0, link ratios 1e-4 … 1e4, scales 1e-3 … 1e6 mm, coincident bases, equal links, condition "
           "numbers to 1e14, tangent ellipses): " +
           (stab.passed() ? "all passed" : std::to_string(stab.failed()) + " FAILED") + "; " +
           std::to_string(stab.ill_conditioned()) +
           " flagged ill-conditioned (double precision cannot give more digits there; the bound says how many).\n\n";
    std::size_t listed = 0;
    for (const StabilityCase& c : stab.cases) {
      if (c.passed || listed >= 20) continue;
      out += "- ✗ " + md::code(c.mechanism) + " " + c.group + ", " + c.name + " (" + c.operation + "): " +
             c.explanation + "\n";
      ++listed;
    }
    if (listed > 0) out += "\n";
    out += "Plots (error against run time, fitted orders in the legends): ";
    bool first = true;
    for (const auto& f : plots) {
      if (f.extension() != ".png") continue;
      out += std::string(first ? "" : ", ") + "[" + f.stem().string() + "](report/" + f.generic_string() + ")";
      first = false;
    }
    out += "; full data in `report/accuracy.json` and `report/stability.json`.\n";

    Json ks = Json::array();
    for (std::size_t i = 0; i < acc.fk.strata.size(); ++i) {
      const PrecisionCell* f = cell(acc.fk, "fk()", i);
      const PrecisionCell* g = cell(acc.ik, "ik()", i);
      ks.push_back({{"sin_range", {acc.fk.strata[i][0], std::min(1.0, acc.fk.strata[i][1])}},
                    {"fk_max_error_mm", f ? Json(f->max_error_mm) : Json(nullptr)},
                    {"ik_max_error_mm", g ? Json(g->max_error_mm) : Json(nullptr)}});
    }
    b.result = {{"mechanisms", mechs},
                {"kinematics", ks},
                {"stability", {{"cases", stab.cases.size()},
                               {"failed", stab.failed()},
                               {"ill_conditioned", stab.ill_conditioned()}}},
                {"accuracy_seconds", acc.seconds}};
    b.markdown = out;
    b.passed = stab.passed();
    b.check = stab.passed() ? "all " + std::to_string(stab.cases.size()) + " stability cases passed (" +
                                  std::to_string(stab.ill_conditioned()) + " ill-conditioned, flagged)"
                            : std::to_string(stab.failed()) + " of " + std::to_string(stab.cases.size()) +
                                  " stability cases FAILED";
    return b;
  };
  return p;
}

}  // namespace fivebar::products
