#pragma once
/// Joint limits from the hardware: the range each motor joint can really use, from its
/// potentiometer's electrical travel and from the linkage's own hard stops, intersected with the
/// design's declared `joint_limits`; and the check that the target ellipse and every pattern keep
/// a margin inside it. `fivebar export` gates on it and writes the ranges as the ros2_control
/// position limits (fivebar/export/export.hpp); the URDF carries them too (fivebar/export/urdf.hpp).
///
/// Potentiometer window (controller.potentiometer.travel_deg, fivebar/sections/controller.hpp)
/// ------------------------------------------------------------------------------------------
/// The potentiometer is a voltage divider: it reads 0 V at one end of its electrical travel T and
/// T / |k| volts at the other, k = rad_per_volt, and theta = k (V - V0) (V0 = volts_at_zero). So the
/// joint is read only on the arc between k (0 - V0) and k (T / |k| - V0): from
/// lo = min(-k V0, sign(k) T - k V0), T wide. Beyond it the reading saturates and the controller
/// no longer knows where the joint is. (The showcase: 60 deg/V, V0 = 0.25 V, T = 300 deg reads
/// [-15, 285] deg.) Without travel_deg the potentiometer is taken to read every angle.
///
/// Hard stops (geometry:, the collision model of fivebar/collision.hpp)
/// ------------------------------------------------------------------
/// A proximal link L_i turns about O_i in its plane (geometry.layers[i]) and is there the capsule of
/// the segment O_i A_i of radius r = link_width[i]/2 together with a disk of radius
/// r_e = max(link_width[i], boss_diameter)/2 at each end. It stops where it touches (clearance 0):
///   - the base: at every other base joint O_k of the station (the other motor of its mechanism,
///     and the two of the other mechanism) whose proximal link shares L_i's plane, that link's
///     round end about its motor shaft, a disk of radius r_k = max(link_width[k], boss)/2 that does
///     not move whatever its own angle. With d = |O_k - O_i| and phi = the direction of O_k from
///     O_i, the link touches it exactly when |theta - phi| < alpha* (hard_stop_half_angle()):
///       end disk:  |A_i - O_k| < r_e + r_k   <=>   cos(theta - phi) > (d^2 + L^2 - (r_e + r_k)^2) / (2 d L);
///       segment:   d sin|theta - phi| < r + r_k with the foot of the perpendicular on the segment,
///                  which at the critical angle needs sqrt(d^2 - (r + r_k)^2) <= L;
///     alpha* is the larger of the two half-angles (0 where a condition never holds, pi when the
///     obstacle overlaps the link's own end at O_i, d < r_e + r_k: then no angle is free).
///     Both distances grow with |theta - phi| in [0, pi], so each blocked set is one arc.
///   - the other leg's links (its proximal link and its distal link, when in L_i's plane): they
///     move with the other joint, so this stop is a curve in the (theta1, theta2) plane that a
///     box of per-joint limits cannot hold; it is not part of the ranges below, and
///     check_joint_margins() measures it instead over the target and every pattern (clearance
///     >= geometry.min_clearance).
///
/// Usable range
/// ------------
/// Per joint, the arc around its reference angle (the IK angle at the target centre, normalised
/// to (-pi, pi]) left by the potentiometer window, the declared joint_limits and the blocked arcs:
/// from the reference, the nearest end of any allowed arc or start of any blocked arc, going
/// clockwise (lo) and counter-clockwise (hi). A joint with none of them is unlimited. When the
/// reference itself is outside (the target centre's angle is blocked) the joint has no usable
/// range: a status, not a guess.

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"

namespace fivebar {

/// The arc a potentiometer reads (above), or std::nullopt without `travel`.
std::optional<JointRange> potentiometer_window(const Potentiometer& pot);

/// alpha* (rad, in [0, pi]) of a link of length `L` (mm) from its axis, segment radius `r_link`,
/// end radius `r_end` (>= r_link), against a disk of radius `r_obstacle` at distance `d` > 0:
/// the link overlaps the disk exactly when |theta - phi| < alpha*. pi: at every angle.
double hard_stop_half_angle(double d, double L, double r_link, double r_end, double r_obstacle);

/// One base obstacle of a proximal link: its blocked arc (phi - half_angle, phi + half_angle).
struct HardStop {
  std::string obstacle;    ///< "lower O2" (the other motor's shaft end), "upper O1", ...
  double direction = 0.0;  ///< phi, rad
  double half_angle = 0.0; ///< alpha*, rad (0: never touches)
};

/// The base stops of joint `joint` (1 or 2) of `m` in `station` (every other base joint of the
/// station whose proximal link shares the plane), whether they block anything or not.
std::vector<HardStop> hard_stops(const Station& station, const Mechanism& m, int joint, const Geometry& g);

/// The usable range of one joint.
struct UsableRange {
  std::string joint;         ///< `<station>_<mechanism>_theta<j>`
  bool limited = false;      ///< false: no travel, no stop, no declared limit (every angle)
  bool usable = true;        ///< false: the reference angle itself is excluded (see `problem`)
  double reference = 0.0;    ///< IK angle at the target centre, rad in (-pi, pi]
  double lo = 0.0;           ///< rad, on the reference's branch: lo <= reference <= hi
  double hi = 0.0;
  std::string lo_by, hi_by;  ///< what sets each end: "potentiometer travel", "joint_limits", "hard stop at lower O2"
  std::string problem;       ///< why not usable
  double span() const { return hi - lo; }
};

/// Both joints' usable ranges of `m` in `station` (above); `design` gives `controller:` (the
/// potentiometers, when present) and `geometry:` (the stops, when present). The reference is the IK
/// at the target centre; an unreachable centre leaves the joints unusable.
std::array<UsableRange, 2> usable_ranges(const Design& design, const Station& station, const Mechanism& m);

/// `station` with each mechanism's joint_limits replaced by its usable ranges (a joint without
/// limits while the other has them gets the full turn around its reference); a mechanism whose
/// joints are both unlimited keeps its joint_limits unset. Unusable joints keep the declared
/// limits, so the gate's own checks report them.
Station with_usable_limits(const Design& design, const Station& station);

/// How far inside its usable range a joint angle is (rad); negative outside (by how much).
double range_margin(const UsableRange& range, double theta);

struct JointMarginOptions {
  int boundary_samples = 720;  ///< on the target's boundary
  int rings = 8;               ///< concentric rings inside it
  int angles = 64;             ///< points per ring
};

/// One check of check_joint_margins().
struct JointMarginCheck {
  std::string subject;        ///< "index/lower" (the target), "index stretch" (a pattern, both mechanisms)
  bool passed = false;
  double worst_margin = 0.0;  ///< rad, smallest range_margin() over the samples (limited joints)
  std::string worst_joint;    ///< where it is
  double min_link_clearance_mm = 0.0;  ///< proximal link vs the other leg's links; +inf when none shares a plane
  std::size_t samples = 0;
  std::string detail;         ///< one line
};

/// The target of each mechanism of `station` (IK over the centre, the boundary and rings inside)
/// and, with `patterns:`, each of the station's patterns (both tactors at the pattern's points, fivebar/pattern.hpp
/// pattern_path(), before any priority move):
/// every limited joint at least controller.joint_margin inside its usable range, every proximal
/// link at least geometry.min_clearance from the other leg's links in its plane. Without
/// `controller:` the margin is 0; without `geometry:` no clearance is measured. Unreachable samples
/// are left to the coverage and pattern checks.
std::vector<JointMarginCheck> check_joint_margins(const Design& design, const Station& station,
                                                  const JointMarginOptions& options = {});

/// The range of one joint in a line: "[19.38, 285.00] deg (hard stop at lower O2 ... potentiometer
/// travel)", "every angle", or the problem.
std::string describe(const UsableRange& range);

/// The motor's steady output speed at full duty (rad/s, >= 0): the speed at which the torque it
/// gives at the supply voltage, eta N k_t min((V - k_e N w) / R, I_limit), equals what friction
/// takes, b w + tau_c (the motor model of fivebar/dynamics.hpp with the inductance settled):
///   w = (eta N k_t V / R - tau_c) / (eta N^2 k_t k_e / R + b)   (current below its limit),
///   w = (eta N k_t I_limit - tau_c) / b                          (current at its limit).
/// Below the no-load speed V / (k_e N) by what friction takes (343.5 instead of 343.8 deg/s with
/// the showcase's assumed motor); 0 when friction holds the motor at rest.
double motor_free_speed(const MotorParams& motor);
/// The one joint speed limit (rad/s) of joint `joint` (1 or 2) of `mechanism`: in every exported
/// file (joint_limits.<joint>.max_velocity, the URDF's limit velocity) and in the export gate's
/// pattern checks: the smaller of controller.max_velocity (a stated limit) and
/// motor_free_speed() of the joint's motor; either alone when the design has only that section, 0
/// with neither.
double joint_speed_limit(const Design& design, const Station& station, const Mechanism& mechanism, int joint);
/// The smallest joint_speed_limit() of the station's motor joints: what a pattern moving all of
/// them is checked against (check_pattern()'s max_joint_speed).
double station_joint_speed_limit(const Design& design, const Station& station);
/// The joint speed every check of a pattern of `station` uses (`fivebar pattern`, `fivebar
/// animate`, their products, simulate's references and the export gate): station_joint_speed_limit(),
/// or `patterns.max_joint_speed_deg_s` (its default without a `patterns:` section) for a design
/// with neither a `controller:` nor a `motor:` section.
double pattern_joint_speed_limit(const Design& design, const Station& station);

}  // namespace fivebar
