// End-to-end tests of `fivebar replay`: the software-in-the-loop run reports simulate's figures to
// the last digit; its log, replayed against the exported JSON file (a second reading of the
// configuration, from disk), gives the logged duties exactly; a changed duty or gain is caught and
// named; bad logs and configurations are exit 2 naming the column or key.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli_test.hpp"

namespace {

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using ft::slurp;
using nlohmann::json;
using ::testing::HasSubstr;

class CliReplay : public ft::CliTest {
 protected:
  CliReplay() : CliTest("fivebar_test_cli_replay") {}

  /// The index station's export (JSON) and a SIL log of its stretch pattern, once per test.
  void prepare() {
    const Outcome e = run({"export", kDesign, "-s", "index", "--format", "json", "--out", "export"});
    ASSERT_EQ(e.code, 0) << e.err;
    for (const auto& f : fs::directory_iterator(dir_ / "export"))
      if (f.path().extension() == ".json") config_ = f.path().string();
    ASSERT_FALSE(config_.empty());
    const Outcome s = run({"replay", kDesign, "--sil", "-s", "index", "--pattern", "stretch", "--out", "sil", "--json"});
    ASSERT_EQ(s.code, 0) << s.err;
    sil_ = parse(s);
    log_ = sil_["runs"][0]["log"].get<std::string>();
    if (fs::path(log_).is_relative()) log_ = (dir_ / log_).string();
  }
  std::string config_, log_;
  json sil_;
};

TEST_F(CliReplay, SoftwareInTheLoopReportsSimulatesFiguresAndItsLogReplaysExactly) {
  prepare();
  ASSERT_FALSE(HasFailure());
  // The same figures as `fivebar simulate` (closed-form masses: --no-render).
  const Outcome sim = run({"simulate", kDesign, "-s", "index", "--pattern", "stretch", "--no-render", "--out", "sim", "--json"});
  ASSERT_EQ(sim.code, 0) << sim.err;
  const json a = parse(sim)["runs"][0], b = sil_["runs"][0];
  ASSERT_EQ(a["mechanisms"].size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    for (const char* key : {"max_error_mm", "rms_error_mm", "peak_duty", "saturation_s", "peak_current_A"}) {
      EXPECT_EQ(a["mechanisms"][k][key], b["mechanisms"][k][key]) << key;
    }
  }
  EXPECT_EQ(a["samples"], b["samples"]);
  // The log through a runtime read from the exported file: every duty bit for bit.
  const Outcome r = run({"replay", log_, "--config", config_, "--tolerance", "0", "--json"});
  ASSERT_EQ(r.code, 0) << r.err << r.out;
  const json j = parse(r);
  EXPECT_EQ(j["mode"], "log");
  EXPECT_EQ(j["mismatches"], 0);
  EXPECT_EQ(j["max_duty_difference"], 0.0);
  EXPECT_EQ(j["rows"], b["samples"]);
  EXPECT_EQ(j["joints"].size(), 4u);
  for (const json& m : j["mechanisms"]) EXPECT_EQ(m["statuses"]["ok"], j["rows"]) << m.dump();
}

TEST_F(CliReplay, AChangedDutyOrGainIsAMismatchNamedByRowAndJoint) {
  prepare();
  ASSERT_FALSE(HasFailure());
  // One logged duty changed: row 31, index_upper_theta2.
  std::istringstream in(slurp(log_));
  std::string header, line, text;
  std::getline(in, header);
  text = header + "\n";
  std::vector<std::string> cols;
  {
    std::stringstream h(header);
    for (std::string c; std::getline(h, c, ',');) cols.push_back(c);
  }
  std::size_t duty_col = 0;
  for (std::size_t i = 0; i < cols.size(); ++i)
    if (cols[i] == "index_upper_theta2_duty") duty_col = i;
  ASSERT_GT(duty_col, 0u);
  for (int row = 1; std::getline(in, line); ++row) {
    if (row == 31) {
      std::vector<std::string> cells;
      std::stringstream s(line);
      for (std::string c; std::getline(s, c, ',');) cells.push_back(c);
      cells[duty_col] = std::to_string(std::stod(cells[duty_col]) + 0.01);
      line.clear();
      for (std::size_t i = 0; i < cells.size(); ++i) line += (i ? "," : "") + cells[i];
    }
    text += line + "\n";
  }
  const fs::path changed = write("changed.csv", text);
  Outcome r = run({"replay", changed.string(), "--config", config_, "--json"});
  ASSERT_EQ(r.code, 1) << r.err;
  json j = parse(r);
  EXPECT_EQ(j["mismatches"], 1);
  EXPECT_EQ(j["first_mismatch"]["row"], 31);  // data rows from 1, as the text counts
  EXPECT_EQ(j["first_mismatch"]["joint"], "index_upper_theta2");
  EXPECT_NEAR(j["max_duty_difference"].get<double>(), 0.01, 1e-6);
  // A configuration with another gain: the device does not run it.
  std::string cfg = slurp(config_);
  // gains.index_lower_theta1.d (gains come first of the joint-keyed maps: keys are sorted).
  const auto joint = cfg.find("\"index_lower_theta1\": {", cfg.find("\"gains\""));
  ASSERT_NE(joint, std::string::npos);
  const std::string key = "\"d\": ";
  const auto pos = cfg.find(key, joint);
  ASSERT_NE(pos, std::string::npos);
  const auto end = cfg.find_first_of(",\n", pos + key.size());
  cfg.replace(pos + key.size(), end - pos - key.size(), "0.5");
  const fs::path other = write("other.json", cfg);
  r = run({"replay", log_, "--config", other.string(), "--json"});
  ASSERT_EQ(r.code, 1) << r.err;
  j = parse(r);
  EXPECT_GT(j["mismatches"].get<int>(), 0);
  EXPECT_EQ(j["first_mismatch"]["joint"], "index_lower_theta1");
}

TEST_F(CliReplay, BadLogsAndConfigurationsAreExitTwoNamingTheColumnOrKey) {
  const fs::path cfg = write("bad.json", "{\"n\": {\"ros__parameters\": {\"fivebar\": {\"design\": \"d\", \"design_hash\": \"h\", \"hash_algorithm\": \"a\", \"tool_version\": \"v\", \"format_version\": 1, \"units\": \"SI\"}, \"loop_rate_hz\": 100.0, \"pwm_hz\": 1000.0}}}");
  const fs::path log = write("log.csv", "time_s,index_lower_theta1_counts\n0,1\n");
  Outcome r = run({"replay", log.string(), "--config", cfg.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("adc: missing key"));
  r = run({"replay", log.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--config"));
  const Outcome e = run({"export", kDesign, "-s", "index", "--format", "json", "--out", "export"});
  ASSERT_EQ(e.code, 0) << e.err;
  std::string good;
  for (const auto& f : fs::directory_iterator(dir_ / "export")) good = f.path().string();
  r = run({"replay", log.string(), "--config", good});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("column 'index_lower_theta1_duty' is missing"));
  const fs::path nan = write("nan.csv", slurp(log).substr(0, slurp(log).find('\n') + 1) + "0,abc\n");
  r = run({"replay", nan.string(), "--config", good});
  EXPECT_EQ(r.code, 2);
}

// The device log goes through the bench's one reader (docs/bench-files.md): the showcase's log with
// one cell or the header changed is refused at its line and column, exit 2; /dev/zero is refused
// after one bounded line; --json leads with command and design (docs/conventions.md).
TEST_F(CliReplay, TheDeviceLogIsReadStrictlyAndBounded) {
  const Outcome e = run({"export", kDesign, "-s", "index", "--format", "json", "--out", "export"});
  ASSERT_EQ(e.code, 0) << e.err;
  std::string good;
  for (const auto& f : fs::directory_iterator(dir_ / "export"))
    if (f.path().extension() == ".json") good = f.path().string();
  const std::string text = slurp(fs::path(FIVEBAR_SOURCE_DIR) / "designs/bench/replay.csv");
  const std::size_t header_end = text.find('\n', text.find("time_s"));
  const std::size_t header_line = 1 + std::count(text.begin(), text.begin() + header_end, '\n');
  // The unchanged log replays (the reference for the changed ones below).
  const fs::path ok = write("ok.csv", text);
  Outcome r = run({"replay", ok.string(), "--config", good, "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  std::string compact;  // the document without its layout's blanks: command and design lead
  for (const char ch : r.out)
    if (ch != ' ' && ch != '\n') compact += ch;
  EXPECT_EQ(compact.find("{\"command\":\"replay\",\"design\":\"iros2022\""), 0u) << r.out.substr(0, 80);
  // A counts cell in hexadecimal, or with text after the number: refused, not read as 16 or 41496.
  const std::string first_row = text.substr(header_end + 1, text.find(',', header_end + 1) - header_end);  // "0,"
  for (const std::string cell : {"0x10", "41496junk", "1e999", "nan"}) {
    std::string t = text;
    const std::size_t at = header_end + 1 + first_row.size();
    t.replace(at, t.find(',', at) - at, cell);
    const fs::path bad = write("bad.csv", t);
    r = run({"replay", bad.string(), "--config", good});
    EXPECT_EQ(r.code, 2) << cell;
    EXPECT_THAT(r.err, HasSubstr("bad.csv:" + std::to_string(header_line + 1) + ": column 'index_lower_theta1_counts' = '" + cell + "'"));
  }
  // A duplicated column: refused at the header, not replayed against one of the two.
  {
    std::string t = text;
    t.replace(t.find("index_upper_theta1_counts"), std::string("index_upper_theta1_counts").size(), "index_lower_theta1_counts");
    const fs::path bad = write("dup.csv", t);
    r = run({"replay", bad.string(), "--config", good});
    EXPECT_EQ(r.code, 2);
    EXPECT_THAT(r.err, HasSubstr("dup.csv:" + std::to_string(header_line) + ": column 6 'index_lower_theta1_counts': duplicate of column 2"));
  }
  r = run({"replay", "/dev/zero", "--config", good});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("/dev/zero:1: line longer than 4096 bytes"));
  r = run({"replay", ok.string(), "--config", "/dev/zero"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("larger than 16777216 bytes"));
}

// `replay --sil --config` with a configuration that lacks the station: refused before the output
// folder is created.
TEST_F(CliReplay, SilWithAConfigurationWithoutTheStationWritesNothing) {
  const Outcome e = run({"export", kDesign, "-s", "index", "--format", "json", "--out", "export"});
  ASSERT_EQ(e.code, 0) << e.err;
  std::string index_only;
  for (const auto& f : fs::directory_iterator(dir_ / "export"))
    if (f.path().extension() == ".json") index_only = f.path().string();
  const Outcome r = run({"replay", kDesign, "--sil", "-s", "thumb", "--pattern", "stretch", "--config", index_only, "--out", "sil"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("has no station 'thumb'"));
  EXPECT_FALSE(fs::exists(dir_ / "sil"));
}

}  // namespace

// The `replay` product of `fivebar run`: software in the loop with the export product's JSON as
// written, every pattern of both stations; each run's figures equal `fivebar replay --sil --config`
// on that same file (a second path: the CLI), and each log replays with no duty difference.
TEST_F(CliReplay, TheRunProductRunsTheExportedFileInTheLoopAndReplaysEveryLog) {
  const Outcome r = run({"run", kDesign, "-P", "replay", "-o", "scene", "-q", "-j", "1", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json summary = parse(r);
  const json& result = summary["results"]["replay"];
  const std::string config = (dir_ / "scene" / "iros2022" / result["config"].get<std::string>()).string();
  ASSERT_TRUE(fs::exists(config)) << config;
  ASSERT_EQ(result["runs"].size(), 8u);  // 2 stations x 4 patterns
  for (const json& run : result["runs"]) {
    SCOPED_TRACE(run["station"].get<std::string>() + " " + run["reference"].get<std::string>());
    EXPECT_EQ(run["status"], "ok");
    EXPECT_TRUE(fs::exists(dir_ / "scene" / "iros2022" / run["log"].get<std::string>()));
    EXPECT_GT(run["replay"]["rows"].get<double>(), 100);
    EXPECT_EQ(run["replay"]["mismatches"].get<double>(), 0);
    EXPECT_EQ(run["replay"]["max_duty_difference"].get<double>(), 0.0);
  }
  const Outcome s = run({"replay", kDesign, "--sil", "-s", "index", "--pattern", "stretch", "--config", config, "--out", "sil",
                         "--json"});
  ASSERT_EQ(s.code, 0) << s.err;
  const json a = parse(s)["runs"][0];
  const json& b = result["runs"][0];
  ASSERT_EQ(b["station"], "index");
  ASSERT_EQ(b["reference"], "stretch");
  ASSERT_EQ(a["mechanisms"].size(), 2u);
  for (std::size_t k = 0; k < 2; ++k) {
    for (const char* key : {"max_error_mm", "rms_error_mm", "peak_duty", "saturation_s", "peak_current_A"}) {
      EXPECT_EQ(a["mechanisms"][k][key], b["mechanisms"][k][key]) << key;
    }
  }
}

// The `bench_replay` product of `fivebar run`: a device log the design names (`bench.replay_logs`)
// replayed against the export product's JSON; its figures are those of `fivebar replay LOG
// --config` on that same file (a second path: the command), for a log the runtime wrote (passes,
// exit 0) and for one with a changed duty (flagged, exit 1); a bad name is the design's
// FILE:LINE: key and exit 2.
TEST_F(CliReplay, TheBenchReplayProductReportsTheCommandsFiguresPerLog) {
  prepare();
  ASSERT_FALSE(HasFailure());
  fs::create_directories(dir_ / "logs");
  fs::copy_file(log_, dir_ / "logs" / "good.csv");
  std::string changed = slurp(log_);
  // The second row's first duty (index_lower_theta1_duty, the third column) moved by 0.125.
  const auto row2 = changed.find('\n', changed.find('\n') + 1) + 1;
  const auto c1 = changed.find(',', row2), c2 = changed.find(',', c1 + 1), c3 = changed.find(',', c2 + 1);
  const std::string duty = changed.substr(c2 + 1, c3 - c2 - 1);
  changed.replace(c2 + 1, c3 - c2 - 1, std::to_string(std::stod(duty) + 0.125));
  write("logs/changed.csv", changed);

  const auto check = [&](const std::string& log, int code) {
    SCOPED_TRACE(log);
    const fs::path design = design_with("d.yaml", "replay_logs: [bench/replay.csv]", "replay_logs: [logs/" + log + "]");
    const Outcome r = run({"run", design.string(), "-P", "bench_replay", "-o", "scene-" + log, "-q", "-j", "1", "--json"});
    ASSERT_EQ(r.code, code) << r.err;
    const json result = parse(r)["results"]["bench_replay"];
    ASSERT_EQ(result["logs"].size(), 1u);
    const json& p = result["logs"][0];
    const std::string config = (dir_ / ("scene-" + log) / "iros2022" / result["config"].get<std::string>()).string();
    const Outcome c = run({"replay", (dir_ / "logs" / log).string(), "--config", config, "--json"});
    ASSERT_EQ(c.code, code) << c.err;
    const json cli = parse(c);
    for (const char* key : {"rows", "max_duty_difference", "mismatches", "passed", "first_mismatch", "joints", "mechanisms"}) {
      EXPECT_EQ(p[key], cli[key]) << key;
    }
    EXPECT_TRUE(fs::exists(dir_ / ("scene-" + log) / "iros2022" / p["duties_csv"].get<std::string>()));
  };
  check("good.csv", 0);
  check("changed.csv", 1);

  const fs::path bad = design_with("bad.yaml", "replay_logs: [bench/replay.csv]", "replay_logs: [\"\"]");
  const std::string text = slurp(bad);
  const auto line = 1 + std::count(text.begin(), text.begin() + text.find("replay_logs: [\"\"]"), '\n');
  const Outcome r = run({"run", bad.string(), "-P", "bench_replay", "-o", "scene-bad", "-q"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("bad.yaml:" + std::to_string(line) + ": bench.replay_logs[0] = \"\": must be a file name"));
  EXPECT_FALSE(fs::exists(dir_ / "scene-bad"));
}
