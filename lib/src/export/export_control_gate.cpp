// The loop checks of the export gate (lib/src/export/export_control_gate.hpp): stability over every target
// (fivebar/control.hpp) and the simulated patterns' tracking error and saturation
// (fivebar/dynamics.hpp).

#include "export/export_control_gate.hpp"
#include "fivebar/format.hpp"

#include <algorithm>
#include <cstdio>
#include <map>

#include "fivebar/control.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/motor.hpp"

namespace fivebar::detail {

namespace {

// Fixed point without a sign on zero ("-0.00" never appears in a message): fivebar/format.hpp.
using format::fixed;

std::string point(const Vec2& p) { return "(" + fixed(p.x(), 2) + ", " + fixed(p.y(), 2) + ") mm"; }

/// Grid per axis over a target for the gate's map: ~310 poses, every 0.5 mm on the paper's ellipse.
constexpr int kGateGrid = kControlGateGrid;  // the tuner constrains rho on the same grid
/// Grid per axis for the bandwidth carried in the files (~70 poses).
constexpr int kGatePerformanceGrid = 9;
/// CVODE tolerance of the gate's simulations: measured on the paper's device, its tracking errors
/// are those at the default 1e-6 to 1 um, in half the time.
constexpr double kGateRtol = 1e-4;

}  // namespace

ControlGate control_gate(const Design& d, const std::vector<std::string>& stations,
                         const std::function<void(std::string_view)>& progress) {
  ControlGate out;
  if (!d.get<Geometry>() || !d.get<MotorSettings>() || !d.get<ControllerSettings>()) return out;
  const ControllerSettings& c = *d.get<ControllerSettings>();
  const auto say = [&](const std::string& s) {
    if (progress) progress(s);
  };
  const auto add = [&out](std::string kind, std::string subject, bool passed, std::string detail) {
    out.checks.push_back(GateCheck{std::move(kind), std::move(subject), passed, std::move(detail)});
  };
  StabilityOptions so;
  so.grid = kGateGrid;
  for (const std::string& name : stations) {
    const Station& s = *d.station(name);
    if (s.mechanisms().empty()) continue;
    const auto inertia = station_inertia(d, s, nullptr, {});
    say("export gate: loop stability of station " + name);
    const std::vector<Vec2> points = ellipse_lattice(s.target, so.grid);
    for (const LoopModel& loop : loop_models(d, s, inertia)) {
      const StabilityMap m = stability_map(loop, points, so);
      const std::string subject = name + "/" + m.mechanism;
      const Vec2 w = m.worst_P_mm();
      const std::size_t ok = m.poses.size() - m.not_ok;
      std::string detail;
      if (ok == 0) {
        detail = "no pose of the target is reachable and regular: the loop cannot be checked";
      } else {
        detail = std::string(m.stable ? "stable" : "UNSTABLE") + ": max spectral radius " + fixed(m.max_rho, 4) +
                 (m.stable ? " < 1" : " >= 1") + " at " + point(w) + " over " + std::to_string(ok) +
                 " poses of the target; margins kp x" + fixed(m.kp_margin, 2) + ", kd x" + fixed(m.kd_margin, 2) +
                 "; least-damped oscillation zeta " + fixed(m.oscillatory_damping, 3) + " at " +
                 fixed(m.oscillatory_frequency_hz, 2) + " Hz";
      }
      add("stability", subject, m.stable, detail);
      Json& f = out.figures[name][m.mechanism];
      f["max_rho"] = m.max_rho;
      f["kp_margin"] = m.kp_margin;
      f["kd_margin"] = m.kd_margin;
      f["worst_pose_m"] = Json::array({1e-3 * w.x(), 1e-3 * w.y()});
      f["oscillatory_damping"] = m.oscillatory_damping;
      f["oscillatory_frequency_hz"] = m.oscillatory_frequency_hz;
      const PerformanceMap perf = performance_map(d, loop, ellipse_lattice(s.target, kGatePerformanceGrid));
      f["min_bandwidth_hz"] = perf.worst_bandwidth.bandwidth_hz;
    }
    if (!(s.lower && s.upper)) continue;  // patterns move both tactors
    SimulationRequest request;
    request.station = name;
    SimulationOptions sim;
    sim.rtol = kGateRtol;
    sim.record = false;
    std::map<std::string, double> worst_error, worst_saturation;
    for (const SimulationInput& in : simulation_inputs(d, request, inertia)) {
      const std::string subject = name + " " + in.reference_name;
      if (!in.unusable.empty()) {
        add("tracking", subject, false, "not simulated: " + in.unusable);
        continue;
      }
      say("export gate: simulating " + subject);
      const SimulationResult r = simulate(in, sim);
      if (!r.ok()) {
        add("tracking", subject, false,
            "the simulation did not finish (" + std::string(to_string(r.status)) + "): " + r.reason);
        continue;
      }
      std::string tracking, saturation, tracking_bad, saturation_bad;
      for (const MechanismSummary& m : r.summary) {
        const double fraction = r.t_end > 0.0 ? m.saturation_s / r.t_end : 0.0;
        worst_error[m.name] = std::max(worst_error[m.name], m.max_error_mm);
        worst_saturation[m.name] = std::max(worst_saturation[m.name], fraction);
        tracking += (tracking.empty() ? "" : ", ") + m.name + " " + fixed(m.max_error_mm, 3) + " mm";
        saturation += (saturation.empty() ? "" : ", ") + m.name + " " + fixed(100.0 * fraction, 1) + " %";
        if (m.max_error_mm > c.max_tracking_error_mm) {
          tracking_bad += (tracking_bad.empty() ? "" : "; ") + m.name + " max tracking error " +
                          fixed(m.max_error_mm, 3) + " mm > " + fixed(c.max_tracking_error_mm, 3) + " mm";
        }
        if (fraction > c.max_saturation_fraction) {
          saturation_bad += (saturation_bad.empty() ? "" : "; ") + m.name + " saturated " +
                            fixed(100.0 * fraction, 1) + " % of " + fixed(r.t_end, 2) + " s > " +
                            fixed(100.0 * c.max_saturation_fraction, 1) + " %";
        }
      }
      add("tracking", subject, tracking_bad.empty(),
          tracking_bad.empty() ? "max tracking error " + tracking + " (controller.max_tracking_error_mm " +
                                     fixed(c.max_tracking_error_mm, 3) + " mm)"
                               : tracking_bad + " (controller.max_tracking_error_mm)");
      add("saturation", subject, saturation_bad.empty(),
          saturation_bad.empty() ? "time saturated " + saturation + " (controller.max_saturation_fraction " +
                                       fixed(100.0 * c.max_saturation_fraction, 1) + " %)"
                                 : saturation_bad + " (controller.max_saturation_fraction)");
    }
    for (const auto& [mech, e] : worst_error) {
      out.figures[name][mech]["max_tracking_error_m"] = 1e-3 * e;
      out.figures[name][mech]["max_saturation_fraction"] = worst_saturation[mech];
    }
  }
  return out;
}

}  // namespace fivebar::detail
