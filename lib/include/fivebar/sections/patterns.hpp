#pragma once
/// The `patterns:` section of a design file: the skin-deformation patterns to check. One module of the design (see
/// docs/architecture.md "Design sections"): the struct and its validate() here, its loader and
/// writer hooks in lib/src/sections/patterns.cpp. A Design holds it as `design.get<PatternSettings>()`.

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

/// A station's own pattern of one kind (`patterns.stations.<station>.<kind>`): an override with the
/// scope rule of `controller:` and `motor:` (fivebar/sections/scope.hpp) at station level; a
/// pattern drives the station's pair, so `mechanism` and `joint` stay empty.
struct PatternOverride : JointScope {
  PatternSpec spec;  ///< already merged over the top-level entry of its kind
  PatternOverride() = default;
  PatternOverride(std::string station_name, PatternSpec pattern);
};

/// `patterns:`: which patterns to check, on which stations, at what rate and motor speed.
struct PatternSettings {
  static constexpr std::string_view kKey = "patterns";
  double rate_hz = 100.0;  ///< default rate of every pattern (paper: 100 Hz control loop)
  /// Largest motor speed (rad/s; file: max_joint_speed_deg_s, default 360 deg/s). In a design
  /// with a `controller:` section this is controller.max_velocity (its max_velocity_deg_s).
  double max_joint_speed = 6.283185307179586;
  std::vector<PatternSpec> global;  ///< kinds given at the top level: checked on every station
  /// Kinds given under `stations.<name>`, in file order (a later entry of a station's kind replaces
  /// an earlier one).
  std::vector<PatternOverride> overrides;
  /// The patterns of a station: for each kind in the order stretch, slip, twist, pivot, its own
  /// entry if any (apply_overrides() at the station's level), else the top-level one.
  std::vector<PatternSpec> for_station(std::string_view station) const;
  void validate() const;
};

}  // namespace fivebar
