// Gains per mechanism by NLopt's COBYLA (fivebar/control.hpp "Tuning"); the only file that sees NLopt.

#include <nlopt.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

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
  bool out_of_time = false;  ///< the tuning's wall-time bound passed: not measured
};

using Clock = std::chrono::steady_clock;

/// The tuning's time bound (TuneOptions::max_seconds) is checked inside the loops (issue 31
/// family 2): before every evaluation and between the pattern runs of one, and each run is itself
/// cut at the bound, so the tuning ends at most one simulation step past it.
Tracking track(const std::vector<SimulationInput>& runs, const std::array<PidGains, 2>& gains, double rtol,
               Clock::time_point deadline) {
  Tracking t;
  SimulationOptions o;
  o.rtol = rtol;
  o.record = false;
  for (SimulationInput in : runs) {
    const double left = std::chrono::duration<double>(deadline - Clock::now()).count();
    if (left <= 0.0) {
      t.ok = false;
      t.out_of_time = true;
      return t;
    }
    o.max_wall_s = std::min(10.0, left);
    in.mechanisms[0].control[0].pid = gains[0];
    in.mechanisms[0].control[1].pid = gains[1];
    const SimulationResult r = simulate(in, o);
    if (Clock::now() >= deadline) {
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

/// Gains from the unknowns: (ln kp, ln ki, ln kd) for both joints, or per joint (six).
std::array<PidGains, 2> with(const std::array<PidGains, 2>& base, const std::vector<double>& x) {
  std::array<PidGains, 2> g = base;
  for (std::size_t j = 0; j < 2; ++j) {
    const std::size_t o = x.size() == 6 ? 3 * j : 0;
    g[j].kp = std::exp(x[o]);
    g[j].ki = std::exp(x[o + 1]);
    g[j].kd = std::exp(x[o + 2]);
  }
  return g;
}

constexpr double kFloor = 1e-3;        // a zero gain starts here (ln 0 is not a start)
constexpr double kSaturationPenaltyMm = 10.0;
constexpr double kFailedRunMm = 1e3;   // a run that did not finish
constexpr double kRange = 5.0;         // ln of the factor each gain may move by: e^5 ~ 148
constexpr double kRhoSafety = 0.003;   // COBYLA ends within its tolerance of the constraint: aim inside

struct Problem {
  const std::vector<SimulationInput>* runs;
  const std::vector<PoseLoop>* poses;
  std::array<PidGains, 2> base;
  double rho_limit, saturation_limit, rtol;
  bool delay;
  int evaluations = 0;
  const TuneOptions* options;
  std::string label;
  // The best evaluated point that meets the constraints, and its tracking.
  std::vector<double> best_x;
  double best_value = std::numeric_limits<double>::infinity();
  Tracking best_tracking;
  Clock::time_point deadline;
};

double objective(unsigned n, const double* x, double*, void* data) {
  auto& p = *static_cast<Problem*>(data);
  if (Clock::now() >= p.deadline) throw nlopt::forced_stop();
  const std::array<PidGains, 2> g = with(p.base, std::vector<double>(x, x + n));
  ++p.evaluations;
  // An unstable loop is not simulated: its error is that of a failed run.
  const double rho = max_spectral_radius(*p.poses, g, p.delay, 1.0);
  double value = kFailedRunMm;
  if (rho < 1.0) {
    const Tracking t = track(*p.runs, g, p.rtol, p.deadline);
    if (t.out_of_time) throw nlopt::forced_stop();  // abandoned: not a measurement
    if (t.ok) value = t.error_mm + kSaturationPenaltyMm * std::max(0.0, t.saturation - p.saturation_limit);
    if (t.ok && rho <= p.rho_limit && t.saturation <= p.saturation_limit && value < p.best_value) {
      p.best_value = value;
      p.best_x.assign(x, x + n);
      p.best_tracking = t;
    }
  }
  if (p.options->progress) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s: evaluation %d, kp %.4g ki %.4g kd %.4g: max rho %.4f, objective %.4f mm",
                  p.label.c_str(), p.evaluations, g[0].kp, g[0].ki, g[0].kd, rho, value);
    p.options->progress(buf);
  }
  return value;
}

double constraint(unsigned n, const double* x, double*, void* data) {
  auto& p = *static_cast<Problem*>(data);
  return max_spectral_radius(*p.poses, with(p.base, std::vector<double>(x, x + n)), p.delay) - (p.rho_limit - kRhoSafety);
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
  const auto rho = [&](double omega, double stop_at) {
    return max_spectral_radius(poses, pole_placement_gains(plant, model.motors, omega, per_joint, base), loop.delay,
                               stop_at);
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
  double f1 = rho(std::exp(x1), 1e300), f2 = rho(std::exp(x2), 1e300);
  for (int it = 0; it < 30 && b0 - a0 > 1e-4; ++it) {
    if (f1 < f2) {
      b0 = x2, x2 = x1, f2 = f1;
      x1 = b0 - phi * (b0 - a0);
      f1 = rho(std::exp(x1), 1e300);
    } else {
      a0 = x1, x1 = x2, f1 = f2;
      x2 = a0 + phi * (b0 - a0);
      f2 = rho(std::exp(x2), 1e300);
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

TuneOptions tune_options(const ControllerSettings& c) {
  TuneOptions o;
  const TuneSettings t = c.tune.value_or(TuneSettings{});
  o.rho_limit = t.rho_limit;
  o.max_evaluations = t.evaluations;
  o.max_seconds = t.max_seconds;
  o.per_joint = t.per_joint;
  o.start = t.start == "hand_set" ? TuneStart::hand_set : TuneStart::pole_placement;
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

TuneResult tune_controller(const Design& d, const std::vector<const Station*>& stations,
                           const std::map<std::string, std::map<std::string, MechanismInertia>>& inertia,
                           const TuneOptions& options) {
  const auto start = Clock::now();
  const Clock::time_point deadline =
      start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(std::min(options.max_seconds, 1e7)));
  if (!d.get<ControllerSettings>()) throw InputError("tune: the design has no `controller:` section");
  const ControllerSettings& ctl = *d.get<ControllerSettings>();
  const double saturation_limit = ctl.max_saturation_fraction;
  TuneResult result;
  result.rho_limit = options.rho_limit;
  // Every mechanism's pattern runs and constraint poses first (InputError before any work).
  struct Job {
    const Station* station;
    LoopModel loop;
    std::vector<SimulationInput> runs;
    std::vector<PoseLoop> poses;
  };
  std::vector<Job> jobs;
  for (const Station* s : stations) {
    const auto it = inertia.find(s->name);
    if (it == inertia.end()) throw InputError("tune: no mass properties for station " + s->name);
    SimulationRequest request;
    request.station = s->name;
    const std::vector<SimulationInput> all = simulation_inputs(d, request, it->second);
    std::size_t k = 0;
    for (const LoopModel& loop : loop_models(d, *s, it->second)) {
      Job job{s, loop, {}, {}};
      for (const SimulationInput& in : all) {
        if (!in.unusable.empty()) throw InputError("tune: station " + s->name + " " + in.reference_name + ": " + in.unusable);
        SimulationInput one = in;
        one.mechanisms = {in.mechanisms[k]};
        job.runs.push_back(std::move(one));
      }
      for (const Vec2& P : ellipse_lattice(s->target, options.grid)) job.poses.push_back(pose_loop(loop, P));
      jobs.push_back(std::move(job));
      ++k;
    }
  }
  for (std::size_t j = 0; j < jobs.size(); ++j) {
    Job& job = jobs[j];
    TunedMechanism t;
    t.station = job.station->name;
    t.mechanism = job.loop.model.mechanism.name;
    t.design = job.loop.gains;
    for (int k = 0; k < 2; ++k) t.before[std::size_t(k)] = ctl.hand_set_pid(t.station, t.mechanism, k + 1);
    t.rho_before = max_spectral_radius(job.poses, t.before, job.loop.delay);
    const Tracking tb = track(job.runs, t.before, options.rtol, deadline);
    t.error_before_mm = tb.ok ? tb.error_mm : std::numeric_limits<double>::infinity();
    t.saturation_before = tb.saturation;

    Problem p{&job.runs, &job.poses, t.before, options.rho_limit, saturation_limit, options.rtol, job.loop.delay, 0,
              &options, t.station + "/" + t.mechanism, {}, std::numeric_limits<double>::infinity(), {}, deadline};
    t.start = t.before;
    if (options.start == TuneStart::pole_placement) {
      const PolePlacement pp = pole_placement(job.loop, job.station->target.center, job.poses, options.per_joint, t.before);
      if (pp.status == Status::ok) {
        t.start = pp.gains;
        t.start_omega_rad_s = pp.omega_rad_s;
      }
    }
    t.rho_start = max_spectral_radius(job.poses, t.start, job.loop.delay);
    if (options.progress) {
      options.progress(p.label + ": start kp " + format::shortest(t.start[0].kp) + " ki " + format::shortest(t.start[0].ki) +
                       " kd " + format::shortest(t.start[0].kd) + ", max rho " + format::shortest(t.rho_start));
    }
    const std::size_t unknowns = options.per_joint ? 6 : 3;
    std::vector<double> x(unknowns);
    for (std::size_t i = 0; i < unknowns; ++i) {
      const PidGains& g = t.start[i / 3];
      x[i] = std::log(std::max(i % 3 == 0 ? g.kp : i % 3 == 1 ? g.ki : g.kd, kFloor));
    }
    std::vector<double> lo(unknowns), hi(unknowns);
    for (std::size_t i = 0; i < unknowns; ++i) {
      lo[i] = x[i] - kRange;
      hi[i] = x[i] + kRange;
    }
    nlopt::opt opt(nlopt::LN_COBYLA, unsigned(unknowns));
    opt.set_lower_bounds(lo);
    opt.set_upper_bounds(hi);
    opt.set_min_objective(objective, &p);
    opt.add_inequality_constraint(constraint, &p, 1e-4);
    opt.set_initial_step(std::log(2.0));
    opt.set_xtol_rel(1e-3);
    opt.set_maxeval(options.max_evaluations);
    const double left = std::chrono::duration<double>(deadline - Clock::now()).count();
    // What is left of the bound, less a second for each mechanism still to come: a loaded machine
    // slows one mechanism without cutting the next ones' evaluations short. The bound itself is
    // checked inside the evaluations (Problem::deadline): no floor here.
    const double share = left - 1.0 * double(jobs.size() - j - 1);
    opt.set_maxtime(std::max(std::min(left, 0.5), share));
    double best = 0.0;
    nlopt::result r = nlopt::MAXTIME_REACHED;
    if (left > 0.0 && !tb.out_of_time) {
      try {
        r = opt.optimize(x, best);
      } catch (const nlopt::roundoff_limited&) {
        r = nlopt::ROUNDOFF_LIMITED;
      } catch (const nlopt::forced_stop&) {
        r = Clock::now() >= deadline ? nlopt::MAXTIME_REACHED : nlopt::FORCED_STOP;
      }
    }
    t.stop = stop_text(r);
    t.evaluations = p.evaluations;
    const bool found = !p.best_x.empty();
    if (found) x = p.best_x;  // the best feasible point COBYLA evaluated
    t.after = with(t.before, x);
    t.rho_after = max_spectral_radius(job.poses, t.after, job.loop.delay);
    // The best point was simulated with these very inputs: its tracking is reused, not re-run.
    const Tracking ta = found ? p.best_tracking : track(job.runs, t.after, options.rtol, deadline);
    t.error_after_mm = ta.ok ? ta.error_mm : std::numeric_limits<double>::infinity();
    t.saturation_after = ta.saturation;
    t.feasible = ta.ok && t.rho_after <= options.rho_limit && t.saturation_after <= saturation_limit;
    result.mechanisms.push_back(t);
  }
  result.wall_s = std::chrono::duration<double>(Clock::now() - start).count();
  return result;
}

std::string tuned_patch_yaml(const TuneResult& result) {
  std::string out =
      "# Tuned by fivebar (control --tune, or the control product of run): per mechanism the PID minimising\n"
      "# the worst simulated tracking error over the station's patterns with the loop's spectral radius <= " +
      format::shortest(result.rho_limit) +
      "\n# over the target. Merge into the design's controller: section.\n"
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

Json to_json(const TuneResult& result) {
  Json mechs = Json::array();
  for (const TunedMechanism& t : result.mechanisms) {
    const auto gains = [](const PidGains& g) { return Json{{"kp", g.kp}, {"ki", g.ki}, {"kd", g.kd}, {"i_clamp", g.i_clamp}}; };
    mechs.push_back({{"station", t.station},
                     {"mechanism", t.mechanism},
                     {"start", {{"gains", gains(t.start[0])}, {"gains_theta2", gains(t.start[1])},
                                {"omega_rad_s", t.start_omega_rad_s}, {"max_rho", t.rho_start}}},
                     {"before", {{"gains", gains(t.before[0])}, {"gains_theta2", gains(t.before[1])}, {"max_rho", t.rho_before},
                                 {"max_tracking_error_mm", t.error_before_mm}, {"saturation_fraction", t.saturation_before}}},
                     {"after", {{"gains", gains(t.after[0])}, {"gains_theta2", gains(t.after[1])}, {"max_rho", t.rho_after},
                                {"max_tracking_error_mm", t.error_after_mm}, {"saturation_fraction", t.saturation_after}}},
                     {"design", {{"gains", gains(t.design[0])}, {"gains_theta2", gains(t.design[1])}, {"applied", t.applied()}}},
                     {"evaluations", t.evaluations},
                     {"feasible", t.feasible},
                     {"stop", t.stop}});
  }
  return {{"rho_limit", result.rho_limit}, {"wall_s", result.wall_s}, {"mechanisms", mechs}};
}

std::string tuning_csv(const TuneResult& result) {
  const auto num = [](double v) { return std::isfinite(v) ? format::shortest(v) : std::string(); };
  std::string csv =
      "station,mechanism,kp_before,ki_before,kd_before,kp_after,ki_after,kd_after,max_rho_before,max_rho_after,"
      "max_tracking_error_before_mm,max_tracking_error_after_mm,saturation_before,saturation_after,evaluations,"
      "feasible,applied,stop\n";
  for (const TunedMechanism& t : result.mechanisms) {
    csv += t.station + "," + t.mechanism + "," + num(t.before[0].kp) + "," + num(t.before[0].ki) + "," +
           num(t.before[0].kd) + "," + num(t.after[0].kp) + "," + num(t.after[0].ki) + "," + num(t.after[0].kd) + "," +
           num(t.rho_before) + "," + num(t.rho_after) + "," + num(t.error_before_mm) + "," + num(t.error_after_mm) +
           "," + num(t.saturation_before) + "," + num(t.saturation_after) + "," + std::to_string(t.evaluations) + "," +
           (t.feasible ? "true" : "false") + "," + (t.applied() ? "true" : "false") + "," + t.stop + "\n";
  }
  return csv;
}

}  // namespace fivebar
