// fivebar coverage: is the target ellipse inside each mechanism's reachable region and the shared
// one, with what margin, conditioning and force capability?

#include <cstdio>
#include <iostream>
#include <memory>

#include "common.hpp"
#include "fivebar/tolerance.hpp"
#include "fivebar/coverage/coverage.hpp"
#include "fivebar/coverage/report.hpp"
#include "fivebar/error.hpp"

namespace fivebar::cli {

namespace {

struct CoverageCliOptions {
  std::string design;
  std::string station;
  std::string mechanism;  ///< "lower" / "upper": that one alone (no shared region); empty: both
  std::string ellipse;  ///< "CX,CY,AX,AY,ANGLE"
  bool ellipse_given = false;
  bool robust = false;  ///< also: covered by tolerance.robust_fraction of printed devices
  bool json = false;
};

std::string point(const Vec2& p) { return "(" + fixed(p.x(), 3) + ", " + fixed(p.y(), 3) + ")"; }

void print_station(const Station& s, const Ellipse& e, bool overridden, const StationCoverage& c) {
  std::cout << "station " << s.name << "  target" << (overridden ? " (--ellipse)" : "") << ": centre ("
            << fixed(e.center.x(), 3) << ", " << fixed(e.center.y(), 3) << ") mm, full axes " << fixed(e.axes.x(), 3)
            << " x " << fixed(e.axes.y(), 3) << " mm, angle " << fixed(angle_deg(e.angle), 2) << " deg\n";
  std::printf("  %-7s %-12s %11s %9s %-20s %8s %-20s %10s %9s %8s\n", "region", "verdict", "margin (mm)", "covered",
              "worst point (mm)", "min LCI", "at (mm)", "min force", "assembly", "LCI ok");
  std::vector<std::pair<const char*, const CoverageResult*>> rows;
  if (c.lower) rows.emplace_back("lower", &*c.lower);
  if (c.upper) rows.emplace_back("upper", &*c.upper);
  if (c.shared) rows.emplace_back("shared", &*c.shared);
  for (const auto& [name, r] : rows) {
    std::printf("  %-7s %-12s %11s %8s%% %-20s %8s %-20s %10s %9s %8s\n", name,
                !r->decided ? "UNDECIDED" : r->covered ? "covered" : "NOT COVERED", fixed(r->margin_mm, 4).c_str(), fixed(100.0 * r->covered_fraction, 2).c_str(),
                point(r->worst_point).c_str(), fixed(r->min_lci, 4).c_str(), point(r->min_lci_point).c_str(),
                fixed(r->min_force_capability, 4).c_str(), r->assembly_ok ? "ok" : r->decided ? "CROSSES" : "undecided", r->lci_ok ? "yes" : "NO");
  }
  std::fflush(stdout);
  for (const auto& [name, r] : rows) {
    std::cout << "  " << name << ": " << (r->reason.empty() ? "" : r->reason + "; ") << "margin " << r->margin_mm
              << " mm +- " << r->margin_error_mm << " mm; method: " << r->method << "\n";
  }
  std::cout << "\n";
}

int run_coverage(const CoverageCliOptions& opt) {
  // The override is checked before the design is read: a typo in it is the user's first problem.
  std::optional<Ellipse> override_target;
  if (opt.ellipse_given) override_target = parse_ellipse(opt.ellipse, "--ellipse");
  const Design design = load(opt.design);
  const auto stations = design.select_stations(opt.station);
  if (stations.empty()) throw InputError("design '" + design.name + "' has no station with a mechanism");
  // --mechanism: the station with the other mechanism removed, so only that one (and no shared
  // region) is judged. Checked for every station before any work, like workspace.
  std::vector<Station> chosen;
  for (const Station* s : stations) {
    Station copy = *s;
    if (!opt.mechanism.empty()) {
      if (copy.mechanism(opt.mechanism) == nullptr) {
        throw InputError("station '" + s->name + "' has no " + opt.mechanism + " mechanism");
      }
      (opt.mechanism == "lower" ? copy.upper : copy.lower).reset();
    }
    chosen.push_back(std::move(copy));
  }
  const auto progress = terminal_progress("coverage");

  Json doc = {{"command", "coverage"}, {"design", design.name}};
  doc["target_override"] = override_target ? to_json(*override_target) : Json(nullptr);
  doc["stations"] = Json::array();
  bool all = true;
  for (const Station& s : chosen) {
    if (progress) progress("station " + s.name);
    const StationCoverage c = station_coverage(s, override_target);
    all = all && c.covered();
    Json js = to_json(c, s.name);
    const Ellipse& target = override_target ? *override_target : s.target;
    if (!opt.json) print_station(s, target, override_target.has_value(), c);
    if (opt.robust) {
      // Robust coverage (fivebar/tolerance.hpp): the margin that tolerance.robust_fraction of
      // printed devices keep, with the Monte Carlo of tolerance.samples devices beside it.
      for (Json& jm : js["mechanisms"]) {
        const Mechanism* m = s.mechanism(jm["mechanism"].get<std::string>());
        const ToleranceSources src = tolerance_sources(design, s, *m);
        const RobustCoverage r = robust_coverage(*m, target, src.spread(), src.robust_fraction, src.samples, src.seed);
        all = all && r.covered;
        jm["robust"] = to_json(r);
        if (!opt.json) {
          std::cout << "  " << m->name << " robust: " << fixed(100.0 * r.fraction, 1) << " % of printed devices keep "
                    << fixed(r.robust_margin_mm, 4) << " mm at " << point(r.robust_point) << " -> "
                    << (r.covered ? "covered" : "NOT COVERED") << " (Monte Carlo: "
                    << fixed(100.0 * r.fraction_monte_carlo, 2) << " % of " << r.samples << " devices cover; "
                    << fixed(100.0 - 100.0 * r.fraction, 1) << " % quantile of their margins "
                    << fixed(r.quantile_margin_mm, 4) << " mm)" << (r.calibrated ? " [sigmas: the calibration's posterior covariance]" : "")
                    << "\n";
        }
      }
      if (!opt.json) std::cout << "\n";
    }
    doc["stations"].push_back(std::move(js));
  }
  if (opt.json) {
    print_json(doc);
  } else {
    std::cout << (all ? "every mechanism covers its target\n" : "NOT every mechanism covers its target\n");
  }
  return all ? kOk : kCheckFailed;
}

}  // namespace

void setup_coverage(CLI::App& app) {
  auto [sub, opt] = add_command<CoverageCliOptions>(
      app, "coverage",
      "Is the target ellipse inside each mechanism's reachable region and the shared one? Margin (mm), covered "
      "fraction, min LCI and force capability over the ellipse",
      run_coverage);
  add_design_argument(*sub, opt->design);
  add_station_option(*sub, opt->station, "every station");
  sub->add_option("-m,--mechanism", opt->mechanism,
                  "Only this mechanism of each station, without the shared region (default: both and shared)")
      ->check(CLI::IsMember({"lower", "upper"}));
  // An init-capture: clang 14 (the fuzz build) does not capture a structured binding.
  sub->add_option_function<std::string>(
         "--ellipse",
         [o = opt](const std::string& text) {
           o->ellipse = text;
           o->ellipse_given = true;
         },
         "Target instead of the design's: centre CX,CY (mm), full axis lengths AX,AY (mm) and rotation "
         "ANGLE (deg), e.g. --ellipse 6.25,15.5,15,12,0; applies to every station checked")
      ->type_name("CX,CY,AX,AY,ANGLE");
  sub->add_flag("--robust", opt->robust,
                "Also require the target covered by tolerance.robust_fraction of printed devices (the design's "
                "tolerance: section, or its assumed defaults): the margin less the tolerances' error at each boundary "
                "point, with a Monte Carlo of tolerance.samples devices");
  add_json_flag(*sub, opt->json,
                "{\"command\", \"design\", \"stations\": [{\"station\", \"mechanisms\": [{\"mechanism\", ...}], "
                "\"shared\"}]}");
  sub->footer(
      "The margin is the signed distance from the ellipse to the region boundary (negative: outside by that much).\n" +
      exit_status({.ok = "every mechanism covers the target (inside, assembly side kept, LCI >= min_lci; with --robust "
                         "also for the printed devices)",
                    .failed = "otherwise"}));
}

}  // namespace fivebar::cli
