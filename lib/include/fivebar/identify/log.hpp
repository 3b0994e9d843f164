#pragma once
/// Identification logs (docs/identify.md "Logs"): a CSV with a header, `time_s` and, per joint, one
/// drive column, one reading column and optionally a measured current. Unprefixed columns are one
/// joint (a motor on the bench); `<station>_<mechanism>_theta<1|2>_<column>` names a joint of the
/// design. A linear axis spells the same model with `force_N` and `position_m`.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <istream>
#include <string>
#include <vector>

namespace fivebar::identify {

/// What drives the joint.
enum class DriveKind { duty, voltage, current, torque };
/// What the log reads of the joint's position.
enum class ReadingKind { volts, counts, angle };

/// Limits of a log (bad input beyond them is refused, never truncated).
inline constexpr std::size_t kMaxLogLine = 4096;                 ///< characters per line
inline constexpr std::size_t kMaxLogRows = 20'000'000;           ///< data rows
inline constexpr std::uintmax_t kMaxLogBytes = 1ull << 30;       ///< file size
inline constexpr double kMaxLogValue = 1e9;                       ///< |cell|, SI (keeps every product finite)

/// One joint's columns, SI (or the linear axis' newtons and metres).
struct JointLog {
  std::string prefix;      ///< "" (a bench motor) or "index_lower_theta1"
  std::size_t column = 0;  ///< 1-based column of the header that first names this joint (messages)
  std::string station;     ///< from the prefix, else empty
  std::string mechanism;   ///< from the prefix, else empty
  int joint = 0;           ///< 1 or 2 from the prefix, else 0
  bool linear = false;     ///< force_N / position_m: a linear axis
  DriveKind drive = DriveKind::torque;
  std::string drive_column;
  std::vector<double> drive_values;
  ReadingKind reading = ReadingKind::angle;
  std::string reading_column;
  std::vector<double> reading_values;
  std::vector<double> current;  ///< measured current_A next to a duty or voltage drive; empty if none
  /// The reference the joint's controller followed while the log was taken (`theta_ref_rad`, or
  /// `position_ref_m` for a linear axis), rad (m); empty if the log has none (closed-loop
  /// identification, docs/identify.md "Closed loop").
  std::string reference_column;
  std::vector<double> reference;
};

struct IdentifyLog {
  std::string path;          ///< for messages
  std::size_t header_line = 0;  ///< 1-based line of the header (messages)
  std::vector<double> time;  ///< s, strictly increasing
  std::vector<JointLog> joints;
  double sample_time() const;  ///< median step, s
};

/// Parses a log; InputError naming `path`, the line and the column on any fault (missing or
/// unknown column, duplicate, empty, non-finite or out-of-range (kMaxLogValue) cell, time not increasing or not evenly sampled
/// within 5 %, a line longer than kMaxLogLine, too few rows, a linear drive with a rotary reading).
IdentifyLog read_identify_log(std::istream& in, const std::string& path);
/// Same, from a file (InputError when it cannot be opened or exceeds kMaxLogBytes).
IdentifyLog read_identify_log(const std::filesystem::path& path);

}  // namespace fivebar::identify
