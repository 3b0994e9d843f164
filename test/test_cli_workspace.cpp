// End-to-end tests of `fivebar workspace` and its `fivebar run` product:
// real processes, stdout, stderr, exit codes and the files they leave. Expected numbers are derived
// here from the paper's Table 1 (two annuli per mechanism, radii |L_i -+ L_{i+2}|), independently
// of the library.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "cli_geometry.hpp"
#include "cli_test.hpp"
#include "json_records.hpp"

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using ft::slurp;
using nlohmann::json;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::Not;

namespace {

using namespace ::fivebar::testing::paper;  // test/cli_geometry.hpp

// --- running the binary (test/cli_test.hpp) ---------------------------------------------------------

class CliWorkspace : public ft::CliTest {
 protected:
  CliWorkspace() : CliTest("fivebar_test_cli_ws") {}
};

// --- workspace --------------------------------------------------------------------------------

TEST_F(CliWorkspace, WorkspaceJsonAreasMatchTheAnnuliOfTableOne) {
  const fs::path out = dir_ / "ws";
  const Outcome r = run({"workspace", kDesign, "--out", out.string(), "--spacing", "0.5", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = parse(r);
  EXPECT_EQ(j["command"], "workspace");
  EXPECT_EQ(j["design"], "iros2022");
  EXPECT_EQ(j["spacing_mm"], 0.5);
  ASSERT_EQ(j["stations"].size(), 2u);
  // Index: annuli 6..24 about bases 12.5 apart; thumb: 8.5..26.5. No joint limits, so the exact
  // region is the intersection of the two annuli.
  struct Expect {
    const char* station;
    double r, R;
    int holes;  // inner disks disjoint (2 r < 12.5) or overlapping
  };
  const Expect expect[2] = {{"index", 6.0, 24.0, 2}, {"thumb", 8.5, 26.5, 1}};
  for (int s = 0; s < 2; ++s) {
    const json& st = j["stations"][s];
    SCOPED_TRACE(expect[s].station);
    EXPECT_EQ(st["station"], expect[s].station);
    const double area = annuli_area(expect[s].r, expect[s].R, 12.5);
    for (const char* m : {"lower", "upper"}) {
      const json& mech = ft::mechanism(st, m);
      EXPECT_NEAR(mech["area_mm2"].get<double>(), area, 1e-9 * area) << m;
      EXPECT_EQ(mech["components"], 1) << m;
      EXPECT_EQ(mech["holes"], expect[s].holes) << m;
      // The restricted regions are subsets of the exact region, measured with an error estimate.
      const double assembly = mech["assembly_area_mm2"].get<double>(), err = mech["assembly_error_mm2"].get<double>();
      EXPECT_GT(assembly, 0.5 * area);
      EXPECT_LE(assembly, area + err);
      EXPECT_GT(err, 0.0);
      EXPECT_LT(err, 0.01 * area);
      EXPECT_LE(mech["lci_area_mm2"].get<double>(), assembly + err);
    }
    // The regions are mirror images about y = (base distance)/2: same area; the shared region
    // is smaller than either and not empty.
    const double shared = st["shared"]["area_mm2"].get<double>();
    EXPECT_GT(shared, 0.0);
    EXPECT_LT(shared, area);
    ASSERT_EQ(st["files"].size(), 5u);
    for (const auto& f : st["files"]) EXPECT_TRUE(fs::exists(f.get<std::string>())) << f;
  }
  // Files only in --out: nothing under the working directory but the output directory.
  EXPECT_EQ(tree(dir_), (std::vector<std::string>{
                            "ws", "ws/index-lower-field.vti", "ws/index-regions.vtp", "ws/index-upper-field.vti",
                            "ws/index-workspace.png", "ws/index-workspace.svg", "ws/thumb-lower-field.vti",
                            "ws/thumb-regions.vtp", "ws/thumb-upper-field.vti", "ws/thumb-workspace.png",
                            "ws/thumb-workspace.svg"}));
}
TEST_F(CliWorkspace, WorkspaceTableStationMechanismAndDefaultDirectory) {
  const Outcome r = run({"workspace", kDesign, "--station", "thumb", "--mechanism", "upper", "--spacing", "1"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, IsEmpty());  // no progress lines when stderr is not a terminal
  const std::string area = [] {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3f", annuli_area(8.5, 26.5, 12.5));
    return std::string(buf);
  }();
  EXPECT_THAT(r.out, AllOf(HasSubstr("station thumb"), HasSubstr("upper"), HasSubstr(area), Not(HasSubstr("lower")),
                           Not(HasSubstr("shared"))));
  EXPECT_EQ(tree(dir_ / "outputs"),
            (std::vector<std::string>{"iros2022", "iros2022/workspace", "iros2022/workspace/thumb-regions.vtp",
                                      "iros2022/workspace/thumb-upper-field.vti",
                                      "iros2022/workspace/thumb-workspace.png",
                                      "iros2022/workspace/thumb-workspace.svg"}));
}
TEST_F(CliWorkspace, WorkspaceBadInputIsExitTwoAndWritesNothing) {
  const fs::path out = dir_ / "never";
  struct Case {
    std::vector<std::string> args;
    const char* message;
  };
  const std::vector<Case> cases{
      {{"--spacing", "0"}, "--spacing"},
      {{"--spacing", "-0.5"}, "--spacing"},
      {{"--spacing", "abc"}, "--spacing"},
      {{"--spacing", "0.00001"}, "coarser spacing"},
      {{"--station", "pinky"}, "pinky"},
      {{"--mechanism", "middle"}, "--mechanism"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args{"workspace", kDesign, "--out", out.string()};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const Outcome r = run(args);
    SCOPED_TRACE(c.args[0] + " " + c.args[1]);
    EXPECT_EQ(r.code, 2) << r.out << r.err;
    EXPECT_THAT(r.err, HasSubstr(c.message));
    EXPECT_THAT(r.out, IsEmpty());
  }
  const Outcome missing = run({"workspace", (dir_ / "nope.yaml").string(), "--out", out.string()});
  EXPECT_EQ(missing.code, 2);
  EXPECT_FALSE(fs::exists(out));
}

// --- products of `fivebar run` -----------------------------------------------------------------

TEST_F(CliWorkspace, RunBuildsWorkspaceAndCoverageWithSummarySections) {
  const fs::path out = dir_ / "out";
  const Outcome r = run({"run", kDesign, "--out", out.string(), "--products", "workspace,coverage", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  const fs::path scene = out / "iros2022";
  const json s = json::parse(slurp(scene / "summary.json"));
  std::vector<std::string> built;
  for (const auto& b : s["built"]) built.push_back(b["name"]);
  EXPECT_EQ(built, (std::vector<std::string>{"workspace", "coverage"}));
  for (const char* f : {"workspace/index-workspace.png", "workspace/index-workspace.svg", "workspace/index-regions.vtp",
                        "workspace/index-lower-field.vti", "workspace/thumb-upper-field.vti"})
    EXPECT_TRUE(fs::exists(scene / f)) << f;
  // Coverage results in the summary are the document `fivebar coverage --json` prints.
  const Outcome cov = run({"coverage", kDesign, "--json"});
  EXPECT_EQ(s["results"]["coverage"]["stations"], json::parse(cov.out)["stations"]);
  const double area = annuli_area(6, 24, 12.5);
  EXPECT_NEAR(ft::mechanism(s["results"]["workspace"]["stations"][0], "lower")["area_mm2"].get<double>(), area,
              1e-9 * area);

  const std::string md = slurp(scene / "summary.md");
  EXPECT_THAT(md, AllOf(HasSubstr("## Reachable workspace"), HasSubstr("## Target coverage"),
                        HasSubstr("![Station index workspace](workspace/index-workspace.png)"),
                        HasSubstr("| lower | ✓ covered |"), HasSubstr("exact area (mm²)")));
}

}  // namespace
