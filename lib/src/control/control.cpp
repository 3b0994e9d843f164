// The sampled-data loop of one mechanism: linearised plant, ZOH discretisation, the PID with one
// period of delay, spectral radius over the target (fivebar/control.hpp).

#include "fivebar/control.hpp"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <unsupported/Eigen/MatrixFunctions>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <numbers>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/motor.hpp"

namespace fivebar {

LinearPlant linear_plant(const MechanismModel& model, const Eigen::Vector2d& theta, const ContactSettings* contact) {
  LinearPlant p;
  p.theta = theta;
  const DynamicsTerms t = dynamics_terms(model, theta, Eigen::Vector2d::Zero());
  p.status = t.status;
  if (t.status == Status::unreachable || t.status == Status::singular_type2) {
    p.status = t.status == Status::unreachable ? Status::unreachable : Status::singular_type2;
    return p;
  }
  p.status = Status::ok;
  p.M = t.M;
  p.J = t.J;
  p.P_mm = 1e3 * t.P;
  Eigen::Matrix2d K = Eigen::Matrix2d::Zero();  // N m / rad
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();  // N m s / rad
  if (contact) {
    const Eigen::Matrix2d JtJ = t.J.transpose() * t.J;
    K = contact->shear_stiffness_N_per_mm * 1e3 * JtJ;
    C = contact->damping_N_s_per_mm * 1e3 * JtJ;
  }
  Eigen::Matrix2d Kt = Eigen::Matrix2d::Zero();
  for (int j = 0; j < 2; ++j) {
    const MotorParams& mp = model.motors[static_cast<std::size_t>(j)];
    C(j, j) += mp.viscous_friction();
    Kt(j, j) = mp.gearbox_efficiency * mp.gear_ratio * mp.torque_constant();
  }
  const Eigen::Matrix2d Minv = t.M.inverse();
  p.A.block<2, 2>(0, 2) = Eigen::Matrix2d::Identity();
  p.A.block<2, 2>(2, 0) = -Minv * K;
  p.A.block<2, 2>(2, 2) = -Minv * C;
  p.A.block<2, 2>(2, 4) = Minv * Kt;
  for (int j = 0; j < 2; ++j) {
    const MotorParams& mp = model.motors[static_cast<std::size_t>(j)];
    const double L = mp.inductance();
    p.A(4 + j, 2 + j) = -mp.back_emf_constant() * mp.gear_ratio / L;
    p.A(4 + j, 4 + j) = -mp.resistance() / L;
    p.B(4 + j, j) = mp.supply_voltage_V / L;
  }
  return p;
}

std::array<Eigen::MatrixXd, 2> zoh(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, double period_s) {
  const Eigen::Index n = A.rows();
  const Eigen::Index m = B.cols();
  Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(n + m, n + m);
  aug.topLeftCorner(n, n) = A * period_s;
  aug.topRightCorner(n, m) = B * period_s;
  const Eigen::MatrixXd e = aug.exp();
  return {e.topLeftCorner(n, n), e.topRightCorner(n, m)};
}

DiscretePlant discretise(const LinearPlant& plant, double period_s) {
  constexpr int n = kPlantStates + 2;
  Eigen::Matrix<double, n, n> aug = Eigen::Matrix<double, n, n>::Zero();
  aug.topLeftCorner<kPlantStates, kPlantStates>() = plant.A * period_s;
  aug.topRightCorner<kPlantStates, 2>() = plant.B * period_s;
  const Eigen::Matrix<double, n, n> e = aug.exp();
  DiscretePlant d;
  d.Ad = e.topLeftCorner<kPlantStates, kPlantStates>();
  d.Bd = e.topRightCorner<kPlantStates, 2>();
  d.period_s = period_s;
  return d;
}

LoopMatrix closed_loop(const DiscretePlant& plant, const std::array<PidGains, 2>& gains, bool delay) {
  const double T = plant.period_s;
  LoopMatrix phi = LoopMatrix::Zero();
  // duty_k = -g theta_k + ki s_{k-1} - (kd / T) e_{k-1}, g = kp + ki T + kd / T (per joint).
  Eigen::Matrix<double, 2, kLoopStates> duty = Eigen::Matrix<double, 2, kLoopStates>::Zero();
  for (int j = 0; j < 2; ++j) {
    const PidGains& g = gains[static_cast<std::size_t>(j)];
    duty(j, j) = -(g.kp + g.ki * T + g.kd / T);
    duty(j, 8 + j) = g.ki;
    duty(j, 10 + j) = -g.kd / T;
  }
  phi.topLeftCorner<kPlantStates, kPlantStates>() = plant.Ad;
  if (delay) {
    phi.block<kPlantStates, 2>(0, 6) = plant.Bd;
  } else {
    phi.topRows<kPlantStates>() += plant.Bd * duty;
  }
  phi.middleRows<2>(6) = duty;
  for (int j = 0; j < 2; ++j) {
    phi(8 + j, 8 + j) = 1.0;   // s_k = s_{k-1} + T e_k, e_k = -theta_k
    phi(8 + j, j) = -T;
    phi(10 + j, j) = -1.0;     // e_prev <- e_k
  }
  return phi;
}

LoopPoles loop_poles(const LoopMatrix& phi, double period_s) {
  LoopPoles out;
  if (!phi.allFinite()) {
    out.rho = std::numeric_limits<double>::infinity();
    out.damping = -1.0;
    return out;
  }
  Eigen::EigenSolver<LoopMatrix> es(phi, false);
  const auto ev = es.eigenvalues();
  for (Eigen::Index i = 0; i < ev.size(); ++i) {
    const double r = std::abs(ev[i]);
    // Of a conjugate pair, the one with the positive imaginary part.
    if (r > out.rho || (r == out.rho && ev[i].imag() > out.dominant.imag())) {
      out.rho = r;
      out.dominant = ev[i];
    }
  }
  for (Eigen::Index i = 0; i < ev.size(); ++i) {
    if (!(ev[i].imag() > 1e-12 * std::max(1.0, std::abs(ev[i])))) continue;
    const std::complex<double> s = std::log(ev[i]) / period_s;
    const double zeta = -s.real() / std::abs(s);
    if (zeta < out.oscillatory_damping) {
      out.oscillatory_damping = zeta;
      out.oscillatory_frequency_hz = s.imag() / (2.0 * std::numbers::pi);
    }
  }
  if (out.rho > 0.0) {
    const std::complex<double> s = std::log(out.dominant) / period_s;
    const double mag = std::abs(s);
    out.damping = mag > 0.0 ? -s.real() / mag : 1.0;
    out.frequency_hz = std::abs(s.imag()) / (2.0 * std::numbers::pi);
  }
  return out;
}

std::vector<LoopModel> loop_models(const Design& design, const Station& station,
                                   const std::map<std::string, MechanismInertia>& inertia) {
  const std::string where = design.source.empty() ? std::string("control: ") : design.source.string() + ": control: ";
  if (!design.get<Geometry>()) throw InputError(where + "the design has no `geometry:` section (link outlines, masses)");
  if (!design.get<MotorSettings>()) {
    throw InputError(where + "the design has no `motor:` section (motor.terminal_resistance_ohm, ... : the motors' data)");
  }
  if (!design.get<ControllerSettings>()) {
    throw InputError(where + "the design has no `controller:` section (controller.pid, loop_rate_hz: the loop to check)");
  }
  const ControllerSettings& ctl = *design.get<ControllerSettings>();
  const MotorSettings& motor = *design.get<MotorSettings>();
  const ContactSettings skin = design.get<ContactSettings>() ? *design.get<ContactSettings>() : ContactSettings{};
  std::vector<LoopModel> out;
  for (const Mechanism* m : station.mechanisms()) {
    LoopModel l;
    l.station = station.name;
    l.model.mechanism = *m;
    const auto it = inertia.find(m->name);
    if (it == inertia.end()) throw InputError("control: no mass properties for the " + m->name + " mechanism");
    l.model.inertia = it->second;
    for (int j = 0; j < 2; ++j) {
      l.model.motors[static_cast<std::size_t>(j)] = motor.joint(station.name, m->name, j + 1);
      l.gains[static_cast<std::size_t>(j)] = ctl.joint(station.name, m->name, j + 1).pid;
    }
    l.period_s = 1.0 / ctl.loop_rate_hz;
    l.skin = skin;
    out.push_back(std::move(l));
  }
  return out;
}

PoseLoop pose_loop(const LoopModel& loop, const Vec2& P_mm) {
  PoseLoop out;
  out.P_mm = P_mm;
  const AnglesResult a = ik_angles(loop.model.mechanism, P_mm);
  if (a.status != Status::ok) {
    out.status = a.status;
    return out;
  }
  MechanismModel model = loop.model;
  if (model.branch == AssemblyMode::Any) {
    const Pose p = fk(model.mechanism, a.theta1, a.theta2);
    if (p.assembly != 0) model.branch = p.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
  }
  const LinearPlant plant =
      linear_plant(model, Eigen::Vector2d(a.theta1, a.theta2), loop.contact ? &loop.skin : nullptr);
  out.status = plant.status;
  if (plant.status != Status::ok) return out;
  out.plant = discretise(plant, loop.period_s);
  out.poles = loop_poles(closed_loop(out.plant, loop.gains, loop.delay), loop.period_s);
  return out;
}

std::vector<Vec2> ellipse_lattice(const Ellipse& e, int n) {
  std::vector<Vec2> out;
  if (n < 1) return out;
  const double c = std::cos(e.angle);
  const double s = std::sin(e.angle);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double u = n == 1 ? 0.0 : -1.0 + 2.0 * i / (n - 1);
      const double v = n == 1 ? 0.0 : -1.0 + 2.0 * j / (n - 1);
      if (u * u + v * v > 1.0) continue;
      const double x = 0.5 * e.axes.x() * u;
      const double y = 0.5 * e.axes.y() * v;
      out.push_back(e.center + Vec2(c * x - s * y, s * x + c * y));
    }
  }
  return out;
}

double max_spectral_radius(const std::vector<PoseLoop>& poses, const std::array<PidGains, 2>& gains, bool delay,
                           double stop_at) {
  double worst = 0.0;
  for (const PoseLoop& p : poses) {
    if (p.status != Status::ok) continue;
    worst = std::max(worst, loop_poles(closed_loop(p.plant, gains, delay), p.plant.period_s).rho);
    if (worst >= stop_at) break;
  }
  return worst;
}

}  // namespace fivebar
