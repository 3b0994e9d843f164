#pragma once
/// The `controller:` section of a design file: the ROS controller of the device (loop, PWM, ADC, PID, potentiometers). One module of the design (see
/// docs/architecture.md "Design sections"): the struct and its validate() here, its loader and
/// writer hooks in lib/src/sections/controller.cpp. A Design holds it as `design.get<ControllerSettings>()`.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/sections/scope.hpp"

namespace fivebar {

/// PID gains of one motor (`controller.pid`). The controller acts on the joint angle error
/// e = theta_target - theta_measured in radians (ROS convention) and outputs the PWM duty cycle in
/// [-1, 1]: duty = kp e + clamp(ki * integral(e dt), -i_clamp, i_clamp) + kd de/dt.
struct PidGains {
  double kp = 5.0;        ///< duty per rad: full duty at 0.2 rad (11.5 deg) of error
  double ki = 1.0;        ///< duty per (rad s)
  double kd = 0.05;       ///< duty per (rad/s)
  double i_clamp = 0.2;   ///< bound of the integral term, duty in [0, 1]
  void validate() const;
};

/// Potentiometer on a motor shaft, read through the ADC (`controller.potentiometer`):
/// theta = rad_per_volt * (V - volts_at_zero), theta in the station frame (docs/conventions.md "Frames": from +x,
/// counter-clockwise). The file takes volts_per_rad (the datasheet's sensitivity) or rad_per_volt.
///
/// Electrical travel (`travel_deg`, optional): the potentiometer is a voltage divider that reads
/// 0 V at one end of its travel and travel / |rad_per_volt| volts at the other, so the joint reads
/// only on the arc theta in [rad_per_volt (0 - volts_at_zero), rad_per_volt (travel/|rad_per_volt|
/// - volts_at_zero)] (ends swapped when wired reversed); potentiometer_window() in
/// fivebar/device/joint_limits.hpp. Without it the potentiometer is taken to read on every angle.
struct Potentiometer {
  double volts_at_zero = 2.5;                   ///< reading at theta = 0, V
  double rad_per_volt = 1.0471975511965976;     ///< 5 V over 300 deg: 60 deg/V; negative when wired reversed
  std::optional<double> travel;                 ///< electrical travel, rad in (0, 2 pi] (file: travel_deg)
  void validate() const;
};

/// What one joint of the controller gets once the overrides are applied.
struct JointControl {
  PidGains pid;
  Potentiometer potentiometer;
};

/// An override of some PID or potentiometer keys. Scopes, from the widest: the lower or upper
/// mechanism of every station (`controller.mechanisms.<mechanism>`), one of its joints
/// (`...<mechanism>.theta1|theta2`), a station (`controller.stations.<station>`), one of its
/// mechanisms, one of their joints. A scope naming a station is narrower than any that does not.
/// Unset keys keep the value of the wider scope.
struct ControlOverride : JointScope {
  std::optional<double> kp, ki, kd, i_clamp;
  std::optional<double> volts_at_zero, rad_per_volt;
  std::optional<double> travel;  ///< rad (potentiometer.travel_deg)
};

/// `controller.tune`: what `fivebar run` (the `control` product) and `fivebar control --tune` tune
/// the PID with (fivebar/control.hpp "Tuning"). Present in a design: the product tunes every
/// station with both mechanisms and reports the hand-set gains beside the tuned ones.
struct TuneSettings {
  double rho_limit = 0.9;     ///< max spectral radius allowed over the target, in (0, 1)
  int evaluations = 60;       ///< objective evaluations per mechanism (each simulates every pattern)
  double max_seconds = 30.0;  ///< wall-time bound of the whole tuning, s
  bool per_joint = false;     ///< kp, ki, kd per joint instead of one set per mechanism
  /// Where the optimiser starts: "design" (the gains the design runs, per joint), "pole_placement"
  /// (on the linearised model at the target's centre) or "hand_set" (the file's gains without the
  /// `stations.<s>.<m>` scopes a tuning patch writes). Whatever the start, the result is never
  /// worse than the design's gains (docs/control.md).
  std::string start = "design";
  /// Least damping ratio of any oscillatory closed-loop pole allowed anywhere on the target grid.
  /// 0.3 is a stated engineering floor, not a datasheet value: a second-order loop at zeta = 0.3
  /// overshoots a step by exp(-pi zeta / sqrt(1 - zeta^2)) = 37 %; the tuned large step (with the
  /// duty saturation and the integral clamp) must not overshoot more than that either.
  double min_damping = 0.3;
  /// Least factor on kp and on kd (each alone, the others fixed) that must keep max rho < 1 over
  /// the target: a classical gain margin floor of 2 (6 dB), an engineering convention.
  double min_gain_margin = 2.0;
  void validate() const;
};

/// The ROS controller on the device (`controller:`; paper Sec. II-D): per mechanism an IK module,
/// FK of the measured joints for collision checks with the upper mechanism's priority, and a PID
/// per motor at loop_rate_hz driving the motor by PWM at pwm_hz; joint angles read from
/// potentiometers through an ADC (the paper's 16-bit DAQ, USB-1608G). Read by fivebar/export/export.hpp.
///
/// Joint speed limit: max_velocity is the one source of truth when a design has this section;
/// `patterns:` then takes it from here (the loader refuses patterns.max_joint_speed_deg_s next to
/// a controller section, and Design::validate() requires both values to agree).
struct ControllerSettings {
  static constexpr std::string_view kKey = "controller";
  std::string node = "fivebar_controller";  ///< ROS 2 node name: the parameters file's top key
  double loop_rate_hz = 100.0;   ///< PID, IK and collision loop (paper: 100 Hz)
  double pwm_hz = 1000.0;        ///< motor PWM (paper: 1 kHz)
  int adc_bits = 16;             ///< DAQ resolution (paper: 16-bit)
  std::array<double, 2> adc_range_v{-10.0, 10.0};  ///< input range of the DAQ, V
  double max_velocity = 6.283185307179586;  ///< rad/s (file: max_velocity_deg_s, default 360)
  std::string collision_priority = "upper";  ///< the paper's rule; the only one fivebar checks
  /// Export gate: LCI over every target ellipse must be at least max(min_lci, the mechanism's
  /// min_lci): the ellipse keeps this far from singularities.
  double min_lci = 0.05;
  /// Export gate: the target ellipse and every pattern keep at least this far (rad) inside each
  /// joint's usable range (fivebar/device/joint_limits.hpp; file: joint_margin_deg, default 5 deg, an
  /// assumption: room for the PID's overshoot before a hard stop or the end of a potentiometer).
  double joint_margin = 0.08726646259971647;
  /// Export gate (with `motor:`): the tactor's tracking error |P - P_ref| in every simulated
  /// pattern (fivebar/dynamics.hpp) must stay at most this, mm. 0.5 mm is an ASSUMPTION (a sixth
  /// of the patterns' default 3 mm amplitude), to replace with the rendering task's requirement.
  double max_tracking_error_mm = 0.5;
  /// Export gate (with `motor:`): the share of a simulated pattern's time a mechanism may spend
  /// saturated (a joint at full duty or at the driver's current limit), in [0, 1]. 0.05 is an
  /// ASSUMPTION: brief saturation at a pattern's start is tolerated, sustained saturation is not.
  double max_saturation_fraction = 0.05;
  /// The stiffness of virtual wall the device should render passively (N/mm): the `control`
  /// study reports the loop rate it needs (fivebar/control.hpp "Z-width"). 1.0 N/mm: a hard
  /// surface needs at least 0.8-1.0 N/mm (Choi & Tan, "Effect of update rate on perceived
  /// instability of virtual haptic texture", IROS 2004), the fingertip-device literature's figure.
  double target_stiffness_N_per_mm = 1.0;
  /// Export gate: these groups of values (fivebar/provenance.hpp: kinematics, potentiometer,
  /// motor, contact, density, tolerance) must be measured, i.e. carry `provenance:` entries;
  /// empty: assumptions are allowed (the gate only lists them).
  std::vector<std::string> require_measured;
  PidGains pid;                   ///< every joint, unless overridden
  Potentiometer potentiometer;    ///< every joint, unless overridden
  std::optional<TuneSettings> tune;  ///< `tune:`; none: the `control` product does not tune
  std::vector<ControlOverride> overrides;  ///< in file order; applied widest scope first

  /// Gains and calibration of joint `joint` (1 or 2) of a mechanism: the defaults, then the
  /// overrides from the widest scope to the narrowest (ControlOverride), in file order within one.
  JointControl joint(std::string_view station, std::string_view mechanism, int joint) const;
  /// The hand-set gains of a joint: as joint(), without the PID keys of the scopes a tuning patch
  /// writes (`stations.<s>.<m>` and `stations.<s>.<m>.theta1|theta2`, levels 3 and 4): what the
  /// tuner starts from and reports as "before".
  PidGains hand_set_pid(std::string_view station, std::string_view mechanism, int joint) const;
  /// Rules that need no design (ranges, names); Design::validate() checks the override scopes.
  void validate() const;
};

/// True when `name` is a ROS 2 node name: [A-Za-z_][A-Za-z0-9_]*, at most 255 characters.
bool is_ros_node_name(std::string_view name);

}  // namespace fivebar
