// `fivebar replay`: a device log through the runtime (fivebar/replay.hpp).

#include "fivebar/replay.hpp"

#include <algorithm>
#include <cmath>
#include <istream>
#include <limits>
#include <map>
#include <ostream>

#include "fivebar/csv_reader.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"

namespace fivebar {

namespace {

const char* kind_suffix(runtime::Reading k) {
  return k == runtime::Reading::counts ? "_counts" : k == runtime::Reading::volts ? "_volts" : "_theta_rad";
}

struct Columns {
  std::vector<std::string> joints, mechanisms;  // joint names; "<station>_<mechanism>"
};

Columns columns_of(const runtime::Config& c) {
  Columns out;
  for (const auto& s : c.stations)
    for (const auto& m : s.mechanisms) {
      out.mechanisms.push_back(s.name + "_" + m.name);
      for (const auto& j : m.joints) out.joints.push_back(j.name);
    }
  return out;
}

}  // namespace

ReplayLog read_replay_log(std::istream& in, const runtime::Config& config, const std::string& origin) {
  // The bench's one reader (fivebar/csv_reader.hpp, docs/bench-files.md): bounded, comment and
  // blank lines skipped, a duplicated column refused.
  csv::Reader reader(in, origin);
  const std::string header_at = reader.where();
  const std::vector<std::string>& header = reader.header();
  std::map<std::string, std::size_t> at;
  for (std::size_t i = 0; i < header.size(); ++i) at[header[i]] = i;
  const auto column = [&](const std::string& name) { return reader.require(name); };
  ReplayLog log;
  runtime::Config present = config;
  present.stations.clear();
  for (const auto& st : config.stations) {
    const std::string& j = st.mechanisms.front().joints[0].name;
    if (at.count(j + "_counts") || at.count(j + "_volts") || at.count(j + "_theta_rad")) {
      present.stations.push_back(st);
      log.stations.push_back(st.name);
    }
  }
  if (present.stations.empty()) {
    const std::string& j = config.stations.front().mechanisms.front().joints[0].name;
    throw InputError(header_at + "column " + j + "_counts (or _volts, _theta_rad) is missing: the log has no joint of the configuration");
  }
  const Columns cols = columns_of(present);
  bool kind_found = false;
  for (runtime::Reading k : {runtime::Reading::counts, runtime::Reading::volts, runtime::Reading::radians}) {
    if (at.count(cols.joints.front() + kind_suffix(k))) {
      if (kind_found) throw InputError(header_at + cols.joints.front() + ": more than one reading column (counts, volts, theta_rad)");
      log.kind = k;
      kind_found = true;
    }
  }
  if (!kind_found) {
    throw InputError(header_at + "column " + cols.joints.front() + "_counts (or _volts, _theta_rad) is missing");
  }
  const std::size_t t_col = column("time_s");
  std::vector<std::size_t> reading_col, duty_col, target_col;
  for (const std::string& j : cols.joints) {
    reading_col.push_back(column(j + kind_suffix(log.kind)));
    duty_col.push_back(column(j + "_duty"));
  }
  for (const std::string& m : cols.mechanisms) {
    target_col.push_back(column(m + "_x_ref_mm"));
    target_col.push_back(column(m + "_y_ref_mm"));
  }
  // The optional status columns: all of them or none.
  std::vector<std::size_t> status_col;
  for (const std::string& m : cols.mechanisms)
    if (at.count(m + "_status")) status_col.push_back(at[m + "_status"]);
  if (!status_col.empty() && status_col.size() != cols.mechanisms.size()) {
    for (const std::string& m : cols.mechanisms) column(m + "_status");  // names the first one missing
  }
  const auto status = [&](std::size_t c) {
    for (std::size_t s = 0; s < 6; ++s)
      if (reader.cell(c) == runtime::to_string(static_cast<runtime::Status>(s))) return static_cast<runtime::Status>(s);
    throw InputError(reader.at(c) + "not a status (ok, moved_by_priority, unreachable, singular, limit, sensor_fault)");
  };
  while (reader.next()) {
    const auto number = [&](std::size_t c) { return reader.number(c, csv::kMaxBenchValue); };
    log.time_s.push_back(number(t_col));
    std::vector<double> r, t, d;
    // The documented marker of a failed reading: an empty cell (NaN to the runtime, a sensor fault).
    for (std::size_t c : reading_col) {
      const bool failed = reader.cell(c).empty();
      log.failed_readings += failed ? 1 : 0;
      r.push_back(failed ? std::numeric_limits<double>::quiet_NaN() : number(c));
    }
    for (std::size_t c : duty_col) d.push_back(number(c));
    for (std::size_t i = 0; i < target_col.size(); ++i) t.push_back(number(target_col[i]) / 1000.0);
    log.readings.push_back(std::move(r));
    log.duties.push_back(std::move(d));
    log.targets_m.push_back(std::move(t));
    if (!status_col.empty()) {
      std::vector<runtime::Status> st;
      for (std::size_t c : status_col) st.push_back(status(c));
      log.statuses.push_back(std::move(st));
    }
  }
  if (log.time_s.empty()) throw InputError(origin + ": the log has no data row");
  return log;
}

void write_replay_header(std::ostream& out, const runtime::Config& config, runtime::Reading kind) {
  const Columns cols = columns_of(config);
  out << "time_s";
  for (const std::string& j : cols.joints) out << "," << j << kind_suffix(kind) << "," << j << "_duty";
  for (const std::string& m : cols.mechanisms) out << "," << m << "_x_ref_mm," << m << "_y_ref_mm";
  out << "\n";
}

void write_replay_row(std::ostream& out, double t, const std::vector<double>& readings, const std::vector<double>& targets,
                      const double* duties, std::size_t joints) {
  out << format::shortest(t);
  // A failed reading (NaN) is written as the documented marker, an empty cell.
  for (std::size_t j = 0; j < joints; ++j) {
    out << "," << (std::isnan(readings[j]) ? std::string() : format::shortest(readings[j])) << "," << format::shortest(duties[j]);
  }
  for (double v : targets) out << "," << format::shortest(v * 1000.0);
  out << "\n";
}

runtime::Config config_for_log(const runtime::Config& config, const ReplayLog& log) {
  runtime::Config c = config;
  c.stations.clear();
  for (const auto& st : config.stations)
    for (const std::string& name : log.stations)
      if (st.name == name) c.stations.push_back(st);
  return c;
}

ReplayResult replay_log(const runtime::Config& full, const ReplayLog& log, double tolerance, ReplayTrace* trace) {
  const runtime::Config config = config_for_log(full, log);
  runtime::Controller ctl(config);
  const Columns cols = columns_of(config);
  ReplayResult r;
  r.tolerance = tolerance;
  r.rows = log.time_s.size();
  for (const std::string& j : cols.joints) r.joints.push_back({j, 0.0, 0, 0});
  std::vector<std::size_t> mechanism_of;  // per joint: its mechanism (runtime order), for the failed readings' check
  for (const auto& s : config.stations)
    for (const auto& m : s.mechanisms) {
      for (std::size_t i = 0; i < m.joints.size(); ++i) mechanism_of.push_back(r.mechanisms.size());
      r.mechanisms.push_back(s.name + "/" + m.name);
    }
  r.status_counts.assign(r.mechanisms.size(), {});
  if (trace) {
    trace->duties.assign(r.rows, {});
    trace->statuses.assign(r.rows, {});
  }
  for (std::size_t row = 0; row < r.rows; ++row) {
    ctl.cycle(log.readings[row].data(), log.kind, log.targets_m[row].data());
    for (std::size_t k = 0; k < r.mechanisms.size(); ++k) {
      const runtime::Status st = ctl.mechanism(k).status;
      ++r.status_counts[k][static_cast<std::size_t>(st)];
      if (log.statuses.empty() || log.statuses[row][k] == st) continue;
      ++r.status_mismatches;
      if (!r.first_status_mismatch) {
        r.first_status_mismatch = true;
        r.first_status_row = row;
        r.first_status_mechanism = r.mechanisms[k];
        r.first_status_logged = log.statuses[row][k];
        r.first_status_runtime = st;
      }
    }
    if (trace) {
      trace->duties[row].assign(ctl.duties(), ctl.duties() + cols.joints.size());
      for (std::size_t k = 0; k < r.mechanisms.size(); ++k) trace->statuses[row].push_back(ctl.mechanism(k).status);
    }
    for (std::size_t j = 0; j < cols.joints.size(); ++j) {
      // A failed reading: the runtime must give that joint zero duty and its mechanism sensor_fault
      // (docs/runtime.md "One cycle"); the logged duty is compared below like any other.
      if (std::isnan(log.readings[row][j])) {
        ++r.failed_readings;
        ++r.joints[j].failed_readings;
        if (ctl.duties()[j] != 0.0 || ctl.mechanism(mechanism_of[j]).status != runtime::Status::sensor_fault) ++r.failed_not_faulted;
      }
      // A logged duty may be rounded by the device's logger: the difference, not bits, is compared.
      const double diff = std::fabs(ctl.duties()[j] - log.duties[row][j]);
      ReplayJoint& rj = r.joints[j];
      rj.max_difference = std::max(rj.max_difference, diff);
      r.max_difference = std::max(r.max_difference, diff);
      if (diff > tolerance) {
        ++rj.mismatches;
        ++r.mismatches;
        if (!r.first_mismatch) {
          r.first_mismatch = true;
          r.first_row = row;
          r.first_time_s = log.time_s[row];
          r.first_joint = cols.joints[j];
          r.first_logged = log.duties[row][j];
          r.first_runtime = ctl.duties()[j];
        }
      }
    }
  }
  return r;
}

void write_replay_comparison_csv(std::ostream& out, const ReplayLog& log, const ReplayResult& r, const ReplayTrace& trace) {
  out << "time_s";
  for (const ReplayJoint& j : r.joints) out << "," << j.joint << "_logged_duty," << j.joint << "_runtime_duty," << j.joint << "_duty_difference";
  for (std::string m : r.mechanisms) {
    std::replace(m.begin(), m.end(), '/', '_');
    out << "," << m << "_status";
  }
  out << "\n";
  for (std::size_t row = 0; row < r.rows; ++row) {
    out << format::shortest(log.time_s[row]);
    for (std::size_t j = 0; j < r.joints.size(); ++j) {
      const double logged = log.duties[row][j], runtime = trace.duties[row][j];
      out << "," << format::shortest(logged) << "," << format::shortest(runtime) << "," << format::shortest(runtime - logged);
    }
    for (runtime::Status st : trace.statuses[row]) out << "," << runtime::to_string(st);
    out << "\n";
  }
}

Json to_json(const ReplayResult& r) {
  Json j;
  j["rows"] = r.rows;
  j["tolerance"] = r.tolerance;
  j["max_duty_difference"] = r.max_difference;
  j["mismatches"] = r.mismatches;
  j["failed_readings"] = r.failed_readings;
  j["failed_readings_not_faulted"] = r.failed_not_faulted;
  j["status_mismatches"] = r.status_mismatches;
  j["first_status_mismatch"] = r.first_status_mismatch ? Json{{"row", r.first_status_row + 1},
                                                              {"mechanism", r.first_status_mechanism},
                                                              {"logged_status", runtime::to_string(r.first_status_logged)},
                                                              {"runtime_status", runtime::to_string(r.first_status_runtime)}}
                                                       : Json(nullptr);
  j["passed"] = r.passed();
  j["first_mismatch"] = r.first_mismatch ? Json{{"row", r.first_row + 1},  // data rows from 1, as the text
                                                {"time_s", r.first_time_s},
                                                {"joint", r.first_joint},
                                                {"logged_duty", r.first_logged},
                                                {"runtime_duty", r.first_runtime}}
                                         : Json(nullptr);
  Json joints = Json::array();
  for (const ReplayJoint& rj : r.joints) {
    joints.push_back({{"joint", rj.joint}, {"max_duty_difference", rj.max_difference}, {"mismatches", rj.mismatches},
                      {"failed_readings", rj.failed_readings}});
  }
  j["joints"] = joints;
  Json mechs = Json::array();
  for (std::size_t k = 0; k < r.mechanisms.size(); ++k) {
    const auto slash = r.mechanisms[k].find('/');
    Json counts = Json::object();
    for (std::size_t s = 0; s < 6; ++s) counts[runtime::to_string(static_cast<runtime::Status>(s))] = r.status_counts[k][s];
    mechs.push_back({{"station", r.mechanisms[k].substr(0, slash)},
                     {"mechanism", r.mechanisms[k].substr(slash + 1)},
                     {"statuses", counts}});
  }
  j["mechanisms"] = mechs;
  return j;
}

}  // namespace fivebar
