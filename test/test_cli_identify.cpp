// End-to-end tests of `fivebar identify`: real processes, exit codes, the JSON document, the files.
// The expected values are the synthetic truth the logs were generated from (identify_synthetic.hpp)
// and the EMPS benchmark's published parameters (Janot, Gautier, Brunot 2019).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "cli_test.hpp"
#include "fivebar/design.hpp"
#include "fivebar/provenance.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/sections/provenance.hpp"
#include "fivebar/sha256.hpp"
#include "identify_synthetic.hpp"

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using nlohmann::json;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

namespace {

class CliIdentify : public ft::CliTest {
 protected:
  CliIdentify() : CliTest("fivebar_test_cli_identify") {}

  static const json& parameter(const json& joint, const std::string& key) {
    for (const json& p : joint["parameters"]) {
      if (p["parameter"] == key) return p;
    }
    static const json none;
    ADD_FAILURE() << "no parameter " << key;
    return none;
  }
};

TEST_F(CliIdentify, SyntheticMotorLogGivesTheTruthWithinThreeSigmaAndWritesItsFiles) {
  ft::SyntheticTruth truth;
  const fs::path log = write("bench.csv", ft::synthetic_log(truth, 11).csv());
  const fs::path val = write("val.csv", ft::synthetic_log(truth, 12).csv());
  const Outcome r = run({"identify", kDesign, log.string(), "--validation", val.string(), "--rig", "motor", "--json", "--out", "out"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = parse(r);
  EXPECT_EQ(j["command"], "identify");
  ASSERT_EQ(j["joints"].size(), 1u);
  const json& joint = j["joints"][0];
  const std::vector<std::pair<std::string, double>> want = {
      {"inertia_kg_m2", truth.J}, {"viscous_Nm_s_per_rad", truth.b}, {"coulomb_Nm", truth.c}, {"offset_Nm", truth.offset}};
  for (const auto& [key, value] : want) {
    const json& p = parameter(joint, key);
    EXPECT_TRUE(p["identified"].get<bool>()) << key;
    EXPECT_LE(std::abs(p["value"].get<double>() - value), 3.0 * p["sigma"].get<double>()) << key;
  }
  // The design keys in the design's units: the Coulomb friction in mNm.
  EXPECT_NEAR(parameter(joint, "motor.coulomb_friction_mNm")["value"].get<double>(),
              1e3 * parameter(joint, "coulomb_Nm")["value"].get<double>(), 1e-9);
  EXPECT_FALSE(parameter(joint, "motor.terminal_resistance_ohm")["identified"].get<bool>());
  EXPECT_GT(joint["fit"]["validation"]["idim_ls"]["drive_fit_percent"].get<double>(), 80.0);
  EXPECT_EQ(tree(dir_ / "out"), (std::vector<std::string>{"identify.json", "iros2022-identified.yaml", "motor-estimation.png", "motor-estimation.svg",
                                                         "motor-validation.png", "motor-validation.svg"}));
}

// The patch goes through calibrate's provenance writer: a design that loads, whose identified keys
// hold the reported values and are measured (their entry names the log, its hash and the sigma),
// and whose other motor keys stay assumptions.
TEST_F(CliIdentify, ThePatchedDesignLoadsWithTheIdentifiedKeysMeasured) {
  ft::SyntheticTruth truth;
  for (const bool joint_scope : {false, true}) {
    std::string csv = ft::synthetic_log(truth, 21).csv();
    if (joint_scope) csv.replace(0, csv.find('\n'), "time_s,index_lower_theta1_current_A,index_lower_theta1_theta_rad");
    const fs::path log = write(joint_scope ? "joint.csv" : "bench.csv", csv);
    const std::string out = joint_scope ? "joint" : "bench";
    const Outcome r = run({"identify", kDesign, log.string(), "--no-output-error", "--json", "--out", out});
    ASSERT_EQ(r.code, 0) << r.err;
    const json j = parse(r);
    const fs::path patched = dir_ / out / "iros2022-identified.yaml";
    ASSERT_TRUE(fs::exists(patched));
    const fivebar::Design d = fivebar::load_design(patched);
    const std::string mk = joint_scope ? "motor.stations.index.lower.theta1." : "motor.";
    const std::vector<std::string> want = {mk + "rotor_inertia_g_cm2", mk + "viscous_friction_mNm_s_per_rad", mk + "coulomb_friction_mNm"};
    EXPECT_EQ(j["patched"].get<std::vector<std::string>>(), want);
    const auto* prov = d.get<fivebar::ProvenanceSettings>();
    ASSERT_NE(prov, nullptr);
    for (const std::string& key : want) {
      const json& p = parameter(j["joints"][0], key);
      EXPECT_TRUE(fivebar::is_measured(d, key)) << key;
      EXPECT_EQ(fivebar::design_number(d, key), p["value"].get<double>()) << key;
      const auto e = prov->entries.find(key);
      ASSERT_NE(e, prov->entries.end()) << key;
      // Recorded relative to the patched design's folder, where require_measured resolves it.
      EXPECT_TRUE(fs::path(e->second.source).is_relative()) << e->second.source;
      EXPECT_TRUE(fs::equivalent(patched.parent_path() / e->second.source, log)) << e->second.source;
      EXPECT_EQ(e->second.sha256, fivebar::sha256_file(log));
      EXPECT_THAT(e->second.method, HasSubstr("IDIM-LS"));
      ASSERT_TRUE(e->second.sigma.has_value());
      EXPECT_DOUBLE_EQ(*e->second.sigma, p["sigma"].get<double>());
    }
    // The Coulomb friction the design now holds is the truth's, within its 3 sigma (mNm).
    const fivebar::MotorParams m = d.get<fivebar::MotorSettings>()->joint("index", "lower", 1);
    EXPECT_LE(std::abs(m.coulomb_friction_mNm - 1e3 * truth.c), 3.0 * parameter(j["joints"][0], mk + "coulomb_friction_mNm")["sigma"].get<double>());
    // Held keys stay assumptions, and the motor group is still (partly) assumed.
    EXPECT_FALSE(fivebar::is_measured(d, mk + "terminal_resistance_ohm"));
    const auto assumed = fivebar::assumed_values(d, "motor");
    EXPECT_EQ(std::count(assumed.begin(), assumed.end(), mk + "coulomb_friction_mNm"), 0);
    if (joint_scope) {
      // Another joint keeps the design's defaults.
      EXPECT_EQ(d.get<fivebar::MotorSettings>()->joint("index", "upper", 1).coulomb_friction_mNm,
                fivebar::load_design(kDesign).get<fivebar::MotorSettings>()->joint("index", "upper", 1).coulomb_friction_mNm);
    }
  }
}

TEST_F(CliIdentify, AParameterTheLogCannotSeparateIsNamedAndRefusedWhenAskedFor) {
  ft::SyntheticTruth truth;
  truth.bias_current = 0.2;
  truth.amplitude = 0.02;
  const auto full = ft::synthetic_log(truth, 3);
  ft::SyntheticLog cut;
  for (std::size_t i = 2000; i < full.time.size(); ++i) {
    cut.time.push_back(full.time[i]);
    cut.current.push_back(full.current[i]);
    cut.theta.push_back(full.theta[i]);
  }
  const fs::path log = write("forward.csv", cut.csv());
  Outcome r = run({"identify", kDesign, log.string(), "--no-files", "--no-output-error"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("not identifiable from this log (held at the prior): offset_Nm"));
  r = run({"identify", kDesign, log.string(), "--no-files", "--no-output-error", "--fit", "offset_Nm", "--out", "o"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_THAT(r.out, HasSubstr("NOT IDENTIFIABLE (asked by --fit): offset_Nm"));
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

// The quality gate (docs/identify.md): a log whose drive did not move the joint (its current
// column played backwards) is fitted, but the model explains little of the drive: exit 1, the
// failed test printed, no design written.
TEST_F(CliIdentify, ALogTheModelDoesNotDescribeIsRefusedByTheGateAndNothingIsPatched) {
  ft::SyntheticTruth truth;
  ft::SyntheticLog log = ft::synthetic_log(truth, 41);
  const fs::path good = write("good.csv", log.csv());
  std::reverse(log.current.begin(), log.current.end());
  const fs::path bad = write("reversed.csv", log.csv());
  Outcome r = run({"identify", kDesign, bad.string(), "--no-output-error", "--out", "bad"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_THAT(r.out, HasSubstr("quality gate: refused, nothing patched"));
  EXPECT_THAT(r.err, HasSubstr("did not pass the quality gate"));
  EXPECT_THAT(r.err, HasSubstr("joint motor: drive fit"));
  EXPECT_FALSE(fs::exists(dir_ / "bad" / "iros2022-identified.yaml"));
  EXPECT_TRUE(fs::exists(dir_ / "bad" / "identify.json"));
  r = run({"identify", kDesign, bad.string(), "--no-output-error", "--no-files", "--json"});
  EXPECT_EQ(r.code, 1);
  const json j = parse(r);
  EXPECT_FALSE(j["gate"]["passed"].get<bool>());
  EXPECT_THAT(j["patched"], IsEmpty());
  // The same log with its current in order passes, and its entries record the gate.
  r = run({"identify", kDesign, good.string(), "--no-output-error", "--out", "good"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("quality gate: passed"));
  const fivebar::Design d = fivebar::load_design(dir_ / "good" / "iros2022-identified.yaml");
  const auto& e = d.get<fivebar::ProvenanceSettings>()->entries.at("motor.coulomb_friction_mNm");
  ASSERT_TRUE(e.gate.has_value());
  EXPECT_TRUE(e.gate->passed);
  EXPECT_THAT(e.gate->tests, HasSubstr("drive fit"));
}

TEST_F(CliIdentify, BadLogsExitTwoNamingTheLineAndColumnAndWriteNothing) {
  const fs::path bad = write("bad.csv", "time_s,current_A,theta_rad\n0,1,0\n0.001,1,0\n0.001,1,0\n");
  Outcome r = run({"identify", kDesign, bad.string(), "--out", "o"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("bad.csv:4: column 'time_s'"));
  const fs::path unknown = write("unknown.csv", "time_s,current_A,theta_rad,rpm\n");
  r = run({"identify", kDesign, unknown.string(), "--out", "o"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("unknown.csv:1: column 4 'rpm': unknown column"));
  r = run({"identify", kDesign, bad.string(), "--rig", "mechanism", "--out", "o"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("STATION/MECHANISM"));
  // The assembled mechanism needs both motors' columns: a bench motor's log names what is missing.
  ft::SyntheticTruth truth;
  const fs::path motor = write("motor.csv", ft::synthetic_log(truth, 5).csv());
  r = run({"identify", kDesign, motor.string(), "--out", "o", "--rig", "mechanism", "index/lower"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("no columns for joint index_lower_theta1"));
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

// One log format (docs/bench-files.md): the device's own log, which `replay` reads, is identified as
// it is (its x_ref_mm/y_ref_mm targets are the log's columns, not unknown ones); a duplicated
// column is refused at the header; /dev/zero after one bounded line.
// A log taken while the design's PID ran (controller.pid at 1 kHz, duty and current logged with the
// reference): --closed-loop reports IDIM-IV, converged, within 3 sigma of the truth; the patched
// design's entries say IDIM-IV. Two logs fit together. A log without the reference is refused.
TEST_F(CliIdentify, ClosedLoopLogsGiveTheTruthByInstrumentalVariables) {
  ft::SyntheticTruth truth;
  truth.voltage_drive = true;
  truth.closed_loop = true;
  truth.resonance_hz = 0.0;
  truth.substeps = 40;
  truth.reading_noise = 2e-3;
  truth.kp = 5.0;  // designs/iros2022.yaml controller.pid
  truth.ki = 1.0;
  truth.kd = 0.05;
  truth.i_clamp = 0.2;
  const fs::path a = write("closed-a.csv", ft::synthetic_log(truth, 31).csv());
  const fs::path b = write("closed-b.csv", ft::synthetic_log(truth, 32).csv());
  const Outcome r = run({"identify", kDesign, a.string(), b.string(), "--closed-loop", "--no-output-error", "--json", "--out", "closed"});
  ASSERT_EQ(r.code, 0) << r.err << r.out;
  const json j = parse(r);
  EXPECT_EQ(j["method"], "IDIM-IV");
  EXPECT_EQ(j["logs"].size(), 2u);
  const json& joint = j["joints"][0];
  EXPECT_EQ(joint["method"], "IDIM-IV");
  EXPECT_EQ(joint["logs"], 2);
  EXPECT_TRUE(joint["idim_iv"]["converged"].get<bool>()) << joint["idim_iv"]["status"];
  EXPECT_TRUE(joint["fit"]["estimation"].contains("idim_iv"));
  const std::vector<std::pair<std::string, double>> want = {
      {"inertia_kg_m2", truth.J}, {"viscous_Nm_s_per_rad", truth.b}, {"coulomb_Nm", truth.c}, {"offset_Nm", truth.offset}};
  for (const auto& [key, value] : want) {
    const json& p = parameter(joint, key);
    EXPECT_EQ(p["note"], "IDIM-IV") << key;
    EXPECT_LE(std::abs(p["value"].get<double>() - value), 3.0 * p["sigma"].get<double>()) << key;
  }
  // The fit passes the gate as a whole (solver, drive fit); a value whose sigma the bound refuses (the
  // viscous friction of this short excitation) stays an assumption, the others are written.
  EXPECT_THAT(j["gate"]["reasons"], IsEmpty()) << j["gate"].dump(1);
  EXPECT_TRUE(j["gate"]["solver"]["converged"].get<bool>());
  EXPECT_GE(j["gate"]["solver"]["iterations"].get<int>(), 1);
  EXPECT_THAT(j["patched"].dump(), HasSubstr("motor.rotor_inertia_g_cm2"));
  const std::string patched = ft::slurp(dir_ / "closed" / "iros2022-identified.yaml");
  EXPECT_THAT(patched, HasSubstr("(IDIM-IV)"));
  EXPECT_THAT(patched, HasSubstr("with ../" + b.filename().string() + " (sha256 " + fivebar::sha256_file(b)));
  // Without --closed-loop the same log is fitted by IDIM-LS, and the text says what the reference means.
  // (Exit 1: the quality gate refuses it, drive fit 73 % below the 80 % floor: the rows near the
  // PID's many reversals left out, a third of them, and IDIM-LS is biased under feedback.)
  const Outcome ls = run({"identify", kDesign, a.string(), "--no-output-error", "--no-files"});
  EXPECT_EQ(ls.code, 1) << ls.err << ls.out;
  EXPECT_THAT(ls.err, HasSubstr("drive fit"));
  EXPECT_THAT(ls.out, HasSubstr("add --closed-loop"));
  // A log with no reference, or a torque drive, cannot be simulated in the loop: exit 2, nothing written.
  ft::SyntheticTruth open;
  const fs::path c = write("open.csv", ft::synthetic_log(open, 33).csv());
  const Outcome bad = run({"identify", kDesign, c.string(), "--closed-loop", "--out", "bad"});
  EXPECT_EQ(bad.code, 2);
  EXPECT_THAT(bad.err, HasSubstr("has no reference column (theta_ref_rad)"));
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
  const Outcome oe = run({"identify", kDesign, a.string(), "--closed-loop", "--method", "oe", "--out", "bad"});
  EXPECT_EQ(oe.code, 2);
  EXPECT_THAT(oe.err, HasSubstr("--method oe: not with --closed-loop"));
}

TEST_F(CliIdentify, TheDeviceLogOfReplayIsIdentified) {
  const std::string log = (fs::path(FIVEBAR_SOURCE_DIR) / "designs/bench/replay.csv").string();
  Outcome r = run({"identify", kDesign, log, "--rig", "mechanism", "index/lower", "--no-files", "--no-output-error", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const std::string text = ft::slurp(log);
  // With the status columns device_loop --io linux logs (text, not numbers): read, not used; the
  // same figures.
  {
    std::istringstream in(text);
    std::string with, line;
    bool header = true;
    while (std::getline(in, line)) {
      if (line.empty() || line[0] == '#') {
        with += line + "\n";
        continue;
      }
      with += line + (header ? ",index_lower_status,index_upper_status\n" : ",ok,sensor_fault\n");
      header = false;
    }
    const Outcome s = run({"identify", kDesign, write("status.csv", with).string(), "--rig", "mechanism", "index/lower", "--no-files",
                           "--no-output-error", "--json"});
    ASSERT_EQ(s.code, 0) << s.err;
    EXPECT_EQ(parse(s)["joints"], parse(r)["joints"]);
  }
  std::string dup = text;
  dup.replace(dup.find("index_upper_x_ref_mm"), std::string("index_upper_x_ref_mm").size(), "index_lower_x_ref_mm");
  r = run({"identify", kDesign, write("dup.csv", dup).string(), "--rig", "mechanism", "index/lower", "--no-files"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("column 12 'index_lower_x_ref_mm': duplicate of column 10"));
  r = run({"identify", kDesign, "/dev/zero", "--no-files"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("/dev/zero:1: line longer than 4096 bytes"));
}

// A flag given is used or refused, never replaced by its default: --cutoff 0 ran with a tenth of
// the sample rate, --decimation 0 with 10. Refused before the log is read or a file is written.
TEST_F(CliIdentify, FlagsOutsideTheirRangeAreRefusedNotDefaulted) {
  ft::SyntheticTruth truth;
  const fs::path motor = write("motor.csv", ft::synthetic_log(truth, 5).csv());
  for (const auto& [flag, value] : std::vector<std::pair<std::string, std::string>>{
           {"--cutoff", "0"}, {"--cutoff", "-1"}, {"--decimation", "0"}, {"--decimation", "-1"}}) {
    const Outcome r = run({"identify", kDesign, motor.string(), flag, value, "--out", "o"});
    EXPECT_EQ(r.code, 2) << flag << " " << value;
    EXPECT_THAT(r.err, HasSubstr(flag)) << r.err;
    EXPECT_THAT(r.err, HasSubstr(value)) << r.err;
  }
  const Outcome p = run({"identify", kDesign, "--plan", "--drive-noise", "0", "--out", "o"});
  EXPECT_EQ(p.code, 2);
  EXPECT_THAT(p.err, HasSubstr("--drive-noise = 0"));
  EXPECT_FALSE(fs::exists(dir_ / "o"));
}

TEST_F(CliIdentify, PlanWritesAnExcitationWithinTheLimits) {
  const Outcome r = run({"identify", kDesign, "--plan", "--range-deg", "-60,60", "--json", "--out", "plan"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = parse(r);
  EXPECT_EQ(j["plan"]["expected"].size(), 4u);
  EXPECT_TRUE(fs::exists(dir_ / "plan" / "identify-plan.csv"));
}

TEST_F(CliIdentify, EmpsBenchmarkThroughTheCommandLine) {
  const fs::path dir = fs::path(fivebar_test_paths::shared_data_dir()) / "sysid" / "emps";
  if (!fs::exists(dir / "est.csv")) GTEST_SKIP() << "EMPS data not found under " << dir;
  const Outcome r = run({"identify", kDesign, (dir / "est.csv").string(), "--validation", (dir / "val.csv").string(),
                         "--instant-drive", "--json", "--no-files"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = parse(r);
  const json& joint = j["joints"][0];
  // Published IDIM-LS (Janot, Gautier, Brunot 2019), tolerance 3 published sigmas (test_identify.cpp).
  EXPECT_NEAR(parameter(joint, "inertia_kg_m2")["value"].get<double>(), 95.1089, 3 * 0.1085);
  EXPECT_NEAR(parameter(joint, "viscous_Nm_s_per_rad")["value"].get<double>(), 203.5034, 3 * 1.1460);
  EXPECT_NEAR(parameter(joint, "coulomb_Nm")["value"].get<double>(), 20.3935, 3 * 0.1012);
  EXPECT_NEAR(parameter(joint, "offset_Nm")["value"].get<double>(), -3.1648, 3 * 0.0444);
}

}  // namespace
