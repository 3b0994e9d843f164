// The sampled-data loop (fivebar/control.hpp) against independent references: central finite
// differences of the nonlinear right-hand side the simulation integrates, the closed-form ZOH of a
// first-order plant and of a double integrator, a fine RK4 integration over one period, the loop
// stepped by hand with the device's DiscretePid, and the nonlinear simulation (CVODE) of a small
// step at the worst pose, decaying for the design's gains and growing beyond the kp margin.

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <cmath>
#include <iostream>
#include <fstream>
#include <sstream>
#include <map>
#include <numbers>
#include <tuple>
#include <string>
#include <vector>

#include "simulate/system.hpp"
#include "fivebar/control.hpp"
#include "fivebar/design/file_edit.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/error.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/sections/contact.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/sections/print.hpp"

namespace fivebar {
namespace {


const Design& paper() {
  static const Design d = load_design(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  return d;
}

std::map<std::string, MechanismInertia> paper_inertia(const std::string& station) {
  const Design& d = paper();
  std::map<std::string, MechanismInertia> out;
  for (const Mechanism* m : d.require_station(station).mechanisms()) {
    out[m->name] = closed_form_inertia(*m, *d.get<Geometry>(), *d.get<PrintSettings>());
  }
  return out;
}

LoopModel paper_loop(const std::string& station, const std::string& which) {
  const Design& d = paper();
  for (LoopModel& l : loop_models(d, d.require_station(station), paper_inertia(station))) {
    if (l.model.mechanism.name == which) return l;
  }
  throw std::logic_error("no such mechanism");
}

/// The right-hand side of fivebar/dynamics.hpp (lib/src/simulate/system.cpp) for one mechanism
/// at a state (theta, w, i), the skin anchored at `anchor` (m) and sticking, a held duty.
struct Rhs {
  SimulationInput input;
  SimulationOptions options;
  Vec2 anchor{0.0, 0.0};
  Eigen::Matrix<double, 6, 1> operator()(const Eigen::Matrix<double, 6, 1>& x, const Eigen::Vector2d& duty) const {
    dynamics_detail::System s = dynamics_detail::make_system(input, options);
    s.duty[0] = {duty[0], duty[1]};
    double y[dynamics_detail::kStateSize] = {x[0], x[1], x[2], x[3], x[4], x[5], anchor.x(), anchor.y()};
    const dynamics_detail::Evaluation ev = dynamics_detail::evaluate(s, 0, y);
    EXPECT_TRUE(ev.ok);
    Eigen::Matrix<double, 6, 1> dy;
    for (int k = 0; k < 6; ++k) dy[k] = ev.dy[static_cast<std::size_t>(k)];
    return dy;
  }
};

TEST(Control, LinearPlantIsTheJacobianOfTheSimulatedRightHandSide) {
  const Design& d = paper();
  for (const std::string which : {"lower", "upper"}) {
    SCOPED_TRACE(which);
    LoopModel loop = paper_loop("index", which);
    // Coulomb friction is left out of the linear model (fivebar/control.hpp): out of the reference too.
    for (MotorParams& mp : loop.model.motors) mp.coulomb_friction_mNm = 0.0;
    const Ellipse& e = d.require_station("index").target;
    for (const Vec2& P : {e.center, e.boundary_point(0.7), e.boundary_point(3.9)}) {
      const AnglesResult a = ik_angles(loop.model.mechanism, P);
      ASSERT_EQ(a.status, Status::ok);
      const LinearPlant plant = linear_plant(loop.model, Eigen::Vector2d(a.theta1, a.theta2), &loop.skin);
      ASSERT_EQ(plant.status, Status::ok);
      Rhs f;
      SimulatedMechanism sm;
      sm.name = which;
      sm.model = loop.model;
      f.input.mechanisms.push_back(sm);
      f.input.contact = loop.skin;
      f.anchor = 1e-3 * P;
      Eigen::Matrix<double, 6, 1> x0;
      x0 << a.theta1, a.theta2, 0.0, 0.0, 0.0, 0.0;
      const Eigen::Vector2d u0 = Eigen::Vector2d::Zero();
      EXPECT_LT(f(x0, u0).norm(), 1e-9);  // an equilibrium
      const double h = 1e-6;
      for (int k = 0; k < 6; ++k) {
        Eigen::Matrix<double, 6, 1> dx = Eigen::Matrix<double, 6, 1>::Zero();
        dx[k] = h;
        const Eigen::Matrix<double, 6, 1> col = (f(x0 + dx, u0) - f(x0 - dx, u0)) / (2 * h);
        EXPECT_LT((col - plant.A.col(k)).norm(), 1e-6 * std::max(1.0, col.norm())) << "column " << k << "\n"
                                                                                 << col.transpose() << "\n"
                                                                                 << plant.A.col(k).transpose();
      }
      for (int k = 0; k < 2; ++k) {
        const Eigen::Vector2d du = h * Eigen::Vector2d::Unit(k);
        const Eigen::Matrix<double, 6, 1> col = (f(x0, du) - f(x0, -du)) / (2 * h);
        EXPECT_LT((col - plant.B.col(k)).norm(), 1e-6 * col.norm()) << "input " << k;
      }
    }
  }
}

TEST(Control, ZeroOrderHoldMatchesTheClosedForms) {
  const double T = 0.01;
  // First order dx/dt = a x + b u: Ad = e^{aT}, Bd = (e^{aT} - 1) b / a.
  for (const double a : {-3.0, 0.5, -2000.0}) {
    Eigen::MatrixXd A(1, 1), B(1, 1);
    A << a;
    B << 2.0;
    const auto [Ad, Bd] = zoh(A, B, T);
    EXPECT_NEAR(Ad(0, 0), std::exp(a * T), 1e-14);
    EXPECT_NEAR(Bd(0, 0), (std::exp(a * T) - 1.0) * 2.0 / a, 1e-14);
  }
  // Double integrator: Ad = [1 T; 0 1], Bd = [T^2 / 2; T].
  Eigen::MatrixXd A(2, 2), B(2, 1);
  A << 0, 1, 0, 0;
  B << 0, 1;
  const auto [Ad, Bd] = zoh(A, B, T);
  EXPECT_NEAR(Ad(0, 0), 1.0, 1e-15);
  EXPECT_NEAR(Ad(0, 1), T, 1e-15);
  EXPECT_NEAR(Ad(1, 0), 0.0, 1e-15);
  EXPECT_NEAR(Ad(1, 1), 1.0, 1e-15);
  EXPECT_NEAR(Bd(0, 0), 0.5 * T * T, 1e-16);
  EXPECT_NEAR(Bd(1, 0), T, 1e-15);
}

TEST(Control, DiscretisedPlantAgreesWithAFineIntegrationOverOnePeriod) {
  const LoopModel loop = paper_loop("index", "lower");
  const Vec2 P = paper().require_station("index").target.center;
  const AnglesResult a = ik_angles(loop.model.mechanism, P);
  const LinearPlant plant = linear_plant(loop.model, Eigen::Vector2d(a.theta1, a.theta2), &loop.skin);
  const DiscretePlant dp = discretise(plant, loop.period_s);
  Eigen::Matrix<double, 6, 1> x0;
  x0 << 1e-3, -2e-3, 0.05, 0.02, 0.1, -0.05;
  const Eigen::Vector2d u(0.3, -0.2);
  // Classical RK4 at 1 us (the electrical time constant is 100 us).
  const auto f = [&](const Eigen::Matrix<double, 6, 1>& x) { return (plant.A * x + plant.B * u).eval(); };
  Eigen::Matrix<double, 6, 1> x = x0;
  const int n = 10000;
  const double h = loop.period_s / n;
  for (int k = 0; k < n; ++k) {
    const auto k1 = f(x), k2 = f(x + 0.5 * h * k1), k3 = f(x + 0.5 * h * k2), k4 = f(x + h * k3);
    x += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  const Eigen::Matrix<double, 6, 1> exact = dp.Ad * x0 + dp.Bd * u;
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(exact[k], x[k], 1e-9 * std::max(1.0, std::abs(x[k]))) << k;
}

TEST(Control, ClosedLoopMatrixEqualsSteppingThePlantWithTheDevicesPid) {
  const LoopModel loop = paper_loop("index", "upper");
  const PoseLoop pl = pose_loop(loop, paper().require_station("index").target.center);
  ASSERT_EQ(pl.status, Status::ok);
  std::array<PidGains, 2> gains = loop.gains;
  gains[0] = {4.0, 3.0, 0.07, 1e9};  // joints differ; no integral clamp in the small-signal range
  gains[1] = {6.0, 1.5, 0.03, 1e9};
  for (const bool delay : {true, false}) {
    SCOPED_TRACE(delay ? "delay" : "no delay");
    const LoopMatrix phi = closed_loop(pl.plant, gains, delay);
    Eigen::Matrix<double, 6, 1> x;
    x << 2e-3, -1e-3, 0.0, 0.0, 0.0, 0.0;
    // The loop state at the first sample: nothing applied yet, no integral, previous error = this
    // error (DiscretePid's derivative is 0 at its first sample).
    Eigen::Matrix<double, kLoopStates, 1> z = Eigen::Matrix<double, kLoopStates, 1>::Zero();
    z.head<6>() = x;
    z[10] = -x[0];
    z[11] = -x[1];
    std::array<DiscretePid, 2> pid{DiscretePid(gains[0], pl.plant.period_s), DiscretePid(gains[1], pl.plant.period_s)};
    Eigen::Vector2d pending = Eigen::Vector2d::Zero();
    for (int k = 0; k < 60; ++k) {
      Eigen::Vector2d fresh;
      for (int j = 0; j < 2; ++j) fresh[j] = pid[static_cast<std::size_t>(j)].update(0.0 - x[j]);
      const Eigen::Vector2d applied = delay ? pending : fresh;
      pending = fresh;
      x = pl.plant.Ad * x + pl.plant.Bd * applied;
      z = phi * z;
      ASSERT_LT(fresh.cwiseAbs().maxCoeff(), 1.0);  // the duty clamp stays inactive
      for (int i = 0; i < 6; ++i) EXPECT_NEAR(z[i], x[i], 1e-12 + 1e-9 * x.cwiseAbs().maxCoeff()) << k << " " << i;
      EXPECT_NEAR(z[8], pid[0].integral(), 1e-12);
      EXPECT_NEAR(z[9], pid[1].integral(), 1e-12);
    }
  }
}

TEST(Control, DampingAndFrequencyOfTheDominantPoleComeFromItsLogarithm) {
  // A loop matrix whose eigenvalues are known: a rotation-scaling block r (cos a, -sin a; sin a, cos a).
  LoopMatrix phi = LoopMatrix::Zero();
  const double r = 0.9, ang = 0.3, T = 0.01;
  phi(0, 0) = phi(1, 1) = r * std::cos(ang);
  phi(0, 1) = -r * std::sin(ang);
  phi(1, 0) = r * std::sin(ang);
  phi(2, 2) = 0.5;
  const LoopPoles p = loop_poles(phi, T);
  EXPECT_NEAR(p.rho, r, 1e-14);
  const double sr = std::log(r) / T, si = ang / T;
  EXPECT_NEAR(p.damping, -sr / std::hypot(sr, si), 1e-12);
  EXPECT_NEAR(p.frequency_hz, si / (2 * std::numbers::pi), 1e-9);
  EXPECT_NEAR(p.oscillatory_damping, p.damping, 1e-12);
  // A slower real pole (an integrator's) dominates; the oscillation is still reported.
  phi(3, 3) = 0.95;
  const LoopPoles q = loop_poles(phi, T);
  EXPECT_NEAR(q.rho, 0.95, 1e-14);
  EXPECT_NEAR(q.damping, 1.0, 1e-12);
  EXPECT_NEAR(q.frequency_hz, 0.0, 1e-9);
  EXPECT_NEAR(q.oscillatory_damping, -sr / std::hypot(sr, si), 1e-12);
  EXPECT_NEAR(q.oscillatory_frequency_hz, si / (2 * std::numbers::pi), 1e-9);
}

/// A small step of one mechanism's tactor at P (mm) simulated by CVODE with `gains`: the largest
/// joint error over the first and the last `window` seconds, relative to the step's.
struct StepResponse {
  SimStatus status;
  double initial = 0.0;  ///< joint error of the step, rad
  double late = 0.0;     ///< largest joint error over the last window, rad
};

StepResponse simulate_step(const LoopModel& loop, const Vec2& P, const std::array<PidGains, 2>& gains) {
  const Design& d = paper();
  SimulationInput in;
  in.station = loop.station;
  in.reference_name = "step";
  in.controller = *d.get<ControllerSettings>();
  in.contact = loop.skin;
  SimulatedMechanism sm;
  sm.name = loop.model.mechanism.name;
  sm.model = loop.model;
  sm.control[0].pid = gains[0];
  sm.control[1].pid = gains[1];
  const AnglesResult a0 = ik_angles(loop.model.mechanism, P);
  const Vec2 target = P + Vec2(0.05, 0.0);
  const AnglesResult a1 = ik_angles(loop.model.mechanism, target);
  EXPECT_EQ(a0.status, Status::ok);
  EXPECT_EQ(a1.status, Status::ok);
  const std::size_t n = 150;  // 1.5 s at 100 Hz
  sm.reference.assign(n, {a1.theta1, a1.theta2});
  sm.reference.front() = {a0.theta1, a0.theta2};
  sm.reference_point_mm.assign(n, target);
  sm.reference_point_mm.front() = P;
  sm.theta0 = {a0.theta1, a0.theta2};
  in.mechanisms.push_back(sm);
  SimulationOptions o;
  o.quantise = false;
  o.settle_s = 0.0;
  o.max_wall_s = 20.0;
  const SimulationResult r = simulate(in, o);
  StepResponse out;
  out.status = r.status;
  out.initial = std::max(std::abs(a1.theta1 - a0.theta1), std::abs(a1.theta2 - a0.theta2));
  for (const TimeSample& s : r.samples) {
    if (s.t < r.t_end - 0.3) continue;
    const MechanismSample& m = s.mechanisms[0];
    out.late = std::max({out.late, std::abs(m.theta[0] - m.theta_ref[0]), std::abs(m.theta[1] - m.theta_ref[1])});
  }
  return out;
}

TEST(Control, TheVerdictAgreesWithTheNonlinearSimulationOfAStepAtTheWorstPose) {
  const Design& d = paper();
  const LoopModel loop = paper_loop("index", "lower");
  const StabilityMap map = stability_map(loop, ellipse_lattice(d.require_station("index").target, 15));
  ASSERT_EQ(map.not_ok, 0u);
  ASSERT_TRUE(map.stable) << map.max_rho;
  ASSERT_GT(map.kp_margin, 1.0);
  const Vec2 worst = map.worst_P_mm();
  // The margin is where max rho crosses 1.
  std::array<PidGains, 2> below = loop.gains, above = loop.gains;
  for (int j = 0; j < 2; ++j) {
    below[static_cast<std::size_t>(j)].kp *= map.kp_margin * 0.99;
    above[static_cast<std::size_t>(j)].kp *= map.kp_margin * 1.01;
  }
  EXPECT_LT(max_spectral_radius(map.poses, below, true), 1.0);
  EXPECT_GE(max_spectral_radius(map.poses, above, true), 1.0);

  // The design's gains: the step settles.
  const StepResponse ok = simulate_step(loop, worst, loop.gains);
  ASSERT_EQ(ok.status, SimStatus::ok);
  EXPECT_LT(ok.late, 0.05 * ok.initial);
  // 30 % beyond the kp margin: the linear verdict says unstable; the simulation grows (or leaves
  // the workspace trying).
  std::array<PidGains, 2> unstable = loop.gains;
  for (PidGains& g : unstable) g.kp *= 1.3 * map.kp_margin;
  ASSERT_GT(max_spectral_radius(map.poses, unstable, true), 1.0);
  const StepResponse bad = simulate_step(loop, worst, unstable);
  if (bad.status == SimStatus::ok) EXPECT_GT(bad.late, 2.0 * bad.initial);
}

TEST(Control, TheKdMarginBoundsTheDerivativeGainBothWays) {
  const Design& d = paper();
  const LoopModel loop = paper_loop("index", "upper");
  const StabilityMap map = stability_map(loop, ellipse_lattice(d.require_station("index").target, 11));
  ASSERT_TRUE(map.stable);
  ASSERT_GT(map.kd_margin, 0.0);
  ASSERT_LT(map.kd_margin, StabilityOptions{}.margin_cap);
  std::array<PidGains, 2> g = loop.gains;
  for (PidGains& x : g) x.kd *= 1.2 * map.kd_margin;
  EXPECT_GT(max_spectral_radius(map.poses, g, true), 1.0);
  const StepResponse bad = simulate_step(loop, map.worst_P_mm(), g);
  if (bad.status == SimStatus::ok) EXPECT_GT(bad.late, 2.0 * bad.initial);
}

TEST(ControlTune, TheTimeBoundIsCheckedInsideTheEvaluations) {
  // docs/reliability.md: --tune-seconds 0.5 took 3.8-8 s: each mechanism got at least 0.5 s of
  // COBYLA, and the tracking before and after ran outside the bound. Now the bound is checked
  // before every evaluation and between the pattern runs of one: a bound already spent allows no
  // evaluation, whatever the evaluation count allows, and the result says the time limit stopped it.
  const Design& d = paper();
  const Station& index = d.require_station("index");
  TuneOptions o;
  o.max_evaluations = 1000;
  o.max_seconds = 1e-9;
  std::map<std::string, std::map<std::string, MechanismInertia>> inertia{{"index", paper_inertia("index")}};
  const TuneResult r = tune_controller(d, {&index}, inertia, o);
  ASSERT_EQ(r.mechanisms.size(), 2u);
  for (const TunedMechanism& t : r.mechanisms) {
    SCOPED_TRACE(t.mechanism);
    EXPECT_EQ(t.evaluations, 0);
    EXPECT_EQ(t.stop, "time limit");
    EXPECT_FALSE(t.feasible);  // nothing measured: no claim
    // The bound covers the figures too (docs/control.md "The budget"): none simulated, each named,
    // and the design's gains kept to the last bit.
    EXPECT_FALSE(t.improved);
    EXPECT_TRUE(std::isnan(t.error_before_mm));
    EXPECT_TRUE(std::isnan(t.error_after_mm));
    EXPECT_TRUE(std::isnan(t.chirp_bandwidth_after_hz));
    EXPECT_TRUE(std::isnan(t.kp_margin_after));
    EXPECT_EQ(t.simulated_before_s, 0.0);
    EXPECT_GT(t.patterns_s, 1.0);
    EXPECT_EQ(t.not_computed_after, (std::vector<std::string>{"tracking", "margins", "step", "chirp"}));
    for (std::size_t j = 0; j < 2; ++j) {
      EXPECT_EQ(t.after[j].kp, t.design[j].kp);
      EXPECT_EQ(t.after[j].ki, t.design[j].ki);
      EXPECT_EQ(t.after[j].kd, t.design[j].kd);
    }
  }
}

TEST(ControlTune, DeterministicWithinTheConstraintAndItsPatchReadsBackAsTheTunedGains) {
  const Design& d = paper();
  const Station& index = d.require_station("index");
  TuneOptions o;
  o.start = TuneStart::pole_placement;
  o.max_evaluations = 8;
  o.max_seconds = 120.0;  // the evaluation count stops it: deterministic
  // Eight evaluations do not reach the damping and margin floors from the pole placement (the
  // showcase's full tuning does: TunedShowcaseMeetsTheFloors... below); the floors off here.
  o.min_damping = 0.0;
  o.min_gain_margin = 1.0;
  std::map<std::string, std::map<std::string, MechanismInertia>> inertia{{"index", paper_inertia("index")}};
  const TuneResult a = tune_controller(d, {&index}, inertia, o);
  const TuneResult b = tune_controller(d, {&index}, inertia, o);
  ASSERT_EQ(a.mechanisms.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    const TunedMechanism& t = a.mechanisms[k];
    SCOPED_TRACE(t.mechanism);
    EXPECT_EQ(t.after[0].kp, b.mechanisms[k].after[0].kp);
    EXPECT_EQ(t.after[0].ki, b.mechanisms[k].after[0].ki);
    EXPECT_EQ(t.after[0].kd, b.mechanisms[k].after[0].kd);
    EXPECT_EQ(t.evaluations, 8);
    EXPECT_EQ(t.after[0].i_clamp, t.before[0].i_clamp);
    // The figures after are those of the gains after, recomputed independently here.
    const LoopModel loop = paper_loop("index", t.mechanism);
    std::vector<PoseLoop> poses;
    for (const Vec2& P : ellipse_lattice(index.target, o.grid)) poses.push_back(pose_loop(loop, P));
    EXPECT_NEAR(max_spectral_radius(poses, t.after, true), t.rho_after, 1e-12);
    EXPECT_NEAR(max_spectral_radius(poses, t.before, true), t.rho_before, 1e-12);
    EXPECT_EQ(t.feasible, t.rho_after <= o.rho_limit && t.saturation_after <= d.get<ControllerSettings>()->max_saturation_fraction &&
                              t.damping_after >= o.min_damping && t.kp_margin_after >= o.min_gain_margin &&
                              t.kd_margin_after >= o.min_gain_margin &&
                              t.overshoot_after_mm <= a.max_overshoot_fraction * SimulationRequest{}.step_mm);
    // Started from the pole placement, which already meets the constraint on the showcase: the
    // result is the best feasible point evaluated, so it meets it too, on the export gate's grid.
    EXPECT_EQ(o.grid, kControlGateGrid);
    EXPECT_LT(t.rho_start, o.rho_limit);
    EXPECT_GT(t.start_omega_rad_s, 0.0);
    EXPECT_TRUE(t.feasible);
    EXPECT_LE(t.error_after_mm, t.error_before_mm);
    // "before" is the design's own pid (the showcase's station scopes), whatever the start; the
    // result is the design's gains exactly unless it beat them.
    EXPECT_EQ(t.before[0].kp, loop.gains[0].kp);
    EXPECT_EQ(t.design[0].kp, loop.gains[0].kp);
    if (!t.improved) EXPECT_EQ(t.after[0].kp, loop.gains[0].kp);
    if (t.improved) EXPECT_LT(t.objective_after_mm, t.objective_before_mm);
  }
  // The patch, merged into the design file, gives each mechanism the tuned gains on both joints.
  const std::string patch = tuned_patch_yaml(a);
  std::ifstream in(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string design = text.str();
  const std::size_t stations = patch.find("  stations:\n");
  ASSERT_NE(stations, std::string::npos);
  // The showcase's own station scopes (an earlier tuning) out first: the patch replaces them.
  const std::size_t own = design.find("  stations:\n    index:\n      lower: {pid:");
  ASSERT_NE(own, std::string::npos);
  design.erase(own, design.find("\n\n", own) + 1 - own);
  const std::size_t end = design.find("\n# The motors and drivers");
  ASSERT_NE(end, std::string::npos);
  design.insert(end + 1, patch.substr(stations));
  const Design merged = load_design_from_string(design, "merged.yaml");
  for (const TunedMechanism& t : a.mechanisms) {
    for (int j = 1; j <= 2; ++j) {
      const PidGains g = merged.get<ControllerSettings>()->joint("index", t.mechanism, j).pid;
      EXPECT_EQ(g.kp, t.after[0].kp);
      EXPECT_EQ(g.ki, t.after[0].ki);
      EXPECT_EQ(g.kd, t.after[0].kd);
    }
    const PidGains other = merged.get<ControllerSettings>()->joint("thumb", t.mechanism, 1).pid;
    EXPECT_EQ(other.kp, d.get<ControllerSettings>()->pid.kp);  // the other station: its own (hand-set) gains
  }
}

TEST(ControlPerformance, TactorGainEqualsTheSteadyStateOfTheLoopSteppedByHand) {
  LoopModel loop = paper_loop("index", "lower");
  for (PidGains& g : loop.gains) g = {6.5, 40.0, 0.19, 1e9};  // a faster integrator: short transients
  const Vec2 P = paper().require_station("index").target.center + Vec2(1.0, -2.0);
  const AnglesResult a = ik_angles(loop.model.mechanism, P);
  const LinearPlant plant = linear_plant(loop.model, Eigen::Vector2d(a.theta1, a.theta2), &loop.skin);
  const DiscretePlant dp = discretise(plant, loop.period_s);
  const double T = loop.period_s, f = 5.0, w = 2 * std::numbers::pi * f;
  // H(:, c) from a sine on joint c's reference, stepped with DiscretePid and the one-period delay.
  Eigen::Matrix2cd H;
  for (int c = 0; c < 2; ++c) {
    std::array<DiscretePid, 2> pid{DiscretePid(loop.gains[0], T), DiscretePid(loop.gains[1], T)};
    Eigen::Matrix<double, 6, 1> x = Eigen::Matrix<double, 6, 1>::Zero();
    Eigen::Vector2d pending = Eigen::Vector2d::Zero();
    const int n = 6000, keep = 2000;  // 100 periods kept after the transient
    Eigen::Vector2cd acc = Eigen::Vector2cd::Zero();
    for (int k = 0; k < n; ++k) {
      const double r = 1e-3 * std::sin(w * k * T);
      if (k >= n - keep) acc += x.head<2>().cast<std::complex<double>>() * std::polar(1.0, -w * k * T);
      Eigen::Vector2d fresh;
      for (int j = 0; j < 2; ++j) fresh[j] = pid[std::size_t(j)].update((j == c ? r : 0.0) - x[j]);
      x = dp.Ad * x + dp.Bd * pending;
      pending = fresh;
    }
    // sin has the complex amplitude -j: X = H (-j) 1e-3.
    H.col(c) = (2.0 / keep) * acc / (std::complex<double>(0.0, -1.0) * 1e-3);
  }
  const Eigen::Matrix2cd Ht = plant.J.cast<std::complex<double>>() * H * plant.J.inverse().cast<std::complex<double>>();
  const Eigen::JacobiSVD<Eigen::Matrix2cd> svd(Ht);
  const std::array<double, 2> g = tactor_gain(dp, loop.gains, true, plant.J, f);
  EXPECT_NEAR(g[0], svd.singularValues()[1], 1e-6);
  EXPECT_NEAR(g[1], svd.singularValues()[0], 1e-6);
  // At zero frequency the integral makes the loop exact: unit gain in every direction.
  const std::array<double, 2> dc = tactor_gain(dp, loop.gains, true, plant.J, 0.0);
  EXPECT_NEAR(dc[0], 1.0, 1e-9);
  EXPECT_NEAR(dc[1], 1.0, 1e-9);
}

TEST(ControlPerformance, ResolutionForceAndZWidthAgreeWithFiniteDifferencesOfTheKinematics) {
  const Design& d = paper();
  const LoopModel loop = paper_loop("index", "upper");
  const ControllerSettings& c = *d.get<ControllerSettings>();
  const std::array<Potentiometer, 2> pots{c.joint("index", "upper", 1).potentiometer, c.joint("index", "upper", 2).potentiometer};
  const Vec2 P = d.require_station("index").target.center + Vec2(-1.5, 1.0);
  const PoseFigures f = pose_figures(loop, P, c.adc_bits, c.adc_range_v, pots);
  ASSERT_EQ(f.status, Status::ok);
  const AnglesResult a = ik_angles(loop.model.mechanism, P);
  // J by central differences of FK (mm/rad -> m/rad).
  Eigen::Matrix2d J;
  const double h = 1e-6;
  for (int j = 0; j < 2; ++j) {
    const double d1 = j == 0 ? h : 0.0, d2 = j == 1 ? h : 0.0;
    const Vec2 p = fk_point(loop.model.mechanism, a.theta1 + d1, a.theta2 + d2).P;
    const Vec2 m = fk_point(loop.model.mechanism, a.theta1 - d1, a.theta2 - d2).P;
    J.col(j) = 1e-3 * (p - m) / (2 * h);
  }
  // Resolution: the tactor's move for one count on the worse joint, by FK.
  double step_um = 0.0;
  for (int j = 0; j < 2; ++j) {
    const double count = std::abs(pots[std::size_t(j)].rad_per_volt) * (c.adc_range_v[1] - c.adc_range_v[0]) / 65536.0;
    const Vec2 p0 = fk_point(loop.model.mechanism, a.theta1, a.theta2).P;
    const Vec2 p1 = fk_point(loop.model.mechanism, a.theta1 + (j == 0 ? count : 0.0), a.theta2 + (j == 1 ? count : 0.0)).P;
    step_um = std::max(step_um, 1e3 * (p1 - p0).norm());
  }
  EXPECT_NEAR(f.resolution_um, step_um, 1e-3 * step_um);
  // Force in every direction: the worst of 3600 directions of min_j tau_j / |J_j . u|.
  double worst = 1e300;
  for (int k = 0; k < 3600; ++k) {
    const Vec2 u(std::cos(k * std::numbers::pi / 3600), std::sin(k * std::numbers::pi / 3600));
    double fu = 1e300;
    for (int j = 0; j < 2; ++j) {
      const MotorParams& mp = loop.model.motors[std::size_t(j)];
      const double tau = mp.gearbox_efficiency * mp.gear_ratio * mp.torque_constant() * mp.current_limit_A;
      fu = std::min(fu, tau / std::abs(J.col(j).dot(u)));
    }
    worst = std::min(worst, fu);
  }
  EXPECT_NEAR(f.force_N, worst, 1e-4 * worst);
  // Z-width: the least tactor damping over 3600 directions, b(u) = min over F . u for unit speed along u.
  double bmin = 1e300;
  Eigen::Matrix2d Bj = Eigen::Matrix2d::Zero();
  for (int j = 0; j < 2; ++j) {
    const MotorParams& mp = loop.model.motors[std::size_t(j)];
    Bj(j, j) = mp.viscous_friction() + mp.gearbox_efficiency * mp.gear_ratio * mp.gear_ratio * mp.torque_constant() *
                                           mp.back_emf_constant() / mp.resistance();
  }
  for (int k = 0; k < 3600; ++k) {
    const Vec2 u(std::cos(k * std::numbers::pi / 3600), std::sin(k * std::numbers::pi / 3600));
    const Eigen::Vector2d wdot = J.inverse() * u;           // joint rates for unit tactor speed along u
    bmin = std::min(bmin, wdot.dot(Bj * wdot));             // power dissipated = b(u)
  }
  EXPECT_NEAR(f.damping_N_s_per_mm, 1e-3 * bmin, 1e-4 * 1e-3 * bmin);
  EXPECT_NEAR(f.zwidth_N_per_mm, 2.0 * f.damping_N_s_per_mm / loop.period_s, 1e-9);
}

TEST(Control, EllipseGridStaysInsideAndHoldsTheCentre) {
  Ellipse e;
  e.center = {3.0, -2.0};
  e.axes = {10.0, 4.0};
  e.angle = 0.4;
  const std::vector<Vec2> pts = ellipse_lattice(e, 21);
  bool centre = false;
  for (const Vec2& p : pts) {
    const Vec2 q = p - e.center;
    const double u = (std::cos(e.angle) * q.x() + std::sin(e.angle) * q.y()) / 5.0;
    const double v = (-std::sin(e.angle) * q.x() + std::cos(e.angle) * q.y()) / 2.0;
    EXPECT_LE(u * u + v * v, 1.0 + 1e-12);
    centre = centre || q.norm() < 1e-12;
  }
  EXPECT_TRUE(centre);
  // About one point per cell of the 20 x 20 cells over the box, pi/4 of them: pi 10^2.
  EXPECT_NEAR(double(pts.size()), 100 * std::numbers::pi, 8.0);
}


// The pole placement against an independent reduced model: m, c, k, b of each joint from the
// dynamics' mass matrix and Jacobian, the skin and the motors' data (not from the linear plant's
// rows, which the library reads), and the closed loop (theta, w, int theta) of the continuous PID,
// whose three eigenvalues must sit at -omega.
TEST(ControlTune, PolePlacementPutsEachJointsThreeRootsAtMinusOmega) {
  const Design& d = paper();
  const LoopModel loop = paper_loop("thumb", "lower");
  const Vec2 centre = d.require_station("thumb").target.center;
  const AnglesResult a = ik_angles(loop.model.mechanism, centre);
  ASSERT_EQ(a.status, Status::ok);
  const Eigen::Vector2d theta(a.theta1, a.theta2);
  const LinearPlant plant = linear_plant(loop.model, theta, &loop.skin);
  ASSERT_EQ(plant.status, Status::ok);
  const DynamicsTerms t = dynamics_terms(loop.model, theta, Eigen::Vector2d::Zero());
  const Eigen::Matrix2d JtJ = t.J.transpose() * t.J;
  std::array<double, 2> m{}, c{}, k{}, b{};
  for (int j = 0; j < 2; ++j) {
    const MotorParams& mp = loop.model.motors[std::size_t(j)];
    m[std::size_t(j)] = t.M(j, j);
    k[std::size_t(j)] = 1e3 * loop.skin.shear_stiffness_N_per_mm * JtJ(j, j);
    // Settled current i = (V u - k_e N w) / R: torque eta N k_t i.
    c[std::size_t(j)] = 1e3 * loop.skin.damping_N_s_per_mm * JtJ(j, j) + mp.viscous_friction() +
                        mp.gearbox_efficiency * mp.gear_ratio * mp.torque_constant() * mp.back_emf_constant() *
                            mp.gear_ratio / mp.resistance();
    b[std::size_t(j)] = mp.gearbox_efficiency * mp.gear_ratio * mp.torque_constant() * mp.supply_voltage_V / mp.resistance();
  }
  const std::array<PidGains, 2> base{PidGains{}, PidGains{}};
  for (const double omega : {30.0, 60.0}) {
    SCOPED_TRACE(omega);
    const std::array<PidGains, 2> g = pole_placement_gains(plant, loop.model.motors, omega, /*per_joint=*/true, base);
    for (std::size_t j = 0; j < 2; ++j) {
      Eigen::Matrix3d A;
      A << 0.0, 1.0, 0.0,  //
          -(k[j] + b[j] * g[j].kp) / m[j], -(c[j] + b[j] * g[j].kd) / m[j], -b[j] * g[j].ki / m[j],  //
          1.0, 0.0, 0.0;
      const Eigen::Vector3cd ev = A.eigenvalues();
      // A triple root moves by ~eps^(1/3) under rounding: 1e-3 of omega.
      for (int r = 0; r < 3; ++r) EXPECT_NEAR(std::abs(ev[r] + omega), 0.0, 1e-3 * omega) << "joint " << j + 1;
      EXPECT_EQ(g[j].i_clamp, base[j].i_clamp);
    }
    // One set for both joints: the joints' means.
    const std::array<PidGains, 2> one = pole_placement_gains(plant, loop.model.motors, omega, false, base);
    const double mm = 0.5 * (m[0] + m[1]), cm = 0.5 * (c[0] + c[1]), km = 0.5 * (k[0] + k[1]), bm = 0.5 * (b[0] + b[1]);
    for (std::size_t j = 0; j < 2; ++j) {
      EXPECT_NEAR(one[j].kp, (3 * mm * omega * omega - km) / bm, 1e-9 * one[j].kp);
      EXPECT_NEAR(one[j].ki, mm * omega * omega * omega / bm, 1e-9 * one[j].ki);
      EXPECT_NEAR(one[j].kd, (3 * mm * omega - cm) / bm, 1e-9 * one[j].kd);
    }
  }
  // The chosen omega: no omega of a fine scan gives a smaller max rho over the poses (to 1e-3).
  std::vector<PoseLoop> poses;
  for (const Vec2& P : ellipse_lattice(d.require_station("thumb").target, 9)) poses.push_back(pose_loop(loop, P));
  const PolePlacement pp = pole_placement(loop, centre, poses, false, base);
  ASSERT_EQ(pp.status, Status::ok);
  EXPECT_NEAR(max_spectral_radius(poses, pp.gains, true), pp.max_rho, 1e-12);
  double scan = 1e300;
  for (int i = 0; i <= 400; ++i) {
    const double omega = 2.0 * std::numbers::pi * 0.2 * std::pow(125.0, i / 400.0);
    scan = std::min(scan, max_spectral_radius(poses, pole_placement_gains(plant, loop.model.motors, omega, false, base), true));
  }
  EXPECT_LE(pp.max_rho, scan + 1e-3);
}

/// The showcase's text with the index mechanisms' gains set through the design-edit API (the numbers
/// of `controller.stations.index.<m>.pid`), and the design it loads.
std::string showcase_text() {
  std::ifstream in(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}
Design showcase_with_index_gains(const PidGains& lower, const PidGains& upper) {
  std::vector<FileEdit> edits;
  for (const auto& [m, g] : {std::pair<std::string, PidGains>{"lower", lower}, {"upper", upper}}) {
    const std::string key = "controller.stations.index." + m + ".pid.";
    edits.push_back({key + "kp", g.kp});
    edits.push_back({key + "ki", g.ki});
    edits.push_back({key + "kd", g.kd});
  }
  return load_design_from_string(edit_design_text(showcase_text(), "spoilt.yaml", edits), "spoilt.yaml");
}

/// The tuner's objective of one index mechanism under `gains`, computed here from the simulation
/// alone (each pattern run with this mechanism, as the objective is defined): the worst tracking
/// error plus 10 mm per unit of saturated-time fraction beyond the design's limit.
double simulated_objective(const Design& d, const std::string& mechanism, const std::array<PidGains, 2>& gains, double rtol) {
  SimulationRequest rq;
  rq.station = "index";
  const std::size_t k = mechanism == "lower" ? 0 : 1;
  double error = 0.0, saturation = 0.0;
  for (SimulationInput in : simulation_inputs(d, rq, paper_inertia("index"))) {
    in.mechanisms = {in.mechanisms[k]};
    in.mechanisms[0].control[0].pid = gains[0];
    in.mechanisms[0].control[1].pid = gains[1];
    SimulationOptions so;
    so.rtol = rtol;
    so.record = false;
    const SimulationResult r = simulate(in, so);
    EXPECT_TRUE(r.ok()) << r.reason;
    error = std::max(error, r.summary.at(0).max_error_mm);
    saturation = std::max(saturation, r.summary.at(0).saturation_s / r.t_end);
  }
  return error + 10.0 * std::max(0.0, saturation - d.get<ControllerSettings>()->max_saturation_fraction);
}

// docs/control.md: the search starts from the design's gains; from spoilt ones (the showcase's
// ki and kd, kp 5.5 instead of 6.4: every floor met, the tracking worse) it improves until COBYLA
// converges, and the simulation, run here, confirms the result's objective is below the start's.
// Tuned again from the result (the tuner's optimum), no candidate beats it: it comes back to the
// last bit.
TEST(ControlTune, ABadStartImprovesAndGainsAtTheOptimumComeBackUnchanged) {
  const PidGains spoilt{5.5, 62.45, 0.1132, 0.2};
  const Design d = showcase_with_index_gains(spoilt, spoilt);
  const Station& index = d.require_station("index");
  TuneOptions o = tune_options(*d.get<ControllerSettings>());
  ASSERT_EQ(o.start, TuneStart::design);
  o.max_evaluations = 200;  // COBYLA converges first (about 40 evaluations here)
  o.max_seconds = 3600.0;
  std::map<std::string, std::map<std::string, MechanismInertia>> inertia{{"index", paper_inertia("index")}};
  const TuneResult r = tune_controller(d, {&index}, inertia, o);
  ASSERT_EQ(r.mechanisms.size(), 2u);
  for (const TunedMechanism& t : r.mechanisms) {
    SCOPED_TRACE(t.mechanism);
    for (std::size_t j = 0; j < 2; ++j) {
      EXPECT_EQ(t.start[j].kp, spoilt.kp);  // the design's gains, per joint
      EXPECT_EQ(t.before[j].ki, spoilt.ki);
      EXPECT_EQ(t.before[j].kd, spoilt.kd);
    }
    EXPECT_EQ(t.stop, "converged");
    ASSERT_TRUE(t.improved);
    EXPECT_TRUE(t.feasible);
    const double before = simulated_objective(d, t.mechanism, t.before, o.rtol);
    const double after = simulated_objective(d, t.mechanism, t.after, o.rtol);
    std::cout << t.mechanism << ": objective " << before << " -> " << after << " mm, kp " << t.after[0].kp << " ki "
              << t.after[0].ki << " kd " << t.after[0].kd << ", " << t.evaluations << " evaluations\n";
    EXPECT_LT(after, before);
    // Both admissible (every floor met, the step within its bound): the objective is the tracking.
    EXPECT_NEAR(before, t.objective_before_mm, 1e-9);
    EXPECT_NEAR(after, t.objective_after_mm, 1e-9);
  }
  // The result as the design's gains: tuned again with the same options, it is kept exactly.
  const Design at_optimum = showcase_with_index_gains(r.mechanisms[0].after[0], r.mechanisms[1].after[0]);
  const TuneResult again = tune_controller(at_optimum, {&at_optimum.require_station("index")}, inertia, o);
  ASSERT_EQ(again.mechanisms.size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    const TunedMechanism& t = again.mechanisms[k];
    SCOPED_TRACE(t.mechanism);
    EXPECT_GT(t.evaluations, 1);
    EXPECT_FALSE(t.improved);
    for (std::size_t j = 0; j < 2; ++j) {
      EXPECT_EQ(t.after[j].kp, r.mechanisms[k].after[0].kp);
      EXPECT_EQ(t.after[j].ki, r.mechanisms[k].after[0].ki);
      EXPECT_EQ(t.after[j].kd, r.mechanisms[k].after[0].kd);
    }
    EXPECT_EQ(t.objective_after_mm, t.objective_before_mm);
    EXPECT_NEAR(t.objective_before_mm, r.mechanisms[k].objective_after_mm, 1e-12);  // the same figure, re-simulated
  }
}

// The merge's edits (gain_merge) give the tuned mechanisms their gains and leave every other joint's;
// a number shared with a joint that was not tuned is refused, not edited.
TEST(ControlTune, MergeEditsSetTheTunedGainsAndRefuseASharedNumber) {
  const Design& d = paper();
  TuneResult r;
  TunedMechanism t;
  t.station = "index";
  t.mechanism = "upper";
  t.design = t.before = paper_loop("index", "upper").gains;
  t.after = t.before;
  t.after[0].kp = t.after[1].kp = 7.25;
  t.after[0].ki = t.after[1].ki = 55.5;
  t.rho_after = 0.85;
  t.error_after_mm = 0.2;
  t.damping_after = 0.4;
  t.kp_margin_after = t.kd_margin_after = 3.0;
  t.feasible = t.improved = true;
  r.mechanisms.push_back(t);
  r.max_overshoot_fraction = 0.37;
  const GainMerge m = gain_merge(d, r);
  EXPECT_TRUE(m.refusals.empty()) << m.refusals.front();
  ASSERT_EQ(m.edits.size(), 2u);  // kp and ki of stations.index.upper; kd unchanged
  EXPECT_EQ(m.edits[0].key, "controller.stations.index.upper.pid.kp");
  const Design merged = load_design_from_string(edit_design_text(showcase_text(), "m.yaml", m.edits), "m.yaml");
  const ControllerSettings& c = *merged.get<ControllerSettings>();
  for (int j = 1; j <= 2; ++j) {
    EXPECT_EQ(c.joint("index", "upper", j).pid.kp, 7.25);
    EXPECT_EQ(c.joint("index", "upper", j).pid.ki, 55.5);
    EXPECT_EQ(c.joint("index", "upper", j).pid.kd, t.before[0].kd);
    EXPECT_EQ(c.joint("index", "lower", j).pid.kp, d.get<ControllerSettings>()->joint("index", "lower", j).pid.kp);
  }
  // Without the station scopes every joint's gains are controller.pid's: the index's tuned gains
  // would change the thumb's too.
  Design shared = d;
  auto& overrides = shared.get<ControllerSettings>()->overrides;
  std::erase_if(overrides, [](const ControlOverride& o) { return o.level() >= 3 && o.kp; });
  const GainMerge refused = gain_merge(shared, r);
  ASSERT_FALSE(refused.refusals.empty());
  EXPECT_NE(refused.refusals.front().find("controller.pid.kp"), std::string::npos) << refused.refusals.front();
  // A tuned loop that misses the export gate's tracking check is refused whatever the keys.
  r.mechanisms[0].error_after_mm = 2.0;
  const GainMerge gate = gain_merge(d, r);
  ASSERT_EQ(gate.refusals.size(), 1u);
  EXPECT_NE(gate.refusals[0].find("max_tracking_error_mm"), std::string::npos) << gate.refusals[0];
}

// A per-joint result writes theta1 / theta2 scopes, which read back as each joint's gains, and the
// hand-set gains leave out exactly the scopes a patch writes.
TEST(ControlTune, PerJointPatchReadsBackPerJointAndHandSetGainsLeaveThePatchOut) {
  TuneResult r;
  TunedMechanism t;
  t.station = "thumb";
  t.mechanism = "upper";
  t.after[0] = {7.5, 150.0, 0.15, 0.2};
  t.after[1] = {8.25, 175.0, 0.125, 0.2};
  t.feasible = true;
  r.mechanisms.push_back(t);
  const std::string patch = tuned_patch_yaml(r);
  EXPECT_NE(patch.find("upper: {theta1: {pid: {kp: 7.5, ki: 150, kd: 0.15}}, theta2: {pid: {kp: 8.25, ki: 175, kd: 0.125}}}"),
            std::string::npos)
      << patch;
  std::ifstream in(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string design = text.str();
  // After the controller's last line (its station scopes), as more of thumb's scopes.
  const std::string thumb = "    thumb:\n";
  const std::size_t at = design.find(thumb, design.find("\ncontroller:"));
  ASSERT_NE(at, std::string::npos);
  const std::size_t line = patch.find("      upper: {theta1");
  design.insert(design.find("\n\n", at) + 1, patch.substr(line, patch.find('\n', line) + 1 - line));
  // The thumb already has an `upper:` key (the showcase's tuning): keep the joints' scopes only.
  const std::size_t dup = design.find("      upper: {pid:", at);
  ASSERT_NE(dup, std::string::npos);
  design.erase(dup, design.find('\n', dup) + 1 - dup);
  const Design merged = load_design_from_string(design, "merged.yaml");
  const ControllerSettings& c = *merged.get<ControllerSettings>();
  for (int j = 1; j <= 2; ++j) {
    const PidGains g = c.joint("thumb", "upper", j).pid;
    EXPECT_EQ(g.kp, t.after[std::size_t(j - 1)].kp);
    EXPECT_EQ(g.ki, t.after[std::size_t(j - 1)].ki);
    EXPECT_EQ(g.kd, t.after[std::size_t(j - 1)].kd);
    const PidGains h = c.hand_set_pid("thumb", "upper", j);
    EXPECT_EQ(h.kp, c.pid.kp);
    EXPECT_EQ(h.ki, c.pid.ki);
    EXPECT_EQ(h.kd, c.pid.kd);
  }
  // A wider scope's gains are hand-set: kept.
  ControllerSettings wide = c;
  ControlOverride o;
  o.mechanism = "upper";
  o.joint = 2;
  o.kp = 3.0;
  wide.overrides.push_back(o);
  EXPECT_EQ(wide.hand_set_pid("thumb", "upper", 2).kp, 3.0);
  EXPECT_EQ(wide.hand_set_pid("thumb", "upper", 1).kp, c.pid.kp);
}

TEST(ControlTune, TheTuneKeyReadsWritesBackAndNamesABadValue) {
  const Design& d = paper();
  ASSERT_TRUE(d.get<ControllerSettings>()->tune.has_value());
  const TuneOptions from_file = tune_options(*d.get<ControllerSettings>());
  EXPECT_EQ(from_file.start, TuneStart::design);
  Design e = d;
  TuneSettings& t = *e.get<ControllerSettings>()->tune;
  t.rho_limit = 0.85;
  t.evaluations = 7;
  t.max_seconds = 12.5;
  t.per_joint = true;
  t.start = "hand_set";
  const Design back = load_design_from_string(to_yaml(e), "back.yaml");
  const TuneOptions o = tune_options(*back.get<ControllerSettings>());
  EXPECT_EQ(o.rho_limit, 0.85);
  EXPECT_EQ(o.max_evaluations, 7);
  EXPECT_EQ(o.max_seconds, 12.5);
  EXPECT_TRUE(o.per_joint);
  EXPECT_EQ(o.start, TuneStart::hand_set);
  std::ifstream in(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string bad = text.str();
  const std::string key = "tune: {rho_limit: 0.9,";
  const std::size_t at = bad.find(key);
  ASSERT_NE(at, std::string::npos);
  bad.replace(at, key.size(), "tune: {rho_limit: 1.5,");
  try {
    (void)load_design_from_string(bad, "bad.yaml");
    ADD_FAILURE() << "rho_limit 1.5 accepted";
  } catch (const InputError& err) {
    EXPECT_NE(std::string(err.what()).find("controller.tune.rho_limit"), std::string::npos) << err.what();
    EXPECT_NE(std::string(err.what()).find("bad.yaml"), std::string::npos) << err.what();
  }
}


// Abbott-Okamura against the 1-DOF closed form: with J = a I, the joints' damping b, Coulomb torque
// tau and quantum delta alike, every direction sees at least the damping b / a^2, the friction
// tau / a and a quantum a delta (the axes are the worst), so K <= min(2 b / (a^2 T), 2 tau / (a^2 delta)),
// and a target K* needs the rate K* a^2 / (2 b) unless 2 tau / (a^2 delta) < K*.
TEST(ControlPerformance, AbbottOkamuraBoundIsTheOneDofClosedFormForAnIsotropicJacobian) {
  const double a = 0.015, T = 0.01;
  const Eigen::Matrix2d J = a * Eigen::Matrix2d::Identity();
  for (const auto& [b, tau, delta] : {std::tuple{0.01, 5e-4, 3e-4}, std::tuple{1e-4, 5e-2, 1e-5}}) {
    SCOPED_TRACE(b);
    PoseFigures f;
    abbott_okamura(J, b * Eigen::Matrix2d::Identity(), {tau, tau}, {delta, delta}, T, 1.0, f);
    const double kb = 2 * b / (a * a * T), kq = 2 * tau / (a * a * delta);  // N/m
    EXPECT_NEAR(f.coulomb_N, tau / a, 1e-12 * tau / a);
    EXPECT_NEAR(f.quantum_um, 1e6 * a * delta, 1e-9 * 1e6 * a * delta);
    EXPECT_NEAR(f.zwidth_quantisation_N_per_mm, 1e-3 * kq, 1e-9 * 1e-3 * kq);
    EXPECT_NEAR(f.zwidth_abbott_okamura_N_per_mm, 1e-3 * std::min(kb, kq), 1e-9 * 1e-3 * std::min(kb, kq));
    if (kq >= 1e3) {
      EXPECT_NEAR(f.rate_for_target_hz, 1e3 * a * a / (2 * b), 1e-9 * 1e3 * a * a / (2 * b));
    } else {
      EXPECT_TRUE(std::isinf(f.rate_for_target_hz));
    }
  }
  // Little friction: quantisation-limited below 1 N/mm, so no rate renders 1 N/mm; a tenth of its bound is renderable.
  PoseFigures g;
  abbott_okamura(J, 1e-4 * Eigen::Matrix2d::Identity(), {5e-7, 5e-7}, {3e-4, 3e-4}, T, 1.0, g);
  EXPECT_LT(g.zwidth_quantisation_N_per_mm, 1.0);
  EXPECT_TRUE(std::isinf(g.rate_for_target_hz));
  abbott_okamura(J, 1e-4 * Eigen::Matrix2d::Identity(), {5e-7, 5e-7}, {3e-4, 3e-4}, T, 0.1 * g.zwidth_quantisation_N_per_mm, g);
  EXPECT_TRUE(std::isfinite(g.rate_for_target_hz));
}

// A rigid rotation of the tactor plane (J -> R J) turns every direction's figures with it: the
// bounds over the directions do not change (R by a whole number of the 0.5 deg direction steps).
TEST(ControlPerformance, AbbottOkamuraBoundIsInvariantUnderARotationOfTheTactorPlane) {
  Eigen::Matrix2d J;
  J << 0.012, -0.004, 0.007, 0.016;
  const Eigen::Matrix2d B = Eigen::Vector2d(0.02, 0.05).asDiagonal();
  PoseFigures f, r;
  abbott_okamura(J, B, {4e-4, 7e-4}, {2e-4, 5e-4}, 0.01, 1.0, f);
  const double angle = 37.5 * std::numbers::pi / 180.0;
  const Eigen::Matrix2d R = Eigen::Rotation2Dd(angle).toRotationMatrix();
  abbott_okamura(R * J, B, {4e-4, 7e-4}, {2e-4, 5e-4}, 0.01, 1.0, r);
  EXPECT_NEAR(r.zwidth_abbott_okamura_N_per_mm, f.zwidth_abbott_okamura_N_per_mm, 1e-9 * f.zwidth_abbott_okamura_N_per_mm);
  EXPECT_NEAR(r.zwidth_quantisation_N_per_mm, f.zwidth_quantisation_N_per_mm, 1e-9 * f.zwidth_quantisation_N_per_mm);
  EXPECT_NEAR(r.coulomb_N, f.coulomb_N, 1e-9 * f.coulomb_N);
  EXPECT_NEAR(r.quantum_um, f.quantum_um, 1e-9 * f.quantum_um);
}

// On the showcase: the position quantum's worst direction is along the coarser joint's column (the
// resolution figure, from FK by its own test above), and friction can only lower the Z-width.
TEST(ControlPerformance, AbbottOkamuraOnTheShowcaseAgreesWithTheResolutionAndColgate) {
  const Design& d = paper();
  const LoopModel loop = paper_loop("index", "lower");
  const ControllerSettings& c = *d.get<ControllerSettings>();
  const std::array<Potentiometer, 2> pots{c.joint("index", "lower", 1).potentiometer, c.joint("index", "lower", 2).potentiometer};
  for (const Vec2& off : {Vec2(0, 0), Vec2(5, -4), Vec2(-6, 2)}) {
    const PoseFigures f = pose_figures(loop, d.require_station("index").target.center + off, c.adc_bits, c.adc_range_v,
                                       pots, c.target_stiffness_N_per_mm);
    ASSERT_EQ(f.status, Status::ok);
    EXPECT_NEAR(f.quantum_um, f.resolution_um, 1e-4 * f.resolution_um);  // 0.5 deg steps: cos 0.25 deg
    EXPECT_LE(f.zwidth_abbott_okamura_N_per_mm, f.zwidth_N_per_mm * (1 + 1e-9));
    EXPECT_LE(f.zwidth_abbott_okamura_N_per_mm, f.zwidth_quantisation_N_per_mm * (1 + 1e-9));
    // The showcase's assumed motors: friction over a ~5 um quantum allows ~10 N/mm, above the target.
    EXPECT_GT(f.zwidth_abbott_okamura_N_per_mm, c.target_stiffness_N_per_mm);
    EXPECT_LT(f.rate_for_target_hz, c.loop_rate_hz);
  }
}

TEST(ControlTune, TunedShowcaseMeetsTheFloorsOverTheTargetAndItsChirpDoesNotSaturateBelowTheBandwidth) {
  // The showcase's own controller.tune (designs/iros2022.yaml) on the index station, stopped by
  // its evaluation count (deterministic). The floors are checked here on the tuned loop by the
  // stability map (its own pose loops and margin bisections), the chirp simulated here.
  const Design& d = paper();
  const Station& index = d.require_station("index");
  TuneOptions o = tune_options(*d.get<ControllerSettings>());
  o.max_seconds = 3600.0;
#ifdef FIVEBAR_SANITIZE
  o.max_evaluations = 12;
#endif
  ASSERT_EQ(o.min_damping, 0.3);
  ASSERT_EQ(o.min_gain_margin, 2.0);
  std::map<std::string, std::map<std::string, MechanismInertia>> inertia{{"index", paper_inertia("index")}};
  const TuneResult r = tune_controller(d, {&index}, inertia, o);
  ASSERT_EQ(r.mechanisms.size(), 2u);
  EXPECT_NEAR(r.max_overshoot_fraction, std::exp(-std::numbers::pi * 0.3 / std::sqrt(1.0 - 0.09)), 1e-15);
  for (const TunedMechanism& t : r.mechanisms) {
    SCOPED_TRACE(t.mechanism);
    std::cout << t.mechanism << ": zeta " << t.damping_before << " -> " << t.damping_after << ", kp x" << t.kp_margin_before
              << " -> x" << t.kp_margin_after << ", kd x" << t.kd_margin_before << " -> x" << t.kd_margin_after
              << ", step overshoot " << t.overshoot_before_mm << " -> " << t.overshoot_after_mm << " mm, chirp -3 dB "
              << t.chirp_bandwidth_before_hz << " -> " << t.chirp_bandwidth_after_hz << " Hz, saturates at "
              << t.chirp_saturation_before_hz << " -> " << t.chirp_saturation_after_hz << " Hz, tracking "
              << t.error_before_mm << " -> " << t.error_after_mm << " mm, gains kp " << t.after[0].kp << " ki "
              << t.after[0].ki << " kd " << t.after[0].kd << ", " << t.evaluations << " evaluations\n";
    ASSERT_TRUE(t.feasible);
    LoopModel loop = paper_loop("index", t.mechanism);
    loop.gains = t.after;
    const StabilityMap map = stability_map(loop, ellipse_lattice(index.target, o.grid));
    ASSERT_TRUE(map.stable);
    EXPECT_LE(map.max_rho, o.rho_limit);
    EXPECT_GE(map.oscillatory_damping, o.min_damping);
    EXPECT_GE(map.kp_margin, o.min_gain_margin);
    EXPECT_GE(map.kd_margin, o.min_gain_margin);
    EXPECT_NEAR(t.damping_after, map.oscillatory_damping, 1e-12);
    EXPECT_EQ(t.kp_margin_after, map.kp_margin);
    EXPECT_EQ(t.kd_margin_after, map.kd_margin);
    EXPECT_LE(t.overshoot_after_mm, r.max_overshoot_fraction * SimulationRequest{}.step_mm);
    EXPECT_TRUE(std::isfinite(t.error_after_mm));
    EXPECT_GT(t.error_before_mm, 0.0);
    // The chirp of this mechanism with the tuned gains: below the reported bandwidth no duty
    // reaches its limit.
    SimulationRequest rq;
    rq.station = "index";
    rq.chirp = true;
    SimulationInput in = simulation_inputs(d, rq, paper_inertia("index")).front();
    const std::size_t k = t.mechanism == "lower" ? 0 : 1;
    in.mechanisms = {in.mechanisms[k]};
    in.mechanisms[0].control[0].pid = t.after[0];
    in.mechanisms[0].control[1].pid = t.after[1];
    SimulationOptions so;
    so.rtol = o.rtol;
    const SimulationResult sim = simulate(in, so);
    ASSERT_TRUE(sim.ok());
    ASSERT_GT(t.bandwidth_after_hz, 0.0);
    const double f0 = rq.chirp_f0_hz, f1 = 0.25 * in.controller.loop_rate_hz, D = rq.chirp_duration_s;
    std::size_t below = 0;
    for (const TimeSample& sample : sim.samples) {
      const double f = f0 * std::pow(f1 / f0, std::min(sample.t, D) / D);
      if (f >= t.bandwidth_after_hz) break;
      ++below;
      const auto& duty = sample.mechanisms[0].duty;
      EXPECT_LT(std::max(std::abs(duty[0]), std::abs(duty[1])), 1.0) << "at " << sample.t << " s, " << f << " Hz";
    }
    EXPECT_GT(below, 100u);
  }
}

}  // namespace
}  // namespace fivebar
