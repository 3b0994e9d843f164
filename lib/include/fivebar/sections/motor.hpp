#pragma once
/// The `motor:` section of a design file: the DC gearmotor and driver of every joint, in datasheet
/// names and units, overridable per mechanism, station and joint like `controller:`. One module of
/// the design (docs/architecture.md "Design sections"): the struct and its validate() here, its
/// loader and writer hooks in lib/src/sections/motor.cpp. A Design holds it as
/// `design.get<MotorSettings>()`; the dynamics (fivebar/dynamics.hpp) read it.
///
/// The paper names the motor (RS PRO 752-2005) and the driver (DFRobot DFR0592) but gives none of
/// their data, and fivebar does not invent a datasheet: every default below is an ASSUMPTION of a
/// small 6 V gearmotor, to replace with the values of the motors on the bench.

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/sections/scope.hpp"

namespace fivebar {

/// One joint's motor, gearbox and driver (file units; SI accessors below). Every default is an
/// assumption (see above).
struct MotorParams {
  double terminal_resistance_ohm = 5.0;     ///< R, winding resistance at the terminals
  double inductance_mH = 0.5;               ///< L, terminal inductance
  double torque_constant_mNm_per_A = 5.0;   ///< k_t at the motor shaft
  /// k_e at the motor shaft; 0.5236 mV/rpm is 5 mV s/rad, equal to k_t in SI as for an ideal motor.
  double back_emf_mV_per_rpm = 0.5235987755982988;
  double rotor_inertia_g_cm2 = 0.5;         ///< J_r of the rotor, at the motor shaft
  /// N = motor turns per output turn. With the other defaults, 200 gives a no-load output speed of
  /// 6 V / (k_e N) = 344 deg/s (the controller's 360 deg/s limit) and keeps the exported PID stable
  /// at 100 Hz with one period of delay; 30 does not (fivebar simulate shows the limit cycle).
  double gear_ratio = 200.0;
  double gearbox_efficiency = 0.7;          ///< eta, in (0, 1]: output torque = eta N k_t i
  double viscous_friction_mNm_s_per_rad = 0.01;  ///< b at the output shaft
  double coulomb_friction_mNm = 0.5;        ///< tau_c at the output shaft
  double supply_voltage_V = 6.0;            ///< driver supply: |V| <= supply at duty +-1
  double current_limit_A = 1.0;             ///< driver's current limit

  double resistance() const { return terminal_resistance_ohm; }         ///< ohm
  double inductance() const { return inductance_mH * 1e-3; }            ///< H
  double torque_constant() const { return torque_constant_mNm_per_A * 1e-3; }  ///< N m / A
  /// V s / rad (mV/rpm x 60 / (2 pi) / 1000).
  double back_emf_constant() const;
  double rotor_inertia() const { return rotor_inertia_g_cm2 * 1e-7; }   ///< kg m^2
  double viscous_friction() const { return viscous_friction_mNm_s_per_rad * 1e-3; }  ///< N m s / rad
  double coulomb_friction() const { return coulomb_friction_mNm * 1e-3; }            ///< N m
  /// Throws ValidationError naming the key ("terminal_resistance_ohm").
  void validate() const;
};

/// A key of MotorParams as the file spells it: name, unit for messages, field, range
/// (lo < v <= hi, or lo <= v <= hi when `zero_ok` and lo = 0).
struct MotorField {
  std::string_view key;
  std::string_view unit;
  double MotorParams::*member;
  double lo;
  double hi;
  bool zero_ok;
};
inline constexpr std::size_t kMotorFieldCount = 11;
/// Every key of MotorParams, in the order a written file lists them.
const std::array<MotorField, kMotorFieldCount>& motor_fields();

/// An override of some motor keys, scoped as controller overrides are (ControlOverride): the lower
/// or upper mechanism of every station (`motor.mechanisms.<m>`), one of its joints
/// (`...<m>.theta1|theta2`), a station (`motor.stations.<s>`), one of its mechanisms, one of their
/// joints; narrower scopes win. Unset keys keep the wider scope's value.
/// The motor keys one scope of `motor:` gives (scope rule: fivebar/sections/scope.hpp).
struct MotorOverride : JointScope {
  std::array<std::optional<double>, kMotorFieldCount> values;  ///< indexed as motor_fields()
};

/// `motor:`: the motor of every joint, unless overridden.
struct MotorSettings {
  static constexpr std::string_view kKey = "motor";
  std::string model = "RS PRO 752-2005";  ///< for the summary; the paper's motor
  MotorParams defaults;
  std::vector<MotorOverride> overrides;   ///< in file order; applied widest scope first
  /// The motor of joint `joint` (1 or 2) of a mechanism, overrides applied.
  MotorParams joint(std::string_view station, std::string_view mechanism, int joint) const;
  void validate() const;
};

}  // namespace fivebar
