// End-to-end tests of `fivebar pattern`: trajectories checked against the paper's geometry
// (test/cli_geometry.hpp).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "cli_geometry.hpp"
#include "cli_test.hpp"

namespace {

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using ft::slurp;
using nlohmann::json;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

using namespace ::fivebar::testing::paper;  // test/cli_geometry.hpp

/// The paper's design and a scratch directory per test (test/cli_test.hpp).
class CliTactors : public ft::CliTest {
 protected:
  CliTactors() : CliTest("fivebar_test_cli_pattern") {}
};

// --- pattern ------------------------------------------------------------------------------------------

TEST_F(CliTactors, StretchWritesTrajectoriesThatCloseTheLoop) {
  const fs::path out = dir_ / "pat";
  const Outcome r = run({"pattern", kDesign, "-s", "index", "--pattern", "stretch", "--amplitude", "3", "--duration", "0.5",
                         "--rate", "50", "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, AllOf(HasSubstr("pattern stretch"), HasSubstr("26 samples"), HasSubstr("renderable")));
  const std::string csv = slurp(out / "index-stretch.csv");
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "time_s,station,mechanism,theta1_deg,theta2_deg,x_mm,y_mm,status,target_x_mm,target_y_mm,lci");
  int rows = 0;
  while (std::getline(in, line)) {
    std::vector<std::string> c;
    std::stringstream ls(line);
    std::string cell;
    while (std::getline(ls, cell, ',')) c.push_back(cell);
    ASSERT_EQ(c.size(), 11u) << line;
    EXPECT_EQ(c[1], "index");
    EXPECT_EQ(c[7], "ok");
    const Linkage& k = c[2] == "upper" ? kIndexUpper : kIndexLower;
    // The elbows from the written angles are L1 (L2) from the bases, and the written tactor point is
    // L3 (L4) from them: the angles reproduce the point.
    const double t1 = std::stod(c[3]) * kDeg, t2 = std::stod(c[4]) * kDeg;
    const double x = std::stod(c[5]), y = std::stod(c[6]);
    const double a1x = k.O1[0] + k.L[0] * std::cos(t1), a1y = k.O1[1] + k.L[0] * std::sin(t1);
    const double a2x = k.O2[0] + k.L[1] * std::cos(t2), a2y = k.O2[1] + k.L[1] * std::sin(t2);
    EXPECT_NEAR(std::hypot(x - a1x, y - a1y), k.L[2], 1e-9) << line;
    EXPECT_NEAR(std::hypot(x - a2x, y - a2y), k.L[3], 1e-9) << line;
    // Stretch: the upper 4 mm above the centre moving right, the lower 4 mm below moving left.
    EXPECT_DOUBLE_EQ(y, c[2] == "upper" ? 19.5 : 11.5);
    EXPECT_TRUE(c[2] == "upper" ? x >= 6.25 : x <= 6.25);
    ++rows;
  }
  EXPECT_EQ(rows, 2 * 26);
  for (const char* f : {"index-stretch.svg", "index-stretch.png"}) EXPECT_TRUE(fs::exists(out / f)) << f;
}
TEST_F(CliTactors, LongTwistIsNotRenderableOnTheIndex) {
  const fs::path out = dir_ / "pat";
  const Outcome r = run({"pattern", kDesign, "-s", "index", "--pattern", "twist", "--amplitude", "6", "--out", out.string(),
                         "--json"});
  EXPECT_EQ(r.code, 1);
  const json doc = parse(r);
  EXPECT_FALSE(doc["passed"].get<bool>());
  EXPECT_EQ(doc["first_failure"]["status"], "collision_moved");
  EXPECT_EQ(doc["first_failure"]["mechanism"], "lower");
  EXPECT_GT(doc["worst"]["moved_samples"].get<int>(), 0);
  EXPECT_THAT(r.err, HasSubstr("not renderable"));
  // The trajectory is still written, moved samples marked.
  EXPECT_THAT(slurp(out / "index-twist.csv"), HasSubstr(",collision_moved,"));
  // The thumb's longer links let the same twist pass.
  EXPECT_EQ(run({"pattern", kDesign, "-s", "thumb", "--pattern", "twist", "--amplitude", "5", "--out", out.string()}).code, 0);
}
TEST_F(CliTactors, PatternParametersFromTheDesignAndOverrides) {
  const fs::path out = dir_ / "pat";
  // The showcase gives the thumb a 5.5 mm twist; the index keeps 4 mm.
  const json thumb = parse(run({"pattern", kDesign, "-s", "thumb", "--pattern", "twist", "--out", out.string(), "--json"}));
  EXPECT_EQ(thumb["spec"]["amplitude_mm"].get<double>(), 5.5);
  const json index = parse(run({"pattern", kDesign, "-s", "index", "--pattern", "twist", "--out", out.string(), "--json"}));
  EXPECT_EQ(index["spec"]["amplitude_mm"].get<double>(), 4.0);
  const json pivot = parse(run({"pattern", kDesign, "-s", "index", "--pattern", "pivot", "--amplitude-deg", "10",
                                "--frequency", "1", "--out", out.string(), "--json", "--samples"}));
  EXPECT_EQ(pivot["spec"]["amplitude_deg"].get<double>(), 10.0);
  EXPECT_EQ(pivot["spec"]["samples"].get<int>(), 201);  // 2 s at 100 Hz from the design
  EXPECT_EQ(pivot["samples"].size(), 201u);
  const json centred = parse(run({"pattern", kDesign, "-s", "index", "--pattern", "slip", "--center", "-1,15",
                                  "--separation", "6", "--out", out.string(), "--json"}));
  EXPECT_EQ(xy(centred["spec"]["center_mm"]), (std::array<double, 2>{-1.0, 15.0}));
  // A motor limit below the pattern's peak speed fails it.
  const Outcome slow = run({"pattern", kDesign, "-s", "index", "--pattern", "stretch", "--max-joint-speed", "5",
                            "--out", out.string(), "--json"});
  EXPECT_EQ(slow.code, 1);
  EXPECT_EQ(parse(slow)["first_failure"]["status"], "too_fast");
}
// One joint speed (docs/export.md): a pattern is checked against the speed every exported file
// writes as each joint's max_velocity, the smaller of controller.max_velocity_deg_s (360 deg/s on the
// showcase) and the motors' steady speed less friction; the export's smallest per-joint value of the
// station is the pattern's limit.
TEST_F(CliTactors, PatternsAreCheckedAgainstTheExportsJointSpeed) {
  const fs::path out = dir_ / "speed";
  const json pat = parse(run({"pattern", kDesign, "-s", "index", "--pattern", "stretch", "--out", out.string(), "--json"}));
  ASSERT_EQ(run({"export", kDesign, "-s", "index", "--format", "json", "--out", (dir_ / "x").string()}).code, 0);
  const json exported = json::parse(slurp(dir_ / "x" / "iros2022_controller_index.json"));
  double smallest = std::numeric_limits<double>::infinity();
  for (const auto& [joint, limits] : exported["fivebar_controller"]["ros__parameters"]["joint_limits"].items()) {
    smallest = std::min(smallest, limits["max_velocity"].get<double>() * 180.0 / std::numbers::pi);
  }
  ASSERT_TRUE(std::isfinite(smallest));
  EXPECT_LT(smallest, 360.0);
  EXPECT_NEAR(pat["max_joint_speed_deg_s"].get<double>(), smallest, 1e-9);
}

TEST_F(CliTactors, PatternBadInputExitsTwo) {
  const Outcome kind = run({"pattern", kDesign, "-s", "index", "--pattern", "wiggle"});
  EXPECT_EQ(kind.code, 2);
  EXPECT_THAT(kind.err, HasSubstr("stretch, slip, twist or pivot"));
  const Outcome mm = run({"pattern", kDesign, "-s", "index", "--pattern", "pivot", "--amplitude", "3"});
  EXPECT_EQ(mm.code, 2);
  EXPECT_THAT(mm.err, HasSubstr("--amplitude-deg"));
  const Outcome neg = run({"pattern", kDesign, "-s", "index", "--pattern", "stretch", "--amplitude", "-2"});
  EXPECT_EQ(neg.code, 2);
  EXPECT_THAT(neg.err, HasSubstr("amplitude_mm = -2 mm"));
  const Outcome none = run({"pattern", kDesign, "-s", "index"});
  EXPECT_EQ(none.code, 2);
  EXPECT_FALSE(fs::exists(dir_ / "outputs")) << "bad input writes nothing";
}

}  // namespace
