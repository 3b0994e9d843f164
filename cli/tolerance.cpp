// fivebar tolerance: how far the printed device's tactor can be from where the controller believes
// it is, per mechanism, at the target centre and over the filled target ellipse (first order, with
// a Monte Carlo check at the centre; fivebar/tolerance.hpp).

#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>

#include "common.hpp"
#include "fivebar/error.hpp"
#include "fivebar/sections/tolerance.hpp"
#include "fivebar/tolerance.hpp"

namespace fivebar::cli {

namespace {

struct ToleranceCliOptions {
  std::string design;
  std::string station;
  bool json = false;
};

/// Grid points per axis of the target ellipse's bounding box (those inside the ellipse are used).
constexpr int kGrid = 21;

/// Points of a kGrid x kGrid grid over the filled ellipse (its own frame), centre included.
std::vector<Vec2> ellipse_grid(const Ellipse& e) {
  std::vector<Vec2> out;
  const double c = std::cos(e.angle);
  const double s = std::sin(e.angle);
  for (int i = 0; i < kGrid; ++i) {
    for (int j = 0; j < kGrid; ++j) {
      const double u = -1.0 + 2.0 * i / (kGrid - 1);
      const double v = -1.0 + 2.0 * j / (kGrid - 1);
      if (u * u + v * v > 1.0) continue;
      const double x = 0.5 * e.axes.x() * u;
      const double y = 0.5 * e.axes.y() * v;
      out.push_back(e.center + Vec2(c * x - s * y, s * x + c * y));
    }
  }
  return out;
}

Json point_json(const Vec2& p) { return Json::array({p.x(), p.y()}); }
std::string point(const Vec2& p) { return "(" + fixed(p.x(), 3) + ", " + fixed(p.y(), 3) + ")"; }

struct MechanismTolerance {
  ToleranceEstimate centre;
  MonteCarloTolerance monte_carlo;
  double mc_3sigma_mm = 0.0;  ///< 3 sqrt(largest eigenvalue) of the Monte Carlo covariance
  double worst_3sigma_mm = 0.0;
  Vec2 worst_3sigma_at{0.0, 0.0};
  double worst_case_mm = 0.0;
  Vec2 worst_case_at{0.0, 0.0};
  double worst_resolution_um = 0.0;
  std::size_t points = 0;
  std::size_t not_ok = 0;  ///< grid points unreachable or singular (no estimate)
};

MechanismTolerance analyse(const Mechanism& m, const Ellipse& target, const ToleranceSettings& t) {
  MechanismTolerance r;
  const ParameterSigmas sigma = parameter_sigmas(t);
  const double per_count = angle_per_count(t.adc_bits);
  r.centre = tolerance_first_order(m, target.center, sigma, per_count);
  r.monte_carlo = tolerance_monte_carlo(m, target.center, sigma, t.samples, t.seed);
  const Eigen::Matrix2d& C = r.monte_carlo.covariance;
  const double mid = 0.5 * (C(0, 0) + C(1, 1));
  r.mc_3sigma_mm = 3.0 * std::sqrt(std::max(0.0, mid + std::hypot(0.5 * (C(0, 0) - C(1, 1)), C(0, 1))));
  for (const Vec2& p : ellipse_grid(target)) {
    ++r.points;
    const ToleranceEstimate e = tolerance_first_order(m, p, sigma, per_count);
    if (e.status != Status::ok) {
      ++r.not_ok;
      continue;
    }
    if (e.ellipse_semi_axes.x() > r.worst_3sigma_mm) {
      r.worst_3sigma_mm = e.ellipse_semi_axes.x();
      r.worst_3sigma_at = p;
    }
    if (e.worst_case_mm > r.worst_case_mm) {
      r.worst_case_mm = e.worst_case_mm;
      r.worst_case_at = p;
    }
    r.worst_resolution_um = std::max(r.worst_resolution_um, e.resolution_um);
  }
  return r;
}

Json to_json(const MechanismTolerance& r) {
  Json j;
  j["centre_status"] = std::string(to_string(r.centre.status));
  j["centre_3sigma_mm"] = r.centre.ellipse_semi_axes.x();
  j["centre_3sigma_minor_mm"] = r.centre.ellipse_semi_axes.y();
  j["centre_3sigma_angle_deg"] = angle_deg(r.centre.ellipse_angle);
  j["centre_worst_case_mm"] = r.centre.worst_case_mm;
  j["centre_resolution_um"] = r.centre.resolution_um;
  j["centre_monte_carlo_3sigma_mm"] = r.mc_3sigma_mm;
  j["monte_carlo_samples_used"] = r.monte_carlo.used;
  j["monte_carlo_samples_failed"] = r.monte_carlo.failed;
  j["target_points"] = r.points;
  j["target_points_not_ok"] = r.not_ok;
  j["target_worst_3sigma_mm"] = r.worst_3sigma_mm;
  j["target_worst_3sigma_at_mm"] = point_json(r.worst_3sigma_at);
  j["target_worst_case_mm"] = r.worst_case_mm;
  j["target_worst_case_at_mm"] = point_json(r.worst_case_at);
  j["target_worst_resolution_um"] = r.worst_resolution_um;
  return j;
}

int run_tolerance(const ToleranceCliOptions& opt) {
  const Design design = load(opt.design);
  const auto stations = design.select_stations(opt.station);
  if (stations.empty()) throw InputError("design '" + design.name + "' has no station with a mechanism");
  const ToleranceSettings* given = design.get<ToleranceSettings>();
  const ToleranceSettings t = given ? *given : ToleranceSettings{};
  const ParameterSigmas sigma = parameter_sigmas(t);
  const auto progress = terminal_progress("tolerance");

  Json doc = {{"command", "tolerance"}, {"design", design.name}};
  doc["tolerance"] = {{"source", given ? "design" : "defaults (assumptions)"},
                      {"link_length_sigma_mm", sigma[0]},
                      {"base_sigma_mm", sigma[4]},
                      {"angle_sigma_deg", t.angle_sigma_deg},
                      {"adc_bits", t.adc_bits},
                      {"samples", t.samples},
                      {"seed", t.seed}};
  doc["stations"] = Json::array();
  if (!opt.json) {
    std::cout << "tolerances " << (given ? "from the design" : "by default (assumptions to replace)")
              << ": link length sigma " << fixed(sigma[0], 4) << " mm, base " << fixed(sigma[4], 4)
              << " mm per axis, joint angle " << fixed(t.angle_sigma_deg, 3) << " deg, " << t.adc_bits
              << "-bit counts per turn; Monte Carlo " << t.samples << " devices, seed " << t.seed << "\n";
  }
  for (const Station* s : stations) {
    if (progress) progress("station " + s->name);
    Json js = {{"station", s->name}, {"mechanisms", Json::array()}};
    if (!opt.json) std::cout << "station " << s->name << "\n";
    for (const Mechanism* m : s->mechanisms()) {
      const MechanismTolerance r = analyse(*m, s->target, t);
      Json jm = {{"mechanism", m->name}};
      jm.update(to_json(r));
      js["mechanisms"].push_back(std::move(jm));
      if (opt.json) continue;
      std::cout << "  " << m->name << ": at the centre " << point(s->target.center) << ": ";
      if (r.centre.status != Status::ok) {
        std::cout << to_string(r.centre.status) << " (no first-order estimate)\n";
      } else {
        std::cout << "3-sigma " << fixed(r.centre.ellipse_semi_axes.x(), 4) << " mm (Monte Carlo "
                  << fixed(r.mc_3sigma_mm, 4) << " mm), worst case " << fixed(r.centre.worst_case_mm, 4)
                  << " mm, resolution " << fixed(r.centre.resolution_um, 3) << " um per count\n";
      }
      std::cout << "    over the target (" << r.points << " points): 3-sigma up to " << fixed(r.worst_3sigma_mm, 4)
                << " mm at " << point(r.worst_3sigma_at) << ", worst case up to " << fixed(r.worst_case_mm, 4)
                << " mm at " << point(r.worst_case_at) << ", resolution up to " << fixed(r.worst_resolution_um, 3)
                << " um per count";
      if (r.not_ok > 0) std::cout << "; " << r.not_ok << " points unreachable or singular (no estimate)";
      std::cout << "\n";
    }
    doc["stations"].push_back(std::move(js));
  }
  if (opt.json) print_json(doc);
  return kOk;
}

}  // namespace

void setup_tolerance(CLI::App& app) {
  auto opt = std::make_shared<ToleranceCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "tolerance",
      "How far the printed device's tactor can be from where the controller believes it is: 3-sigma and "
      "worst-case error (mm) and resolution per ADC count at the target centre and over the target ellipse");
  add_design_argument(*sub, opt->design);
  sub->add_option("-s,--station", opt->station, "Only this station (default: every station)")->type_name("NAME");
  sub->add_flag("--json", opt->json,
                "Print {\"tolerance\": {...}, \"stations\": {S: {\"lower\": ..., \"upper\": ...}}} on stdout and "
                "nothing else");
  sub->footer(
      "Tolerances come from the design's tolerance: section (docs/design-file.md), else from its defaults, which are "
      "assumptions.\nExit status: 0 success, 2 bad input, 3 internal error.");
  sub->callback([opt]() { finish(run_tolerance(*opt)); });
}

}  // namespace fivebar::cli
