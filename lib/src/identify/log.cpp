// Identification logs (fivebar/identify/log.hpp).

#include "fivebar/identify/log.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <system_error>

#include "fivebar/csv_reader.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"

namespace fivebar::identify {

namespace {

struct ColumnKind {
  const char* suffix;
  enum Role { drive, reading, current, reference } role;
  DriveKind drive_kind;
  ReadingKind reading_kind;
  int linear;  ///< 1 linear, 0 rotary, -1 either
};

constexpr ColumnKind kColumns[] = {
    {"duty", ColumnKind::drive, DriveKind::duty, ReadingKind::angle, -1},
    {"voltage_V", ColumnKind::drive, DriveKind::voltage, ReadingKind::angle, -1},
    {"torque_Nm", ColumnKind::drive, DriveKind::torque, ReadingKind::angle, 0},
    {"force_N", ColumnKind::drive, DriveKind::torque, ReadingKind::angle, 1},
    {"current_A", ColumnKind::current, DriveKind::current, ReadingKind::angle, -1},
    {"volts", ColumnKind::reading, DriveKind::torque, ReadingKind::volts, -1},
    {"counts", ColumnKind::reading, DriveKind::torque, ReadingKind::counts, -1},
    {"theta_rad", ColumnKind::reading, DriveKind::torque, ReadingKind::angle, 0},
    {"position_m", ColumnKind::reading, DriveKind::torque, ReadingKind::angle, 1},
    {"theta_ref_rad", ColumnKind::reference, DriveKind::torque, ReadingKind::angle, 0},
    {"position_ref_m", ColumnKind::reference, DriveKind::torque, ReadingKind::angle, 1},
};

std::string where(const std::string& path, std::size_t line) { return path + ":" + std::to_string(line) + ": "; }

/// Joint part of a column name: "" or "<station>_<mechanism>_theta<1|2>_"; false when malformed.
/// `x_ref_mm`, `y_ref_mm`, or either after "<station>_<mechanism>_": the targets of the device log.
bool is_reference_column(const std::string& name) {
  // The device log's targets and (device_loop --io linux) its statuses: read, not used.
  for (const std::string suffix : {"x_ref_mm", "y_ref_mm", "status"}) {
    if (name == suffix) return true;
    if (name.size() > suffix.size() + 1 && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0 &&
        name[name.size() - suffix.size() - 1] == '_') {
      return true;
    }
  }
  return false;
}

bool parse_prefix(const std::string& prefix, JointLog& j) {
  if (prefix.empty()) return true;
  const std::size_t theta = prefix.rfind("_theta");
  if (theta == std::string::npos || prefix.size() != theta + 8 || prefix.back() != '_') return false;
  const char digit = prefix[theta + 6];
  if (digit != '1' && digit != '2') return false;
  const std::string sm = prefix.substr(0, theta);
  const std::size_t cut = sm.rfind('_');
  if (cut == std::string::npos || cut == 0 || cut + 1 == sm.size()) return false;
  j.station = sm.substr(0, cut);
  j.mechanism = sm.substr(cut + 1);
  j.joint = digit - '0';
  return true;
}

/// A status column of the device log (`status`, `<station>_<mechanism>_status`): text, not used.
bool is_status_column(const std::string& n) { return n == "status" || (n.size() > 7 && n.compare(n.size() - 7, 7, "_status") == 0); }

/// Even sampling (central differences and the filters assume it): each step within 5 % of the mean,
/// else InputError at the row's line.
void require_even_sampling(const IdentifyLog& log, const std::vector<std::size_t>& row_lines, const std::string& path) {
  const double dt = log.sample_time();
  for (std::size_t i = 0; i + 1 < log.time.size(); ++i) {
    const double step = log.time[i + 1] - log.time[i];
    if (std::abs(step - dt) > 0.05 * dt) {
      throw InputError(where(path, row_lines[i + 1]) + "column 'time_s': step " + format::shortest(step) +
                       " s differs from the log's sample time " + format::shortest(dt) + " s by more than 5 % (resample the log evenly)");
    }
  }
}

}  // namespace

double IdentifyLog::sample_time() const {
  if (time.size() < 2) return 0.0;
  std::vector<double> dt(time.size() - 1);
  for (std::size_t i = 0; i + 1 < time.size(); ++i) dt[i] = time[i + 1] - time[i];
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
  return dt[dt.size() / 2];
}

IdentifyLog read_identify_log(std::istream& in, const std::string& path) {
  IdentifyLog log;
  log.path = path;
  csv::Reader reader(in, path, csv::Limits{kMaxLogLine, kMaxLogBytes, kMaxLogRows});
  const std::vector<std::string>& header = reader.header();
  const std::size_t header_line = reader.header_line();
  log.header_line = header_line;
  int time_col = -1;
  std::map<std::string, std::size_t> joint_index;  // prefix -> joints[]
  struct Binding {
    std::size_t joint;
    const ColumnKind* kind;
  };
  std::vector<std::optional<Binding>> bind(header.size());
  for (std::size_t c = 0; c < header.size(); ++c) {
    const std::string& name = header[c];
    const std::string at = where(path, header_line) + "column " + std::to_string(c + 1) + " '" + csv::shown(name) + "': ";
    if (name == "time_s") {
      time_col = static_cast<int>(c);
      continue;
    }
    if (is_reference_column(name)) continue;  // the device log's targets and statuses (docs/bench-files.md): read, not used
    const ColumnKind* kind = nullptr;
    std::string prefix;
    for (const ColumnKind& k : kColumns) {
      const std::string suffix = k.suffix;
      if (name == suffix || (name.size() > suffix.size() + 1 && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0 &&
                             name[name.size() - suffix.size() - 1] == '_')) {
        kind = &k;
        prefix = name.substr(0, name.size() - suffix.size());
        break;
      }
    }
    JointLog probe;
    if (kind == nullptr || !parse_prefix(prefix, probe)) {
      throw InputError(at +
                       "unknown column (expected time_s and, per joint, [<station>_<mechanism>_theta<1|2>_] followed by "
                       "duty, voltage_V, current_A, torque_Nm or force_N, and volts, counts, theta_rad or position_m, and "
                       "optionally theta_ref_rad or position_ref_m (the controller's reference); "
                       "[<station>_<mechanism>_]x_ref_mm and y_ref_mm are the device log's targets)");
    }
    auto [it, added] = joint_index.emplace(prefix, log.joints.size());
    if (added) {
      probe.prefix = prefix.empty() ? "" : prefix.substr(0, prefix.size() - 1);
      probe.column = c + 1;
      log.joints.push_back(probe);
    }
    bind[c] = Binding{it->second, kind};
  }
  if (time_col < 0) throw InputError(where(path, header_line) + "missing column 'time_s'");
  if (log.joints.empty()) throw InputError(where(path, header_line) + "no joint columns (a drive and a reading per joint)");
  // Roles per joint.
  struct Roles {
    int drive = -1, reading = -1, current = -1, reference = -1;
  };
  std::vector<Roles> roles(log.joints.size());
  for (std::size_t c = 0; c < header.size(); ++c) {
    if (!bind[c]) continue;
    Roles& r = roles[bind[c]->joint];
    const ColumnKind& k = *bind[c]->kind;
    const std::string at = where(path, header_line) + "column '" + header[c] + "': ";
    int& slot = k.role == ColumnKind::drive     ? r.drive
                : k.role == ColumnKind::reading ? r.reading
                : k.role == ColumnKind::current ? r.current
                                                : r.reference;
    if (slot >= 0) {
      const char* what = k.role == ColumnKind::reading ? "reading" : k.role == ColumnKind::reference ? "reference" : "drive";
      throw InputError(at + "a second " + what + " column for the joint (already '" +
                       header[static_cast<std::size_t>(slot)] + "')");
    }
    slot = static_cast<int>(c);
  }
  for (std::size_t j = 0; j < log.joints.size(); ++j) {
    JointLog& jl = log.joints[j];
    Roles& r = roles[j];
    const std::string who = jl.prefix.empty() ? std::string("the joint") : "joint '" + jl.prefix + "'";
    if (r.drive < 0 && r.current >= 0) {  // a current-controlled driver: the current is the drive
      r.drive = r.current;
      r.current = -1;
    }
    if (r.drive < 0) {
      throw InputError(where(path, header_line) + "missing drive column for " + who +
                       " (one of duty, voltage_V, current_A, torque_Nm, force_N)");
    }
    if (r.reading < 0) {
      throw InputError(where(path, header_line) + "missing reading column for " + who +
                       " (one of volts, counts, theta_rad, position_m)");
    }
    const ColumnKind& dk = *bind[static_cast<std::size_t>(r.drive)]->kind;
    const ColumnKind& rk = *bind[static_cast<std::size_t>(r.reading)]->kind;
    if (dk.linear >= 0 && rk.linear >= 0 && dk.linear != rk.linear) {
      throw InputError(where(path, header_line) + "columns '" + header[static_cast<std::size_t>(r.drive)] + "' and '" +
                       header[static_cast<std::size_t>(r.reading)] +
                       "': units do not match (a linear axis is force_N with position_m, a rotary one torque_Nm with theta_rad)");
    }
    jl.linear = dk.linear == 1 || rk.linear == 1;
    if (jl.linear && (dk.linear != 1 || rk.linear != 1)) {
      throw InputError(where(path, header_line) + "a linear axis takes force_N and position_m together (found '" +
                       header[static_cast<std::size_t>(r.drive)] + "' and '" + header[static_cast<std::size_t>(r.reading)] + "')");
    }
    jl.drive = dk.drive_kind;
    jl.drive_column = header[static_cast<std::size_t>(r.drive)];
    jl.reading = rk.reading_kind;
    jl.reading_column = header[static_cast<std::size_t>(r.reading)];
    if (r.reference >= 0) {
      const ColumnKind& fk = *bind[static_cast<std::size_t>(r.reference)]->kind;
      if (fk.linear != (jl.linear ? 1 : 0)) {
        throw InputError(where(path, header_line) + "column '" + header[static_cast<std::size_t>(r.reference)] +
                         "': units do not match the joint's reading '" + jl.reading_column +
                         "' (theta_ref_rad for a rotary joint, position_ref_m for a linear axis)");
      }
      jl.reference_column = header[static_cast<std::size_t>(r.reference)];
    }
  }
  // Rows.
  std::vector<std::size_t> row_lines;
  std::vector<double> v(header.size());
  while (reader.next()) {
    const std::size_t line_no = reader.line();
    for (std::size_t c = 0; c < header.size(); ++c) {
      if (is_status_column(header[c])) continue;  // text (ok, sensor_fault, ...), not used
      v[c] = reader.number(c, kMaxLogValue, "no bench quantity is that large in SI units");
    }
    const double time = v[static_cast<std::size_t>(time_col)];
    if (!log.time.empty() && !(time > log.time.back())) {
      throw InputError(where(path, line_no) + "column 'time_s': " + format::shortest(time) + " does not increase (previous row " +
                       format::shortest(log.time.back()) + ")");
    }
    log.time.push_back(time);
    row_lines.push_back(line_no);
    for (std::size_t j = 0; j < log.joints.size(); ++j) {
      log.joints[j].drive_values.push_back(v[static_cast<std::size_t>(roles[j].drive)]);
      log.joints[j].reading_values.push_back(v[static_cast<std::size_t>(roles[j].reading)]);
      if (roles[j].current >= 0) log.joints[j].current.push_back(v[static_cast<std::size_t>(roles[j].current)]);
      if (roles[j].reference >= 0) log.joints[j].reference.push_back(v[static_cast<std::size_t>(roles[j].reference)]);
    }
  }
  if (log.time.size() < 16) {
    throw InputError(path + ": " + std::to_string(log.time.size()) + " data rows; an identification log needs at least 16");
  }
  require_even_sampling(log, row_lines, path);
  return log;
}

IdentifyLog read_identify_log(const std::filesystem::path& path) {
  // Bounded while reading (kMaxLogBytes, kMaxLogLine), so a device or a pipe is refused as early
  // as a large regular file.
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open the log");
  return read_identify_log(in, path.string());
}

}  // namespace fivebar::identify
