// The replay library (fivebar/replay.hpp, fivebar/replay/sil.hpp) and the `bench_replay` product:
// a log the runtime wrote in the loop replays with no duty difference; a log whose duties were
// changed, or a configuration whose gains were scaled, is flagged with the figure the known change
// predicts (the changed values and their offsets; c x the logged duty, from the log alone); the
// `bench.replay_logs` key's bad names are the design file's FILE:LINE: key messages.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include "fivebar/error.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/format.hpp"
#include "fivebar/replay.hpp"
#include "fivebar/replay/sil.hpp"
#include "fivebar/runtime/json_config.hpp"
#include "fivebar/scene.hpp"
#include "fivebar/sections/bench.hpp"
#include "process.hpp"

namespace fivebar {
namespace {

namespace fs = std::filesystem;
namespace rt = fivebar::runtime;
using ::testing::HasSubstr;

const fs::path kDesign = fs::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml";

using fivebar::testing::slurp;

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::stringstream s(line);
  for (std::string c; std::getline(s, c, ',');) out.push_back(c);
  return out;
}

class Replay : public ::testing::Test {
 protected:

  static const Design& paper() {
    static const Design d = load_design(kDesign.string());
    return d;
  }
  /// The showcase's export as the device reads it (the JSON text through the runtime's reader).
  static rt::Config exported(const std::vector<std::string>& stations = {}) {
    return rt::parse_config_json(render_json(controller_parameters(paper(), stations)), "x.json");
  }

  /// The index station's stretch pattern in the loop with the index station's export (the log has
  /// its columns only, as a device of one station logs; it replays against the export of both).
  SilRun sil(bool replay) {
    SilRequest request;
    request.stations = {"index"};
    request.pattern = PatternKind::stretch;
    request.config = std::make_shared<const rt::Config>(exported({"index"}));
    request.replay = replay;
    request.open_log = [this](const std::string& name) { return AtomicFile(dir_ / name); };
    std::vector<SilRun> runs = run_sil(paper(), request);
    EXPECT_EQ(runs.size(), 1u);
    return runs.at(0);
  }

  static ReplayLog read(const std::string& text, const rt::Config& config) {
    std::istringstream in(text);
    return read_replay_log(in, config, "log.csv");
  }

  fivebar::testing::ScratchDir scratch_{"fivebar_test_replay"};
  const fs::path& dir_ = scratch_.path();
};

TEST_F(Replay, ALogTheRuntimeWroteInTheLoopReplaysWithNoDutyDifference) {
  const SilRun run = sil(true);
  ASSERT_TRUE(run.simulated());
  ASSERT_TRUE(run.result.ok()) << run.result.reason;
  EXPECT_EQ(run.log, dir_ / "index-stretch-sil.csv");
  ASSERT_TRUE(run.replay.has_value());
  const ReplayResult& r = *run.replay;
  // One log row per controller cycle, every duty reproduced exactly (tolerance 0).
  EXPECT_EQ(r.rows, run.figures["samples"].get<std::size_t>());
  EXPECT_GT(r.rows, 100u);
  EXPECT_EQ(r.max_difference, 0.0);
  EXPECT_EQ(r.mismatches, 0u);
  EXPECT_TRUE(run.ok());
  ASSERT_EQ(r.joints.size(), 4u);
  EXPECT_EQ(to_json(run)["replay"]["max_duty_difference"], 0.0);
  // The log is the one replayed: read again, and with a comment line added, it gives the same.
  const rt::Config config = exported();
  const std::string text = slurp(run.log);
  const ReplayLog log = read("# a comment\n\n" + text, config);
  EXPECT_EQ(log.time_s.size(), r.rows);
  EXPECT_EQ(log.stations, std::vector<std::string>{"index"});
  const ReplayResult again = replay_log(config, log, 0.0);
  EXPECT_EQ(again.max_difference, 0.0);
}

// Duties changed by known offsets at known rows: exactly those values are flagged, the largest
// difference is the largest offset, the first mismatch is the earliest changed value.
TEST_F(Replay, ChangedDutiesAreFlaggedWithTheInjectedOffsets) {
  const SilRun run = sil(false);
  ASSERT_TRUE(run.result.ok());
  std::istringstream in(slurp(run.log));
  std::string header;
  std::getline(in, header);
  const std::vector<std::string> cols = split(header);
  const auto column = [&](const std::string& name) {
    for (std::size_t i = 0; i < cols.size(); ++i)
      if (cols[i] == name) return i;
    ADD_FAILURE() << name;
    return std::size_t{0};
  };
  struct Change {
    std::size_t row;
    std::string joint;
    double offset;
  };
  const std::vector<Change> changes{{40, "index_upper_theta1", 0.02}, {12, "index_lower_theta2", -0.005}, {90, "index_lower_theta1", 3e-7}};
  std::string text = header + "\n";
  std::string line;
  for (std::size_t row = 0; std::getline(in, line); ++row) {
    std::vector<std::string> cells = split(line);
    for (const Change& c : changes) {
      if (c.row != row) continue;
      const std::size_t k = column(c.joint + "_duty");
      cells[k] = format::shortest(std::stod(cells[k]) + c.offset);
    }
    line.clear();
    for (std::size_t i = 0; i < cells.size(); ++i) line += (i ? "," : "") + cells[i];
    text += line + "\n";
  }
  const rt::Config config = exported();
  const ReplayResult r = replay_log(config, read(text, config), 1e-9);
  EXPECT_EQ(r.mismatches, 3u);
  EXPECT_NEAR(r.max_difference, 0.02, 1e-15);
  ASSERT_TRUE(r.first_mismatch);
  EXPECT_EQ(r.first_row, 12u);
  EXPECT_EQ(r.first_joint, "index_lower_theta2");
  EXPECT_NEAR(r.first_logged - r.first_runtime, -0.005, 1e-15);
  for (const ReplayJoint& j : r.joints) {
    double expected = 0.0;
    for (const Change& c : changes)
      if (c.joint == j.joint) expected = std::fabs(c.offset);
    EXPECT_NEAR(j.max_difference, expected, 1e-15) << j.joint;
    EXPECT_EQ(j.mismatches, expected > 0.0 ? 1u : 0u) << j.joint;
  }
  // A tolerance above the smallest offset lets that one pass.
  EXPECT_EQ(replay_log(config, read(text, config), 1e-6).mismatches, 2u);
}

// The runtime's PID is linear in its gains until the duty saturates (docs/runtime.md "One cycle":
// duty = p e + i s + d d, s clamped to i_clamp / i), and a replay feeds it the logged readings, not
// its own plant: with p, i, d and i_clamp of the lower mechanism scaled by c, its duties are c
// times the logged ones and the upper mechanism's are unchanged. The figure follows from the log.
TEST_F(Replay, ScaledGainsAreFlaggedWithTheDifferenceTheScalePredicts) {
  const SilRun run = sil(false);
  ASSERT_TRUE(run.result.ok());
  const double c = 1.25;
  rt::Config scaled = exported();
  for (auto& st : scaled.stations)
    for (auto& m : st.mechanisms)
      if (st.name == "index" && m.name == "lower")
        for (auto& j : m.joints) {
          j.gains.p *= c;
          j.gains.i *= c;
          j.gains.d *= c;
          j.gains.i_clamp *= c;
        }
  const ReplayLog log = read(slurp(run.log), scaled);
  ReplayTrace trace;
  const ReplayResult r = replay_log(scaled, log, 1e-9, &trace);
  ASSERT_EQ(trace.duties.size(), r.rows);
  ASSERT_EQ(r.joints.size(), 4u);
  std::vector<double> expected(4, 0.0);
  std::size_t expected_mismatches = 0;
  for (std::size_t row = 0; row < r.rows; ++row) {
    for (std::size_t j = 0; j < 4; ++j) {
      const bool lower = r.joints[j].joint.rfind("index_lower", 0) == 0;
      const double logged = log.duties[row][j];
      ASSERT_LT(std::fabs(c * logged), 1.0);  // no saturation: the scale holds
      const double predicted = lower ? c * logged : logged;
      EXPECT_NEAR(trace.duties[row][j], predicted, 1e-12) << "row " << row << " " << r.joints[j].joint;
      expected[j] = std::max(expected[j], std::fabs(predicted - logged));
      if (std::fabs(predicted - logged) > 1e-9 + 1e-12) ++expected_mismatches;
    }
  }
  for (std::size_t j = 0; j < 4; ++j) {
    EXPECT_NEAR(r.joints[j].max_difference, expected[j], 1e-12) << r.joints[j].joint;
    if (r.joints[j].joint.rfind("index_upper", 0) == 0) EXPECT_EQ(r.joints[j].max_difference, 0.0);
  }
  EXPECT_GT(r.max_difference, 0.01);  // a quarter of a peak duty of about 0.1
  EXPECT_EQ(r.mismatches, expected_mismatches);
  EXPECT_FALSE(r.passed());
  // The per-cycle CSV holds both duties and their difference.
  std::ostringstream csv;
  write_replay_comparison_csv(csv, log, r, trace);
  std::istringstream lines(csv.str());
  std::string head, first;
  std::getline(lines, head);
  std::getline(lines, first);
  const std::vector<std::string> h = split(head), v = split(first);
  ASSERT_EQ(h.size(), 1 + 4 * 3 + 2u);
  ASSERT_EQ(v.size(), h.size());
  EXPECT_EQ(h[1], "index_lower_theta1_logged_duty");
  EXPECT_EQ(h[3], "index_lower_theta1_duty_difference");
  EXPECT_EQ(h.back(), "index_upper_status");
  EXPECT_DOUBLE_EQ(std::stod(v[2]) - std::stod(v[1]), std::stod(v[3]));
  EXPECT_NEAR(std::stod(v[2]), c * std::stod(v[1]), 1e-12);
}

// Failed readings (docs/runtime.md "Replay": an empty reading cell). The device here is the
// runtime fed NaN for the lower mechanism's readings at known rows, its log written with
// write_replay_row: the written cells are empty, the log replays clean, the lower mechanism's
// duties on those rows are 0 (the runtime's sensor fault), the upper mechanism's duties are the
// fault-free log's bit for bit (the priority rule follows the upper mechanism, not the lower). A
// non-zero logged duty on a failed row is flagged at that row and joint; a cell that is not the
// marker (`nan`, `-`) stays refused at its line and column.
TEST_F(Replay, FailedReadingsReplayCleanAndANonZeroDutyOnOneIsFlaggedAtItsRow) {
  const SilRun run = sil(false);
  ASSERT_TRUE(run.result.ok());
  const rt::Config full = exported();
  const ReplayLog clean = read(slurp(run.log), full);
  const rt::Config config = config_for_log(full, clean);
  ASSERT_EQ(clean.readings.front().size(), 4u);  // index lower theta1, theta2, upper theta1, theta2
  const std::vector<std::pair<std::size_t, std::size_t>> failed{{30, 0}, {31, 1}, {75, 0}, {75, 1}, {120, 1}};
  rt::Controller device(config);
  std::ostringstream text;
  write_replay_header(text, config, clean.kind);
  std::vector<std::vector<double>> duties;
  for (std::size_t row = 0; row < clean.time_s.size(); ++row) {
    std::vector<double> readings = clean.readings[row];
    for (const auto& [r, j] : failed)
      if (r == row) readings[j] = std::numeric_limits<double>::quiet_NaN();
    device.cycle(readings.data(), clean.kind, clean.targets_m[row].data());
    duties.emplace_back(device.duties(), device.duties() + 4);
    write_replay_row(text, clean.time_s[row], readings, clean.targets_m[row], device.duties(), 4);
  }
  const std::string log_text = text.str();
  const ReplayLog log = read(log_text, full);
  EXPECT_EQ(log.failed_readings, failed.size());
  for (const auto& [r, j] : failed) {
    EXPECT_TRUE(std::isnan(log.readings[r][j])) << r;
    EXPECT_EQ(duties[r][0], 0.0) << r;  // the lower mechanism's two duties
    EXPECT_EQ(duties[r][1], 0.0) << r;
  }
  for (std::size_t row = 0; row < duties.size(); ++row) {
    EXPECT_EQ(duties[row][2], clean.duties[row][2]) << row;
    EXPECT_EQ(duties[row][3], clean.duties[row][3]) << row;
  }
  // The marker on the line: two commas with nothing between them where the reading was.
  std::istringstream lines(log_text);
  std::string line;
  for (std::size_t n = 0; n <= 31 + 1; ++n) std::getline(lines, line);  // header + 31 rows, then row 31 (0-based)
  EXPECT_THAT(line, ::testing::StartsWith(format::shortest(clean.time_s[31]) + ","));
  EXPECT_THAT(line, HasSubstr(",,"));
  const ReplayResult r = replay_log(full, log, 0.0);
  EXPECT_TRUE(r.passed());
  EXPECT_EQ(r.mismatches, 0u);
  EXPECT_EQ(r.failed_readings, failed.size());
  EXPECT_EQ(r.failed_not_faulted, 0u);
  EXPECT_EQ(r.joints[0].failed_readings, 2u);
  EXPECT_EQ(r.joints[1].failed_readings, 3u);
  EXPECT_EQ(r.status_counts[0][static_cast<std::size_t>(rt::Status::sensor_fault)], 4u);  // rows 30, 31, 75, 120
  // The same log with a duty of 0.25 logged on failed row 75 (data row 76): flagged there.
  std::vector<std::string> rows;
  for (std::istringstream in(log_text); std::getline(in, line);) rows.push_back(line);
  std::vector<std::string> cells = split(rows[1 + 75]);
  const std::vector<std::string> header = split(rows[0]);
  const std::size_t duty_col = static_cast<std::size_t>(std::find(header.begin(), header.end(), "index_lower_theta2_duty") - header.begin());
  ASSERT_LT(duty_col, header.size());
  ASSERT_EQ(cells[duty_col], "0");
  cells[duty_col] = "0.25";
  std::string changed;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    std::string l = rows[i];
    if (i == 1 + 75) {
      l.clear();
      for (std::size_t k = 0; k < cells.size(); ++k) l += (k ? "," : "") + cells[k];
    }
    changed += l + "\n";
  }
  const ReplayResult bad = replay_log(full, read(changed, full), 1e-9);
  EXPECT_FALSE(bad.passed());
  EXPECT_EQ(bad.mismatches, 1u);
  ASSERT_TRUE(bad.first_mismatch);
  EXPECT_EQ(bad.first_row, 75u);
  EXPECT_EQ(bad.first_joint, "index_lower_theta2");
  EXPECT_EQ(bad.first_logged, 0.25);
  EXPECT_EQ(bad.first_runtime, 0.0);
  EXPECT_EQ(bad.failed_not_faulted, 0u);  // the runtime did its part
  // Other non-numbers in a reading cell stay refused, naming the line and the column.
  const std::size_t reading_col = static_cast<std::size_t>(std::find(header.begin(), header.end(), "index_lower_theta1_counts") - header.begin());
  for (const std::string& cell : {std::string("nan"), std::string("-"), std::string("inf")}) {
    std::vector<std::string> c = split(rows[1 + 10]);
    c[reading_col] = cell;
    std::string t = rows[0] + "\n";
    for (std::size_t i = 1; i < rows.size(); ++i) {
      std::string l = rows[i];
      if (i == 1 + 10) {
        l.clear();
        for (std::size_t k = 0; k < c.size(); ++k) l += (k ? "," : "") + c[k];
      }
      t += l + "\n";
    }
    try {
      read(t, full);
      ADD_FAILURE() << cell << " was accepted";
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr("log.csv:12: column 'index_lower_theta1_counts'")) << cell;
    }
  }
  // With the device loop's status columns (the statuses it logged: sensor_fault on the lower
  // mechanism exactly at the failed rows, ok elsewhere, as the clean SIL run is ok throughout): the
  // log replays; a failed row logged `ok` is a status mismatch at that row; a cell that is not a
  // status is refused at its line and column.
  const auto with_statuses = [&](std::size_t bad_row, const std::string& bad_status) {
    std::string t = rows[0] + ",index_lower_status,index_upper_status\n";
    for (std::size_t i = 1; i < rows.size(); ++i) {
      const std::size_t row = i - 1;
      bool fault = false;
      for (const auto& [fr, j] : failed) fault = fault || fr == row;
      t += rows[i] + "," + (row == bad_row ? bad_status : fault ? "sensor_fault" : "ok") + ",ok\n";
    }
    return t;
  };
  const ReplayResult with = replay_log(full, read(with_statuses(9999, ""), full), 0.0);
  EXPECT_TRUE(with.passed());
  EXPECT_EQ(with.status_mismatches, 0u);
  const ReplayResult wrong = replay_log(full, read(with_statuses(120, "ok"), full), 0.0);
  EXPECT_FALSE(wrong.passed());
  EXPECT_EQ(wrong.status_mismatches, 1u);
  ASSERT_TRUE(wrong.first_status_mismatch);
  EXPECT_EQ(wrong.first_status_row, 120u);
  EXPECT_EQ(wrong.first_status_mechanism, "index/lower");
  EXPECT_EQ(wrong.first_status_logged, rt::Status::ok);
  EXPECT_EQ(wrong.first_status_runtime, rt::Status::sensor_fault);
  EXPECT_EQ(wrong.mismatches, 0u);
  try {
    read(with_statuses(5, "faulty"), full);
    ADD_FAILURE() << "a status 'faulty' was accepted";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("log.csv:7: column 'index_lower_status' = 'faulty'"));
  }
}

TEST(ReplayDesign, BadLogNamesAreTheDesignFilesLineAndKey) {
  const std::string text = slurp(kDesign);
  const std::string from = "replay_logs: [bench/replay.csv]";
  ASSERT_NE(text.find(from), std::string::npos);
  int line = 1;
  for (std::size_t i = 0; i < text.find(from); ++i) line += text[i] == '\n';
  const auto with = [&](const std::string& to) {
    std::string t = text;
    t.replace(t.find(from), from.size(), to);
    return t;
  };
  const std::string at = "d.yaml:" + std::to_string(line) + ": bench.replay_logs";
  const auto message = [&](const std::string& to) {
    try {
      (void)load_design_from_string(with(to), "d.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("loaded");
  };
  EXPECT_THAT(message("replay_logs: [\"\"]"), HasSubstr(at + "[0] = \"\": must be a file name, not empty"));
  EXPECT_THAT(message("replay_logs: {a: 1}"), HasSubstr(at + " = {a: 1}: must be a list of file names"));
  EXPECT_THAT(message("replay_logs: []"), HasSubstr(at + ": must name at least one log"));
  EXPECT_THAT(message("replay_logs: [a/run.csv, b/run.csv]"), HasSubstr(at + "[1] = b/run.csv: replay_logs[0]"));
  EXPECT_THAT(message("replay_logs: [a.csv]\n  replay_tolerance: -1"),
              HasSubstr("d.yaml:" + std::to_string(line + 1) + ": bench.replay_tolerance"));
  // A directory is a wrong name (the file is looked for beside the design file).
  EXPECT_THAT(message("replay_logs: [.]"), HasSubstr(at + "[0] = .: is a directory"));
  // Bench files stay beside the design (docs/bench-files.md): no absolute path, no '..'.
  EXPECT_THAT(message("replay_logs: [/]"), HasSubstr(at + "[0] = /: must be a path relative to the design file's folder"));
  EXPECT_THAT(message("replay_logs: [/etc/passwd]"), HasSubstr(at + "[0] = /etc/passwd: must be a path relative"));
  EXPECT_THAT(message("replay_logs: [logs/../../x.csv]"), HasSubstr(at + "[0] = logs/../../x.csv: must not leave the design file's folder"));
  const auto other = [&](const std::string& from_key, const std::string& to) {
    std::string t = text;
    t.replace(t.find(from_key), from_key.size(), to);
    try {
      (void)load_design_from_string(t, "d.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("loaded");
  };
  EXPECT_THAT(other("calibration: bench/calibration.csv", "calibration: ../m.csv"), HasSubstr("bench.calibration = ../m.csv: must not leave"));
  EXPECT_THAT(other("identification: bench/identification.csv", "identification: /dev/zero"),
              HasSubstr("bench.identification = /dev/zero: must be a path relative"));
  // Unless the caller allows it (the command line's --allow-outside-paths): then each is loaded
  // as written, and the next load without the permission refuses them again.
  allow_bench_paths_outside(true);
  EXPECT_EQ(message("replay_logs: [/etc/passwd]"), "loaded");
  EXPECT_EQ(message("replay_logs: [logs/../../x.csv]"), "loaded");
  EXPECT_EQ(other("calibration: bench/calibration.csv", "calibration: ../m.csv"), "loaded");
  allow_bench_paths_outside(false);
  EXPECT_THAT(message("replay_logs: [/etc/passwd]"), HasSubstr(at + "[0] = /etc/passwd: must be a path relative"));
  // One name without a list, written back as a list.
  const Design one = load_design_from_string(with("replay_logs: x/log.csv"), "d.yaml");
  ASSERT_NE(one.get<BenchSettings>(), nullptr);
  EXPECT_EQ(one.get<BenchSettings>()->replay_logs, std::vector<std::string>{"x/log.csv"});
  EXPECT_EQ(load_design_from_string(to_yaml(one), "w.yaml").get<BenchSettings>()->replay_logs, std::vector<std::string>{"x/log.csv"});
}

// The `bench_replay` product of `fivebar run`: the showcase's logs beside a design file in a
// scratch folder; the export product's JSON is the configuration.
class BenchReplayScene : public Replay {
 protected:
  SceneReport scene(const std::string& logs, const std::vector<std::pair<std::string, std::string>>& edits = {}) {
    std::string text = slurp(kDesign);
    const std::string from = "replay_logs: [bench/replay.csv]";
    text.replace(text.find(from), from.size(), "replay_logs: " + logs);
    for (const auto& [a, b] : edits) {
      EXPECT_NE(text.find(a), std::string::npos) << a;
      text.replace(text.find(a), a.size(), b);
    }
    const fs::path file = dir_ / "d.yaml";
    std::ofstream(file, std::ios::binary) << text;
    SceneOptions o;
    o.out_root = dir_ / "out";
    o.products = std::vector<std::string>{"bench_replay"};
    o.jobs = 1;
    return run_scene(load_design(file.string()), o);
  }
  static const ProductOutcome& outcome(const SceneReport& r) {
    for (const ProductOutcome& p : r.products)
      if (p.name == "bench_replay") return p;
    throw std::logic_error("no bench_replay");
  }
};

TEST_F(BenchReplayScene, TheRuntimesOwnLogPassesAndAChangedOneIsFlagged) {
  const SilRun run = sil(false);
  ASSERT_TRUE(run.result.ok());
  // The same log with one duty moved by 0.03 at data row 20.
  std::istringstream in(slurp(run.log));
  std::string header, line, changed;
  std::getline(in, header);
  changed = "# changed by the test\n" + header + "\n";
  const std::vector<std::string> cols = split(header);
  for (std::size_t row = 0; std::getline(in, line); ++row) {
    if (row == 20) {
      std::vector<std::string> cells = split(line);
      for (std::size_t i = 0; i < cols.size(); ++i)
        if (cols[i] == "index_upper_theta2_duty") cells[i] = format::shortest(std::stod(cells[i]) + 0.03);
      line.clear();
      for (std::size_t i = 0; i < cells.size(); ++i) line += (i ? "," : "") + cells[i];
    }
    changed += line + "\n";
  }
  fs::create_directories(dir_ / "logs");
  fs::copy_file(run.log, dir_ / "logs" / "good.csv");
  std::ofstream(dir_ / "logs" / "changed.csv", std::ios::binary) << changed;

  const SceneReport r = scene("[logs/good.csv, logs/changed.csv]");
  const ProductOutcome& p = outcome(r);
  ASSERT_EQ(p.state, ProductOutcome::State::built) << p.reason;
  EXPECT_FALSE(p.passed);
  EXPECT_FALSE(r.ok());
  EXPECT_THAT(p.check, HasSubstr("1 of 2 log(s) differ"));
  const Json& logs = p.result["logs"];
  ASSERT_EQ(logs.size(), 2u);
  EXPECT_EQ(logs[0]["log"], "logs/good.csv");
  EXPECT_TRUE(logs[0]["passed"].get<bool>());
  EXPECT_EQ(logs[0]["max_duty_difference"], 0.0);
  EXPECT_EQ(logs[0]["rows"], run.figures["samples"]);
  EXPECT_FALSE(logs[1]["passed"].get<bool>());
  EXPECT_EQ(logs[1]["mismatches"], 1);
  EXPECT_NEAR(logs[1]["max_duty_difference"].get<double>(), 0.03, 1e-15);
  EXPECT_EQ(logs[1]["first_mismatch"]["row"], 21);  // from 1, as the markdown below
  EXPECT_EQ(logs[1]["first_mismatch"]["joint"], "index_upper_theta2");
  EXPECT_THAT(p.markdown, HasSubstr("✗ does not run this configuration"));
  EXPECT_THAT(p.markdown, HasSubstr("first mismatch at row 21"));
  // The CSV for a notebook: one row per log and joint.
  const std::string csv = slurp(r.out_dir / "bench_replay" / "bench_replay.csv");
  EXPECT_THAT(csv, HasSubstr("logs/changed.csv,index_upper_theta2," + std::to_string(logs[1]["rows"].get<int>()) + ",1e-09,"));
  EXPECT_TRUE(fs::exists(r.out_dir / "bench_replay" / "changed-duties.csv"));
  EXPECT_TRUE(fs::exists(r.out_dir / "bench_replay" / "good-duties.csv"));
}

TEST_F(BenchReplayScene, ADesignWithOtherGainsDoesNotRunTheLogAndAMissingLogLeavesTheProductOut) {
  const SilRun run = sil(false);
  ASSERT_TRUE(run.result.ok());
  fs::create_directories(dir_ / "logs");
  fs::copy_file(run.log, dir_ / "logs" / "good.csv");
  // The index station's lower gains scaled by 1.25 (i_clamp too): its duties become 1.25 x the
  // logged ones, the upper mechanism's stay (the previous test's property, through the export).
  const double c = 1.25;
  const std::string lower = "lower: {pid: {kp: 6.376473352297236, ki: 62.44954783058385, kd: 0.11315351641304752}}";
  const std::string scaled = "lower: {pid: {kp: " + format::shortest(6.376473352297236 * c) + ", ki: " +
                             format::shortest(62.44954783058385 * c) + ", kd: " + format::shortest(0.11315351641304752 * c) +
                             ", i_clamp: 0.25}}";
  const SceneReport r = scene("[logs/good.csv]", {{lower, scaled}});
  const ProductOutcome& p = outcome(r);
  ASSERT_EQ(p.state, ProductOutcome::State::built) << p.reason;
  EXPECT_FALSE(p.passed);
  const ReplayLog log = read(slurp(run.log), exported());
  double peak_lower = 0.0;
  for (const auto& row : log.duties) peak_lower = std::max({peak_lower, std::fabs(row[0]), std::fabs(row[1])});
  const Json& j = p.result["logs"][0];
  EXPECT_NEAR(j["max_duty_difference"].get<double>(), (c - 1.0) * peak_lower, 1e-12);
  for (const Json& joint : j["joints"]) {
    if (joint["joint"].get<std::string>().rfind("index_upper", 0) == 0) EXPECT_EQ(joint["max_duty_difference"], 0.0);
  }
  EXPECT_EQ(j["first_mismatch"]["joint"].get<std::string>().rfind("index_lower", 0), 0u);

  // Named but not there: left out with the reason, as the other bench products.
  const SceneReport missing = scene("[logs/none.csv]");
  const ProductOutcome& q = outcome(missing);
  EXPECT_EQ(q.state, ProductOutcome::State::left_out);
  EXPECT_THAT(q.reason, HasSubstr("`logs/none.csv` (`bench.replay_logs[0]`) is not there"));
}

}  // namespace
}  // namespace fivebar
