// Gains per mechanism by NLopt's COBYLA (fivebar/control.hpp "Tuning"); the only file that sees NLopt.

#include <nlopt.hpp>

#include <algorithm>
#include <chrono>
#include <exception>
#include <optional>
#include <cmath>
#include <cstdio>
#include <atomic>
#include <limits>
#include <mutex>
#include <numbers>
#include <thread>

#include <Eigen/Dense>

#include "fivebar/control.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"

namespace fivebar {

namespace {

/// Worst tracking error (mm) and saturated fraction of one mechanism over its pattern runs.
struct Tracking {
  double error_mm = 0.0;
  double saturation = 0.0;
  bool ok = true;
  bool out_of_time = false;  ///< the tuning's wall-time bound passed: not measured in full
  double simulated_s = 0.0;  ///< seconds of the patterns simulated (of patterns_seconds())
};

using Clock = std::chrono::steady_clock;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double seconds_left(Clock::time_point deadline) { return std::chrono::duration<double>(deadline - Clock::now()).count(); }

/// The simulated length of the runs (s): each reference's length plus the settling time, as
/// simulate() runs them (lib/src/simulate/simulate.cpp).
double patterns_seconds(const std::vector<SimulationInput>& runs) {
  const SimulationOptions o;
  double total = 0.0;
  for (const SimulationInput& in : runs) {
    if (in.mechanisms.empty() || in.mechanisms[0].reference.empty()) continue;
    total += double(in.mechanisms[0].reference.size() - 1) / in.controller.loop_rate_hz + o.settle_s;
  }
  return total;
}

/// The tuning's time bound (TuneOptions::max_seconds) is checked inside the loops (docs/reliability.md
/// "Resource bounds"): before every run, and each run is itself cut at the bound, so the tuning
/// ends at most one simulation step past it. A run cut there leaves out_of_time set and
/// simulated_s short of the patterns' length.
Tracking track(const std::vector<SimulationInput>& runs, const std::array<PidGains, 2>& gains, double rtol,
               Clock::time_point deadline) {
  Tracking t;
  SimulationOptions o;
  o.rtol = rtol;
  o.record = false;
  for (SimulationInput in : runs) {
    const double left = seconds_left(deadline);
    if (left <= 0.0) {
      t.ok = false;
      t.out_of_time = true;
      return t;
    }
    o.max_wall_s = std::min(10.0, left);
    in.mechanisms[0].control[0].pid = gains[0];
    in.mechanisms[0].control[1].pid = gains[1];
    const SimulationResult r = simulate(in, o);
    t.simulated_s += r.t_end;
    if (r.status == SimStatus::wall_time_limit && Clock::now() >= deadline) {
      t.ok = false;
      t.out_of_time = true;
      return t;
    }
    if (!r.ok() || r.summary.empty()) {
      t.ok = false;
      return t;
    }
    t.error_mm = std::max(t.error_mm, r.summary[0].max_error_mm);
    t.saturation = std::max(t.saturation, r.t_end > 0.0 ? r.summary[0].saturation_s / r.t_end : 0.0);
  }
  return t;
}

/// The figures of the linear loop over the constraint's grid that the constraints read.
struct Linear {
  double rho = 0.0;           ///< max spectral radius
  double damping = 1.0;       ///< least oscillatory damping ratio
  double damping_hz = 0.0;
  double rho_kp = 0.0, rho_kd = 0.0;  ///< max rho with kp (kd) times the margin floor
};

Linear linear_figures(const std::vector<PoseLoop>& poses, const std::array<PidGains, 2>& gains, bool delay,
                      double margin) {
  Linear l;
  for (const PoseLoop& p : poses) {
    if (p.status != Status::ok) continue;
    const LoopPoles poles = loop_poles(closed_loop(p.plant, gains, delay), p.plant.period_s);
    l.rho = std::max(l.rho, poles.rho);
    if (poles.oscillatory_damping < l.damping) {
      l.damping = poles.oscillatory_damping;
      l.damping_hz = poles.oscillatory_frequency_hz;
    }
  }
  std::array<PidGains, 2> g = gains;
  for (PidGains& x : g) x.kp *= margin;
  l.rho_kp = max_spectral_radius(poses, g, delay, 1.0);
  g = gains;
  for (PidGains& x : g) x.kd *= margin;
  l.rho_kd = max_spectral_radius(poses, g, delay, 1.0);
  return l;
}

/// Largest overshoot (mm) of the tactor past the step's final reference, along the step (+x); inf
/// for a run that failed, NaN when the time bound cut it (not measured).
double step_overshoot(SimulationInput step, const std::array<PidGains, 2>& gains, double rtol, Clock::time_point deadline) {
  step.mechanisms[0].control[0].pid = gains[0];
  step.mechanisms[0].control[1].pid = gains[1];
  SimulationOptions o;
  o.rtol = rtol;
  const double left = seconds_left(deadline);
  if (left <= 0.0) return kNaN;
  o.max_wall_s = std::min(10.0, left);
  const SimulationResult r = simulate(step, o);
  if (r.status == SimStatus::wall_time_limit && Clock::now() >= deadline) return kNaN;
  if (!r.ok() || r.samples.empty()) return std::numeric_limits<double>::infinity();
  const double end = r.samples.back().mechanisms[0].P_ref_mm.x();
  double over = 0.0;
  for (const TimeSample& t : r.samples) over = std::max(over, t.mechanisms[0].P_mm.x() - end);
  return over;
}

/// The chirp with these gains: -3 dB bandwidth, saturation onset (instantaneous frequency of the
/// first sample with a duty at its limit; inf when none), and the smaller, as TunedMechanism says.
struct ChirpFigures {
  double bandwidth_hz = 0.0, saturation_hz = std::numeric_limits<double>::infinity(), reported_hz = 0.0;
};
/// All three NaN when the time bound cut the run (not measured).
ChirpFigures chirp_figures(SimulationInput chirp, const SimulationRequest& request, const std::array<PidGains, 2>& gains,
                           double rtol, Clock::time_point deadline) {
  ChirpFigures c;
  chirp.mechanisms[0].control[0].pid = gains[0];
  chirp.mechanisms[0].control[1].pid = gains[1];
  SimulationOptions o;
  o.rtol = rtol;
  const double left = seconds_left(deadline);
  if (left <= 0.0) return {kNaN, kNaN, kNaN};
  o.max_wall_s = std::min(20.0, left);
  const SimulationResult r = simulate(chirp, o);
  if (r.status == SimStatus::wall_time_limit && Clock::now() >= deadline) return {kNaN, kNaN, kNaN};
  const double rate = chirp.controller.loop_rate_hz;
  const double f0 = request.chirp_f0_hz, f1 = request.chirp_f1_hz > 0.0 ? request.chirp_f1_hz : 0.25 * rate;
  const double D = request.chirp_duration_s;
  if (!r.ok() || r.samples.empty()) {
    c.saturation_hz = 0.0;
    return c;
  }
  const BodeResult bode = chirp_bode(chirp, r, request);
  c.bandwidth_hz = !bode.bandwidth_hz.empty() && bode.bandwidth_hz[0] ? *bode.bandwidth_hz[0] : f1;
  for (const TimeSample& t : r.samples) {
    const auto& d = t.mechanisms[0].duty;
    if (std::max(std::abs(d[0]), std::abs(d[1])) >= 1.0 - 1e-12) {
      c.saturation_hz = f0 * std::pow(f1 / f0, std::min(t.t, D) / D);
      break;
    }
  }
  c.reported_hz = std::min(c.bandwidth_hz, c.saturation_hz);
  return c;
}

constexpr double kFloor = 1e-3;        // a zero gain starts here (ln 0 is not a start)
constexpr double kSaturationPenaltyMm = 10.0;
constexpr double kFailedRunMm = 1e3;   // a run that did not finish
constexpr double kRange = 5.0;         // ln of the factor each gain may move by: e^5 ~ 148
constexpr double kRhoSafety = 0.003;   // COBYLA ends within its tolerance of the constraint: aim inside

constexpr double kDampingSafety = 0.005;  // as kRhoSafety, for the damping floor

/// Gains from the unknowns: the natural logarithms of factors on the start's gains, (kp, ki, kd)
/// for both joints or per joint (six). A coordinate 0 keeps that gain of the start exactly; a zero
/// gain of the start moves from kFloor.
std::array<PidGains, 2> with(const std::array<PidGains, 2>& start, const std::vector<double>& x) {
  std::array<PidGains, 2> g = start;
  for (std::size_t j = 0; j < 2; ++j) {
    const std::size_t o = x.size() == 6 ? 3 * j : 0;
    for (std::size_t i = 0; i < 3; ++i) {
      double& v = i == 0 ? g[j].kp : i == 1 ? g[j].ki : g[j].kd;
      if (x[o + i] != 0.0) v = std::max(v, kFloor) * std::exp(x[o + i]);
    }
  }
  return g;
}

/// One candidate's objective, its constraints' figures and what the simulations measured.
struct Evaluation {
  Linear linear;
  Tracking tracking;
  double overshoot_mm = 0.0;  ///< the 1 mm step's overshoot; NaN: not run (the linear floors missed) or cut
  double value = kFailedRunMm;  ///< the objective, mm
  bool admissible = false;    ///< meets every constraint of the search
  bool measured = true;       ///< false: the time bound cut a simulation, the value is not known
};

/// The shared parts of the search (constant during it).
struct Problem {
  const std::vector<SimulationInput>* runs;
  const std::vector<PoseLoop>* poses;
  const SimulationInput* step;  ///< the 1 mm step of this mechanism (nullptr: none)
  std::array<PidGains, 2> base;  ///< the start: the gains at x = 0
  double rho_limit, saturation_limit, rtol;
  bool delay;
  double min_damping, margin, max_overshoot_mm;
  int evaluations = 0;
  std::function<void(std::string_view)> progress;
  std::string label;
  // The best evaluated point that meets the constraints, and its evaluation.
  std::vector<double> best_x;
  double best_value = std::numeric_limits<double>::infinity();
  // The linear figures of the last point asked (NLopt asks the objective and each constraint at
  // the same point in turn).
  std::vector<double> last_x;
  Linear last;
  const Linear& at(const double* x, unsigned n) {
    if (last_x.size() != n || !std::equal(last_x.begin(), last_x.end(), x)) {
      last_x.assign(x, x + n);
      last = linear_figures(*poses, with(base, last_x), delay, margin);
    }
    return last;
  }
  Clock::time_point deadline;  ///< the search's wall-time bound, checked inside every evaluation
  Evaluation best;             ///< the evaluation of best_x, reused rather than simulated again
  /// The evaluation of x = 0 when the start is the design's gains, already made as "before".
  const Evaluation* at_start = nullptr;
};

/// The objective and constraints of `gains`: an unstable loop is not simulated (its value is that of
/// a failed run) unless `track_unstable`; the step only where the linear floors hold.
Evaluation evaluate(const Problem& p, const std::array<PidGains, 2>& g, const Linear& l, Clock::time_point deadline,
                    bool track_unstable = false) {
  Evaluation e;
  e.linear = l;
  e.overshoot_mm = kNaN;
  if (l.rho >= 1.0 && !track_unstable) {
    e.tracking.ok = false;
    return e;
  }
  e.tracking = track(*p.runs, g, p.rtol, deadline);
  if (e.tracking.out_of_time) {
    e.measured = false;
    return e;
  }
  if (l.rho >= 1.0) return e;
  if (e.tracking.ok) e.value = e.tracking.error_mm + kSaturationPenaltyMm * std::max(0.0, e.tracking.saturation - p.saturation_limit);
  const bool linear_ok = l.rho <= p.rho_limit && l.damping >= p.min_damping && l.rho_kp < 1.0 && l.rho_kd < 1.0;
  // The large step (duty saturation, integral clamp) where the linear constraints hold: its
  // overshoot beyond the bound is penalised like saturation (wind-up steers the search away).
  if (e.tracking.ok && linear_ok) {
    e.overshoot_mm = p.step ? step_overshoot(*p.step, g, p.rtol, deadline) : 0.0;
    if (std::isnan(e.overshoot_mm)) {
      e.measured = false;
      return e;
    }
    e.value += kSaturationPenaltyMm * std::max(0.0, e.overshoot_mm - p.max_overshoot_mm);
    e.admissible = e.tracking.saturation <= p.saturation_limit && e.overshoot_mm <= p.max_overshoot_mm;
  }
  return e;
}

double objective(unsigned n, const double* x, double*, void* data) {
  auto& p = *static_cast<Problem*>(data);
  if (Clock::now() >= p.deadline) throw nlopt::forced_stop();
  const std::vector<double> xv(x, x + n);
  const std::array<PidGains, 2> g = with(p.base, xv);
  ++p.evaluations;
  const Linear& l = p.at(x, n);
  const bool start = std::all_of(xv.begin(), xv.end(), [](double v) { return v == 0.0; });
  const Evaluation e = start && p.at_start != nullptr ? *p.at_start : evaluate(p, g, l, p.deadline);
  if (!e.measured) throw nlopt::forced_stop();  // abandoned: not a measurement
  if (e.admissible && e.value < p.best_value) {
    p.best_value = e.value;
    p.best_x = xv;
    p.best = e;
  }
  if (p.progress) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "%s: evaluation %d, kp %.4g ki %.4g kd %.4g: max rho %.4f, least zeta %.3f, objective %.4f mm",
                  p.label.c_str(), p.evaluations, g[0].kp, g[0].ki, g[0].kd, l.rho, l.damping, e.value);
    p.progress(buf);
  }
  return e.value;
}

double rho_constraint(unsigned n, const double* x, double*, void* data) {
  auto& p = *static_cast<Problem*>(data);
  return p.at(x, n).rho - (p.rho_limit - kRhoSafety);
}
double damping_constraint(unsigned n, const double* x, double*, void* data) {
  auto& p = *static_cast<Problem*>(data);
  return (p.min_damping + kDampingSafety) - p.at(x, n).damping;
}
double kp_margin_constraint(unsigned n, const double* x, double*, void* data) {
  auto& p = *static_cast<Problem*>(data);
  return p.at(x, n).rho_kp - (1.0 - kRhoSafety);
}
double kd_margin_constraint(unsigned n, const double* x, double*, void* data) {
  auto& p = *static_cast<Problem*>(data);
  return p.at(x, n).rho_kd - (1.0 - kRhoSafety);
}

std::string stop_text(nlopt::result r) {
  switch (r) {
    case nlopt::MAXEVAL_REACHED: return "evaluation limit";
    case nlopt::MAXTIME_REACHED: return "time limit";
    case nlopt::XTOL_REACHED:
    case nlopt::FTOL_REACHED: return "converged";
    case nlopt::SUCCESS: return "converged";
    default: return "stopped (" + std::to_string(int(r)) + ")";
  }
}

}  // namespace

std::array<PidGains, 2> pole_placement_gains(const LinearPlant& plant, const std::array<MotorParams, 2>& motors,
                                             double omega, bool per_joint, const std::array<PidGains, 2>& base) {
  // The reduced model of each joint (fivebar/control.hpp "Tuning"): K_s and C_s from the plant's
  // rows (M dw/dt = -K_s dtheta - (C_s + B_v) w + K_t i), the motor from its data.
  const Eigen::Matrix2d K = -plant.M * plant.A.block<2, 2>(2, 0);
  const Eigen::Matrix2d C = -plant.M * plant.A.block<2, 2>(2, 2);  // C_s + B_v
  std::array<double, 2> m{}, c{}, k{}, b{};
  for (std::size_t j = 0; j < 2; ++j) {
    const MotorParams& mp = motors[j];
    const double torque_per_amp = mp.gearbox_efficiency * mp.gear_ratio * mp.torque_constant();
    m[j] = plant.M(Eigen::Index(j), Eigen::Index(j));
    k[j] = K(Eigen::Index(j), Eigen::Index(j));
    c[j] = C(Eigen::Index(j), Eigen::Index(j)) + torque_per_amp * mp.back_emf_constant() * mp.gear_ratio / mp.resistance();
    b[j] = torque_per_amp * mp.supply_voltage_V / mp.resistance();
  }
  if (!per_joint) {
    for (auto* v : {&m, &c, &k, &b}) (*v)[0] = (*v)[1] = 0.5 * ((*v)[0] + (*v)[1]);
  }
  std::array<PidGains, 2> g = base;
  for (std::size_t j = 0; j < 2; ++j) {
    g[j].kp = std::max(kFloor, (3.0 * m[j] * omega * omega - k[j]) / b[j]);
    g[j].ki = std::max(kFloor, m[j] * omega * omega * omega / b[j]);
    g[j].kd = std::max(kFloor, (3.0 * m[j] * omega - c[j]) / b[j]);
  }
  return g;
}

namespace {

/// max_spectral_radius() that tries the pose found worst last time first (`hint`, updated) and
/// stops once a pose is strictly above `stop_at`: the same value whenever the maximum is at most
/// stop_at, and a value above stop_at otherwise. A scan for the least maximum then drops most
/// candidates at their first pose.
double max_rho_hinted(const std::vector<PoseLoop>& poses, const std::array<PidGains, 2>& gains, bool delay,
                      double stop_at, std::size_t& hint) {
  double worst = 0.0;
  std::size_t at = hint;
  const auto visit = [&](std::size_t k) {
    const PoseLoop& p = poses[k];
    if (p.status != Status::ok) return false;
    const double r = loop_poles(closed_loop(p.plant, gains, delay), p.plant.period_s).rho;
    if (r > worst) {
      worst = r;
      at = k;
    }
    return worst > stop_at;
  };
  bool stopped = hint < poses.size() && visit(hint);
  for (std::size_t k = 0; k < poses.size() && !stopped; ++k) {
    if (k != hint) stopped = visit(k);
  }
  hint = at;
  return worst;
}

}  // namespace

PolePlacement pole_placement(const LoopModel& loop, const Vec2& centre_mm, const std::vector<PoseLoop>& poses,
                             bool per_joint, const std::array<PidGains, 2>& base) {
  PolePlacement out;
  out.gains = base;
  const AnglesResult a = ik_angles(loop.model.mechanism, centre_mm);
  out.status = a.status;
  if (a.status != Status::ok) return out;
  MechanismModel model = loop.model;
  if (model.branch == AssemblyMode::Any) {
    const Pose p = fk(model.mechanism, a.theta1, a.theta2);
    if (p.assembly != 0) model.branch = p.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
  }
  const LinearPlant plant = linear_plant(model, Eigen::Vector2d(a.theta1, a.theta2), loop.contact ? &loop.skin : nullptr);
  out.status = plant.status;
  if (plant.status != Status::ok) return out;
  // Each value exact unless it exceeds stop_at, the value it is compared with (the scan's best, the
  // other golden-section point): the comparisons, and so the result, are those of full maxima.
  std::size_t hint = 0;
  const auto rho = [&](double omega, double stop_at) {
    return max_rho_hinted(poses, pole_placement_gains(plant, model.motors, omega, per_joint, base), loop.delay,
                          stop_at, hint);
  };
  // Geometric scan, then golden section between the best value's neighbours.
  constexpr int kScan = 60;
  const double lo = 2.0 * std::numbers::pi * 0.2;
  const double hi = 2.0 * std::numbers::pi * 0.25 / loop.period_s;
  const auto omega_at = [&](int i) { return lo * std::pow(hi / lo, double(i) / (kScan - 1)); };
  int best = 0;
  double best_rho = std::numeric_limits<double>::infinity();
  for (int i = 0; i < kScan; ++i) {
    const double r = rho(omega_at(i), best_rho);
    if (r < best_rho) {
      best_rho = r;
      best = i;
    }
  }
  double a0 = std::log(omega_at(std::max(best - 1, 0))), b0 = std::log(omega_at(std::min(best + 1, kScan - 1)));
  const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = b0 - phi * (b0 - a0), x2 = a0 + phi * (b0 - a0);
  double f1 = rho(std::exp(x1), 1e300);
  double f2 = rho(std::exp(x2), f1);
  for (int it = 0; it < 30 && b0 - a0 > 1e-4; ++it) {
    if (f1 < f2) {
      b0 = x2, x2 = x1, f2 = f1;
      x1 = b0 - phi * (b0 - a0);
      f1 = rho(std::exp(x1), f2);
    } else {
      a0 = x1, x1 = x2, f1 = f2;
      x2 = a0 + phi * (b0 - a0);
      f2 = rho(std::exp(x2), f1);
    }
  }
  double omega = omega_at(best);
  if (std::min(f1, f2) < best_rho) {
    omega = std::exp(f1 < f2 ? x1 : x2);
    best_rho = std::min(f1, f2);
  }
  out.omega_rad_s = omega;
  out.gains = pole_placement_gains(plant, model.motors, omega, per_joint, base);
  out.max_rho = best_rho;
  return out;
}

namespace {

/// pole_placement_gains() of the plant at the target's centre for a given omega (as pole_placement()).
std::optional<std::array<PidGains, 2>> pole_placement_at(const LoopModel& loop, const Vec2& centre_mm, double omega,
                                                         bool per_joint, const std::array<PidGains, 2>& base) {
  const AnglesResult a = ik_angles(loop.model.mechanism, centre_mm);
  if (a.status != Status::ok) return std::nullopt;
  MechanismModel model = loop.model;
  if (model.branch == AssemblyMode::Any) {
    const Pose p = fk(model.mechanism, a.theta1, a.theta2);
    if (p.assembly != 0) model.branch = p.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
  }
  const LinearPlant plant = linear_plant(model, Eigen::Vector2d(a.theta1, a.theta2), loop.contact ? &loop.skin : nullptr);
  if (plant.status != Status::ok) return std::nullopt;
  return pole_placement_gains(plant, model.motors, omega, per_joint, base);
}

}  // namespace

TuneOptions tune_options(const ControllerSettings& c) {
  TuneOptions o;
  const TuneSettings t = c.tune.value_or(TuneSettings{});
  o.rho_limit = t.rho_limit;
  o.max_evaluations = t.evaluations;
  o.max_seconds = t.max_seconds;
  o.per_joint = t.per_joint;
  o.start = t.start == "hand_set" ? TuneStart::hand_set : t.start == "pole_placement" ? TuneStart::pole_placement : TuneStart::design;
  o.min_damping = t.min_damping;
  o.min_gain_margin = t.min_gain_margin;
  return o;
}

bool TunedMechanism::applied() const {
  const auto same = [](double a, double b) { return std::abs(a - b) <= 1e-6 * std::max(std::abs(a), std::abs(b)); };
  for (std::size_t j = 0; j < 2; ++j) {
    if (!same(design[j].kp, after[j].kp) || !same(design[j].ki, after[j].ki) || !same(design[j].kd, after[j].kd)) {
      return false;
    }
  }
  return true;
}

namespace {

/// One mechanism's inputs: its pattern runs, constraint poses, step and chirp.
struct Job {
  const Station* station;
  LoopModel loop;
  std::vector<SimulationInput> runs;
  std::vector<PoseLoop> poses;
  std::optional<SimulationInput> step, chirp;
};

/// What every mechanism's tuning shares.
struct Shared {
  const TuneOptions& options;
  Clock::time_point deadline;  ///< of the whole tuning, figures included
  double saturation_limit;
  double max_overshoot_mm;
  SimulationRequest chirp_request;
  std::function<void(std::string_view)> progress;
};

/// The figures of `g` that the evaluation `e` did not already give (margins by the stability
/// map's bisection, the step when not run, the chirp), each within the bound; into the before or
/// after fields of `t`, with the names of those the bound left uncomputed.
void figures_of(const Job& job, const Shared& s, const std::array<PidGains, 2>& g, const Evaluation& e, TunedMechanism& t,
                bool after) {
  std::vector<std::string>& missing = after ? t.not_computed_after : t.not_computed_before;
  (after ? t.error_after_mm : t.error_before_mm) =
      e.tracking.out_of_time ? kNaN : e.tracking.ok ? e.tracking.error_mm : std::numeric_limits<double>::infinity();
  (after ? t.saturation_after : t.saturation_before) = e.tracking.out_of_time ? kNaN : e.tracking.saturation;
  (after ? t.simulated_after_s : t.simulated_before_s) = e.tracking.simulated_s;
  (after ? t.objective_after_mm : t.objective_before_mm) = e.measured ? e.value : kNaN;
  if (e.tracking.out_of_time) missing.push_back("tracking");
  (after ? t.rho_after : t.rho_before) = e.linear.rho;
  (after ? t.damping_after : t.damping_before) = e.linear.damping;
  (after ? t.damping_hz_after : t.damping_hz_before) = e.linear.damping_hz;
  // The margins over the constraint's grid, bisected as the stability map does, on the poses
  // linearised once for the whole tuning (not cut inside: left out once the bound has passed).
  double kp_margin = kNaN, kd_margin = kNaN;
  if (Clock::now() < s.deadline) {
    LoopModel loop = job.loop;
    loop.gains = g;
    const StabilityMap map = stability_map(loop, job.poses, StabilityOptions{});
    kp_margin = map.kp_margin;
    kd_margin = map.kd_margin;
  } else {
    missing.push_back("margins");
  }
  (after ? t.kp_margin_after : t.kp_margin_before) = kp_margin;
  (after ? t.kd_margin_after : t.kd_margin_before) = kd_margin;
  double over = e.overshoot_mm;
  if (std::isnan(over)) over = job.step ? step_overshoot(*job.step, g, s.options.rtol, s.deadline) : 0.0;
  if (std::isnan(over)) missing.push_back("step");
  (after ? t.overshoot_after_mm : t.overshoot_before_mm) = over;
  ChirpFigures c{0.0, 0.0, 0.0};
  if (job.chirp) c = chirp_figures(*job.chirp, s.chirp_request, g, s.options.rtol, s.deadline);
  if (std::isnan(c.bandwidth_hz)) missing.push_back("chirp");
  (after ? t.chirp_bandwidth_after_hz : t.chirp_bandwidth_before_hz) = c.bandwidth_hz;
  (after ? t.chirp_saturation_after_hz : t.chirp_saturation_before_hz) = c.saturation_hz;
  (after ? t.bandwidth_after_hz : t.bandwidth_before_hz) = c.reported_hz;
}

/// The pole placement start (TuneStart::pole_placement), into t.start and t.start_omega_rad_s.
void pole_placement_start(const Job& job, const Shared& s, TunedMechanism& t) {
  const TuneOptions& options = s.options;
  const PolePlacement pp = pole_placement(job.loop, job.station->target.center, job.poses, options.per_joint, t.before);
  if (pp.status != Status::ok) return;
  t.start = pp.gains;
  t.start_omega_rad_s = pp.omega_rad_s;
  // The least-rho omega may break the damping or margin floors (a fast placement meets the
  // period of delay): among placements from omega* / 0.85^4 down to omega* 0.85^8, the first
  // that meets the linear floors, else the one that misses them least.
  // The violation of linear_figures() pose by pose, in its order (rho_kp and rho_kd stop
  // growing at their first pose >= 1, as max_spectral_radius() stops there): every term only
  // grows, so once the sum reaches `stop` the candidate cannot beat it and is left there; below,
  // the value is that of linear_figures() exactly.
  const auto violation = [&](const std::array<PidGains, 2>& g, double stop) {
    std::array<PidGains, 2> g_kp = g, g_kd = g;
    for (PidGains& x : g_kp) x.kp *= options.min_gain_margin;
    for (PidGains& x : g_kd) x.kd *= options.min_gain_margin;
    Linear l;
    const auto value = [&] {
      return std::max(0.0, l.rho - options.rho_limit) + std::max(0.0, options.min_damping + kDampingSafety - l.damping) +
             std::max(0.0, l.rho_kp - (1.0 - kRhoSafety)) + std::max(0.0, l.rho_kd - (1.0 - kRhoSafety));
    };
    for (const PoseLoop& pose : job.poses) {
      if (pose.status != Status::ok) continue;
      const LoopPoles poles = loop_poles(closed_loop(pose.plant, g, job.loop.delay), pose.plant.period_s);
      l.rho = std::max(l.rho, poles.rho);
      if (poles.oscillatory_damping < l.damping) l.damping = poles.oscillatory_damping;
      if (l.rho_kp < 1.0) {
        l.rho_kp = std::max(l.rho_kp, loop_poles(closed_loop(pose.plant, g_kp, job.loop.delay), pose.plant.period_s).rho);
      }
      if (l.rho_kd < 1.0) {
        l.rho_kd = std::max(l.rho_kd, loop_poles(closed_loop(pose.plant, g_kd, job.loop.delay), pose.plant.period_s).rho);
      }
      if (value() >= stop) break;
    }
    return value();
  };
  const double omega0 = t.start_omega_rad_s;
  double best_violation = violation(t.start, std::numeric_limits<double>::infinity());
  for (int k = -4; k <= 8 && best_violation > 0.0; ++k) {
    if (k == 0) continue;
    const double omega = omega0 * std::pow(0.85, k);
    const std::optional<std::array<PidGains, 2>> g =
        pole_placement_at(job.loop, job.station->target.center, omega, options.per_joint, t.before);
    if (!g) continue;
    const double v = violation(*g, best_violation);
    if (v < best_violation) {
      best_violation = v;
      t.start = *g;
      t.start_omega_rad_s = omega;
    }
  }
}

/// One mechanism: the design's gains evaluated ("before"), the search from the start, and the
/// result: the best candidate when it beats the design's gains, else the design's gains.
TunedMechanism tune_mechanism(const Job& job, const Shared& s, const ControllerSettings& ctl) {
  const TuneOptions& options = s.options;
  TunedMechanism t;
  t.station = job.station->name;
  t.mechanism = job.loop.model.mechanism.name;
  t.design = t.before = job.loop.gains;
  t.patterns_s = patterns_seconds(job.runs);
  Problem p{&job.runs, &job.poses, job.step ? &*job.step : nullptr, t.before, options.rho_limit, s.saturation_limit,
            options.rtol, job.loop.delay, options.min_damping, options.min_gain_margin, s.max_overshoot_mm, 0, s.progress,
            t.station + "/" + t.mechanism, {}, std::numeric_limits<double>::infinity(), {}, {}, s.deadline, {}, nullptr};
  // Before: the design's gains on the search's own objective and constraints, within the bound
  // (simulated even when unstable, for the figure), then its other figures, timed: the search
  // leaves the after figures as long as these took.
  const Evaluation before =
      evaluate(p, t.before, linear_figures(job.poses, t.before, job.loop.delay, options.min_gain_margin), s.deadline, true);
  const auto figures_start = Clock::now();
  figures_of(job, s, t.before, before, t, false);
  const auto reserve = (Clock::now() - figures_start) + std::chrono::milliseconds(20);

  t.start = t.before;
  if (options.start == TuneStart::pole_placement) pole_placement_start(job, s, t);
  if (options.start == TuneStart::hand_set) {
    for (int k = 0; k < 2; ++k) t.start[std::size_t(k)] = ctl.hand_set_pid(t.station, t.mechanism, k + 1);
  }
  t.rho_start = max_spectral_radius(job.poses, t.start, job.loop.delay);
  s.progress(p.label + ": start kp " + format::shortest(t.start[0].kp) + " ki " + format::shortest(t.start[0].ki) + " kd " +
             format::shortest(t.start[0].kd) + ", max rho " + format::shortest(t.rho_start));
  p.base = t.start;
  if (options.start == TuneStart::design && before.measured) p.at_start = &before;
  p.deadline = s.deadline - reserve;
  const std::size_t unknowns = options.per_joint ? 6 : 3;
  std::vector<double> x(unknowns, 0.0), lo(unknowns, -kRange), hi(unknowns, kRange);
  nlopt::opt opt(nlopt::LN_COBYLA, unsigned(unknowns));
  opt.set_lower_bounds(lo);
  opt.set_upper_bounds(hi);
  opt.set_min_objective(objective, &p);
  opt.add_inequality_constraint(rho_constraint, &p, 1e-4);
  opt.add_inequality_constraint(damping_constraint, &p, 1e-4);
  opt.add_inequality_constraint(kp_margin_constraint, &p, 1e-4);
  opt.add_inequality_constraint(kd_margin_constraint, &p, 1e-4);
  opt.set_initial_step(std::log(2.0));
  opt.set_xtol_rel(1e-3);
  opt.set_maxeval(options.max_evaluations);
  const double left = seconds_left(p.deadline);
  // The bound itself is checked inside the evaluations (Problem::deadline).
  opt.set_maxtime(std::max(left, 1e-3));
  double best = 0.0;
  nlopt::result r = nlopt::MAXTIME_REACHED;
  if (left > 0.0 && before.measured) {
    try {
      r = opt.optimize(x, best);
    } catch (const nlopt::roundoff_limited&) {
      r = nlopt::ROUNDOFF_LIMITED;
    } catch (const nlopt::forced_stop&) {
      r = Clock::now() >= p.deadline ? nlopt::MAXTIME_REACHED : nlopt::FORCED_STOP;
    }
  }
  t.stop = stop_text(r);
  t.evaluations = p.evaluations;
  // Never worse than the design: the best admissible candidate replaces the design's gains only
  // when it beats them on the objective (or they miss a constraint); the design's own point (x = 0
  // from the design) is the design's gains exactly.
  const bool at_design = options.start == TuneStart::design &&
                         std::all_of(p.best_x.begin(), p.best_x.end(), [](double v) { return v == 0.0; });
  t.improved = !p.best_x.empty() && !at_design && before.measured && (!before.admissible || p.best_value < before.value);
  if (t.improved) {
    t.after = with(p.base, p.best_x);
    figures_of(job, s, t.after, p.best, t, true);
  } else {
    // The design's gains kept: their figures are the before ones.
    t.after = t.before;
    t.rho_after = t.rho_before;
    t.error_after_mm = t.error_before_mm;
    t.saturation_after = t.saturation_before;
    t.simulated_after_s = t.simulated_before_s;
    t.objective_after_mm = t.objective_before_mm;
    t.damping_after = t.damping_before;
    t.damping_hz_after = t.damping_hz_before;
    t.kp_margin_after = t.kp_margin_before;
    t.kd_margin_after = t.kd_margin_before;
    t.overshoot_after_mm = t.overshoot_before_mm;
    t.chirp_bandwidth_after_hz = t.chirp_bandwidth_before_hz;
    t.chirp_saturation_after_hz = t.chirp_saturation_before_hz;
    t.bandwidth_after_hz = t.bandwidth_before_hz;
    t.not_computed_after = t.not_computed_before;
  }
  const std::vector<std::string>& missing = t.not_computed_after;
  t.feasible = missing.empty() && std::isfinite(t.error_after_mm) && t.rho_after <= options.rho_limit &&
               t.saturation_after <= s.saturation_limit && t.damping_after >= options.min_damping &&
               t.kp_margin_after >= options.min_gain_margin && t.kd_margin_after >= options.min_gain_margin &&
               t.overshoot_after_mm <= s.max_overshoot_mm;
  return t;
}

}  // namespace

TuneResult tune_controller(const Design& d, const std::vector<const Station*>& stations,
                           const std::map<std::string, std::map<std::string, MechanismInertia>>& inertia,
                           const TuneOptions& options) {
  const auto start = Clock::now();
  const Clock::time_point deadline =
      start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(std::min(options.max_seconds, 1e7)));
  if (!d.get<ControllerSettings>()) throw InputError("tune: the design has no `controller:` section");
  const ControllerSettings& ctl = *d.get<ControllerSettings>();
  TuneResult result;
  result.rho_limit = options.rho_limit;
  result.min_damping = options.min_damping;
  result.min_gain_margin = options.min_gain_margin;
  result.budget_s = options.max_seconds;
  const double zeta = options.min_damping;
  result.max_overshoot_fraction = zeta > 0.0 ? std::exp(-std::numbers::pi * zeta / std::sqrt(1.0 - zeta * zeta)) : 1.0;
  // Every mechanism's pattern runs and constraint poses first (InputError before any work).
  SimulationRequest step_request, chirp_request;
  step_request.step = true;
  chirp_request.chirp = true;
  std::vector<Job> jobs;
  for (const Station* s : stations) {
    const auto it = inertia.find(s->name);
    if (it == inertia.end()) throw InputError("tune: no mass properties for station " + s->name);
    SimulationRequest request;
    request.station = s->name;
    const std::vector<SimulationInput> all = simulation_inputs(d, request, it->second);
    step_request.station = chirp_request.station = s->name;
    const std::vector<SimulationInput> steps = simulation_inputs(d, step_request, it->second);
    std::vector<SimulationInput> chirps;
    if (options.chirp) {
      try {
        chirps = simulation_inputs(d, chirp_request, it->second);
      } catch (const InputError&) {
        // A chirp that leaves the workspace: no chirp figures (reported as such), the tuning stands.
      }
    }
    std::size_t k = 0;
    for (const LoopModel& loop : loop_models(d, *s, it->second)) {
      Job job{s, loop, {}, {}, {}, {}};
      for (const SimulationInput& in : all) {
        if (!in.unusable.empty()) throw InputError("tune: station " + s->name + " " + in.reference_name + ": " + in.unusable);
        SimulationInput one = in;
        one.mechanisms = {in.mechanisms[k]};
        job.runs.push_back(std::move(one));
      }
      for (const std::vector<SimulationInput>* source : {&steps, static_cast<const std::vector<SimulationInput>*>(&chirps)}) {
        if (source->empty() || !source->front().unusable.empty()) continue;
        SimulationInput one = source->front();
        one.mechanisms = {one.mechanisms[k]};
        (source == &steps ? job.step : job.chirp) = std::move(one);
      }
      for (const Vec2& P : ellipse_lattice(s->target, options.grid)) job.poses.push_back(pose_loop(loop, P));
      jobs.push_back(std::move(job));
      ++k;
    }
  }
  std::mutex say;
  const Shared shared{options, deadline, ctl.max_saturation_fraction, result.max_overshoot_fraction * step_request.step_mm,
                      chirp_request, [&](std::string_view line) {
                        if (!options.progress) return;
                        const std::lock_guard<std::mutex> lock(say);
                        options.progress(line);
                      }};
  std::vector<TunedMechanism> tuned(jobs.size());
  // One worker per core (or options.threads), each taking the next mechanism.
  const unsigned threads = std::max(1u, std::min<unsigned>(options.threads ? options.threads : std::thread::hardware_concurrency(),
                                                          static_cast<unsigned>(jobs.size())));
  std::atomic<std::size_t> next{0};
  std::exception_ptr failure;
  std::mutex failure_lock;
  const auto worker = [&] {
    for (std::size_t j = next++; j < jobs.size(); j = next++) {
      try {
        tuned[j] = tune_mechanism(jobs[j], shared, ctl);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(failure_lock);
        if (!failure) failure = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned k = 1; k < threads; ++k) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
  result.mechanisms = std::move(tuned);
  result.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

std::string tuned_patch_yaml(const TuneResult& result) {
  std::string out =
      "# Tuned by fivebar (control --tune, or the control product of run): per mechanism the PID minimising\n"
      "# the worst simulated tracking error over the station's patterns with the loop's spectral radius <= " +
      format::shortest(result.rho_limit) + "\n# over the target, every oscillatory pole damped at zeta >= " +
      format::shortest(result.min_damping) + ", kp and kd margins >= x" + format::shortest(result.min_gain_margin) +
      " and the 1 mm step's\n# overshoot within its bound. Merge into the design's controller: section.\n"
      "controller:\n  stations:\n";
  std::string station;
  for (const TunedMechanism& t : result.mechanisms) {
    if (t.station != station) {
      out += "    " + t.station + ":\n";
      station = t.station;
    }
    const auto pid = [](const PidGains& g) {
      return "{pid: {kp: " + format::shortest(g.kp) + ", ki: " + format::shortest(g.ki) + ", kd: " + format::shortest(g.kd) +
             "}}";
    };
    const bool same = t.after[0].kp == t.after[1].kp && t.after[0].ki == t.after[1].ki && t.after[0].kd == t.after[1].kd;
    out += "      " + t.mechanism + ": " +
           (same ? pid(t.after[0]) : "{theta1: " + pid(t.after[0]) + ", theta2: " + pid(t.after[1]) + "}") +
           (t.feasible ? "" : "  # NOT feasible: see the tuning table") + "\n";
  }
  return out;
}

namespace {
/// inf (no saturation in the chirp, a step that did not finish) is written as null.
Json finite_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }
}  // namespace

Json to_json(const TuneResult& result) {
  Json mechs = Json::array();
  const auto gains = [](const PidGains& g) { return Json{{"kp", g.kp}, {"ki", g.ki}, {"kd", g.kd}, {"i_clamp", g.i_clamp}}; };
  for (const TunedMechanism& t : result.mechanisms) {
    const auto side = [&](bool after) {
      const auto v = [after](double b, double a) { return finite_or_null(after ? a : b); };
      return Json{{"gains", gains((after ? t.after : t.before)[0])},
                  {"gains_theta2", gains((after ? t.after : t.before)[1])},
                  {"max_rho", after ? t.rho_after : t.rho_before},
                  {"objective_mm", v(t.objective_before_mm, t.objective_after_mm)},
                  {"max_tracking_error_mm", v(t.error_before_mm, t.error_after_mm)},
                  {"simulated_s", after ? t.simulated_after_s : t.simulated_before_s},
                  {"saturation_fraction", v(t.saturation_before, t.saturation_after)},
                  {"min_damping", after ? t.damping_after : t.damping_before},
                  {"min_damping_hz", after ? t.damping_hz_after : t.damping_hz_before},
                  {"kp_margin", v(t.kp_margin_before, t.kp_margin_after)},
                  {"kd_margin", v(t.kd_margin_before, t.kd_margin_after)},
                  {"step_overshoot_mm", v(t.overshoot_before_mm, t.overshoot_after_mm)},
                  {"chirp_bandwidth_hz", v(t.chirp_bandwidth_before_hz, t.chirp_bandwidth_after_hz)},
                  {"chirp_saturation_hz", v(t.chirp_saturation_before_hz, t.chirp_saturation_after_hz)},
                  {"bandwidth_hz", v(t.bandwidth_before_hz, t.bandwidth_after_hz)},
                  {"not_computed", after ? t.not_computed_after : t.not_computed_before}};
    };
    mechs.push_back({{"station", t.station},
                     {"mechanism", t.mechanism},
                     {"start", {{"gains", gains(t.start[0])}, {"gains_theta2", gains(t.start[1])},
                                {"omega_rad_s", t.start_omega_rad_s}, {"max_rho", t.rho_start}}},
                     {"before", side(false)},
                     {"after", side(true)},
                     {"design", {{"gains", gains(t.design[0])}, {"gains_theta2", gains(t.design[1])}, {"applied", t.applied()}}},
                     {"improved", t.improved},
                     {"patterns_s", t.patterns_s},
                     {"evaluations", t.evaluations},
                     {"feasible", t.feasible},
                     {"stop", t.stop}});
  }
  return {{"rho_limit", result.rho_limit},
          {"min_damping", result.min_damping},
          {"min_gain_margin", result.min_gain_margin},
          {"max_step_overshoot_fraction", result.max_overshoot_fraction},
          {"budget_s", result.budget_s},
          {"wall_s", result.wall_s},
          {"mechanisms", mechs}};
}

std::string tuning_csv(const TuneResult& result) {
  const auto num = [](double v) { return std::isfinite(v) ? format::shortest(v) : std::string(); };
  std::string csv =
      "station,mechanism,kp_before,ki_before,kd_before,kp_after,ki_after,kd_after,max_rho_before,max_rho_after,"
      "max_tracking_error_before_mm,max_tracking_error_after_mm,saturation_before,saturation_after,evaluations,"
      "feasible,applied,stop,min_damping_before,min_damping_after,kp_margin_before,kp_margin_after,kd_margin_before,"
      "kd_margin_after,step_overshoot_before_mm,step_overshoot_after_mm,chirp_bandwidth_before_hz,"
      "chirp_bandwidth_after_hz,chirp_saturation_before_hz,chirp_saturation_after_hz,bandwidth_before_hz,"
      "bandwidth_after_hz,improved,objective_before_mm,objective_after_mm,simulated_before_s,simulated_after_s,"
      "patterns_s\n";
  for (const TunedMechanism& t : result.mechanisms) {
    csv += t.station + "," + t.mechanism + "," + num(t.before[0].kp) + "," + num(t.before[0].ki) + "," +
           num(t.before[0].kd) + "," + num(t.after[0].kp) + "," + num(t.after[0].ki) + "," + num(t.after[0].kd) + "," +
           num(t.rho_before) + "," + num(t.rho_after) + "," + num(t.error_before_mm) + "," + num(t.error_after_mm) +
           "," + num(t.saturation_before) + "," + num(t.saturation_after) + "," + std::to_string(t.evaluations) + "," +
           (t.feasible ? "true" : "false") + "," + (t.applied() ? "true" : "false") + "," + t.stop + "," +
           num(t.damping_before) + "," + num(t.damping_after) + "," + num(t.kp_margin_before) + "," +
           num(t.kp_margin_after) + "," + num(t.kd_margin_before) + "," + num(t.kd_margin_after) + "," +
           num(t.overshoot_before_mm) + "," + num(t.overshoot_after_mm) + "," + num(t.chirp_bandwidth_before_hz) + "," +
           num(t.chirp_bandwidth_after_hz) + "," + num(t.chirp_saturation_before_hz) + "," +
           num(t.chirp_saturation_after_hz) + "," + num(t.bandwidth_before_hz) + "," + num(t.bandwidth_after_hz) + "," +
           (t.improved ? "true" : "false") + "," + num(t.objective_before_mm) + "," + num(t.objective_after_mm) + "," +
           num(t.simulated_before_s) + "," + num(t.simulated_after_s) + "," + num(t.patterns_s) + "\n";
  }
  return csv;
}

}  // namespace fivebar
