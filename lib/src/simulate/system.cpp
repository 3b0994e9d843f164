// The right-hand side of a simulated station (lib/src/simulate/system.hpp; equations in
// fivebar/dynamics.hpp).

#include "simulate/system.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace fivebar::dynamics_detail {

System make_system(const SimulationInput& input, const SimulationOptions& options) {
  System s;
  s.input = &input;
  s.options = &options;
  s.duty.assign(input.mechanisms.size(), {0.0, 0.0});
  s.slipping.assign(input.mechanisms.size(), 0);
  s.on.assign(input.mechanisms.size(), {false, false});
  s.limiting.assign(input.mechanisms.size(), {false, false});
  s.contact_roots = options.contact;
  s.limit_roots = options.pwm == PwmModel::switched && options.drive != Drive::open_circuit;
  s.k = input.contact.shear_stiffness_N_per_mm * 1e3;
  s.c = input.contact.damping_N_s_per_mm * 1e3;
  s.limit = input.contact.friction_coefficient * input.contact.normal_preload_N;
  return s;
}

Evaluation evaluate(System& s, std::size_t k, const double* yall) {
  Evaluation ev;
  const double* y = yall + kStateSize * k;
  const SimulatedMechanism& sm = s.input->mechanisms[k];
  const SimulationOptions& o = *s.options;
  const Eigen::Vector2d theta(y[0], y[1]);
  const Eigen::Vector2d w = o.lock_joints ? Eigen::Vector2d::Zero() : Eigen::Vector2d(y[2], y[3]);
  ev.terms = dynamics_terms(sm.model, theta, w);
  if (ev.terms.status == Status::unreachable || ev.terms.status == Status::singular_type2) {
    s.last_failure_singular = true;
    return ev;
  }
  // Skin contact.
  if (o.contact) {
    const Vec2 a(y[6], y[7]);
    const Vec2 stretch = ev.terms.P - a;
    if (s.slipping[k]) {
      ev.force = -s.k * stretch;
      const double n = stretch.norm();
      if (n > 0.0) {
        const Vec2 u = stretch / n;
        const Vec2 da = u.dot(ev.terms.P_dot) * u;
        ev.dy[6] = da.x();
        ev.dy[7] = da.y();
      }
    } else {
      ev.force = -s.k * stretch - s.c * ev.terms.P_dot;
    }
  }
  Eigen::Vector2d tau = ev.terms.J.transpose() * ev.force - ev.terms.h;
  for (int j = 0; j < 2; ++j) {
    const MotorParams& mp = sm.model.motors[static_cast<std::size_t>(j)];
    const double N = mp.gear_ratio;
    const double back_emf = mp.back_emf_constant() * N * w[j];
    double i = y[4 + j];
    double di = 0.0;
    if (o.drive == Drive::open_circuit) {
      i = 0.0;
    } else {
      const double duty = s.duty[k][static_cast<std::size_t>(j)];
      const double r_limit = mp.resistance() * mp.current_limit_A;
      double v = 0.0;
      bool limited = false;
      if (o.pwm == PwmModel::switched) {
        // Sign-magnitude bridge; on the on-phase the limiter holds the current at I_max once it
        // gets there (a root: V = R I_max + back EMF, di/dt = 0 at the limit), else the full supply.
        const double sign = duty > 0.0 ? 1.0 : duty < 0.0 ? -1.0 : 0.0;
        if (s.on[k][static_cast<std::size_t>(j)] && sign != 0.0) {
          v = sign * mp.supply_voltage_V;
          if (s.limiting[k][static_cast<std::size_t>(j)]) {
            v = sign * r_limit + back_emf;
            limited = true;
          }
        }
      } else {
        v = std::clamp(duty, -1.0, 1.0) * mp.supply_voltage_V;
        const double lo = back_emf - r_limit, hi = back_emf + r_limit;
        limited = v < lo || v > hi;
        v = std::clamp(v, lo, hi);
      }
      v = std::clamp(v, -mp.supply_voltage_V, mp.supply_voltage_V);
      ev.voltage[static_cast<std::size_t>(j)] = v;
      ev.saturated[static_cast<std::size_t>(j)] = limited || std::abs(duty) >= 1.0;
      di = (v - mp.resistance() * i - back_emf) / mp.inductance();
    }
    const double friction = mp.viscous_friction() * w[j] + mp.coulomb_friction() * std::tanh(w[j] / kCoulombSmoothingSpeed);
    tau[j] += mp.gearbox_efficiency * N * mp.torque_constant() * i - friction;
    ev.dy[static_cast<std::size_t>(4 + j)] = di;
  }
  if (!o.lock_joints) {
    const Eigen::Vector2d wd = ev.terms.M.ldlt().solve(tau);
    ev.dy[0] = w[0];
    ev.dy[1] = w[1];
    ev.dy[2] = wd[0];
    ev.dy[3] = wd[1];
  }
  ev.ok = std::isfinite(ev.dy[2]) && std::isfinite(ev.dy[3]);
  return ev;
}

bool rhs(System& s, const double* y, double* dy) {
  for (std::size_t k = 0; k < s.mechanisms(); ++k) {
    const Evaluation ev = evaluate(s, k, y);
    if (!ev.ok) return false;
    std::copy(ev.dy.begin(), ev.dy.end(), dy + kStateSize * k);
  }
  return true;
}

int root_count(const System& s) {
  const std::size_t per = (s.contact_roots ? 1u : 0u) + (s.limit_roots ? 2u : 0u);
  return static_cast<int>(per * s.mechanisms());
}

RootOwner root_owner(const System& s, std::size_t r) {
  const std::size_t per = (s.contact_roots ? 1u : 0u) + (s.limit_roots ? 2u : 0u);
  RootOwner o;
  o.k = r / per;
  const std::size_t local = r % per;
  if (s.contact_roots && local == 0) return o;
  o.joint = static_cast<int>(local - (s.contact_roots ? 1u : 0u));
  return o;
}

namespace {
/// sign(duty) of joint j, 0 when the bridge is off over this segment.
double drive_sign(const System& s, std::size_t k, std::size_t j) {
  if (!s.on[k][j]) return 0.0;
  const double d = s.duty[k][j];
  return d > 0.0 ? 1.0 : d < 0.0 ? -1.0 : 0.0;
}
}  // namespace

void roots(System& s, const double* yall, double* g) {
  std::size_t r = 0;
  for (std::size_t k = 0; k < s.mechanisms(); ++k) {
    const double* y = yall + kStateSize * k;
    const SimulatedMechanism& sm = s.input->mechanisms[k];
    if (s.contact_roots) {
      const Eigen::Vector2d w = s.options->lock_joints ? Eigen::Vector2d::Zero() : Eigen::Vector2d(y[2], y[3]);
      const DynamicsTerms t = dynamics_terms(sm.model, Eigen::Vector2d(y[0], y[1]), w);
      const Vec2 stretch = t.P - Vec2(y[6], y[7]);
      if (s.slipping[k]) {
        const double n = stretch.norm();
        g[r++] = n > 0.0 ? stretch.dot(t.P_dot) / n : 0.0;  // m/s
      } else {
        g[r++] = s.k * stretch.norm() - s.limit;  // N
      }
    }
    if (s.limit_roots) {
      for (std::size_t j = 0; j < 2; ++j) {
        const double sign = drive_sign(s, k, j);
        // Inactive (off, or already limiting): a constant that never crosses zero.
        g[r++] = sign == 0.0 || s.limiting[k][j] ? -1.0 : sign * y[4 + j] - sm.model.motors[j].current_limit_A;  // A
      }
    }
  }
}

std::vector<int> root_directions(const System& s) {
  std::vector<int> d;
  for (std::size_t k = 0; k < s.mechanisms(); ++k) {
    if (s.contact_roots) d.push_back(s.slipping[k] ? -1 : +1);
    if (s.limit_roots) {
      d.push_back(+1);
      d.push_back(+1);
    }
  }
  return d;
}

void reset_limiters(System& s, const double* yall) {
  for (std::size_t k = 0; k < s.mechanisms(); ++k) {
    for (std::size_t j = 0; j < 2; ++j) {
      const double sign = drive_sign(s, k, j);
      s.limiting[k][j] =
          sign != 0.0 && sign * yall[kStateSize * k + 4 + j] >= s.input->mechanisms[k].model.motors[j].current_limit_A;
    }
  }
}

}  // namespace fivebar::dynamics_detail
