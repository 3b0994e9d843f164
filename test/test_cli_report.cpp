// End-to-end tests of `fivebar report`: real processes, stdout, stderr, exit codes and the files
// written (test/cli_test.hpp). The reports' figures are tested in test_report.cpp against their
// references; here what the command adds: one JSON document, the exit codes, --out as the plots'
// directory, an unwritable output.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli_test.hpp"

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using ft::slurp;
using ::testing::AllOf;
using ::testing::HasSubstr;

namespace {

class CliReport : public ft::CliTest {
 protected:
  CliReport() : CliTest("fivebar_test_cli_report") {}
};

TEST_F(CliReport, StabilityJsonAndExitCode) {
  const Outcome r = run({"report", "stability", kDesign, "--station", "index", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  nlohmann::json j;
  ASSERT_NO_THROW(j = nlohmann::json::parse(r.out)) << "stdout is not one JSON document";
  EXPECT_EQ(j["command"], "report stability");
  EXPECT_TRUE(j["passed"].get<bool>());
  EXPECT_EQ(j["failed"], 0);
  EXPECT_EQ(j["cases_total"].get<std::size_t>(), j["cases"].size());
  for (const char* key : {"subject", "group", "case", "operation", "parameter", "status", "expected", "error", "bound",
                          "unit", "conditioning", "finite", "passed", "ill_conditioned", "explanation"})
    EXPECT_TRUE(j["cases"][0].contains(key)) << key;
  for (const auto& c : j["cases"]) {
    // The kinematic cases by mechanism, the dynamic ones (both tactors together) by station.
    EXPECT_TRUE(c["subject"] == "index/lower" || c["subject"] == "index/upper" ||
                (c["subject"] == "index" && c["group"] == "dynamics"))
        << c["subject"];
  }

  const Outcome text = run({"report", "stability", kDesign, "--station", "thumb"});
  EXPECT_EQ(text.code, 0);
  EXPECT_THAT(text.out, AllOf(HasSubstr("thumb/lower  type I distance"), HasSubstr("PASS"), HasSubstr("all cases passed")));
}

TEST_F(CliReport, AccuracyQuickJsonWritesThePlots) {
  const Outcome r =
      run({"report", "accuracy", kDesign, "--station", "index", "--quick", "--json", "--out", (dir_ / "o").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  nlohmann::json j;
  ASSERT_NO_THROW(j = nlohmann::json::parse(r.out));
  EXPECT_EQ(j["command"], "report accuracy");
  EXPECT_TRUE(j["quick"].get<bool>());
  ASSERT_EQ(j["mechanisms"].size(), 2u);
  EXPECT_EQ(j["mechanisms"][0]["station"], "index");
  for (const char* key : {"area", "coverage", "restricted", "tolerance"}) EXPECT_TRUE(j["mechanisms"][0].contains(key)) << key;
  EXPECT_EQ(j["fk"]["strata"].size(), 5u);
  ASSERT_EQ(j["files"].size(), 18u);  // 5 per station, FK, IK, dynamics, stiffness; SVG and PNG
  for (const auto& f : j["files"]) EXPECT_TRUE(fs::exists(f.get<std::string>())) << f;
  EXPECT_TRUE(fs::exists(dir_ / "o" / "accuracy_index_area.png"));
  EXPECT_TRUE(fs::exists(dir_ / "o" / "accuracy_dynamics_stiffness.svg"));
  EXPECT_EQ(j["dynamics"]["station"], "index");
  EXPECT_GT(j["dynamics"]["crossover_stiffness_ratio"].get<double>(), 1.0);
}

TEST_F(CliReport, BadInputExitsTwoAndAnUnwritableOutputThree) {
  const Outcome none = run({"report"});
  EXPECT_EQ(none.code, 2);
  const Outcome missing = run({"report", "stability", (dir_ / "nope.yaml").string()});
  EXPECT_EQ(missing.code, 2);
  EXPECT_THAT(missing.err, HasSubstr("nope.yaml"));
  const Outcome station = run({"report", "stability", kDesign, "--station", "pinky"});
  EXPECT_EQ(station.code, 2);
  EXPECT_THAT(station.err, AllOf(HasSubstr("pinky"), HasSubstr("index"), HasSubstr("thumb")));
  const Outcome acc_station = run({"report", "accuracy", kDesign, "--station", "pinky", "--quick"});
  EXPECT_EQ(acc_station.code, 2);
  std::ofstream(dir_ / "occupied") << "a file, not a directory\n";
  const Outcome unwritable =
      run({"report", "accuracy", kDesign, "--station", "index", "--quick", "--out", (dir_ / "occupied").string()});
  EXPECT_EQ(unwritable.code, 3);
  EXPECT_EQ(slurp(dir_ / "occupied"), "a file, not a directory\n");
}

}  // namespace
