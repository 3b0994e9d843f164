// End-to-end tests of `fivebar calibrate`: real processes, exit codes, JSON, files. The measurement
// files are made here from a device whose parameters are known (the paper's lower index mechanism
// with a longer L3, a shifted O2 and another potentiometer offset), by the library's IK and FK.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <tuple>

#include "cli_test.hpp"
#include "fivebar/design.hpp"
#include "fivebar/format.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/provenance.hpp"
#include "fivebar/sections/provenance.hpp"
#include "fivebar/sections/bench.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sha256.hpp"

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using nlohmann::json;
using ::testing::HasSubstr;

namespace {

class CliCalibrate : public ft::CliTest {
 protected:
  CliCalibrate() : CliTest("fivebar_test_cli_calibrate") {}

  static constexpr double kL3 = 15.2, kO2x = 12.4, kV0 = 0.27;

  /// `n` poses of the true lower index mechanism, noise 0.01 mm, header `header`.
  std::string csv(int n, bool sigma = false) {
    const fivebar::Design d = fivebar::load_design(kDesign);
    fivebar::Mechanism truth = *d.station("index")->lower;
    truth.L[2] = kL3;
    truth.O2.x() = kO2x;
    const auto* c = d.get<fivebar::ControllerSettings>();
    const auto p1 = c->joint("index", "lower", 1).potentiometer, p2 = c->joint("index", "lower", 2).potentiometer;
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    std::normal_distribution<double> noise(0.0, 0.01);
    std::string text = std::string("station,mechanism,volts1,volts2,x_mm,y_mm") + (sigma ? ",sigma_mm" : "") + "\n";
    const auto& t = d.station("index")->target;
    for (int i = 0; i < n;) {
      const fivebar::Vec2 p = t.center + fivebar::Vec2(u(rng) * t.axes.x() / 2, u(rng) * t.axes.y() / 2);
      const fivebar::Pose pose = fivebar::ik(truth, p);
      if (pose.status != fivebar::Status::ok) continue;
      const double v1 = kV0 + pose.theta1 / p1.rad_per_volt, v2 = p2.volts_at_zero + pose.theta2 / p2.rad_per_volt;
      text += "index,lower," + fivebar::format::shortest(v1) + "," + fivebar::format::shortest(v2) + "," +
              fivebar::format::shortest(p.x() + noise(rng)) + "," + fivebar::format::shortest(p.y() + noise(rng)) +
              (sigma ? ",0.01" : "") + "\n";
      ++i;
    }
    return text;
  }

  static const json* param(const json& cal, const std::string& key) {
    for (const json& p : cal["parameters"]) {
      if (p["parameter"] == key) return &p;
    }
    return nullptr;
  }
};

TEST_F(CliCalibrate, FitsTheTrueDeviceAndWritesThePatchWithProvenance) {
  const fs::path meas = write("m.csv", csv(60));
  const ft::Outcome r = run({"calibrate", kDesign, meas.string(), "--json", "--out", "cal", "--holdout", "6"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json doc = parse(r);
  const json& cal = doc["calibration"];
  EXPECT_EQ(cal["poses"], 54);
  const auto check = [&](const std::string& key, double truth) {
    const json* p = param(cal, key);
    ASSERT_NE(p, nullptr) << key;
    EXPECT_TRUE((*p)["identified"].get<bool>()) << key;
    EXPECT_NEAR((*p)["value"].get<double>(), truth, 4.0 * (*p)["sigma"].get<double>() + 1e-9) << key;
    EXPECT_LT((*p)["sigma"].get<double>(), 0.05) << key;
  };
  check("stations.index.mechanisms.lower.links[2]", kL3);
  check("stations.index.mechanisms.lower.bases[1][0]", kO2x);
  check("controller.stations.index.lower.theta1.potentiometer.volts_at_zero", kV0);
  EXPECT_LT(cal["residuals"]["after"]["rms_mm"].get<double>(), 0.03);
  EXPECT_GT(cal["residuals"]["before"]["rms_mm"].get<double>(), 0.1);
  EXPECT_LT(cal["holdout"]["after"]["rms_mm"].get<double>(), 0.05);
  // The patch: loads, carries the estimates, and names its source by hash.
  const fs::path patched = dir_ / "cal" / "iros2022-calibrated.yaml";
  ASSERT_TRUE(fs::exists(patched));
  EXPECT_TRUE(fs::exists(dir_ / "cal" / "calibration-summary.md"));
  const fivebar::Design d = fivebar::load_design(patched);
  EXPECT_NEAR(d.station("index")->lower->L[2], param(cal, "stations.index.mechanisms.lower.links[2]")->at("value").get<double>(), 1e-12);
  EXPECT_TRUE(fivebar::is_measured(d, "stations.index.mechanisms.lower.links[2]"));
  EXPECT_THAT(ft::slurp(patched), HasSubstr(fivebar::sha256_file(meas)));
}

TEST_F(CliCalibrate, AskingForAnUnidentifiableParameterExitsOneAndWritesNothing) {
  const fs::path meas = write("m.csv", csv(40));
  const ft::Outcome r = run({"calibrate", kDesign, meas.string(), "--frame", "fit", "--fit", "L3,O1x,frame.x", "--out", "cal"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_THAT(r.out, HasSubstr("not identifiable: lower.O1x"));
  EXPECT_FALSE(fs::exists(dir_ / "cal"));
  // Without --fit the same poses fit, holding O1 at the design and naming why.
  const ft::Outcome ok = run({"calibrate", kDesign, meas.string(), "--frame", "fit", "--json"});
  EXPECT_EQ(ok.code, 0) << ok.err;
  const json doc = parse(ok);
  std::vector<std::string> held;
  for (const json& u : doc["calibration"]["identifiability"]["unidentifiable"]) held.push_back(u["parameter"]);
  EXPECT_THAT(held, ::testing::UnorderedElementsAre("lower.O1x", "lower.O1y", "lower.O2y"));
}

TEST_F(CliCalibrate, BadInputNamesFileLineAndColumnAndWritesNothing) {
  struct Case {
    std::string text, message;
  };
  const std::vector<Case> cases = {
      {"station,mechanism,volts1,volts2,x_mm\nindex,lower,1,2,3\n", "m.csv:1: column 'y_mm' is missing"},
      {"station,mechanism,volts1,volts2,x_mm,y_mm,z_mm\n", "m.csv:1: column 7 'z_mm': unknown column"},
      {"station,mechanism,volts1,volts2,x_mm,y_mm\nindex,lower,1,nan,3,4\n", "m.csv:2: column 'volts2' = 'nan'"},
      {"station,mechanism,volts1,volts2,x_mm,y_mm\nindex,middle,1,2,3,4\n", "m.csv:2: column 'mechanism' = 'middle'"},
      {csv(3), "6 equations for 12 unknowns"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.message);
    write("m.csv", c.text);
    const ft::Outcome r = run({"calibrate", kDesign, "m.csv", "--out", "cal"});
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_THAT(r.err, HasSubstr(c.message));
    EXPECT_FALSE(fs::exists(dir_ / "cal"));
  }
}

TEST_F(CliCalibrate, PlanWritesJointTargetsThatBeatRandomPoses) {
  const ft::Outcome r = run({"calibrate", kDesign, "--plan", "15", "--station", "index", "--mechanism", "lower", "--json", "--out", "plan"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json doc = parse(r);
  ASSERT_EQ(doc["plan"].size(), 1u);
  const json& p = doc["plan"][0];
  EXPECT_EQ(p["poses"], 15);
  EXPECT_GT(p["observability_index"].get<double>(), p["random_observability_index"].get<double>());
  const std::string plan = ft::slurp(dir_ / "plan" / "calibration-plan.csv");
  EXPECT_EQ(std::count(plan.begin(), plan.end(), '\n'), 16);
  EXPECT_THAT(plan, HasSubstr("station,mechanism,pose,theta1_deg,theta2_deg,volts1,volts2,x_mm,y_mm"));
}

TEST_F(CliCalibrate, RequireMeasuredMakesTheExportGateRefuseAssumedPotentiometers) {
  const fs::path design = design_with("d.yaml", "  joint_margin_deg: 5 ", "  require_measured: [potentiometer]\n  joint_margin_deg: 5 ");
  const ft::Outcome r = run({"export", design.string(), "--json", "--out", "exp", "--station", "index"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_THAT(r.out, HasSubstr("controller.require_measured"));
}

// Poses on one line cannot determine the parameters: the quality gate refuses the fit with the
// reason per parameter, exit 1, nothing written.
TEST_F(CliCalibrate, AFitThatFailsTheQualityGateIsRefusedWithReasonsAndNothingWritten) {
  const fivebar::Design d = fivebar::load_design(kDesign);
  fivebar::Mechanism truth = *d.station("index")->lower;
  truth.L[2] = kL3;
  const auto* c = d.get<fivebar::ControllerSettings>();
  const auto p1 = c->joint("index", "lower", 1).potentiometer, p2 = c->joint("index", "lower", 2).potentiometer;
  const auto& t = d.station("index")->target;
  std::string text = "station,mechanism,volts1,volts2,x_mm,y_mm\n";
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (int i = 0; i < 30; ++i) {
    const fivebar::Vec2 p = t.center + fivebar::Vec2((i / 29.0 - 0.5) * 0.8 * t.axes.x(), 0.0);
    const fivebar::Pose pose = fivebar::ik(truth, p);
    ASSERT_EQ(pose.status, fivebar::Status::ok);
    text += "index,lower," + fivebar::format::shortest(p1.volts_at_zero + pose.theta1 / p1.rad_per_volt) + "," +
            fivebar::format::shortest(p2.volts_at_zero + pose.theta2 / p2.rad_per_volt) + "," + fivebar::format::shortest(p.x() + noise(rng)) +
            "," + fivebar::format::shortest(p.y() + noise(rng)) + "\n";
  }
  const fs::path meas = write("line.csv", text);
  const ft::Outcome r = run({"calibrate", kDesign, meas.string(), "--out", "cal"});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("did not pass the quality gate: nothing written"));
  EXPECT_THAT(r.err, HasSubstr("lower.L3 (stations.index.mechanisms.lower.links[2])"));
  EXPECT_THAT(r.out, HasSubstr("quality gate: refused"));
  EXPECT_FALSE(fs::exists(dir_ / "cal"));
  const ft::Outcome j = run({"calibrate", kDesign, meas.string(), "--json"});
  EXPECT_EQ(j.code, 1);
  const json doc = parse(j);
  EXPECT_FALSE(doc["calibration"]["gate"]["passed"].get<bool>());
  EXPECT_TRUE(doc["files"].empty());
}

// The entry names its measurement file relative to the patched design's folder, the way
// require_measured resolves it: given relative to the working directory (bench/m.csv, the patch
// written into cal/), its hash is still checked when the patch is loaded from anywhere else, and an
// edit of the file after the fit makes every value it measured untrusted. (Recorded as given, the
// entry named cal/bench/m.csv: not found, so never checked.)
TEST_F(CliCalibrate, TheRecordedSourceIsFoundFromThePatchedDesignWhereverItRuns) {
  fs::create_directories(dir_ / "bench");
  write("bench/m.csv", csv(40));
  const ft::Outcome r = run({"calibrate", kDesign, "bench/m.csv", "--out", "cal"});
  ASSERT_EQ(r.code, 0) << r.err;
  const fs::path patched = dir_ / "cal" / "iros2022-calibrated.yaml";
  EXPECT_THAT(ft::slurp(patched), HasSubstr("source: \"../bench/m.csv\""));
  const auto untrusted = [&] {
    return fivebar::untrusted_values(fivebar::load_design(patched), "kinematics", {"index"}, "lower");
  };
  EXPECT_TRUE(untrusted().empty());
  // The kinematic values the fit measured: the first eight calibration keys that have an entry.
  const fivebar::Design d = fivebar::load_design(patched);
  const auto keys = fivebar::calibration_keys(d, "index", "lower");
  const auto measured = std::count_if(keys.begin(), keys.begin() + 8, [&](const std::string& k) { return fivebar::is_measured(d, k); });
  ASSERT_GT(measured, 0);
  std::ofstream(dir_ / "bench" / "m.csv", std::ios::app) << "index,lower,0.1,0.2,1,2\n";
  const auto after = untrusted();
  EXPECT_EQ(static_cast<long>(after.size()), static_cast<long>(measured));
  for (const fivebar::UntrustedValue& v : after) EXPECT_THAT(v.reason, HasSubstr("has changed since the fit")) << v.key;
}

// controller.require_measured follows --station: the index station measured through gated fits is
// exported although the thumb is still assumed; a hand-written entry (no gate) is not trusted.
TEST_F(CliCalibrate, RequireMeasuredFollowsTheExportedStationsAndTrustsOnlyGatedEntries) {
  const fs::path base = design_with("base.yaml", "  joint_margin_deg: 5 ", "  require_measured: [kinematics]\n  joint_margin_deg: 5 ");
  const fivebar::Design d = fivebar::load_design(base);
  std::vector<fivebar::MeasuredValue> values;
  std::vector<fivebar::GateRecord> gates;
  fivebar::GateRecord ok;
  ok.passed = true;
  ok.solver = "CONVERGENCE";
  for (const char* m : {"lower", "upper"}) {
    for (const std::string& k : fivebar::calibration_keys(d, "index", m)) values.push_back({k, 0.01}), gates.push_back(ok);
  }
  const fivebar::MeasurementSource src{"bench.csv", fivebar::sha256_hex("bench"), "2026-11-26", "test"};
  const fs::path gated = write("gated.yaml", fivebar::to_yaml(fivebar::with_measured_values(d, values, src, Eigen::MatrixXd(), gates)));
  const ft::Outcome r = run({"export", gated.string(), "--json", "--out", "exp", "--station", "index"});
  const json doc = parse(r);
  for (const json& check : doc["gate"]["checks"]) {
    if (check["kind"] == "provenance") EXPECT_TRUE(check["passed"].get<bool>()) << check["detail"];
  }
  EXPECT_EQ(std::count(doc["gate"]["assumed"].begin(), doc["gate"]["assumed"].end(), "kinematics"), 0);
  const fs::path hand = write("hand.yaml", fivebar::to_yaml(fivebar::with_measured_values(d, values, src)));
  const ft::Outcome h = run({"export", hand.string(), "--json", "--out", "exp2", "--station", "index"});
  EXPECT_EQ(h.code, 1);
  EXPECT_THAT(h.out, HasSubstr("records no quality gate"));
}

TEST_F(CliCalibrate, HardStopReadingsPatchThePotentiometers) {
  const fivebar::Design d = fivebar::load_design(kDesign);
  const fivebar::Station& st = *d.station("index");
  const double k = d.get<fivebar::ControllerSettings>()->joint("index", "lower", 1).potentiometer.rad_per_volt;
  std::string text = "station,mechanism,joint,stop,volts\n";
  std::string key;
  for (int j = 1; j <= 2 && key.empty(); ++j) {
    const auto range = fivebar::usable_ranges(d, st, *st.lower)[static_cast<std::size_t>(j - 1)];
    for (const auto& [end, by, theta] : {std::tuple{"lo", range.lo_by, range.lo}, std::tuple{"hi", range.hi_by, range.hi}}) {
      if (by.rfind("hard stop", 0) != 0 || !key.empty()) continue;
      // Two readings per stop: one reading has no spread and so no sigma (the quality gate refuses it).
      for (const double dv : {-2e-4, 2e-4}) {
        text += "index,lower," + std::to_string(j) + "," + end + "," + fivebar::format::shortest(0.3 + theta / k + dv) + "\n";
      }
      key = "controller.stations.index.lower.theta" + std::to_string(j) + ".potentiometer.volts_at_zero";
    }
  }
  if (key.empty()) GTEST_SKIP() << "no hard stop on the paper's lower index mechanism";
  write("stops.csv", text);
  const ft::Outcome r = run({"calibrate", kDesign, "--hard-stops", "stops.csv", "--json", "--out", "cal"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json doc = parse(r);
  const json* p = param(doc["hard_stops"], key);
  ASSERT_NE(p, nullptr);
  EXPECT_NEAR((*p)["value"].get<double>(), 0.3, 1e-9);
  // No pose was fitted: the pose figures do not exist (null, docs/conventions.md), they are not 0.
  EXPECT_TRUE(doc["hard_stops"]["identifiability"]["condition_number"].is_null());
  EXPECT_TRUE(doc["hard_stops"]["identifiability"]["observability_index"].is_null());
  const fivebar::Design patched = fivebar::load_design(dir_ / "cal" / "iros2022-calibrated.yaml");
  EXPECT_NEAR(fivebar::design_number(patched, key), 0.3, 1e-9);
  EXPECT_TRUE(fivebar::is_measured(patched, key));
  // A stop the geometry does not define is bad input, nothing written.
  write("bad.csv", "station,mechanism,joint,stop,volts\nindex,lower,1,sideways,1\n");
  const ft::Outcome bad = run({"calibrate", kDesign, "--hard-stops", "bad.csv", "--out", "cal2"});
  EXPECT_EQ(bad.code, 2);
  EXPECT_THAT(bad.err, HasSubstr("bad.csv:2: column 'stop'"));
  EXPECT_FALSE(fs::exists(dir_ / "cal2"));
  // A reading outside the converter (controller.adc.range_v) is a fault, named at its line.
  write("volts.csv", text + "index,lower,1,lo,99\n");
  const ft::Outcome out_of_range = run({"calibrate", kDesign, "--hard-stops", "volts.csv", "--out", "cal3"});
  EXPECT_EQ(out_of_range.code, 2);
  EXPECT_THAT(out_of_range.err, HasSubstr("volts.csv:" + std::to_string(2 + std::count(text.begin(), text.end(), '\n') - 1) +
                                          ": column 'volts' = '99': outside controller.adc.range_v"));
  EXPECT_FALSE(fs::exists(dir_ / "cal3"));
}

}  // namespace

namespace {

/// The first provenance sigma of `key` in a design file.
double provenance_sigma(const fivebar::Design& d, const std::string& key) {
  const fivebar::ProvenanceCovariance pc = fivebar::provenance_covariance(d, {key});
  EXPECT_TRUE(pc.measured[0]) << key;
  return std::sqrt(pc.covariance(0, 0));
}

// `fivebar run` fits the showcase to its synthetic bench files (designs/bench/make_bench.py: the
// truth is this file's kL3, kO2x, kV0 and the motor of its docstring), writes the patched designs,
// and its summary, page and export say what each validated figure rests on; `tolerance` on the
// calibrated design uses the calibration's covariance for the calibrated mechanism only.
TEST_F(CliCalibrate, RunFitsTheBenchFilesAndEveryProductSaysWhatItRestsOn) {
  const ft::Outcome r = run({"run", kDesign, "-P", "calibrate,identify,export", "-o", "out", "-q", "-j", "1"});
  ASSERT_EQ(r.code, 0) << r.err;
  const fs::path root = dir_ / "out" / "iros2022";
  const fs::path calibrated = root / "calibrate" / "iros2022-calibrated.yaml";
  const fs::path identified = root / "identify" / "iros2022-identified.yaml";
  for (const fs::path& f : {calibrated, identified, root / "calibrate" / "calibration-summary.md", root / "identify" / "identify.json"}) {
    EXPECT_TRUE(fs::exists(f)) << f;
  }
  const fivebar::Design cal = fivebar::load_design(calibrated);
  EXPECT_FALSE(cal.has<fivebar::BenchSettings>());
  const std::string mk = "stations.index.mechanisms.lower.";
  EXPECT_LE(std::abs(fivebar::design_number(cal, mk + "links[2]") - kL3), 3 * provenance_sigma(cal, mk + "links[2]"));
  EXPECT_LE(std::abs(fivebar::design_number(cal, mk + "bases[1][0]") - kO2x), 3 * provenance_sigma(cal, mk + "bases[1][0]"));
  const std::string v0 = "controller.stations.index.lower.theta1.potentiometer.volts_at_zero";
  EXPECT_LE(std::abs(fivebar::design_number(cal, v0) - kV0), 3 * provenance_sigma(cal, v0));
  const fivebar::Design ident = fivebar::load_design(identified);
  EXPECT_TRUE(fivebar::is_measured(ident, "motor.coulomb_friction_mNm"));
  EXPECT_LE(std::abs(fivebar::design_number(ident, "motor.coulomb_friction_mNm") - 0.8), 3 * provenance_sigma(ident, "motor.coulomb_friction_mNm"));
  EXPECT_LE(std::abs(fivebar::design_number(ident, "motor.rotor_inertia_g_cm2") - 2.4e-3 / 4e4 * 1e7),
            3 * provenance_sigma(ident, "motor.rotor_inertia_g_cm2"));

  // Summary, page and the export's validation block: what each figure rests on.
  const std::string tracking = "kinematics, potentiometer, motor, contact, density assumed";
  const std::string md = ft::slurp(root / "summary.md");
  EXPECT_THAT(md, HasSubstr("## Kinematic calibration from the bench"));
  EXPECT_THAT(md, HasSubstr("| `index/lower` | max tracking error 0.1"));
  EXPECT_THAT(md, HasSubstr(tracking));
  EXPECT_THAT(ft::slurp(root / "index.html"), HasSubstr(tracking));
  const json summary = json::parse(ft::slurp(root / "summary.json"));
  const json& records = summary["results"]["export"]["rests_on"];
  ASSERT_FALSE(records.empty());
  bool found = false;
  for (const json& rec : records) {
    if (rec["figure"] == "max_tracking_error_m" && rec["subject"] == "index/lower") {
      found = true;
      EXPECT_THAT(rec["text"].get<std::string>(), HasSubstr("max tracking error"));
      EXPECT_THAT(rec["text"].get<std::string>(), HasSubstr(tracking));
    }
  }
  EXPECT_TRUE(found);
  const json exported = json::parse(ft::slurp(root / "export" / "iros2022_controller.json"));
  EXPECT_EQ(exported["fivebar_controller"]["ros__parameters"]["fivebar"]["validation"]["index"]["lower"]["rests_on"]
                    ["max_tracking_error_m"],
            tracking);

  // tolerance on the calibrated design: the lower mechanism's sigmas are the calibration's.
  const ft::Outcome t = run({"tolerance", calibrated.string(), "-s", "index", "--no-files", "--json"});
  ASSERT_EQ(t.code, 0) << t.err;
  const json tj = parse(t);
  const json& mechs = tj["stations"][0]["mechanisms"];
  ASSERT_EQ(mechs.size(), 2u);
  EXPECT_TRUE(mechs[0]["calibrated"].get<bool>());
  EXPECT_THAT(mechs[0]["sigmas_from"].get<std::string>(), HasSubstr("bench/calibration.csv"));
  EXPECT_TRUE(mechs[0]["robust_coverage"]["calibrated"].get<bool>());
  EXPECT_FALSE(mechs[1]["calibrated"].get<bool>());
  EXPECT_LT(mechs[0]["centre_3sigma_first_order_mm"].get<double>(), mechs[1]["centre_3sigma_first_order_mm"].get<double>());
}

}  // namespace
