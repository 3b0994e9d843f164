#pragma once
/// `fivebar replay` (docs/runtime.md "Replay"): a recorded log of the device's measured joints and
/// duties fed through fivebar::runtime, its duties compared with the logged ones (a field check that
/// the device runs this configuration), and the log format the software-in-the-loop run writes.
///
/// Log (CSV, header row, docs/conventions.md bench files): `time_s`; per joint of the configuration
/// `<joint>_counts`, `<joint>_volts` or `<joint>_theta_rad` (one kind for the whole log) and
/// `<joint>_duty`; per mechanism the reference point it was given, `<station>_<mechanism>_x_ref_mm`
/// and `_y_ref_mm`. Other columns are ignored.
///
/// A failed reading (the device could not take it: an ADC read error, a sensor fault) is an empty
/// reading cell: the runtime is fed NaN for it, which it treats as a sensor fault (that mechanism's
/// duties 0, status sensor_fault), so the logged duties of that row must be 0. Any other cell that
/// is not a finite number is refused at its line and column.
///
/// Optional columns `<station>_<mechanism>_status` (what the device's loop logs, runtime::to_string):
/// where the log has them, each row's logged status must be the runtime's (a sensor_fault on a
/// failed reading included); a cell that is not a status name is refused at its line and column.

#include <array>
#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <string>
#include <vector>

#include "fivebar/json.hpp"
#include "fivebar/runtime/controller.hpp"

namespace fivebar {

struct ReplayLog {
  /// The configuration's stations the log has columns for (a station without any is left out:
  /// a log of one station replays against the export of several).
  std::vector<std::string> stations;
  runtime::Reading kind = runtime::Reading::counts;
  std::vector<double> time_s;
  std::vector<std::vector<double>> readings;  ///< per row, in the runtime's joint order; NaN: a failed reading (empty cell)
  std::vector<std::vector<double>> targets_m; ///< per row, 2 per mechanism
  std::vector<std::vector<double>> duties;    ///< per row, logged
  std::size_t failed_readings = 0;            ///< empty reading cells (NaN in `readings`)
  /// Per row, per mechanism: the logged status; empty when the log has no status columns.
  std::vector<std::vector<runtime::Status>> statuses;
};

/// Reads a log for `config` (its joints and mechanisms). InputError "FILE:LINE: column ..." naming
/// a missing column, a cell that is not a number, a row of the wrong length, mixed reading kinds.
ReplayLog read_replay_log(std::istream& in, const runtime::Config& config, const std::string& origin);

/// Header and one row of a log (numbers in their shortest round-trip form).
void write_replay_header(std::ostream& out, const runtime::Config& config, runtime::Reading kind);
void write_replay_row(std::ostream& out, double t_s, const std::vector<double>& readings,
                      const std::vector<double>& targets_m, const double* duties, std::size_t joints);

struct ReplayJoint {
  std::string joint;
  double max_difference = 0.0;  ///< max |runtime duty - logged duty|
  std::size_t mismatches = 0;   ///< rows beyond the tolerance
  std::size_t failed_readings = 0;  ///< rows whose reading of this joint failed (an empty cell)
};

struct ReplayResult {
  std::size_t rows = 0;
  double tolerance = 0.0;
  double max_difference = 0.0;
  std::size_t mismatches = 0;
  bool first_mismatch = false;
  std::size_t first_row = 0;    ///< 0-based data row
  double first_time_s = 0.0;
  std::string first_joint;
  double first_logged = 0.0, first_runtime = 0.0;
  std::vector<ReplayJoint> joints;
  /// Per mechanism (runtime order): "station/mechanism" and the count of each status.
  std::vector<std::string> mechanisms;
  std::vector<std::array<std::size_t, 6>> status_counts;
  /// Failed readings (empty cells) in all, and those where the runtime did not give what it must
  /// (status sensor_fault and duty 0 for that joint): a check of the runtime itself, 0 required.
  std::size_t failed_readings = 0;
  std::size_t failed_not_faulted = 0;
  /// With status columns: values where the logged status is not the runtime's, and the first.
  std::size_t status_mismatches = 0;
  bool first_status_mismatch = false;
  std::size_t first_status_row = 0;  ///< 0-based data row
  std::string first_status_mechanism;  ///< "station/mechanism"
  runtime::Status first_status_logged = runtime::Status::ok, first_status_runtime = runtime::Status::ok;
  bool passed() const { return mismatches == 0 && failed_not_faulted == 0 && status_mismatches == 0; }
};

/// `config` with only the log's stations.
runtime::Config config_for_log(const runtime::Config& config, const ReplayLog& log);

/// What the runtime gave at each row of a replay (optional output of replay_log).
struct ReplayTrace {
  std::vector<std::vector<double>> duties;             ///< per row, in the runtime's joint order
  std::vector<std::vector<runtime::Status>> statuses;  ///< per row, per mechanism (runtime order)
};

/// Runs a fresh runtime of config_for_log(config, log) over the log's rows, in order; with `trace`
/// also keeps its duties and statuses per row.
ReplayResult replay_log(const runtime::Config& config, const ReplayLog& log, double tolerance, ReplayTrace* trace = nullptr);

/// The replay row by row, for a notebook (CSV, header row): time_s; per joint
/// `<joint>_logged_duty`, `<joint>_runtime_duty`, `<joint>_duty_difference` (runtime - logged);
/// per mechanism `<station>_<mechanism>_status` (runtime::to_string). `result` and `trace` are
/// replay_log's for `log`.
void write_replay_comparison_csv(std::ostream& out, const ReplayLog& log, const ReplayResult& result, const ReplayTrace& trace);

Json to_json(const ReplayResult& result);

}  // namespace fivebar
