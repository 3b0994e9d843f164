// Performance of the loop over the target: bandwidth, resolution, force, Z-width, the loop rate
// a target needs (fivebar/control.hpp; the loop itself: control.cpp).

#include "fivebar/control.hpp"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <cstdio>
#include <numbers>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/motor.hpp"

namespace fivebar {

using format::fixed;

std::array<double, 2> tactor_gain(const DiscretePlant& plant, const std::array<PidGains, 2>& gains, bool delay,
                                  const Eigen::Matrix2d& J, double frequency_hz) {
  const double T = plant.period_s;
  const LoopMatrix phi = closed_loop(plant, gains, delay);
  Eigen::Matrix<double, kLoopStates, 2> G = Eigen::Matrix<double, kLoopStates, 2>::Zero();
  Eigen::Matrix2d Dr = Eigen::Matrix2d::Zero();
  for (int j = 0; j < 2; ++j) {
    const PidGains& g = gains[static_cast<std::size_t>(j)];
    Dr(j, j) = g.kp + g.ki * T + g.kd / T;
    G(8 + j, j) = T;
    G(10 + j, j) = 1.0;
  }
  G.middleRows<2>(6) = Dr;
  if (!delay) G.topRows<kPlantStates>() = plant.Bd * Dr;
  using Cmat = Eigen::Matrix<std::complex<double>, kLoopStates, kLoopStates>;
  const std::complex<double> z = std::polar(1.0, 2.0 * std::numbers::pi * frequency_hz * T);
  const Cmat A = z * Cmat::Identity() - phi.cast<std::complex<double>>();
  const Eigen::Matrix<std::complex<double>, kLoopStates, 2> X = A.partialPivLu().solve(G.cast<std::complex<double>>());
  const Eigen::Matrix2cd H = X.topRows<2>();
  const Eigen::Matrix2cd Ht = J.cast<std::complex<double>>() * H * J.inverse().cast<std::complex<double>>();
  const Eigen::JacobiSVD<Eigen::Matrix2cd> svd(Ht);
  const auto sv = svd.singularValues();
  return {sv[1], sv[0]};
}

void abbott_okamura(const Eigen::Matrix2d& J, const Eigen::Matrix2d& Bj, const std::array<double, 2>& coulomb_Nm,
                    const std::array<double, 2>& quantum_rad, double period_s, double target_N_per_mm, PoseFigures& f) {
  const Eigen::Matrix2d Jinv = J.inverse();
  const double target = 1e3 * target_N_per_mm;  // N/m
  double coulomb = std::numeric_limits<double>::infinity(), quantum = 0.0;
  double kq = std::numeric_limits<double>::infinity(), kao = std::numeric_limits<double>::infinity();
  double rate = 0.0;
  constexpr int kDirections = 360;  // over [0, pi): u and -u are the same direction
  for (int k = 0; k < kDirections; ++k) {
    const double a = std::numbers::pi * k / kDirections;
    const Eigen::Vector2d u(std::cos(a), std::sin(a));
    const Eigen::Vector2d w = Jinv * u;  // joint rates at unit tactor speed along u
    const double b = w.dot(Bj * w);      // N s/m
    const double fc = coulomb_Nm[0] * std::abs(w[0]) + coulomb_Nm[1] * std::abs(w[1]);  // N
    const double delta = std::max(std::abs(u.dot(J.col(0))) * quantum_rad[0], std::abs(u.dot(J.col(1))) * quantum_rad[1]);
    const double k_q = delta > 0.0 ? 2.0 * fc / delta : std::numeric_limits<double>::infinity();
    coulomb = std::min(coulomb, fc);
    quantum = std::max(quantum, delta);
    kq = std::min(kq, k_q);
    kao = std::min(kao, std::min(2.0 * b / period_s, k_q));
    rate = std::max(rate, k_q >= target ? target / (2.0 * b) : std::numeric_limits<double>::infinity());
  }
  f.coulomb_N = coulomb;
  f.quantum_um = 1e6 * quantum;
  f.zwidth_quantisation_N_per_mm = 1e-3 * kq;
  f.zwidth_abbott_okamura_N_per_mm = 1e-3 * kao;
  f.rate_for_target_hz = rate;
}

PoseFigures pose_figures(const LoopModel& loop, const Vec2& P_mm, int adc_bits, const std::array<double, 2>& adc_range_v,
                         const std::array<Potentiometer, 2>& pots, double target_N_per_mm) {
  PoseFigures f;
  f.P_mm = P_mm;
  const AnglesResult a = ik_angles(loop.model.mechanism, P_mm);
  if (a.status != Status::ok) {
    f.status = a.status;
    return f;
  }
  const LinearPlant plant = linear_plant(loop.model, Eigen::Vector2d(a.theta1, a.theta2), loop.contact ? &loop.skin : nullptr);
  f.status = plant.status;
  if (plant.status != Status::ok) return f;
  const DiscretePlant dp = discretise(plant, loop.period_s);
  const Eigen::Matrix2d& J = plant.J;
  // Bandwidth: a log scan to Nyquist, then bisection on the first crossing of 1/sqrt(2).
  const double nyquist = 0.5 / loop.period_s;
  const double level = 1.0 / std::sqrt(2.0);
  const auto low = [&](double hz) { return tactor_gain(dp, loop.gains, loop.delay, J, hz)[0] < level; };
  f.bandwidth_hz = nyquist;
  double previous = 0.0;
  constexpr int kScan = 80;
  for (int k = 0; k <= kScan; ++k) {
    const double hz = 0.01 * std::pow(nyquist / 0.01, double(k) / kScan);
    if (low(hz)) {
      double lo = previous, hi = hz;
      for (int it = 0; it < 40 && hi - lo > 1e-6 * hi; ++it) {
        const double mid = 0.5 * (lo + hi);
        (low(mid) ? hi : lo) = mid;
      }
      f.bandwidth_hz = 0.5 * (lo + hi);
      break;
    }
    previous = hz;
  }
  // Resolution, force, damping and Z-width.
  const double span = adc_range_v[1] - adc_range_v[0];
  double torque_min_ratio = std::numeric_limits<double>::infinity();
  Eigen::Matrix2d Bj = Eigen::Matrix2d::Zero();
  std::array<double, 2> coulomb{}, quantum{};
  for (int j = 0; j < 2; ++j) {
    const double dtheta = std::abs(pots[static_cast<std::size_t>(j)].rad_per_volt) * span / std::ldexp(1.0, adc_bits);
    quantum[static_cast<std::size_t>(j)] = dtheta;
    coulomb[static_cast<std::size_t>(j)] = loop.model.motors[static_cast<std::size_t>(j)].coulomb_friction();
    f.resolution_um = std::max(f.resolution_um, 1e6 * J.col(j).norm() * dtheta);
    const MotorParams& mp = loop.model.motors[static_cast<std::size_t>(j)];
    const double torque = mp.gearbox_efficiency * mp.gear_ratio * mp.torque_constant() * mp.current_limit_A;
    torque_min_ratio = std::min(torque_min_ratio, torque / J.col(j).norm());
    Bj(j, j) = mp.viscous_friction() + mp.gearbox_efficiency * mp.gear_ratio * mp.gear_ratio * mp.torque_constant() *
                                           mp.back_emf_constant() / mp.resistance();
  }
  f.force_N = torque_min_ratio;
  const Eigen::Matrix2d Jinv = J.inverse();
  const Eigen::Matrix2d Bx = Jinv.transpose() * Bj * Jinv;  // N s / m
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(0.5 * (Bx + Bx.transpose()), Eigen::EigenvaluesOnly);
  const double bmin = es.eigenvalues()[0];
  f.damping_N_s_per_mm = 1e-3 * bmin;
  f.zwidth_N_per_mm = 1e-3 * 2.0 * bmin / loop.period_s;
  abbott_okamura(J, Bj, coulomb, quantum, loop.period_s, target_N_per_mm, f);
  return f;
}

PerformanceMap performance_map(const Design& design, const LoopModel& loop, const std::vector<Vec2>& points) {
  PerformanceMap m;
  m.station = loop.station;
  m.mechanism = loop.model.mechanism.name;
  const ControllerSettings& c = *design.get<ControllerSettings>();
  const std::array<Potentiometer, 2> pots{c.joint(loop.station, m.mechanism, 1).potentiometer,
                                          c.joint(loop.station, m.mechanism, 2).potentiometer};
  m.target_N_per_mm = c.target_stiffness_N_per_mm;
  m.loop_rate_hz = c.loop_rate_hz;
  bool any = false;
  for (const Vec2& P : points) {
    m.poses.push_back(pose_figures(loop, P, c.adc_bits, c.adc_range_v, pots, c.target_stiffness_N_per_mm));
    const PoseFigures& f = m.poses.back();
    if (f.status != Status::ok) continue;
    if (!any || f.bandwidth_hz < m.worst_bandwidth.bandwidth_hz) m.worst_bandwidth = f;
    if (!any || f.resolution_um > m.worst_resolution.resolution_um) m.worst_resolution = f;
    if (!any || f.force_N < m.worst_force.force_N) m.worst_force = f;
    if (!any || f.zwidth_N_per_mm < m.worst_zwidth.zwidth_N_per_mm) m.worst_zwidth = f;
    if (!any || f.zwidth_abbott_okamura_N_per_mm < m.worst_zwidth_abbott_okamura.zwidth_abbott_okamura_N_per_mm) {
      m.worst_zwidth_abbott_okamura = f;
    }
    if (!any || f.rate_for_target_hz > m.worst_rate.rate_for_target_hz) m.worst_rate = f;
    any = true;
  }
  return m;
}

Json to_json(const PerformanceMap& m) {
  const auto at = [](const PoseFigures& f) { return Json::array({f.P_mm.x(), f.P_mm.y()}); };
  const bool any = std::any_of(m.poses.begin(), m.poses.end(), [](const PoseFigures& f) { return f.status == Status::ok; });
  if (!any) {
    // No pose reachable and regular: the worst figures do not exist (null), and no wall is renderable.
    Json j = {{"station", m.station}, {"mechanism", m.mechanism}, {"poses", m.poses.size()},
              {"target_stiffness_N_per_mm", m.target_N_per_mm}, {"loop_rate_hz", m.loop_rate_hz},
              {"target_renderable", false}};
    for (const char* key : {"min_bandwidth_hz", "min_bandwidth_pose_mm", "max_resolution_um_per_count", "max_resolution_pose_mm",
                            "min_force_every_direction_N", "min_force_pose_mm", "min_tactor_damping_N_s_per_mm",
                            "min_zwidth_N_per_mm", "min_zwidth_pose_mm", "min_coulomb_friction_N", "max_position_quantum_um",
                            "min_zwidth_quantisation_N_per_mm", "min_zwidth_abbott_okamura_N_per_mm",
                            "min_zwidth_abbott_okamura_pose_mm", "loop_rate_for_target_hz", "loop_rate_for_target_pose_mm"}) {
      j[key] = nullptr;
    }
    return j;
  }
  return {{"station", m.station},
          {"mechanism", m.mechanism},
          {"poses", m.poses.size()},
          {"min_bandwidth_hz", m.worst_bandwidth.bandwidth_hz},
          {"min_bandwidth_pose_mm", at(m.worst_bandwidth)},
          {"max_resolution_um_per_count", m.worst_resolution.resolution_um},
          {"max_resolution_pose_mm", at(m.worst_resolution)},
          {"min_force_every_direction_N", m.worst_force.force_N},
          {"min_force_pose_mm", at(m.worst_force)},
          {"min_tactor_damping_N_s_per_mm", m.worst_zwidth.damping_N_s_per_mm},
          {"min_zwidth_N_per_mm", m.worst_zwidth.zwidth_N_per_mm},
          {"min_zwidth_pose_mm", at(m.worst_zwidth)},
          {"min_coulomb_friction_N", m.worst_zwidth_abbott_okamura.coulomb_N},
          {"max_position_quantum_um", m.worst_zwidth_abbott_okamura.quantum_um},
          {"min_zwidth_quantisation_N_per_mm", m.worst_zwidth_abbott_okamura.zwidth_quantisation_N_per_mm},
          {"min_zwidth_abbott_okamura_N_per_mm", m.worst_zwidth_abbott_okamura.zwidth_abbott_okamura_N_per_mm},
          {"min_zwidth_abbott_okamura_pose_mm", at(m.worst_zwidth_abbott_okamura)},
          {"target_stiffness_N_per_mm", m.target_N_per_mm},
          {"loop_rate_hz", m.loop_rate_hz},
          // null when the quantisation forbids the target at some pose (no loop rate renders it)
          {"loop_rate_for_target_hz", std::isfinite(m.worst_rate.rate_for_target_hz) ? Json(m.worst_rate.rate_for_target_hz)
                                                                                      : Json(nullptr)},
          {"loop_rate_for_target_pose_mm", at(m.worst_rate)},
          {"target_renderable", m.worst_rate.rate_for_target_hz <= m.loop_rate_hz}};
}

std::string performance_line(const PerformanceMap& m) {
  const auto at = [](const PoseFigures& f) { return " at (" + fixed(f.P_mm.x(), 2) + ", " + fixed(f.P_mm.y(), 2) + ")"; };
  if (std::none_of(m.poses.begin(), m.poses.end(), [](const PoseFigures& f) { return f.status == Status::ok; })) {
    return m.station + " " + m.mechanism + ": no pose of the target is reachable and regular: no performance figures";
  }
  return m.station + " " + m.mechanism + ": bandwidth >= " + fixed(m.worst_bandwidth.bandwidth_hz, 2) + " Hz" +
         at(m.worst_bandwidth) + "; resolution <= " + fixed(m.worst_resolution.resolution_um, 3) + " um per count" +
         at(m.worst_resolution) + "; force >= " + fixed(m.worst_force.force_N, 2) + " N in every direction" +
         at(m.worst_force) + " (fingertip devices: >= 1.5 N); Z-width >= " + fixed(m.worst_zwidth.zwidth_N_per_mm, 1) +
         " N/mm" + at(m.worst_zwidth) + " (hard surface: 0.8-1.0 N/mm); with Coulomb friction and quantisation " +
         "(Abbott-Okamura) >= " + fixed(m.worst_zwidth_abbott_okamura.zwidth_abbott_okamura_N_per_mm, 2) + " N/mm" +
         at(m.worst_zwidth_abbott_okamura) + "; a " + format::shortest(m.target_N_per_mm) + " N/mm wall needs " +
         (std::isfinite(m.worst_rate.rate_for_target_hz)
              ? "a loop rate >= " + fixed(m.worst_rate.rate_for_target_hz, 2) + " Hz" + at(m.worst_rate) + " (here " +
                    format::shortest(m.loop_rate_hz) + " Hz: " +
                    (m.worst_rate.rate_for_target_hz <= m.loop_rate_hz ? "renderable" : "NOT renderable") + ")"
              : "a finer position sensor or more friction: the quantisation forbids it at any loop rate" +
                    at(m.worst_rate));
}

}  // namespace fivebar
