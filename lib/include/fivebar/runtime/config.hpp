#pragma once
/// The device's configuration as the runtime reads it (docs/runtime.md): every value `fivebar
/// export` writes (fivebar/export/export.hpp, the JSON, the ROS YAML or the C++ header), SI units
/// (m, rad, s, V, Hz). Its keys and nesting are listed once, in fivebar/runtime/config_layout.hpp:
/// the export writes a Config through that list and the runtime reads one back through it, so a
/// Config read from an exported file writes back byte for byte. C++17, standard library only.
/// Validated once by validate(); a Controller never sees an invalid Config.

#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace fivebar::runtime {

/// A configuration the runtime refuses: the message names the key path
/// ("gains.index_lower_theta1.p", "stations.index.lower.link_lengths_m[2]").
class ConfigError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// The PID of one joint (export `gains.<joint>`): duty = clamp(p e + i s + d de/dt, -1, 1),
/// s the integral of e clamped so that |i s| <= i_clamp (fivebar/runtime/controller.hpp).
struct Gains {
  double p = 0.0, i = 0.0, d = 0.0, i_clamp = 0.0;
};

/// One motor joint: `<station>_<mechanism>_theta<1|2>`.
struct JointConfig {
  std::string name;
  Gains gains;
  double volts_at_zero = 0.0;  ///< potentiometers.<joint>: theta = rad_per_volt (V - volts_at_zero)
  double rad_per_volt = 0.0;
  bool has_position_limits = false;  ///< joint_limits.<joint>: the usable range [min, max], max = min + span
  double min_position = 0.0;         ///< rad
  double max_position = 0.0;         ///< rad
  /// joint_limits.<joint>, the rest of ros2_control's layout: the joint speed the patterns and the
  /// export gate were checked against (rad/s; the export always states one), and the limits the
  /// export does not state (acceleration, jerk, effort: false).
  bool has_velocity_limits = false;
  double max_velocity = 0.0;
  bool has_acceleration_limits = false, has_jerk_limits = false, has_effort_limits = false;
};

enum class Assembly : std::int8_t { minus = -1, any = 0, plus = 1 };

/// One five-bar (export `stations.<station>.<mechanism>`).
struct MechanismConfig {
  std::string name;                  ///< "lower" or "upper"
  std::array<double, 2> o1{}, o2{};  ///< base joints, m
  std::array<double, 4> L{};         ///< L1 L2 L3 L4, m
  std::array<std::int8_t, 2> working_mode{};  ///< signs of cross(A_i - O_i, P - A_i)
  Assembly assembly = Assembly::any;          ///< sign of cross(A2 - A1, P - A1)
  std::array<JointConfig, 2> joints;
  double min_lci = 0.0;                       ///< the design's min_lci (informational to the loop)
  /// max(|O2 - O1|, L1 .. L4): the scale of every relative tolerance.
  double length_scale() const;
};

/// The station's target ellipse (export `stations.<station>.target`; informational to the loop).
struct TargetConfig {
  std::array<double, 2> center{};  ///< m
  std::array<double, 2> axes{};    ///< full lengths, m
  double angle = 0.0;              ///< rad
};

struct StationConfig {
  std::string name;
  TargetConfig target;
  std::vector<MechanismConfig> mechanisms;  ///< in the export's order (lower before upper)
};

/// Link outlines for the collision check (export `collision`, fivebar/collision.hpp's model).
struct CollisionConfig {
  std::string priority = "upper";  ///< the mechanism that keeps its target (only "upper" is implemented)
  bool checked = false;            ///< false: the design had no geometry; no priority rule
  double min_clearance = 0.0;      ///< m
  std::array<double, 4> link_widths{};  ///< m
  double link_thickness = 0.0;     ///< m (informational: the outlines are planar)
  std::array<int, 4> layers{};
  double layer_gap = 0.0;          ///< m (informational)
  double pin_diameter = 0.0, boss_diameter = 0.0, tactor_diameter = 0.0, motor_shaft_diameter = 0.0;  ///< m
  double tactor_height = 0.0;      ///< m (informational)
};

struct Config {
  std::string node = "fivebar_controller";  ///< the ROS 2 node: the document's one top-level key
  std::string design;        ///< fivebar.design
  std::string design_hash;   ///< fivebar.design_hash
  std::string hash_algorithm;  ///< fivebar.hash_algorithm (text)
  std::string tool_version;  ///< fivebar.tool_version: the fivebar that wrote the file
  int format_version = 0;    ///< fivebar.format_version: the layout's version (1)
  std::string units;         ///< fivebar.units (text)
  double loop_rate_hz = 0.0;
  double pwm_hz = 0.0;       ///< the motor drivers' PWM frequency (informational to the loop)
  int adc_bits = 0;
  std::array<double, 2> adc_range_v{};
  double volts_per_count = 0.0;  ///< adc.volts_per_count: V = range_v[0] + counts volts_per_count
  /// joint_margin_rad: commanded joint angles stay this far inside [min_position, max_position].
  double joint_margin = 0.0;
  CollisionConfig collision;
  std::vector<StationConfig> stations;

  /// Mechanisms in all stations, in order (the order of every per-mechanism array).
  std::size_t mechanism_count() const;
  /// Throws ConfigError naming the key of the first broken rule (non-finite numbers, L <= 0,
  /// rad_per_volt 0, bits outside [1, 31], an empty range, ...).
  void validate() const;
};

}  // namespace fivebar::runtime
