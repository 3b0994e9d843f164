// End-to-end tests of `fivebar ik`, single and batch (with `fk --theta-file` for the round trip):
// expected values from the paper's geometry (test/cli_geometry.hpp), independently of the library.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "cli_geometry.hpp"
#include "cli_test.hpp"

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using ft::slurp;
using nlohmann::json;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::MatchesRegex;

namespace {

using namespace ::fivebar::testing::paper;  // test/cli_geometry.hpp

/// The paper's design and a scratch directory per test (test/cli_test.hpp).
class Cli : public ft::CliTest {
 protected:
  Cli() : CliTest("fivebar_test_cli") {}
};

// --- ik -------------------------------------------------------------------------------------------

TEST_F(Cli, IkAnglesPlaceTheElbowsAtTheDistalLengths) {
  for (const auto& [x, y] : std::vector<P2>{{6.25, 15.5}, {0.0, 20.0}, {13.75, 15.5}, {-1.0, 12.0}}) {
    char point[64];
    std::snprintf(point, sizeof point, "%g,%g", x, y);
    SCOPED_TRACE(point);
    const Outcome r = run(args({"ik", kDesign}, kIndexLowerArgs, {"--point", point, "--json"}));
    ASSERT_EQ(r.code, 0) << r.err;
    const json j = parse(r);
    EXPECT_EQ(j["status"], "ok");
    const P2 P{x, y};
    const P2 A1 = elbow(kIndexLower.O1, 9.0, j["theta_deg"][0].get<double>());
    const P2 A2 = elbow(kIndexLower.O2, 9.0, j["theta_deg"][1].get<double>());
    EXPECT_NEAR(dist(P, A1), 15.0, 1e-9);
    EXPECT_NEAR(dist(P, A2), 15.0, 1e-9);
    // The design's working mode "-+": leg 1 elbow clockwise, leg 2 counter-clockwise.
    EXPECT_LT(cross(kIndexLower.O1, A1, P), 0.0);
    EXPECT_GT(cross(kIndexLower.O2, A2, P), 0.0);
    EXPECT_EQ(j["mode"], "-+");
    EXPECT_GT(j["theta_deg"][0].get<double>(), -180.0);
    EXPECT_LE(j["theta_deg"][0].get<double>(), 180.0);
  }
}
TEST_F(Cli, IkAllGivesFourBranchesConsistentWithSingleIk) {
  const Outcome all = run(args({"ik", kDesign}, kIndexLowerArgs, {"--point", "6.25,15.5", "--all", "--json"}));
  ASSERT_EQ(all.code, 0) << all.err;
  const json j = parse(all);
  ASSERT_EQ(j["branches"].size(), 4u);
  const std::array<std::string, 4> modes{"++", "+-", "-+", "--"};
  const P2 P{6.25, 15.5};
  for (std::size_t k = 0; k < 4; ++k) {
    const json& b = j["branches"][k];
    SCOPED_TRACE(modes[k]);
    EXPECT_EQ(b["working_mode"], modes[k]);
    EXPECT_EQ(b["mode"], modes[k]) << "realised mode equals the requested one";
    const P2 A1 = elbow(kIndexLower.O1, 9.0, b["theta_deg"][0].get<double>());
    const P2 A2 = elbow(kIndexLower.O2, 9.0, b["theta_deg"][1].get<double>());
    EXPECT_NEAR(dist(P, A1), 15.0, 1e-9);
    EXPECT_NEAR(dist(P, A2), 15.0, 1e-9);
    EXPECT_EQ(cross(kIndexLower.O1, A1, P) > 0, modes[k][0] == '+');
    EXPECT_EQ(cross(kIndexLower.O2, A2, P) > 0, modes[k][1] == '+');
  }
  const Outcome single = run(args({"ik", kDesign}, kIndexLowerArgs, {"--point", "6.25,15.5", "--json"}));
  EXPECT_EQ(json::parse(single.out)["theta_deg"], j["branches"][2]["theta_deg"]);
  const Outcome mode = run(args({"ik", kDesign}, kIndexLowerArgs, {"--point", "6.25,15.5", "--mode", "+-", "--json"}));
  ASSERT_EQ(mode.code, 0) << mode.err;
  EXPECT_EQ(json::parse(mode.out)["theta_deg"], j["branches"][1]["theta_deg"]);

  const Outcome table = run(args({"ik", kDesign}, kIndexLowerArgs, {"--point", "6.25,15.5", "--all"}));
  ASSERT_EQ(table.code, 0);
  EXPECT_THAT(table.out, AllOf(HasSubstr("++"), HasSubstr("+-"), HasSubstr("-+ *"), HasSubstr("--")));
}
TEST_F(Cli, IkUnreachablePointExitsOne) {
  // |P - O1| = sqrt(2) * 100 mm, far beyond L1 + L3 = 24 mm.
  const Outcome r = run(args({"ik", kDesign}, kIndexLowerArgs, {"--point", "100,100", "--json"}));
  EXPECT_EQ(r.code, 1);
  const json j = parse(r);
  EXPECT_EQ(j["status"], "unreachable");
  EXPECT_EQ(j["target_mm"], json::array({100.0, 100.0}));
  EXPECT_TRUE(j["theta_deg"].is_null());
  EXPECT_THAT(r.err, HasSubstr("unreachable"));

  const Outcome all = run(args({"ik", kDesign}, kIndexLowerArgs, {"--point", "100,100", "--all"}));
  EXPECT_EQ(all.code, 1);
  EXPECT_THAT(all.out, HasSubstr("unreachable"));
}

// --- batch ----------------------------------------------------------------------------------------

TEST_F(Cli, BatchRoundTripIkThenFkGivesThePointsBack) {
  std::uint64_t seed = 20220707;
  if (const char* env = std::getenv("FIVEBAR_TEST_SEED")) seed = std::strtoull(env, nullptr, 10);
  SCOPED_TRACE("FIVEBAR_TEST_SEED=" + std::to_string(seed));
  std::mt19937_64 rng(seed);
  // Points inside the index target ellipse (centre (6.25, 15.5), semi-axes 7.5 x 6), all reachable.
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<P2> points;
  std::string csv = "x_mm,y_mm\n";
  while (points.size() < 200) {
    const double a = u(rng), b = u(rng);
    if (a * a + b * b > 1.0) continue;
    points.push_back({6.25 + 7.5 * a, 15.5 + 6.0 * b});
    char line[96];
    std::snprintf(line, sizeof line, "%.17g,%.17g\n", points.back()[0], points.back()[1]);
    csv += line;
  }
  const Outcome ik = run(args({"ik", kDesign}, kIndexLowerArgs, {"--point-file", "-"}), csv);
  ASSERT_EQ(ik.code, 0) << ik.err;
  const auto ik_rows = parse_csv(ik.out);
  ASSERT_EQ(ik_rows.size(), points.size() + 1);
  EXPECT_EQ(ik_rows[0], (std::vector<std::string>{"x_mm", "y_mm", "theta1_deg", "theta2_deg", "status", "lci", "mode",
                                                  "assembly", "within_joint_limits"}));
  for (std::size_t i = 1; i < ik_rows.size(); ++i) EXPECT_EQ(ik_rows[i][4], "ok") << "row " << i;

  // ik's output has the columns fk reads: feed it back through a file written with --output.
  const fs::path angles = dir_ / "angles.csv";
  ASSERT_EQ(run(args({"ik", kDesign}, kIndexLowerArgs, {"--point-file", "-", "--output", angles.string()}), csv).code, 0);
  EXPECT_EQ(slurp(angles), ik.out);
  const Outcome fk = run(args({"fk", kDesign}, kIndexLowerArgs, {"--theta-file", angles.string()}));
  ASSERT_EQ(fk.code, 0) << fk.err;
  const auto fk_rows = parse_csv(fk.out);
  ASSERT_EQ(fk_rows.size(), points.size() + 1);
  for (std::size_t i = 0; i < points.size(); ++i) {
    SCOPED_TRACE("row " + std::to_string(i + 1));
    EXPECT_EQ(fk_rows[i + 1][4], "ok");
    EXPECT_NEAR(std::stod(fk_rows[i + 1][0]), points[i][0], 1e-9);
    EXPECT_NEAR(std::stod(fk_rows[i + 1][1]), points[i][1], 1e-9);
  }
  EXPECT_EQ(tree(dir_), std::vector<std::string>{"angles.csv"}) << "no temporary left behind";
}
TEST_F(Cli, BatchUnreachableRowsAreReportedAndExitOne) {
  const Outcome r = run(args({"ik", kDesign}, kIndexLowerArgs, {"--point-file", "-"}),
                    "# a comment\nx_mm,y_mm,label\n6.25,15.5,centre\n\n100,100,far\n");
  EXPECT_EQ(r.code, 1);
  const auto rows = parse_csv(r.out);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[1][4], "ok");
  EXPECT_EQ(rows[2][0], "100");
  EXPECT_EQ(rows[2][4], "unreachable");
  EXPECT_THAT(r.err, HasSubstr("1 of 2"));
}
TEST_F(Cli, BatchBadRowExitsTwoNamingFileAndLineAndLeavesNoOutputFile) {
  const fs::path points = write("points.csv", "x_mm,y_mm\n6.25,15.5\n6.25,abc\n1,2\n");
  const fs::path out = dir_ / "angles.csv";
  const Outcome r = run(args({"ik", kDesign}, kIndexLowerArgs, {"--point-file", points.string(), "--output", out.string()}));
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("points.csv:3"), HasSubstr("y_mm"), HasSubstr("abc")));
  EXPECT_EQ(tree(dir_), std::vector<std::string>{"points.csv"}) << "neither the output nor its temporary";

  const Outcome header = run(args({"fk", kDesign}, kIndexLowerArgs, {"--theta-file", "-"}), "t1,t2\n1,2\n");
  EXPECT_EQ(header.code, 2);
  EXPECT_THAT(header.err, AllOf(HasSubstr("<stdin>:1"), HasSubstr("theta1_deg")));

  const Outcome short_row = run(args({"fk", kDesign}, kIndexLowerArgs, {"--theta-file", "-"}),
                            "theta1_deg,theta2_deg\n100,80\n100\n");
  EXPECT_EQ(short_row.code, 2);
  EXPECT_THAT(short_row.err, HasSubstr("<stdin>:3"));

  const Outcome missing = run(args({"fk", kDesign}, kIndexLowerArgs, {"--theta-file", "nope.csv"}));
  EXPECT_EQ(missing.code, 2);
  EXPECT_THAT(missing.err, HasSubstr("nope.csv"));
}

}  // namespace
