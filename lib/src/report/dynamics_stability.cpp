// `fivebar report stability`, the dynamic cases (fivebar/report/stability.hpp): the simulation
// (fivebar/dynamics.hpp) at the extremes of its stiffness, friction and current, and along a
// reference that grazes the workspace boundary. Each must finish with finite numbers and a status.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "fivebar/dynamics.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/report.hpp"

namespace fivebar {

namespace {

bool all_finite(const SimulationResult& r) {
  const auto ok = [](double v) { return std::isfinite(v); };
  for (const TimeSample& t : r.samples) {
    for (const MechanismSample& m : t.mechanisms) {
      for (std::size_t j = 0; j < 2; ++j) {
        if (!ok(m.theta[j]) || !ok(m.w[j]) || !ok(m.current[j]) || !ok(m.duty[j]) || !ok(m.voltage[j])) return false;
      }
      if (!ok(m.P_mm.x()) || !ok(m.P_mm.y()) || !ok(m.force_N.x()) || !ok(m.force_N.y()) || !ok(m.energy_J)) return false;
    }
  }
  for (const MechanismSummary& s : r.summary) {
    if (!ok(s.max_error_mm) || !ok(s.rms_error_mm) || !ok(s.peak_current_A) || !ok(s.rms_current_A) ||
        !ok(s.peak_shear_N) || !ok(s.saturation_s)) {
      return false;
    }
  }
  return ok(r.t_end) && ok(r.wall_s);
}

/// The lower tactor's reference ramped at 10 mm/s from its step start to within 1e-6 of the length
/// scale of the nearest IK-reachable boundary (a stretched or folded leg: type I), held 0.2 s; the
/// upper mechanism is left out. Empty `why` on success.
SimulationInput grazing_input(const SimulationInput& step, std::string& why) {
  SimulationInput in = step;
  in.reference_name = "grazing the workspace boundary";
  in.mechanisms.resize(1);
  SimulatedMechanism& sm = in.mechanisms[0];
  const Mechanism& m = sm.model.mechanism;
  const Vec2 start = sm.reference_point_mm.front();
  const double scale = m.length_scale();
  const auto reachable = [&](const Vec2& p) { return ik_angles(m, p).status == Status::ok; };
  if (!reachable(start)) {
    why = "the step's start is not reachable";
    return in;
  }
  // The nearest boundary along eight directions, marched at 1 % of the scale, then bisected.
  Vec2 dir(0.0, -1.0);
  double lo = 0.0, hi = 0.0;
  for (int d = 0; d < 8; ++d) {
    const Vec2 u(std::cos(d * std::numbers::pi / 4), std::sin(d * std::numbers::pi / 4));
    double a = 0.0;
    for (double t = 0.01 * scale; t <= 4.0 * scale && (hi == 0.0 || t < hi); t += 0.01 * scale) {
      if (!reachable(start + t * u)) {
        dir = u;
        lo = a;
        hi = t;
        break;
      }
      a = t;
    }
  }
  if (hi == 0.0) {
    why = "no boundary within 4 length scales of the start";
    return in;
  }
  for (int k = 0; k < 80 && hi - lo > 1e-9 * scale; ++k) {
    const double mid = 0.5 * (lo + hi);
    (reachable(start + mid * dir) ? lo : hi) = mid;
  }
  const double reach = std::max(0.0, lo - 1e-6 * scale);
  const double rate = in.controller.loop_rate_hz;
  // At 10 mm/s (the patterns' speeds are a few mm/s), at least 0.3 s.
  const auto ramp = static_cast<std::size_t>(std::round(std::max(0.3, reach / 10.0) * rate));
  const auto hold = static_cast<std::size_t>(std::round(0.2 * rate));
  sm.reference.clear();
  sm.reference_point_mm.clear();
  std::array<double, 2> previous{0.0, 0.0};
  for (std::size_t s = 0; s <= ramp + hold; ++s) {
    const double f = std::min(1.0, double(s) / double(ramp));
    const Vec2 p = start + f * reach * dir;
    const AnglesResult a = ik_angles(m, p);
    if (a.status != Status::ok) {
      why = "the ramp's point at t = " + format::fixed(double(s) / rate, 3) + " s is " + std::string(to_string(a.status));
      return in;
    }
    std::array<double, 2> th{a.theta1, a.theta2};
    if (s > 0) {
      for (std::size_t j = 0; j < 2; ++j) th[j] = previous[j] + std::remainder(th[j] - previous[j], 2.0 * std::numbers::pi);
    }
    previous = th;
    sm.reference.push_back(th);
    sm.reference_point_mm.push_back(p);
  }
  sm.theta0 = sm.reference.front();
  return in;
}

}  // namespace

std::vector<StabilityCase> dynamics_stability_cases(const Design& design, const Station& station) {
  std::vector<StabilityCase> out;
  if (!station.lower || !station.upper) return out;
  std::vector<SimulationInput> inputs;
  try {
    SimulationRequest request;
    request.station = station.name;
    request.step = true;
    inputs = simulation_inputs(design, request, station_inertia(design, station, nullptr, {}));
  } catch (const InputError&) {
    return out;  // no motor: or controller: section: nothing to simulate
  }
  if (inputs.empty() || !inputs.front().unusable.empty()) return out;
  const SimulationInput& step = inputs.front();

  struct Variant {
    std::string name;
    double parameter;
    SimulationInput input;
    std::string expected = "ok";
    std::string problem;  ///< the input could not be built
    bool wants_saturation = false;
  };
  std::vector<Variant> variants;
  {  // S = T_loop R / L = 1e8: the showcase's L / 1e6 (L/R = 0.1 ns).
    Variant v{"stiffness ratio 1e8 (L/R = 1e-10 s), 1 mm step", 1e8, step, "ok", "", false};
    for (SimulatedMechanism& m : v.input.mechanisms)
      for (MotorParams& mp : m.model.motors) mp.inductance_mH *= 1e-6;
    variants.push_back(std::move(v));
  }
  {
    Variant v{"skin shear stiffness x 1000, 1 mm step", 1e3, step, "ok", "", false};
    v.input.contact.shear_stiffness_N_per_mm *= 1e3;
    variants.push_back(std::move(v));
  }
  {
    Variant v{"ramp to 1e-6 x scale off the workspace boundary", 1e-6, step, "ok", "", false};
    v.input = grazing_input(step, v.problem);
    v.expected = "ok|singular";
    variants.push_back(std::move(v));
  }
  {
    Variant v{"zero friction (motors and skin), 1 mm step", 0.0, step, "ok", "", false};
    for (SimulatedMechanism& m : v.input.mechanisms) {
      for (MotorParams& mp : m.model.motors) mp.viscous_friction_mNm_s_per_rad = mp.coulomb_friction_mNm = 0.0;
    }
    v.input.contact.friction_coefficient = 0.0;
    variants.push_back(std::move(v));
  }
  {
    Variant v{"current limit 0.02 A hit, 1 mm step", 0.02, step, "ok", "", true};
    for (SimulatedMechanism& m : v.input.mechanisms)
      for (MotorParams& mp : m.model.motors) mp.current_limit_A = 0.02;
    variants.push_back(std::move(v));
  }

  for (Variant& v : variants) {
    StabilityCase c;
    c.mechanism = station.name;
    c.group = "dynamics";
    c.name = v.name;
    c.operation = "simulate";
    c.parameter = v.parameter;
    c.expected = v.expected;
    c.conditioning = 1.0;
    if (!v.problem.empty()) {
      c.status = "not constructible";
      c.passed = true;
      c.explanation = v.problem;
      out.push_back(std::move(c));
      continue;
    }
    SimulationOptions o;
    o.max_wall_s = 30.0;
    o.max_steps = 2'000'000;
    const SimulationResult r = simulate(v.input, o);
    c.status = std::string(to_string(r.status));
    c.finite = all_finite(r);
    double saturation = 0.0, peak_current = 0.0, error = 0.0, shear = 0.0;
    for (const MechanismSummary& s : r.summary) {
      saturation = std::max(saturation, s.saturation_s);
      peak_current = std::max(peak_current, s.peak_current_A);
      error = std::max(error, s.max_error_mm);
      shear = std::max(shear, s.peak_shear_N);
    }
    const bool status_ok = v.expected.find(c.status) != std::string::npos;
    c.passed = c.finite && status_ok && (!v.wants_saturation || saturation > 0.0);
    std::ostringstream e;
    e << format::fixed(r.t_end, 3) << " s simulated in " << r.steps << " steps (" << format::fixed(r.wall_s, 3)
      << " s); tracking error max " << format::fixed(error, 4) << " mm, peak current " << format::fixed(peak_current, 4)
      << " A, saturated " << format::fixed(saturation, 3) << " s, peak shear " << format::fixed(shear, 3) << " N";
    if (!r.ok()) e << "; " << r.reason;
    if (!c.finite) e << "; a non-finite number in the results";
    if (v.wants_saturation && saturation == 0.0) e << "; the limit was never reached";
    c.explanation = e.str();
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace fivebar
