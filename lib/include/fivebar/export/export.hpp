#pragma once
/// Validated controller export (docs/architecture.md "Products", README `export`): the configuration the device's ROS controller
/// runs with (paper Sec. II-D: per mechanism an IK module, FK of the measured joints for collision
/// checks with the upper mechanism's priority, a PID per motor at 100 Hz with 1 kHz PWM, joints
/// read from potentiometers through a 16-bit DAQ), written only for a design that passes the
/// export gate, in three formats with one content:
///
///   ros2    ROS 2 parameters YAML, `<node>: {ros__parameters: {...}}` (render_ros2_yaml);
///   json    the same tree as JSON (render_json);
///   header  a C++17 header of `inline constexpr` values for firmware builds (render_header):
///           maps become namespaces (the node's name outermost, `ros__parameters` left out).
///
/// Content (controller_parameters(); the keys are listed once, in fivebar/runtime/config_layout.hpp,
/// and the values come from fivebar/device/config.hpp device_config()), SI units as ROS expects (REP 103: m, rad, s, V, Hz), unit
/// suffixes on fivebar's own keys:
///   fivebar: {design, design_hash, hash_algorithm, tool_version, format_version, units}
///   loop_rate_hz, pwm_hz, adc: {bits, range_v [lo, hi], volts_per_count}, joint_margin_rad (the
///     runtime's margin inside the usable ranges, controller.joint_margin_deg)
///   station_names [..], joint_names [..] (every joint, station and mechanism order)
///   stations.<station>: {target: {center_m, axes_m (full lengths), angle_rad}, mechanisms [..],
///     <lower|upper>: {joint_names, o1_m, o2_m, link_lengths_m [L1..L4], working_mode,
///     assembly_mode, min_lci}}
///   collision: {priority: "upper", checked, and with geometry: min_clearance_m, link_widths_m,
///     link_thickness_m, layers, layer_gap_m, pin_diameter_m, boss_diameter_m, tactor_diameter_m,
///     tactor_height_m, motor_shaft_diameter_m}
///   joint_limits.<joint>: ros2_control layout: has_position_limits, min_position, max_position
///     (only with limits: the joint's usable range of fivebar/device/joint_limits.hpp, i.e. the design's
///     ccw arc cut by the potentiometer's travel and the hard stops, max = min + span), has_velocity_limits,
///     max_velocity (rad/s), has_acceleration_limits, has_jerk_limits, has_effort_limits (false)
///   gains.<joint>: {p, i, d, i_clamp} (duty per rad, see PidGains)
///   potentiometers.<joint>: {volts_at_zero, rad_per_volt}: theta = rad_per_volt (V - volts_at_zero)
///
/// Joint angles are continuous on one branch per joint, the one holding its angle at the target
/// centre normalised to (-pi, pi]: min_position is the representative of the design's lo at most
/// one turn below it, and the potentiometer map and the gate's ranges use the same branch (so an
/// upper mechanism's limits [-200, -60] deg stay [-200, -60], not [160, 300]).
///
/// Joint names: `<station>_<mechanism>_theta<1|2>`, e.g. `index_lower_theta1` (motor at O1 of
/// the index station's lower mechanism). Every double is written as a double (`5.0`, never `5`)
/// in its shortest round-trip form (format_double), so ROS never reads an integer where it
/// declares a double and every value reads back bit for bit.
///
/// Design hash: SHA-256 (FIPS 180-4, fivebar/sha256.hpp) of the canonical design text
/// to_yaml(export_view(design, stations)), written "sha256:<64 hex digits>" in every exported file
/// (the three controller formats under fivebar.design_hash, the URDF's and the MJCF's first
/// comment). The view is the whole design (kinematics, geometry, print, patterns, controller,
/// motor, contact, tolerance, provenance) for the exported stations, without what no exported
/// byte and no figure of the gate reads: `products:`, `sweep:`, `optimize:` and `bench:` (the
/// bench files' names; what was fitted from them is in the values and in provenance:). The writer
/// prints every value, defaults included, in shortest round-trip form, so two designs that differ
/// in any such value hash differently; test_export walks every number of the showcase to hold it.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/coverage/coverage.hpp"
#include "fivebar/design.hpp"
#include "fivebar/device/config.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/json.hpp"
#include "fivebar/export/urdf.hpp"

namespace fivebar {

enum class ExportFormat : std::uint8_t { ros2, json, header };
std::string_view to_string(ExportFormat format);
/// "ros2", "json", "header"; std::nullopt otherwise.
std::optional<ExportFormat> parse_export_format(std::string_view text);
/// ".yaml", ".json", ".hpp".
std::string_view file_extension(ExportFormat format);
/// The three formats, in the order above.
std::vector<ExportFormat> all_export_formats();

struct ExportOptions {
  /// Stations to export (and gate); empty: every station of the design.
  std::vector<std::string> stations;
  CoverageOptions coverage;
  /// Points on each target ellipse's boundary where the joint angles are evaluated (their extremes
  /// over the filled ellipse lie on its boundary away from singularities: dtheta/dP = J^-1 != 0).
  int boundary_samples = 720;
  /// Called with one line per step of the gate ("coverage of station index"); may be empty.
  std::function<void(std::string_view)> progress;
  /// Also write `<design>_<station>.urdf` per exported station (fivebar/export/urdf.hpp) when the design
  /// has `geometry:` (the links' outlines and masses), with these
  /// options (the parts' renders for masses and meshes, when there are).
  bool urdf = false;
  /// Also write `<design>_<station>.xml` per exported station, the MJCF (fivebar/export/mjcf.hpp), with
  /// `geometry:`; the same urdf_options (parts and meshes).
  bool mjcf = false;
  UrdfOptions urdf_options;
  /// Also write the ROS 2 description package of the exported stations (fivebar/export/ros2_package.hpp),
  /// with `geometry:`, into `dir / ros2_package_subdir` ("" : `dir` itself); the same urdf_options.
  bool ros2_package = false;
  std::string ros2_package_subdir;
};

/// One check of the export gate.
struct GateCheck {
  std::string kind;     ///< names, geometry, coverage, singularity, joint_limits, calibration, pattern
  std::string subject;  ///< "index/lower", "index/shared", "index stretch", "design", ...
  bool passed = false;
  std::string detail;   ///< one line: the measured value against its threshold, or why it failed
};

/// Angles one joint takes over the target ellipse (samples), rad, on the joint's branch (above).
struct JointSweep {
  std::string name;  ///< joint name
  double lo = 0.0;
  double hi = 0.0;
};

/// Everything the gate decided. The export is written only when passed().
struct ExportGate {
  std::vector<std::string> stations;  ///< the stations gated (and exported)
  std::vector<GateCheck> checks;      ///< in a fixed order: names, geometry, per station, patterns
  std::vector<JointSweep> joints;     ///< ranges over the ellipses, for reports
  Json validation = Json::object();   ///< the loop checks' figures (above); empty without `motor:`
  /// The groups of values the figures rest on that are assumptions (fivebar/provenance.hpp
  /// assumed_groups(): no `provenance:` entry), e.g. {"motor", "contact"}.
  std::vector<std::string> assumed;
  bool passed() const;
  /// "subject kind: detail" of every failed check.
  std::vector<std::string> reasons() const;
};

/// The export gate, every check run (none stops the others):
///   names        node and station names are identifiers in all three formats: [A-Za-z][A-Za-z0-9_]*,
///                no "__", not a C++ keyword (nor `linux` / `unix`, GNU's predefined macros);
///   geometry     a station with both mechanisms needs `geometry:` (the controller's collision check);
///   coverage     station_coverage() with the design's thresholds: each mechanism and the shared
///                region cover the target ellipse (in the working mode, within the joint limits, on
///                the assembly side, LCI >= the mechanism's min_lci);
///   singularity  min LCI over the ellipse >= max(controller.min_lci, mechanism min_lci) and > 0;
///   joint_limits every boundary and interior sample of the ellipse is within the joint limits
///                (the exact containment of coverage() already covers the joint-limited region);
///   calibration  the joint's range (its limits, else its angles over the ellipse) reads within
///                the ADC's input range through its potentiometer;
///   hardware_limits, joint_margin  the usable range of every joint from its potentiometer's travel
///                and the hard stops (fivebar/device/joint_limits.hpp), and the target and every pattern at
///                least controller.joint_margin inside it, the proximal links clear of the other leg's;
///   pattern      every pattern of `patterns:` for the station passes check_pattern();
/// and, for a design with `motor:` (and `geometry:`), the loop (lib/src/export/export_control_gate.cpp):
///   stability    per mechanism, the sampled PID loop is stable (spectral radius < 1) at every
///                pose of a grid over its target (fivebar/control.hpp);
///   tracking     per pattern, simulated under the PID (fivebar/dynamics.hpp), each tactor stays
///                within controller.max_tracking_error_mm of its reference;
///   saturation   per pattern, each mechanism's motors are saturated for at most
///                controller.max_saturation_fraction of the time.
/// The figures of those checks go into the exported files under fivebar.validation (SI units):
/// `<station>.<mechanism>: {max_rho, kp_margin, kd_margin, worst_pose_m, oscillatory_damping,
/// oscillatory_frequency_hz, min_bandwidth_hz, max_tracking_error_m, max_saturation_fraction}`; check_export()
/// leaves that block out of its comparison (measured figures, not design values).
/// Every check runs on the stations with their usable ranges as joint limits (with_usable_limits()).
/// Throws InputError for a design without `controller:` or an unknown station in options.
ExportGate export_gate(const Design& design, const ExportOptions& options = {});

// joint_name(), export_view(), design_hash() and device_config(): fivebar/device/config.hpp.

/// The parameter tree `{<node>: {ros__parameters: {...}}}` (layout above):
/// configuration_document(device_config(design, stations)), the device's Config written through
/// the one key list (fivebar/runtime/config_layout.hpp). Needs `controller:` (InputError
/// otherwise); does not run the gate.
Json controller_parameters(const Design& design, const std::vector<std::string>& stations);

/// Shortest text that reads back as the same double (std::to_chars), always recognisable as a
/// double by YAML 1.1 and 1.2, ROS and C++: a mantissa without '.' gets ".0" ("5.0", "1.0e-05",
/// "-2.5e+20", "0.1"); "inf", "-inf", "nan" for non-finite values.
std::string format_double(double value);

/// The tree as a ROS 2 parameters file (block maps, flow lists, quoted strings, keys quoted where YAML 1.1
/// would read a boolean or null (`on`, `off`, `yes`, `no`, `y`, `n`, `true`, `false`, `null`, `~`, any case), doubles by
/// format_double). std::logic_error for a value ROS cannot hold (non-finite double, nested or
/// empty or mixed list).
std::string render_ros2_yaml(const Json& parameters);
/// The tree as JSON (2-space indent).
std::string render_json(const Json& parameters);
/// The tree as a C++17 header.
std::string render_header(const Json& parameters);
std::string render(ExportFormat format, const Json& parameters);

/// Reads an exported document back into the tree render() came from: numbers keep their kind
/// (a YAML `5` is an integer, `5.0` a double; a header's `double` is a double). InputError
/// "ORIGIN:LINE: ..." for text that is not such a document.
Json parse_export(ExportFormat format, const std::string& text, const std::string& origin);
/// By extension (.yaml/.yml, .json, .hpp/.h/.hh), else by the first characters.
ExportFormat detect_export_format(const std::filesystem::path& path, const std::string& text);

/// The gate's verdict and, when it passed, the files written.
struct ExportResult {
  ExportGate gate;
  std::string hash;  ///< design_hash() of the exported stations
  Json parameters;   ///< the tree (null when the gate failed)
  std::vector<std::filesystem::path> files;  ///< written, in format order; empty when refused
};

/// `<design>_controller` + `_<station>` for a one-station export of a several-station design.
std::string export_stem(const Design& design, const std::vector<std::string>& stations);

/// Runs the gate; only when it passes, renders every requested format (and, with options.urdf
/// and options.mjcf, the URDF and the MJCF of every exported station) in memory, creates `dir`
/// and writes each file atomically (all temporaries written before the first rename; a target
/// that is not a regular file is refused before anything is written). A failed gate creates and
/// writes nothing. IoError when the files cannot be written.
ExportResult export_controller(const Design& design, const std::vector<ExportFormat>& formats,
                               const std::filesystem::path& dir, const ExportOptions& options = {});

/// One value of an exported file that is not what the design gives.
struct ExportDifference {
  std::string path;      ///< "node.ros__parameters.gains.index_lower_theta1.p"
  std::string expected;  ///< rendered as in the file ("5.0", "\"-+\"", "(absent)")
  std::string found;
};

/// `fivebar export --check`: an exported file compared with the export of a design.
struct ExportCheck {
  std::string format = "ros2";    ///< "ros2", "json", "header", "urdf" or "mjcf"
  std::string file_design;        ///< fivebar.design in the file (the URDF's and MJCF's stamp comment)
  std::string file_hash;          ///< fivebar.design_hash in the file
  std::string design_hash;        ///< of the design, for the file's stations
  std::string file_tool_version;  ///< informational: a different version is not a mismatch
  std::vector<std::string> stations;  ///< fivebar's station_names in the file
  std::vector<ExportDifference> differences;  ///< every value that differs (hash first when it does)
  /// What the comparison left out, and why (a URDF's masses from the parts' renders).
  std::vector<std::string> not_compared;
  bool hash_matches() const { return file_hash == design_hash; }
  bool matches() const { return differences.empty(); }
};

/// Re-reads `text` (an exported file of `format`) and compares every value, and the hash, with
/// controller_parameters() of `design` for the stations the file names. InputError when the text
/// is not an exported document.
ExportCheck check_export(const std::string& text, ExportFormat format, const Design& design,
                         const std::string& origin);
/// A station's URDF (render_urdf()) or MJCF (render_mjcf()) read back and compared, element by
/// element and attribute by attribute (numbers as doubles), with the design's rendering of the
/// station its stamp comment names ("Generated by fivebar V from design D, station S (design hash
/// H)"). A difference's path is the element path with each element keyed by its name
/// ("robot/joint[index_lower_theta1]/limit@velocity", "mujoco/worldbody/body[...]@pos"); the
/// stamp's hash is "(stamp) design hash". A file that names meshes had its masses from the parts'
/// STL renders: its inertials, visuals and mesh assets are then not compared (not_compared says
/// so). InputError "ORIGIN:LINE: ..." for text that is not such a document.
ExportCheck check_robot_export(const std::string& text, const Design& design, const std::string& origin);
/// Largest file `export --check` reads (docs/reliability.md "Resource bounds").
inline constexpr std::uintmax_t kMaxExportedFileBytes = std::uintmax_t{64} << 20;
/// Same, reading `file`: a URDF or MJCF by extension (.urdf, .xml) or by a leading '<', else the
/// controller formats of detect_export_format(). InputError naming the file past
/// kMaxExportedFileBytes (checked while reading).
ExportCheck check_export_file(const std::filesystem::path& file, const Design& design);

/// The gate and the written files as JSON (units at the edges).
Json to_json(const ExportGate& gate);

}  // namespace fivebar
