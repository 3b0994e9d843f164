#pragma once
/// The validated design model (DESIGN.md "Design file"): stations, their target ellipse and
/// their lower/upper five-bar mechanisms. Lengths in mm, angles in radians inside the library.
/// A Design is built once by load_design() (or by hand followed by validate()) and then only read.

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fivebar/error.hpp"

namespace fivebar {

using Vec2 = Eigen::Vector2d;

/// A validation failure: `key` is the path of the offending value relative to the structure that
/// validated it (e.g. "links[2]"); the loader prefixes the file, line and full key path.
/// `rule` either starts with the value ("= -3 mm: must be > 0", what() = "links[2] = -3 mm: must
/// be > 0") or is a bare rule ("must contain at least one of lower, upper", joined with ": ").
class ValidationError : public InputError {
 public:
  ValidationError(std::string key, const std::string& message)
      : InputError(compose(key, message)), key_(std::move(key)), rule_(message) {}
  const std::string& key() const noexcept { return key_; }
  const std::string& rule() const noexcept { return rule_; }
  /// "key = value: rule" or "key: rule", as what() reads.
  static std::string compose(const std::string& key, const std::string& rule) {
    if (rule.starts_with("= ")) return key + " " + rule;
    return key + ": " + rule;
  }

 private:
  std::string key_;
  std::string rule_;
};

/// Working mode (IK branch): for each leg i the sign of cross(A_i - O_i, P - A_i), +1 or -1.
/// Both elbows outward is "-+" for a lower mechanism and "+-" for an upper one.
struct WorkingMode {
  std::int8_t sign1 = -1;
  std::int8_t sign2 = +1;
  friend bool operator==(const WorkingMode&, const WorkingMode&) = default;
};

/// Parses "+-" style strings; std::nullopt when malformed.
std::optional<WorkingMode> parse_working_mode(std::string_view text);
std::string to_string(WorkingMode mode);
/// The four working modes in the fixed order "++", "+-", "-+", "--".
std::array<WorkingMode, 4> all_working_modes();

/// Assembly mode (FK branch): sign of cross(A2 - A1, P - A1); Any = not restricted.
enum class AssemblyMode : std::int8_t { Minus = -1, Any = 0, Plus = 1 };
std::optional<AssemblyMode> parse_assembly_mode(std::string_view text);
std::string to_string(AssemblyMode mode);

/// Counter-clockwise arc of admissible motor angles from lo to hi (radians).
struct JointRange {
  double lo = 0.0;
  double hi = 0.0;
  /// Width of the arc in (0, 2*pi].
  double span() const;
  /// True when angle (any representative) lies on the arc, within tol radians.
  bool contains(double angle, double tol = 0.0) const;
};

/// One five-bar linkage. O1, O2 base joints; L = {L1, L2, L3, L4} (mm); A_i = O_i + L_i e(theta_i);
/// distal links L3 (from A1) and L4 (from A2) meet at the tactor P.
struct Mechanism {
  std::string name;  ///< "lower" or "upper"
  Vec2 O1{0.0, 0.0};
  Vec2 O2{0.0, 0.0};
  std::array<double, 4> L{0.0, 0.0, 0.0, 0.0};
  WorkingMode working_mode{};
  AssemblyMode assembly_mode = AssemblyMode::Any;
  std::optional<std::array<JointRange, 2>> joint_limits;  ///< radians
  double min_lci = 0.0;                                    ///< usability threshold in [0, 1]

  /// Largest length of the linkage (links and base distance), mm: the scale of every tolerance.
  double length_scale() const;
  /// Throws ValidationError naming the key ("links[2]", "bases[1]", ...) on a broken rule.
  void validate() const;
};

/// Filled target ellipse of the fingertip: centre (mm), full axis lengths (mm), rotation (rad).
struct Ellipse {
  Vec2 center{0.0, 0.0};
  Vec2 axes{0.0, 0.0};  ///< full lengths along its own x and y axes
  double angle = 0.0;   ///< radians, counter-clockwise from +x
  void validate() const;
  /// Point on the boundary at parameter t (radians).
  Vec2 boundary_point(double t) const;
};

/// One finger station: a target ellipse and up to two mechanisms sharing it.
struct Station {
  std::string name;  ///< "index", "thumb", ...
  Ellipse target;
  std::optional<Mechanism> lower;
  std::optional<Mechanism> upper;
  void validate() const;
  /// The mechanisms present, lower first.
  std::vector<const Mechanism*> mechanisms() const;
  const Mechanism* mechanism(std::string_view which) const;
};

/// Physical link geometry (`geometry:`), for collision checking and printed parts. Defaults
/// follow the paper's resin-printed device in spirit (mm).
struct Geometry {
  std::array<double, 4> link_width{4.0, 4.0, 4.0, 4.0};  ///< L1..L4: outline is a capsule this wide
  double link_thickness = 2.5;         ///< of every link plate
  double pin_diameter = 2.0;           ///< nominal pin at every joint (O_i, A_i, P)
  double boss_diameter = 5.0;          ///< rounded link end around each pin
  double tactor_diameter = 4.0;        ///< contact disk at P
  double tactor_height = 6.0;          ///< above the top link plane
  std::array<int, 4> layers{0, 0, 1, 1};  ///< plane of L1..L4, 0 nearest the base plate
  double layer_gap = 0.4;              ///< between planes (washers)
  double motor_shaft_diameter = 3.0;   ///< D-shaft of the motors
  double motor_shaft_flat = 0.5;       ///< depth of the shaft's flat
  double min_clearance = 0.3;          ///< a smaller gap between links counts as a collision
  /// Throws ValidationError naming the key ("link_width[2]", "pin_diameter").
  void validate() const;
};

/// Resin printing (`print:`): clearances and minimums of the printer and material.
struct PrintSettings {
  double pin_clearance = 0.15;  ///< radial, mm (Tough 2000 guides: 0.1 - 0.25)
  double min_wall = 0.8;        ///< the printer's minimum wall, mm
  int fn = 96;                  ///< OpenSCAD $fn for printed circles
  double layer_height = 0.05;   ///< mm
  std::string material = "Formlabs Tough 2000";
  void validate() const;
};

/// One swept design variable (`sweep.vary`): NAME = LO:HI:N, in file units (mm).
struct SweepVariable {
  std::string name;  ///< one of sweep_variable_names()
  double lo = 0.0;
  double hi = 0.0;
  int n = 1;  ///< grid points (grid sampling); ignored by random / sobol
};

/// A link-dimension sweep (`sweep:`) over one station.
struct SweepSettings {
  std::string station;
  std::string mechanism;             ///< "lower", "upper" or empty: every mechanism and shared
  std::vector<SweepVariable> vary;
  std::string sample = "grid";       ///< grid | random | sobol
  std::uint64_t count = 0;           ///< random / sobol designs (0: the grid's size)
  std::uint64_t seed = 1;
  std::vector<std::string> objectives{"margin", "min_lci"};  ///< see sweep_objective_names()
  /// Grid spacing (mm) of the per-design collision fraction (see collision_fraction()), computed
  /// for covered designs when the design has `geometry:` and the station both mechanisms; 0: off.
  /// Never finer than 1/24 of the ellipse's larger axis (sweep_collision_spacing()).
  double collision_spacing_mm = 2.0;
  /// Rules that need no design (names, ranges, counts); the design checks the station.
  void validate() const;
};
/// L1 L2 L3 L4, L12 (L1 = L2), L34 (L3 = L4), spacing (base spacing), upper_height (y of the
/// upper bases), ellipse_a, ellipse_b (full axes of the target).
const std::vector<std::string>& sweep_variable_names();
/// margin (max), min_lci (max), force (max), footprint (min: bounding-box area of the linkage),
/// collision (min: fraction of tactor-position pairs in the ellipse whose mechanisms collide).
const std::vector<std::string>& sweep_objective_names();
/// Skin-deformation patterns (paper Sec. IV-A, Fig. 6) and pivoting (Sec. IV-B).
enum class PatternKind : std::uint8_t {
  stretch,  ///< tactors start near the centre and move apart horizontally
  slip,     ///< tactors start in the upper region and move together to the lower one
  twist,    ///< tactors start separated about the centre and turn along a circle
  pivot,    ///< tactors track two contact points of an object rotating about the centre
};
std::string_view to_string(PatternKind kind);
std::optional<PatternKind> parse_pattern_kind(std::string_view text);
/// stretch, slip, twist, pivot.
std::array<PatternKind, 4> all_pattern_kinds();

/// One pattern's parameters (`patterns.<kind>` or `patterns.stations.<station>.<kind>`).
/// Lengths mm, angles radians, times s. The paths themselves are in fivebar/pattern.hpp.
struct PatternSpec {
  PatternKind kind = PatternKind::stretch;
  double amplitude_mm = 3.0;    ///< stretch: travel of each tactor; slip: travel; twist: arc length
  double duration_s = 1.0;      ///< length of the pattern
  double rate_hz = 100.0;       ///< samples per second (the controller loop rate)
  std::optional<Vec2> centre;   ///< default: the station's target centre (mm)
  double separation_mm = 8.0;   ///< distance between the two tactors at the start
  double pivot_amplitude = 0.3490658503988659;  ///< pivot: peak object angle (rad; file: amplitude_deg, 20)
  double pivot_frequency_hz = 0.5;               ///< pivot: angle(t) = amplitude sin(2 pi f t)
  /// Pivot: contact points {upper, lower} relative to the centre (mm); default (0, +-separation/2).
  std::optional<std::array<Vec2, 2>> contact_points;
  /// Number of samples: floor(duration * rate) + 1, both ends included (a product within rounding
  /// of a whole number counts as that number).
  std::size_t samples() const;
  /// Throws ValidationError naming the key ("amplitude_mm", "contact_points[1]").
  void validate() const;
};

/// `patterns:`: which patterns to check, on which stations, at what rate and motor speed.
struct PatternSettings {
  double rate_hz = 100.0;  ///< default rate of every pattern (paper: 100 Hz control loop)
  /// Largest motor speed (rad/s; file: max_joint_speed_deg_s, default 360 deg/s). In a design
  /// with a `controller:` section this is controller.max_velocity (its max_velocity_deg_s).
  double max_joint_speed = 6.283185307179586;
  std::vector<PatternSpec> global;  ///< kinds given at the top level: checked on every station
  /// Kinds given under `stations.<name>`, already merged over the top-level entry of that kind.
  std::vector<std::pair<std::string, PatternSpec>> per_station;
  /// The patterns of a station: for each kind in the order stretch, slip, twist, pivot, its own
  /// entry if any, else the top-level one.
  std::vector<PatternSpec> for_station(std::string_view station) const;
  void validate() const;
};

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
/// theta = rad_per_volt * (V - volts_at_zero), theta in the station frame (DESIGN.md: from +x,
/// counter-clockwise). The file takes volts_per_rad (the datasheet's sensitivity) or rad_per_volt.
struct Potentiometer {
  double volts_at_zero = 2.5;                   ///< reading at theta = 0, V
  double rad_per_volt = 1.0471975511965976;     ///< 5 V over 300 deg: 60 deg/V; negative when wired reversed
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
struct ControlOverride {
  std::string station;    ///< empty: every station (then `mechanism` is set)
  std::string mechanism;  ///< "lower", "upper", or empty: every mechanism of the station
  int joint = 0;          ///< 1 or 2 (theta1, theta2), or 0: both joints
  std::optional<double> kp, ki, kd, i_clamp;
  std::optional<double> volts_at_zero, rad_per_volt;
  /// Key path of this scope relative to `controller` ("stations.index.lower.theta1",
  /// "mechanisms.upper").
  std::string key() const;
  /// 0 ... 4, widest first, in the order above.
  int level() const;
};

/// The ROS controller on the device (`controller:`; paper Sec. II-D): per mechanism an IK module,
/// FK of the measured joints for collision checks with the upper mechanism's priority, and a PID
/// per motor at loop_rate_hz driving the motor by PWM at pwm_hz; joint angles read from
/// potentiometers through an ADC (the paper's 16-bit DAQ, USB-1608G). Read by fivebar/export.hpp.
///
/// Joint speed limit: max_velocity is the one source of truth when a design has this section;
/// `patterns:` then takes it from here (the loader refuses patterns.max_joint_speed_deg_s next to
/// a controller section, and Design::validate() requires both values to agree).
struct ControllerSettings {
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
  PidGains pid;                   ///< every joint, unless overridden
  Potentiometer potentiometer;    ///< every joint, unless overridden
  std::vector<ControlOverride> overrides;  ///< in file order; applied widest scope first

  /// Gains and calibration of joint `joint` (1 or 2) of a mechanism: the defaults, then the
  /// overrides from the widest scope to the narrowest (ControlOverride), in file order within one.
  JointControl joint(std::string_view station, std::string_view mechanism, int joint) const;
  /// Rules that need no design (ranges, names); Design::validate() checks the override scopes.
  void validate() const;
};

/// True when `name` is a ROS 2 node name: [A-Za-z_][A-Za-z0-9_]*, at most 255 characters.
bool is_ros_node_name(std::string_view name);

/// A whole design (and scene).
struct Design {
  std::string name;                   ///< used for outputs/<name>/: a safe file name
  std::filesystem::path source;       ///< file it was loaded from (may be empty)
  std::vector<Station> stations;      ///< in file order
  std::optional<std::vector<std::string>> products;  ///< absent: every product the data allows
  std::optional<Geometry> geometry;       ///< `geometry:`; absent: collision and parts left out
  std::optional<PrintSettings> print;     ///< `print:`; parts use defaults when absent
  std::optional<SweepSettings> sweep;     ///< `sweep:`; the sweep product of `fivebar run`
  std::optional<PatternSettings> patterns;  ///< `patterns:`; absent: the pattern product is left out
  std::optional<ControllerSettings> controller;  ///< `controller:`; absent: nothing to export

  void validate() const;
  /// The station named `name`, or nullptr.
  const Station* station(std::string_view name) const;
  /// The station named `name`; InputError "unknown station 'NAME' in design 'D' (it has: ...)"
  /// listing the design's stations when there is none.
  const Station& require_station(std::string_view name) const;
  /// The stations a whole-station command works on: the one named `name` (as require_station()),
  /// or, for an empty name, every station with a mechanism, in file order.
  std::vector<const Station*> select_stations(std::string_view name) const;
};

/// True when `name` can serve as a design or station name and hence as one path component under
/// outputs/: 1 to 64 characters from [A-Za-z0-9_.-], the first not '.' or '-'.
bool is_safe_name(std::string_view name);

/// Product names a scene may list, in build order.
const std::vector<std::string>& known_products();

/// The design as a design file (YAML, file units, numbers in shortest round-trip form) that
/// load_design_from_string() reads back to an equal design.
std::string to_yaml(const Design& design);
/// Limits on design files (README "Hardening"), checked before the YAML parser sees the text so
/// that no file can exhaust the stack or the memory: larger files, deeper nesting, bytes that are
/// not UTF-8 or characters YAML forbids (control characters) are refused with an InputError.
inline constexpr std::size_t kMaxDesignFileBytes = std::size_t{1} << 20;  ///< 1 MiB
/// Levels of block indentation, "- " / "? " items and [ { brackets, counted together.
inline constexpr int kMaxDesignNesting = 64;

/// Loads and validates a design file. Throws InputError whose message names the file, line, full
/// key path, value and the rule broken ("designs/x.yaml:12: stations.index.mechanisms.lower.links[2]
/// = -3 mm: must be > 0"); problems of the whole file omit the line ("x.yaml: no such design file").
Design load_design(const std::filesystem::path& path);
/// Same, from text (for tests and stdin); `origin` names the source in messages.
Design load_design_from_string(const std::string& text, const std::string& origin);

}  // namespace fivebar
