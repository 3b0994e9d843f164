// simulate() (fivebar/dynamics.hpp): the controller's sample loop around a SUNDIALS stepper
// (lib/src/simulate/stepper.hpp: CVODE BDF or ARKODE ERK), restarted at every controller sample,
// at every PWM switching instant of the switched model and at every stick/slip root. Free of
// SUNDIALS itself.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>

#include "simulate/stepper.hpp"
#include "fivebar/format.hpp"
#include "fivebar/numerics.hpp"
#include "fivebar/runtime/controller.hpp"

namespace fivebar {

using dynamics_detail::Evaluation;
using dynamics_detail::kStateSize;
using dynamics_detail::StepOutcome;
using dynamics_detail::Stepper;
using dynamics_detail::System;

namespace {

std::string state_text(const SimulationInput& input, const double* y) {
  std::ostringstream s;
  for (std::size_t k = 0; k < input.mechanisms.size(); ++k) {
    const double* m = y + kStateSize * k;
    s << (k ? "; " : "") << input.mechanisms[k].name << " theta = (" << format::fixed(m[0] * format::kDegPerRad, 4)
      << ", " << format::fixed(m[1] * format::kDegPerRad, 4) << ") deg, w = (" << format::fixed(m[2], 4) << ", "
      << format::fixed(m[3], 4) << ") rad/s, i = (" << format::fixed(m[4], 4) << ", " << format::fixed(m[5], 4) << ") A";
  }
  return s.str();
}

/// Switching instants closer than this fraction of a PWM period are one (a sliver of 1e-9 of a
/// period, 1 ps at 1 kHz, is not integrated).
constexpr double kPwmMergeRel = 1e-9;

/// The times in (a, b) where the switched PWM of any joint changes level, sorted, with a and b at
/// the ends: every PWM period start and every end of an on-phase.
std::vector<double> pwm_cuts(const System& sys, double a, double b, double period) {
  std::vector<double> cuts{a, b};
  const auto first = static_cast<long long>(std::floor(a / period));
  for (long long p = first;; ++p) {
    const double start = double(p) * period;
    if (start >= b) break;
    cuts.push_back(start);
    for (const auto& duty : sys.duty) {
      for (const double d : duty) cuts.push_back(start + std::min(std::abs(d), 1.0) * period);
    }
  }
  std::sort(cuts.begin(), cuts.end());
  const double merge = kPwmMergeRel * period;
  std::vector<double> out{a};
  for (const double c : cuts) {
    if (c <= a + merge || c >= b - merge) continue;
    if (c - out.back() > merge) out.push_back(c);
  }
  out.push_back(b);
  return out;
}

/// The on/off level of every joint over (a, b), a segment between two switching instants.
void set_pwm_levels(System& sys, double a, double b, double period) {
  const double mid = 0.5 * (a + b);
  const double phase = mid - std::floor(mid / period) * period;
  for (std::size_t k = 0; k < sys.duty.size(); ++k) {
    for (std::size_t j = 0; j < 2; ++j) sys.on[k][j] = phase < std::min(std::abs(sys.duty[k][j]), 1.0) * period;
  }
}

}  // namespace

std::string_view to_string(SimStatus status) {
  switch (status) {
    case SimStatus::ok: return "ok";
    case SimStatus::singular: return "singular";
    case SimStatus::step_limit: return "step_limit";
    case SimStatus::wall_time_limit: return "wall_time_limit";
    case SimStatus::solver_failure: return "solver_failure";
  }
  return "?";
}

std::string_view to_string(Integrator integrator) {
  return integrator == Integrator::erk ? "erk" : "bdf";
}

std::optional<Integrator> parse_integrator(std::string_view text) {
  if (text == "bdf") return Integrator::bdf;
  if (text == "erk") return Integrator::erk;
  return std::nullopt;
}

std::string_view to_string(PwmModel pwm) { return pwm == PwmModel::switched ? "switched" : "averaged"; }

std::optional<PwmModel> parse_pwm_model(std::string_view text) {
  if (text == "averaged") return PwmModel::averaged;
  if (text == "switched") return PwmModel::switched;
  return std::nullopt;
}

SimulationResult simulate(const SimulationInput& given, const SimulationOptions& options) {
  // A copy whose mechanisms stay on the FK branch they start on.
  SimulationInput input = given;
  for (SimulatedMechanism& m : input.mechanisms) {
    if (m.model.branch != AssemblyMode::Any) continue;
    const Pose p0 = fk(m.model.mechanism, m.theta0[0], m.theta0[1]);
    if (p0.assembly != 0) m.model.branch = p0.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
  }
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  SimulationResult result;
  if (input.mechanisms.empty()) throw InputError("simulate: no mechanism to simulate");
  std::size_t n_ref = 0;
  for (const SimulatedMechanism& m : input.mechanisms) {
    if (m.reference.empty() || m.reference.size() != m.reference_point_mm.size()) {
      throw InputError("simulate: mechanism " + m.name + " has no reference (or angles and points differ in length)");
    }
    n_ref = std::max(n_ref, m.reference.size());
  }
  if (!(options.rtol > 0.0) || !(options.rtol < 1.0)) throw InputError("simulate: rtol must be in (0, 1)");
  const bool switched = options.pwm == PwmModel::switched && options.drive != Drive::open_circuit;
  if (switched && !(options.pwm_frequency_hz > 0.0 && std::isfinite(options.pwm_frequency_hz))) {
    throw InputError("simulate: the PWM frequency must be > 0");
  }
  if (!(options.dense_dt_s >= 0.0) || !std::isfinite(options.dense_dt_s)) {
    throw InputError("simulate: the dense output spacing must be >= 0");
  }
  const double pwm_period = switched ? 1.0 / options.pwm_frequency_hz : 0.0;
  const ControllerSettings& ctl = input.controller;
  const double T = 1.0 / ctl.loop_rate_hz;
  const double duration = options.duration_s > 0.0 ? options.duration_s : double(n_ref - 1) * T + options.settle_s;
  const auto n_samples = static_cast<std::size_t>(std::floor(duration / T + tol::kSamplePeriodsRel));
  const std::size_t nm = input.mechanisms.size();
  const std::size_t n = kStateSize * nm;

  System sys = dynamics_detail::make_system(input, options);
  std::vector<double> y0(n, 0.0), atol(n, 0.0);
  for (std::size_t k = 0; k < nm; ++k) {
    const SimulatedMechanism& m = input.mechanisms[k];
    double* yk = y0.data() + kStateSize * k;
    yk[0] = m.theta0[0];
    yk[1] = m.theta0[1];
    yk[2] = options.lock_joints ? 0.0 : m.w0[0];
    yk[3] = options.lock_joints ? 0.0 : m.w0[1];
    yk[4] = yk[5] = 0.0;
    const DynamicsTerms t0 = dynamics_terms(m.model, Eigen::Vector2d(yk[0], yk[1]), Eigen::Vector2d::Zero());
    yk[6] = t0.P.x();
    yk[7] = t0.P.y();
    double* ak = atol.data() + kStateSize * k;
    const double r = options.rtol;
    ak[0] = ak[1] = r * options.angle_scale;
    ak[2] = ak[3] = r * options.rate_scale;
    ak[4] = ak[5] = r * options.current_scale;
    ak[6] = ak[7] = r * options.anchor_scale;
    if (t0.status == Status::unreachable || t0.status == Status::singular_type2) {
      result.status = SimStatus::singular;
      result.reason = "t = 0 s: the initial pose of " + m.name + " is " + std::string(to_string(t0.status));
      result.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
      return result;
    }
  }
  const int n_roots = dynamics_detail::root_count(sys);
  const std::unique_ptr<Stepper> stepper = options.integrator == Integrator::erk
                                               ? dynamics_detail::make_erk(sys, n, options.rtol, atol, n_roots)
                                               : dynamics_detail::make_bdf(sys, n, options.rtol, atol, n_roots);
  double* y = stepper->y();
  std::copy(y0.begin(), y0.end(), y);
  const std::string solver_name = options.integrator == Integrator::erk ? "ARKODE" : "CVODE";
  const auto directions = [&] {
    return n_roots > 0 ? dynamics_detail::root_directions(sys) : std::vector<int>{};
  };

  // The device's controller (fivebar/runtime/controller.hpp), configured as exported; the
  // simulated mechanisms' gains and potentiometers override their joints' (a tuner varies them).
  runtime::Config rt_config = input.runtime ? *input.runtime : runtime_config(input);
  std::vector<std::size_t> rt_index(nm, 0);
  {
    std::size_t station_base = 0;
    std::vector<bool> found(nm, false);
    for (const runtime::StationConfig& st : rt_config.stations) {
      for (std::size_t i = 0; i < st.mechanisms.size(); ++i) {
        for (std::size_t k = 0; k < nm; ++k) {
          const bool named = input.runtime ? st.name == input.station && st.mechanisms[i].name == input.mechanisms[k].name
                                           : st.name == input.station + "_" + std::to_string(k);
          if (named && !found[k]) found[k] = true, rt_index[k] = station_base + i;
        }
      }
      station_base += st.mechanisms.size();
    }
    for (std::size_t k = 0; k < nm; ++k) {
      if (!found[k]) throw InputError("simulate: the runtime configuration has no " + input.mechanisms[k].name + " mechanism of station " + input.station);
    }
    std::size_t base = 0;
    for (runtime::StationConfig& st : rt_config.stations) {
      if (!input.override_runtime_joints) break;
      for (runtime::MechanismConfig& mc : st.mechanisms) {
        for (std::size_t k = 0; k < nm; ++k) {
          if (rt_index[k] != base) continue;
          for (std::size_t j = 0; j < 2; ++j) {
            const JointControl& jc = input.mechanisms[k].control[j];
            mc.joints[j].gains = {jc.pid.kp, jc.pid.ki, jc.pid.kd, jc.pid.i_clamp};
            mc.joints[j].volts_at_zero = jc.potentiometer.volts_at_zero;
            mc.joints[j].rad_per_volt = jc.potentiometer.rad_per_volt;
          }
        }
        ++base;
      }
    }
  }
  runtime::Controller controller = [&] {
    try {
      return runtime::Controller(std::move(rt_config));
    } catch (const runtime::ConfigError& e) {
      throw InputError(std::string("simulate: the runtime refuses the configuration: ") + e.what());
    }
  }();
  const runtime::Config& rt = controller.config();
  const runtime::Reading reading_kind = options.quantise ? runtime::Reading::counts : runtime::Reading::radians;
  std::vector<double> readings(controller.joint_count(), 0.0);
  std::vector<double> targets(2 * controller.mechanism_count(), 0.0);
  std::vector<std::array<double, 2>> pending(nm, {0.0, 0.0});
  std::vector<MechanismSummary> summary(nm);
  std::vector<double> sum_err2(nm, 0.0), sum_i2(nm, 0.0);
  std::vector<double> peak_i(nm, 0.0);
  for (std::size_t k = 0; k < nm; ++k) summary[k].name = input.mechanisms[k].name;

  // One mechanism's sample at state `state`, reference sample `s`.
  const auto make_sample = [&](std::size_t k, std::size_t s, const double* state, Evaluation& ev) {
    const SimulatedMechanism& m = input.mechanisms[k];
    ev = dynamics_detail::evaluate(sys, k, state);
    const double* yk = state + kStateSize * k;
    MechanismSample ms;
    const std::size_t r = std::min(s, m.reference.size() - 1);
    ms.theta_ref = m.reference[r];
    ms.theta = {yk[0], yk[1]};
    ms.w = {yk[2], yk[3]};
    ms.current = {yk[4], yk[5]};
    ms.duty = sys.duty[k];
    ms.voltage = ev.voltage;
    ms.P_ref_mm = m.reference_point_mm[r];
    ms.P_mm = ev.terms.P * 1e3;
    ms.force_N = ev.force;
    ms.slipping = sys.slipping[k] != 0;
    ms.energy_J = 0.5 * Eigen::Vector2d(yk[2], yk[3]).dot(ev.terms.M * Eigen::Vector2d(yk[2], yk[3]));
    return ms;
  };
  // Dense output: the next grid time not yet recorded.
  std::size_t next_dense = 0;
  std::vector<double> interp(n, 0.0);
  const auto record_dense = [&](std::size_t s, double t_from, double t_to) {
    if (!(options.dense_dt_s > 0.0)) return;
    for (;; ++next_dense) {
      const double g = double(next_dense) * options.dense_dt_s;
      if (g > t_to * (1.0 + 1e-14) + 1e-15) break;
      const bool at_end = g >= t_to;
      if (g < t_from || at_end || !stepper->interpolate(g, interp.data())) {
        std::copy(y, y + n, interp.data());  // the step's end (or before the first step: the state)
      }
      TimeSample ts;
      ts.t = std::min(g, t_to);
      Evaluation ev;
      for (std::size_t k = 0; k < nm; ++k) ts.mechanisms.push_back(make_sample(k, s, interp.data(), ev));
      result.dense.push_back(std::move(ts));
    }
  };

  double t = 0.0;
  std::size_t recorded = 0;
  for (std::size_t s = 0;; ++s) {
    const double tk = double(s) * T;
    // The controller at t_k: read, compute, and choose what is applied over [t_k, t_k+1).
    for (std::size_t k = 0; k < nm; ++k) {
      const SimulatedMechanism& m = input.mechanisms[k];
      const std::size_t r = std::min(s, m.reference.size() - 1);
      const Vec2& p = m.target_mm.empty() ? m.reference_point_mm[r] : m.target_mm[std::min(s, m.target_mm.size() - 1)];
      const std::size_t q = rt_index[k];
      targets[2 * q] = p.x() / 1000.0;  // mm -> m, as the export converts
      targets[2 * q + 1] = p.y() / 1000.0;
      for (std::size_t j = 0; j < 2; ++j) {
        const double theta = y[kStateSize * k + j];
        const Potentiometer& pot = m.control[j].potentiometer;
        readings[2 * q + j] = options.quantise ? runtime::adc_code(pot.volts_at_zero + theta / pot.rad_per_volt, rt.adc_bits,
                                                                   rt.adc_range_v, rt.volts_per_count)
                                               : theta;
      }
    }
    controller.cycle(readings.data(), reading_kind, targets.data());
    if (options.controller_log) options.controller_log(tk, readings, reading_kind, targets, controller);
    for (std::size_t k = 0; k < nm; ++k) {
      const std::size_t q = rt_index[k];
      const std::array<double, 2> fresh{controller.duties()[2 * q], controller.duties()[2 * q + 1]};
      if (options.drive == Drive::constant_duty) {
        sys.duty[k] = {options.duty, options.duty};
      } else if (options.drive == Drive::open_circuit) {
        sys.duty[k] = {0.0, 0.0};
      } else {
        sys.duty[k] = options.delay ? pending[k] : fresh;
      }
      pending[k] = fresh;
    }
    if (switched) {
      set_pwm_levels(sys, tk, tk + std::min(T, pwm_period) * 1e-3, pwm_period);
      dynamics_detail::reset_limiters(sys, y);
    }
    if (s == 0) record_dense(0, 0.0, 0.0);
    // Record the sample.
    TimeSample sample;
    sample.t = tk;
    for (std::size_t k = 0; k < nm; ++k) {
      Evaluation ev;
      const MechanismSample ms = make_sample(k, s, y, ev);
      MechanismSummary& sum = summary[k];
      const double err = (ms.P_mm - ms.P_ref_mm).norm();
      sum.max_error_mm = std::max(sum.max_error_mm, err);
      sum_err2[k] += err * err;
      for (std::size_t j = 0; j < 2; ++j) {
        sum.max_joint_error_deg = std::max(sum.max_joint_error_deg, std::abs(ms.theta[j] - ms.theta_ref[j]) * format::kDegPerRad);
        sum.peak_duty = std::max(sum.peak_duty, std::abs(ms.duty[j]));
        sum_i2[k] += ms.current[j] * ms.current[j];
      }
      if (s < n_samples && (ev.saturated[0] || ev.saturated[1])) sum.saturation_s += T;
      sum.peak_shear_N = std::max(sum.peak_shear_N, ms.force_N.norm());
      if (options.record) sample.mechanisms.push_back(ms);
    }
    ++recorded;
    if (options.record) result.samples.push_back(std::move(sample));
    if (s == n_samples) break;

    // Integrate to the next sample over the segments between switching instants (the sample alone
    // when averaged), each a restart with its end a stop time.
    const double t_next = double(s + 1) * T;
    const std::vector<double> cuts = switched ? pwm_cuts(sys, tk, t_next, pwm_period) : std::vector<double>{tk, t_next};
    t = tk;
    for (std::size_t c = 0; c + 1 < cuts.size() && result.status == SimStatus::ok; ++c) {
      const double t_end = cuts[c + 1];
      if (switched) {
        set_pwm_levels(sys, cuts[c], t_end, pwm_period);
        dynamics_detail::reset_limiters(sys, y);
      }
      stepper->restart(cuts[c], t_end, directions());
      ++result.restarts;
      t = cuts[c];
      while (t < t_end) {
        sys.last_failure_singular = false;
        const double t_prev = t;
        const StepOutcome outcome = stepper->step(t_end, t);
        ++result.steps;
        if (outcome == StepOutcome::ok || outcome == StepOutcome::root) record_dense(s, t_prev, t);
        if (outcome == StepOutcome::root) {
          std::vector<int> found;
          stepper->root_info(found);
          for (std::size_t r = 0; r < found.size(); ++r) {
            if (found[r] == 0) continue;
            const dynamics_detail::RootOwner owner = dynamics_detail::root_owner(sys, r);
            const std::size_t k = owner.k;
            if (owner.joint >= 0) {
              sys.limiting[k][static_cast<std::size_t>(owner.joint)] = true;
              continue;
            }
            sys.slipping[k] = !sys.slipping[k];
            if (sys.slipping[k]) {
              summary[k].slipped = true;
              ++summary[k].slips;
            }
          }
          if (t < t_end) {
            stepper->restart(t, t_end, directions());
            ++result.restarts;
          }
        } else if (outcome == StepOutcome::rhs_failure || outcome == StepOutcome::failure) {
          result.status = sys.last_failure_singular || outcome == StepOutcome::rhs_failure ? SimStatus::singular
                                                                                           : SimStatus::solver_failure;
          result.reason = "t = " + format::fixed(t, 6) + " s: " + state_text(input, y) + ": " +
                          (result.status == SimStatus::singular
                               ? "a pose reached a type II singularity or left the workspace; " + solver_name + ": "
                               : solver_name + ": ") +
                          stepper->message();
          break;
        }
        for (std::size_t k = 0; k < nm; ++k) {
          for (std::size_t j = 0; j < 2; ++j) peak_i[k] = std::max(peak_i[k], std::abs(y[kStateSize * k + 4 + j]));
        }
        if (result.steps > options.max_steps) {
          result.status = SimStatus::step_limit;
          result.reason = "t = " + format::fixed(t, 6) + " s: more than " + std::to_string(options.max_steps) +
                          " integrator steps (" + state_text(input, y) + ")";
          break;
        }
        if (std::chrono::duration<double>(Clock::now() - start).count() > options.max_wall_s) {
          result.status = SimStatus::wall_time_limit;
          result.reason = "t = " + format::fixed(t, 6) + " s: more than " + format::fixed(options.max_wall_s, 1) +
                          " s of wall time (" + state_text(input, y) + ")";
          break;
        }
      }
    }
    if (result.status != SimStatus::ok) break;
  }
  result.rhs_evaluations = sys.evaluations;
  result.t_end = result.status == SimStatus::ok ? double(n_samples) * T : t;
  for (std::size_t k = 0; k < nm; ++k) {
    summary[k].rms_error_mm = std::sqrt(sum_err2[k] / double(recorded));
    summary[k].rms_current_A = std::sqrt(sum_i2[k] / double(2 * recorded));
    summary[k].peak_current_A = peak_i[k];
  }
  result.summary = std::move(summary);
  result.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

}  // namespace fivebar
