// fivebar tolerance: how far the printed device's tactor can be from where the controller believes
// it is, per mechanism, at the target centre and over the filled target ellipse (first order, with
// a Monte Carlo check at the centre; fivebar/tolerance.hpp).

#include <cmath>
#include <cstdio>
#include <iostream>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "common.hpp"
#include "fivebar/resources/estimates.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "fivebar/sections/tolerance.hpp"
#include "fivebar/tolerance.hpp"

namespace fivebar::cli {

namespace {

struct ToleranceCliOptions {
  std::string design;
  std::string station;
  std::string out;
  double spacing_mm = 0.25;
  bool no_files = false;
  bool devices = false;
  bool json = false;
  bool yes = false;  ///< run beyond the resource bounds (docs/reliability.md)
};

std::string point(const Vec2& p) { return "(" + fixed(p.x(), 3) + ", " + fixed(p.y(), 3) + ")"; }

void print_mechanism(const ToleranceMap& r) {
  if (r.calibrated) std::cout << "  " << r.mechanism << " sigmas: " << r.spread_source << "\n";
  std::cout << "  " << r.mechanism << ": at the centre " << point(r.target.center) << ": ";
  if (r.centre.status != Status::ok) {
    std::cout << to_string(r.centre.status) << " (no first-order estimate)\n";
  } else {
    std::cout << "3-sigma " << fixed(r.centre.ellipse_semi_axes.x(), 4) << " mm first order (Monte Carlo "
              << fixed(r.centre_monte_carlo_3sigma_mm, 4) << " mm), worst case (+-3-sigma corner, nonlinear) "
              << fixed(r.centre_corners.worst_mm, 4) << " mm (first order " << fixed(r.centre.worst_case_mm, 4)
              << " mm; separate effects added, first order: " << fixed(r.centre.sum_of_effects_mm, 4) << " mm), resolution "
              << fixed(r.centre.resolution_um, 3) << " um per count, play " << fixed(r.centre_play.extent_mm, 4) << " mm"
              << (r.centre.near_singular ? " [near singular: first order not trusted]" : "") << "\n";
  }
  if (r.target_not_ok >= r.target_points) {  // nothing to report: no 0 mm at (0, 0) (docs/reliability.md)
    std::cout << "    over the target (" << r.target_points << " points): no point is reachable and regular (no estimate)";
  } else {
  std::cout << "    over the target (" << r.target_points << " points): 3-sigma up to " << fixed(r.worst_3sigma_mm, 4)
            << " mm first order at " << point(r.worst_3sigma_at) << (r.worst_3sigma_flagged ? " [near singular]" : "")
            << ", worst case (nonlinear corners) up to " << fixed(r.worst_case_mm, 4) << " mm at "
            << point(r.worst_case_at) << (r.worst_case_flagged ? " [near singular]" : "") << " (first order up to "
            << fixed(r.worst_case_first_order_mm, 4) << " mm at " << point(r.worst_case_first_order_at) << "; "
            << r.first_order_low_by_10_percent << " regular points where it is > 10 % low), resolution up to "
            << fixed(r.worst_resolution_um, 3)
            << " um per count, play up to " << fixed(r.worst_play_mm, 4) << " mm at " << point(r.worst_play_at);
  if (r.target_not_ok > 0) std::cout << "; " << r.target_not_ok << " points unreachable or singular (no estimate)";
  }
  std::cout << "\n";
  if (!r.near_singular.empty()) {
    std::cout << "    first order not trusted at " << r.near_singular.size()
              << " target points (near a type II singularity); there the Monte Carlo and the nonlinear corners:\n";
    for (const auto& f : r.near_singular) {
      std::cout << "      " << point(f.at) << ": 3-sigma " << fixed(f.first_order.ellipse_semi_axes.x(), 4)
                << " mm first order, " << fixed(f.monte_carlo_3sigma_mm, 4) << " mm Monte Carlo ("
                << f.monte_carlo.failed << " of " << (f.monte_carlo.used + f.monte_carlo.failed)
                << " devices fail); worst corner " << fixed(f.first_order.worst_case_mm, 4) << " mm first order, "
                << fixed(f.corners.worst_mm, 4) << " mm nonlinear (" << f.corners.failed << " of " << f.corners.corners
                << " corners fail)\n";
    }
  }
  const RobustCoverage& c = r.robust;
  // The first-order certified margin and the Monte Carlo's fraction and quantile side by side.
  std::cout << "    robust coverage at " << fixed(100.0 * c.fraction, 1) << " % of printed devices: margin " << fixed(c.margin_mm, 4)
            << " mm; first order: " << fixed(c.robust_margin_mm, 4) << " mm kept ("
            << (c.robust_certified ? "certified >= " + fixed(c.robust_margin_lower_mm, 4) + " mm" : std::string("sampled, not certified"))
            << ", sigma " << fixed(c.sigma_mm, 4) << " mm at " << point(c.robust_point) << ", at most "
            << fixed(100.0 * c.fraction_first_order, 2) << " % cover) -> " << (c.covered ? "covered" : "NOT covered");
  if (c.samples > 0) {
    std::cout << "; Monte Carlo (" << c.samples << " devices, nonlinear): " << fixed(100.0 * c.fraction_monte_carlo, 2)
              << " % cover, " << fixed(100.0 * (1.0 - c.fraction), 1) << " % quantile of the margins "
              << fixed(c.quantile_margin_mm, 4) << " mm";
  }
  std::cout << "\n";
  if (c.samples > 0) {
    std::cout << "    Monte Carlo: that quantile is >= "
              << (std::isfinite(c.quantile_lower_mm) ? fixed(c.quantile_lower_mm, 4) + " mm" : std::string("? (too few samples)"))
              << " with " << fixed(100.0 * c.quantile_confidence, 0) << " % confidence (order statistic, binomial)\n";
  }
}

int run_tolerance(const ToleranceCliOptions& opt) {
  const Design design = load(opt.design);
  const auto stations = design.select_stations(opt.station);
  if (stations.empty()) throw InputError("design '" + design.name + "' has no station with a mechanism");
  if (!(opt.spacing_mm > 0.0) || !std::isfinite(opt.spacing_mm)) throw InputError("--spacing must be > 0 mm");
  const ToleranceSettings* given = design.get<ToleranceSettings>();
  const ToleranceSettings t = given ? *given : ToleranceSettings{};
  // The Monte Carlo's cost, estimated from tolerance.samples before anything runs (the one
  // resource rule, fivebar/resources/budget.hpp).
  check_budget(tolerance_estimate(design, stations), opt.yes, "confirm with --yes, or lower tolerance.samples");
  const auto progress = terminal_progress("tolerance");

  // Analyse everything before writing anything.
  std::vector<std::vector<ToleranceMap>> maps;
  std::vector<ToleranceSources> first_sources;
  for (const Station* s : stations) {
    if (progress) progress("station " + s->name);
    maps.emplace_back();
    for (const Mechanism* m : s->mechanisms()) {
      const ToleranceSources src = tolerance_sources(design, *s, *m);
      if (first_sources.empty()) first_sources.push_back(src);
      maps.back().push_back(tolerance_map(*m, s->name, s->target, src, opt.spacing_mm));
    }
  }
  const ToleranceSources& src = first_sources.front();
  Json doc = {{"command", "tolerance"}, {"design", design.name}};
  doc["tolerance"] = {{"source", given ? "design" : "defaults (assumptions)"},
                      {"link_length_sigma_mm", src.sigma[0]},
                      {"base_sigma_mm", src.sigma[4]},
                      {"angle_sigma_deg", angle_deg(src.sigma[8])},
                      {"angle_offset_sigma_deg", t.angle_sigma_deg},
                      {"resolution_source", src.resolution_source},
                      {"leg_play_mm", Json::array({src.leg_play_mm[0], src.leg_play_mm[1]})},
                      {"robust_fraction", src.robust_fraction},
                      {"samples", t.samples},
                      {"seed", t.seed}};
  doc["stations"] = Json::array();
  if (!opt.json) {
    std::cout << "tolerances " << (given ? "from the design" : "by default (assumptions to replace)")
              << ": link length sigma " << fixed(src.sigma[0], 4) << " mm, base " << fixed(src.sigma[4], 4)
              << " mm per axis, joint angle " << fixed(angle_deg(src.sigma[8]), 3)
              << " deg (calibration offset and potentiometer linearity), leg play " << fixed(src.leg_play_mm[0], 3) << " / "
              << fixed(src.leg_play_mm[1], 3) << " mm; resolution from " << src.resolution_source << "; Monte Carlo "
              << t.samples << " devices, seed " << t.seed << "\n";
  }
  std::vector<std::string> files;
  std::filesystem::path dir;
  if (!opt.no_files) {
    dir = command_output_dir(opt.out, design.name, "tolerance");
    make_directories(dir);
  }
  std::optional<WriteFence> fence;  // nothing of this command lands outside its folder (fivebar/io.hpp)
  if (!opt.no_files) fence.emplace(dir);
  bool all_covered = true;
  for (std::size_t k = 0; k < stations.size(); ++k) {
    const Station* s = stations[k];
    Json js = {{"station", s->name}, {"mechanisms", Json::array()}};
    if (!opt.json) std::cout << "station " << s->name << "\n";
    for (const ToleranceMap& r : maps[k]) {
      js["mechanisms"].push_back(to_json(r));
      all_covered = all_covered && r.robust.covered;
      if (!opt.json) print_mechanism(r);
    }
    if (!opt.no_files) {
      for (const auto& f : write_tolerance_files(dir, *s, maps[k])) files.push_back(f.generic_string());
    }
    if (opt.devices) {
      for (const Mechanism* m : s->mechanisms()) {
        const ToleranceSources mech = tolerance_sources(design, *s, *m);
        const std::filesystem::path csv = dir / (s->name + "-" + m->name + "-devices.csv");
        AtomicFile file(csv);
        write_devices_csv(file.stream(), tolerance_devices(*m, s->target, mech.spread(), mech.samples, mech.seed));
        file.commit();
        files.push_back(csv.generic_string());
      }
    }
    doc["stations"].push_back(std::move(js));
  }
  doc["files"] = files;
  doc["robust_covered"] = all_covered;
  if (opt.json) {
    print_json(doc);
  } else if (!files.empty()) {
    std::cout << "wrote " << files.size() << " files into " << dir.generic_string() << "\n";
  }
  return all_covered ? kOk : kCheckFailed;
}

}  // namespace

void setup_tolerance(CLI::App& app) {
  auto [sub, opt] = add_command<ToleranceCliOptions>(
      app, "tolerance",
      "How far the printed device's tactor can be from where the controller believes it is: 3-sigma and "
      "worst-case error (mm), resolution per ADC count and clearance play at the target centre and over the target "
      "ellipse, maps over the reachable region, and robust coverage (the target covered by a fraction of printed "
      "devices)",
      run_tolerance);
  add_design_argument(*sub, opt->design);
  add_station_option(*sub, opt->station, "every station");
  sub->add_option("--spacing", opt->spacing_mm, "Grid spacing of the maps over the reachable region (mm)")
      ->capture_default_str()
      ->type_name("MM");
  add_out_option(*sub, opt->out, "the maps", "tolerance");
  sub->add_flag("--no-files", opt->no_files, "Print the figures only: no VTK maps, no pictures");
  sub->add_flag("--devices", opt->devices,
                "Also write the Monte Carlo's printed devices, a CSV per mechanism (<station>-<mechanism>-devices.csv: "
                "parameter errors, tactor error at the target centre, the device's own coverage margin)")
      ->excludes("--no-files");
  add_json_flag(*sub, opt->json);
  sub->add_flag("--yes", opt->yes, "Run a Monte Carlo estimated at over an hour or two gigabytes of memory (refused otherwise)");
  sub->footer(
      "Tolerances come from the design's tolerance: section (docs/design-file.md), else from its defaults, which are "
      "assumptions.\nFiles: <station>-<mechanism>-tolerance.vti (ParaView: three_sigma_first_order_mm, worst_case_first_order_mm, resolution_um, "
      "play_mm, near_singular, status) and <station>-tolerance.svg|.png.\n" +
      exit_status({.ok = "every mechanism covers its target for tolerance.robust_fraction of printed devices",
                   .failed = "one does not"}));
}

}  // namespace fivebar::cli
