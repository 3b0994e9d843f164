#pragma once
/// Measured or assumed (docs/calibrate.md): which values of a design rest on
/// a measurement (a `provenance:` entry, fivebar/sections/provenance.hpp) and which are
/// assumptions, by group:
///   kinematics     every mechanism's links and bases (`stations.<s>.mechanisms.<m>.links`, `bases`)
///   potentiometer  each joint's volts_at_zero and rad_per_volt, at the narrowest `controller` scope
///                  that sets it (fivebar/sections/controller.hpp ControlOverride), else the defaults
///   motor          every number of `motor:`
///   contact        every number of `contact:`
///   density        `print.density_g_cm3`
///   tolerance      every number of `tolerance:`
/// A group the design does not have (no `motor:`) has no values and so no assumptions.

#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/sections/provenance.hpp"

namespace fivebar {

/// The group names above, in that order.
const std::vector<std::string>& provenance_groups();
/// True when `key` or a key path above it has a provenance entry that counts as a measurement: its
/// sha256 is not a placeholder (all zeros) and, when it records a quality gate
/// (fivebar/provenance/gate.hpp), that gate passed.
bool is_measured(const Design& design, std::string_view key);
/// The key paths of `group` that the design has and that are assumptions. InputError for an
/// unknown group.
std::vector<std::string> assumed_values(const Design& design, std::string_view group);
/// The groups (provenance_groups() order) with at least one assumed value.
std::vector<std::string> assumed_groups(const Design& design);

/// What each validated figure rests on: the one table of figure -> groups of values (the groups
/// above), used by the export's `fivebar.validation` block, the `export` product's summary (and so
/// summary.md, summary.json and the HTML page of `fivebar run`) and the export gate's checks.
///   stability (max_rho, kp_margin, kd_margin, oscillatory_*), min_bandwidth_hz: the plant of
///     fivebar/control.hpp: the closed-chain masses (kinematics, density) and the motors (motor);
///   max_tracking_error_m: the simulated patterns (fivebar/simulate): the same plant, the contact
///     with the finger (contact) and the potentiometers the loop reads (potentiometer);
///   max_saturation_fraction: the same without the potentiometers (the drive, not the reading);
///   robust_margin_mm: the reachable region of each printed device (kinematics, tolerance).
struct FigureBasis {
  std::string key;      ///< the figure's key (`fivebar.validation.<station>.<mechanism>.<key>`)
  std::string label;    ///< "max tracking error"
  double scale = 1.0;   ///< to the unit shown
  std::string unit;     ///< "mm", "Hz", "" ...
  int digits = 3;       ///< decimals shown
  std::vector<std::string> groups;  ///< provenance_groups() it rests on, in that order
};
const std::vector<FigureBasis>& figure_bases();
/// The figure of `key`; InputError naming the known keys otherwise.
const FigureBasis& figure_basis(std::string_view key);
/// The values of `group` that one mechanism's figures rest on and that are assumptions: its own
/// links and bases (kinematics), its joints' potentiometers and motors (each value at the narrowest
/// scope that sets it), and the design-wide contact, density and tolerance values.
std::vector<std::string> assumed_values(const Design& design, std::string_view group, std::string_view station,
                                        std::string_view mechanism);
/// The groups of `key`'s basis that have assumed values (provenance_groups() order): for one
/// mechanism's figure when `station` and `mechanism` are given, else over the whole design.
std::vector<std::string> figure_assumed(const Design& design, std::string_view key, std::string_view station = {},
                                        std::string_view mechanism = {});
/// "motor, contact assumed" or "measured (kinematics, density, motor)": what `key` rests on.
std::string rests_on_text(const Design& design, std::string_view key, std::string_view station = {},
                          std::string_view mechanism = {});
/// "max tracking error 0.117 mm: motor, contact assumed" for the figure's value in its key's unit.
std::string rests_on_line(const Design& design, std::string_view key, double value, std::string_view station = {},
                          std::string_view mechanism = {});
/// The figure and its value alone: "max tracking error 0.117 mm".
std::string figure_text(std::string_view key, double value);

/// A value that `controller.require_measured` does not trust as measured, and why.
struct UntrustedValue {
  std::string key;
  std::string reason;  ///< "no provenance: entry", "written without a quality gate", ...
};
/// The values of `group` that the figures of `stations` (every station when empty) rest on and that
/// the export's `controller.require_measured` does not trust: a value is trusted only when its
/// provenance entry (its own or a key path's above it) records a quality gate that passed, its
/// sha256 is not all zeros, and the file it names, when present (resolved against the design
/// file's folder), still has that sha256. Only these stations' mechanisms count for kinematics,
/// potentiometer and motor values, and only `mechanism` of them when it is given; contact, density
/// and tolerance are design-wide.
std::vector<UntrustedValue> untrusted_values(const Design& design, std::string_view group, const std::vector<std::string>& stations,
                                             std::string_view mechanism = {});
/// The groups (provenance_groups() order) with an assumed value that the figures of `stations`
/// (all when empty; only `mechanism` when given) rest on: the export gate's `assumed` list.
std::vector<std::string> assumed_groups(const Design& design, const std::vector<std::string>& stations, std::string_view mechanism = {});

/// The key paths of a mechanism's twelve calibration values, in the order of
/// fivebar/calibrate/model.hpp (links[0..3], bases[0][0], bases[0][1], bases[1][0], bases[1][1]; each
/// joint's volts_at_zero and rad_per_volt at the narrowest `controller` scope that sets it).
std::array<std::string, 12> calibration_keys(const Design& design, std::string_view station, std::string_view mechanism);

/// Where measured values came from: the fields of a provenance entry but the sigma.
struct MeasurementSource {
  std::string file;    ///< relative to the folder of the design the entry is written in (recorded_source())
  std::string sha256;  ///< of its bytes (fivebar/sha256.hpp)
  std::string date;    ///< YYYY-MM-DD, UTC
  std::string method;  ///< "fivebar calibrate: ...", "fivebar identify: IDIM-LS ...", ...
};
/// The path a provenance entry records for `data` (a file read now, a path as the user gave it,
/// relative to the working directory) when the design carrying the entry is written into
/// `design_folder`: relative to that folder, the way untrusted_values() resolves it, so that the
/// file's hash is checked wherever fivebar later runs; absolute when no relative path leads there.
std::string recorded_source(const std::filesystem::path& data, const std::filesystem::path& design_folder);
/// Today's date, YYYY-MM-DD (UTC): the `date` of the entries written now.
std::string today_utc();
/// One measured value: the key path it sets and its standard deviation (the key's file unit).
struct MeasuredValue {
  std::string key;
  double sigma = 0.0;
};
/// The one writer of provenance entries (`fivebar calibrate`, `fivebar identify`): `design` (whose
/// numbers the caller has already set) with an entry per value, and, when `covariance` is given
/// (values.size() square, file units, the values' order), the correlation of every pair as
/// `correlation:` under the key that sorts first. A value's earlier entry is replaced, and the
/// correlations other entries held with it are dropped (a new measurement supersedes the old one).
/// The result is validated (ValidationError).
/// `gates` (empty, or one per value in the values' order) are the quality gates the fit passed
/// (fivebar/provenance/gate.hpp GateResult::records()), kept in each entry.
Design with_measured_values(const Design& design, const std::vector<MeasuredValue>& values, const MeasurementSource& source,
                            const Eigen::MatrixXd& covariance = Eigen::MatrixXd(), const std::vector<GateRecord>& gates = {});

/// The covariance that the provenance entries give for `keys` (file units, keys' order): sigma^2 on
/// the diagonal of each key with an entry and a sigma (its own, or that of a key path above it),
/// sigma_a sigma_b rho_ab off it where an entry names the pair, 0 elsewhere; `measured[i]` says
/// whether key i has a sigma (the rows of the others are zero).
struct ProvenanceCovariance {
  Eigen::MatrixXd covariance;
  std::vector<bool> measured;
  std::vector<std::string> sources;  ///< the distinct source files of the measured keys
};
ProvenanceCovariance provenance_covariance(const Design& design, const std::vector<std::string>& keys);

}  // namespace fivebar
