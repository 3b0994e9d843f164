#pragma once
/// The one-joint model that `fivebar identify --rig motor` fits (docs/identify.md "Model"): the DC
/// motor, gearbox and friction of the `motor:` section exactly as `fivebar simulate` integrates them
/// (fivebar/dynamics.hpp), at the output shaft, with the rig's load:
///
///   L di/dt = V - R i - k_e N w                      (V = duty * supply for a duty drive)
///   J dw/dt = eta N k_t i - b w - tau_c sgn(w) - tau_0 (J = N^2 J_r + J_load; tau_0 a constant offset)
///
/// With L/R much shorter than the mechanical time constant (the design's 0.1 ms against tens of ms)
/// the current follows the voltage, i = (V - k_e N w) / R, and every drive becomes a drive torque
/// linear in the drive value d and the speed:  tau_d = alpha d - g w  (ReducedDrive). The mechanical
/// equation is then linear in the base parameters (J, b or b+ and b-, tau_c, tau_0).
/// A linear axis is the same model in newtons and metres.

#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/identify/log.hpp"
#include "fivebar/sections/motor.hpp"

namespace fivebar::identify {

/// Known quantities of the joint under test: its motor data (the priors), its potentiometer and ADC
/// (to read `volts` and `counts`), an optional known load inertia, and the key path its design
/// values live at.
struct JointPrior {
  MotorParams motor;
  double volts_at_zero = 2.5;   ///< V (controller potentiometer)
  double rad_per_volt = 1.0471975511965976;
  int adc_bits = 16;
  double adc_lo_v = -10.0, adc_hi_v = 10.0;
  double load_inertia = 0.0;    ///< kg m^2 at the output, known (--load-inertia); 0: none
  std::string motor_key = "motor";  ///< "motor" or "motor.stations.index.lower.theta1"
  /// A torque at this joint known from a model, N m per log row (empty: none): the closed chain's
  /// [M_links(theta) dw/dt + h]_j of `--rig mechanism`, subtracted from the drive torque, so that
  /// the inertia left to identify is the joint's own (the reflected rotor, N^2 J_r).
  std::vector<double> known_torque;
};

/// The priors of a joint: its motor (the joint's overrides applied), potentiometer and ADC from the
/// design, and the key path its motor values live at; `station` empty: a motor on the bench (the
/// `motor:` defaults, key `motor`). InputError when `need_motor` and the design has no `motor:`
/// section, or when the station has no such mechanism.
JointPrior joint_prior(const Design& design, const std::string& station, const std::string& mechanism, int joint,
                       double load_inertia, bool need_motor);

/// tau_d = alpha * d - g * w for the drive kind, from the priors (output shaft, SI).
struct ReducedDrive {
  double alpha = 1.0;
  double g = 0.0;
};
ReducedDrive reduced_drive(DriveKind kind, const MotorParams& m);

/// The joint angle (or position) of a reading, rad (m).
std::vector<double> joint_angle(const JointLog& joint, const JointPrior& prior);

/// The mechanical parameters in the order of the regressor: inertia, viscous (one, or + and -),
/// Coulomb, offset. `linear`: the axis' names (mass_kg, N_s_per_m, N).
std::vector<std::string> mechanical_names(bool per_direction, bool linear);

/// Right-hand side of the reduced model: dw/dt for drive torque u (already alpha d), speed w.
/// theta = mechanical parameters in mechanical_names() order; coulomb smoothed by tanh(w / ws).
template <class T>
T acceleration(const T* theta, bool per_direction, double g, double u, const T& w, double ws) {
  using std::tanh;
  const T& J = theta[0];
  T viscous;
  int k = 2;
  if (per_direction) {
    viscous = w > T(0.0) ? theta[1] * w : theta[2] * w;
    k = 3;
  } else {
    viscous = theta[1] * w;
  }
  const T friction = viscous + theta[k] * tanh(w / ws) + theta[k + 1];
  return (T(u) - T(g) * w - friction) / J;
}

}  // namespace fivebar::identify
