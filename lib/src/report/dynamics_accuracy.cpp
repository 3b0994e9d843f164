// `fivebar report accuracy`, the dynamics part: work-precision of CVODE BDF against ARKODE's
// explicit Runge-Kutta on the averaged and the switched PWM model, and their step counts as the
// motors' inductance shrinks (fivebar/report/accuracy.hpp DynamicsAccuracy).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <numbers>

#include "fivebar/dynamics.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/report.hpp"

namespace fivebar {

namespace {

using Clock = std::chrono::steady_clock;

/// The showcase's stiffness ratio moves by scaling every motor's inductance.
SimulationInput with_inductance_scale(const SimulationInput& in, double scale) {
  SimulationInput out = in;
  for (SimulatedMechanism& m : out.mechanisms)
    for (MotorParams& mp : m.model.motors) mp.inductance_mH *= scale;
  return out;
}

/// S = T_loop R / L of the first motor.
double stiffness_ratio(const SimulationInput& in) {
  const MotorParams& mp = in.mechanisms.front().model.motors.front();
  return mp.resistance() / mp.inductance() / in.controller.loop_rate_hz;
}

double max_error_mm(const SimulationResult& run, const SimulationResult& reference) {
  double e = 0.0;
  const std::size_t n = std::min(run.samples.size(), reference.samples.size());
  for (std::size_t s = 0; s < n; ++s) {
    for (std::size_t k = 0; k < run.samples[s].mechanisms.size(); ++k) {
      e = std::max(e, (run.samples[s].mechanisms[k].P_mm - reference.samples[s].mechanisms[k].P_mm).norm());
    }
  }
  return e;
}

/// Wall time of one run: the median of three when a run is short, else the run itself (`runs` = 1:
/// always the run itself, as the quick report times its other series).
SimulationResult timed(const SimulationInput& in, const SimulationOptions& o, double& seconds, int runs) {
  SimulationResult r;
  std::vector<double> times;
  for (int k = 0; k < runs; ++k) {
    const auto t0 = Clock::now();
    r = simulate(in, o);
    times.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    if (times.back() > 0.05) break;
  }
  std::sort(times.begin(), times.end());
  seconds = times[times.size() / 2];
  return r;
}

std::optional<double> fit_slope(const DynamicsSeries& s) {
  std::vector<double> t, e;
  for (const DynamicsPoint& p : s.points) {
    if (p.status != "ok") continue;
    t.push_back(p.time_s);
    e.push_back(p.error_mm);
  }
  return fit_log_slope(t, e, 1e-12);
}

}  // namespace

DynamicsAccuracy dynamics_accuracy(const Design& design, const AccuracyOptions& o) {
  DynamicsAccuracy out;
  out.default_rtol = SimulationOptions{}.rtol;
  const Station* station = nullptr;
  for (const Station* s : design.select_stations(o.station)) {
    if (s->lower && s->upper) {
      station = s;
      break;
    }
  }
  if (station == nullptr) {
    out.skipped = "no station with both mechanisms";
    return out;
  }
  out.station = station->name;
  std::vector<SimulationInput> inputs;
  try {
    SimulationRequest request;
    request.station = station->name;
    request.step = true;
    inputs = simulation_inputs(design, request, station_inertia(design, *station, nullptr, {}));
  } catch (const InputError& e) {
    out.skipped = e.what();
    return out;
  }
  if (inputs.empty() || !inputs.front().unusable.empty()) {
    out.skipped = inputs.empty() ? "no step reference" : inputs.front().unusable;
    return out;
  }
  const SimulationInput& base = inputs.front();
  const double T = 1.0 / base.controller.loop_rate_hz;
  out.duration_s = std::round((o.quick ? 0.05 : 0.1) / T) * T;
  out.scenario = "1 mm step of both tactors (read at t = T, applied at 2T), closed-form masses, ADC off, " +
                 std::to_string(static_cast<int>(std::round(out.duration_s / T))) + " controller periods";
  out.reference_rtol = 1e-12;
  SimulationOptions base_options;
  base_options.quantise = false;
  base_options.duration_s = out.duration_s;
  base_options.max_wall_s = o.quick ? 5.0 : 60.0;

  const std::vector<double> rtols =
      o.quick ? std::vector<double>{1e-3, 1e-5, 1e-7, 1e-9} : std::vector<double>{1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10};
  struct Model {
    PwmModel pwm;
    double inductance_scale;
  };
  // Averaged at the showcase's S = 1e2 and at S = 1e4 (L / 100), switched at S = 1e2.
  const std::vector<Model> models{{PwmModel::averaged, 1.0}, {PwmModel::averaged, 1e-2}, {PwmModel::switched, 1.0}};
  for (const Model& model : models) {
    const SimulationInput in = with_inductance_scale(base, model.inductance_scale);
    SimulationOptions ro = base_options;
    ro.pwm = model.pwm;
    ro.rtol = out.reference_rtol;
    if (o.progress) o.progress("accuracy: dynamics reference (" + std::string(to_string(model.pwm)) + ")");
    const SimulationResult reference = simulate(in, ro);
    for (const Integrator integrator : {Integrator::bdf, Integrator::erk}) {
      DynamicsSeries series;
      series.integrator = std::string(to_string(integrator));
      series.pwm = std::string(to_string(model.pwm));
      series.stiffness_ratio = stiffness_ratio(in);
      for (const double rtol : rtols) {
        SimulationOptions so = base_options;
        so.pwm = model.pwm;
        so.integrator = integrator;
        so.rtol = rtol;
        DynamicsPoint p;
        p.rtol = rtol;
        const SimulationResult r = timed(in, so, p.time_s, o.quick ? 1 : 3);
        p.error_mm = max_error_mm(r, reference);
        p.steps = r.steps;
        p.rhs_evaluations = r.rhs_evaluations;
        p.status = std::string(to_string(r.status));
        if (!reference.ok()) p.status = "reference_" + std::string(to_string(reference.status));
        series.points.push_back(p);
      }
      series.time_slope = fit_slope(series);
      out.series.push_back(std::move(series));
    }
  }

  // Steps per simulated second as L shrinks: S = 1e2 ... 1e8 (quick: 1e2 ... 1e6), default rtol.
  const int top = o.quick ? 6 : 8;
  for (int e = 2; e <= top; ++e) {
    const double scale = std::pow(10.0, 2 - e);
    // Started 1 deg off the reference and without the computation delay, so that the motors work
    // from t = 0: a quiet start (zero duty, nothing excites the winding) lets an explicit method
    // stride beyond its stability bound, and a run cut by the step bound would count only that.
    SimulationInput in = with_inductance_scale(base, scale);
    for (SimulatedMechanism& m : in.mechanisms) m.theta0[0] += format::kRadPerDeg;
    StiffnessPoint sp;
    sp.stiffness_ratio = stiffness_ratio(in);
    sp.l_over_r_s = in.mechanisms.front().model.motors.front().inductance() /
                    in.mechanisms.front().model.motors.front().resistance();
    if (o.progress) o.progress("accuracy: dynamics at stiffness ratio 1e" + std::to_string(e));
    for (std::size_t k = 0; k < 2; ++k) {
      SimulationOptions so = base_options;
      so.integrator = k == 0 ? Integrator::bdf : Integrator::erk;
      so.max_steps = o.quick ? 20'000 : 200'000;
      so.delay = false;
      so.record = false;
      const auto t0 = Clock::now();
      const SimulationResult r = simulate(in, so);
      const double wall = std::chrono::duration<double>(Clock::now() - t0).count();
      const double simulated = r.ok() ? out.duration_s : r.t_end;
      sp.steps_per_s[k] = simulated > 0.0 ? double(r.steps) / simulated : 0.0;
      sp.wall_per_s[k] = simulated > 0.0 ? wall / simulated : 0.0;
      sp.status[k] = std::string(to_string(r.status));
    }
    out.stiffness.push_back(sp);
  }
  for (std::size_t i = 0; i < out.stiffness.size(); ++i) {
    const StiffnessPoint& b = out.stiffness[i];
    const double gap_b = std::log(b.steps_per_s[1]) - std::log(b.steps_per_s[0]);
    if (!(gap_b > 0.0)) continue;
    if (i == 0) {
      out.crossover_ratio = b.stiffness_ratio;
    } else {
      const StiffnessPoint& a = out.stiffness[i - 1];
      const double gap_a = std::log(a.steps_per_s[1]) - std::log(a.steps_per_s[0]);
      const double f = gap_a / (gap_a - gap_b);  // where the log gap crosses zero
      out.crossover_ratio = std::exp(std::log(a.stiffness_ratio) + f * (std::log(b.stiffness_ratio) - std::log(a.stiffness_ratio)));
    }
    break;
  }
  return out;
}

}  // namespace fivebar
