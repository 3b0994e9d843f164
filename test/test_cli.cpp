// End-to-end tests of the `fivebar` executable: real processes, their stdout, stderr and exit
// code (docs/conventions.md "Exit codes"). Expected values are derived here from the geometry of the
// paper's device (Table 1), independently of the library.

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

constexpr double kDeg = std::numbers::pi / 180.0;

// Paper Table 1, index station, lower mechanism: O1 (0,0), O2 (12.5,0), L1=L2=9, L3=L4=15.
struct Linkage {
  std::array<double, 2> O1, O2;
  std::array<double, 4> L;
};
constexpr Linkage kIndexLower{{0.0, 0.0}, {12.5, 0.0}, {9.0, 9.0, 15.0, 15.0}};
constexpr Linkage kIndexUpper{{0.0, 31.0}, {12.5, 31.0}, {9.0, 9.0, 15.0, 15.0}};

using P2 = std::array<double, 2>;
P2 elbow(const P2& O, double L, double theta_deg) {
  return {O[0] + L * std::cos(theta_deg * kDeg), O[1] + L * std::sin(theta_deg * kDeg)};
}
double dist(const P2& a, const P2& b) { return std::hypot(a[0] - b[0], a[1] - b[1]); }
double cross(const P2& o, const P2& a, const P2& b) {  // cross(a - o, b - o)
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}
P2 xy(const json& j) { return {j.at(0).get<double>(), j.at(1).get<double>()}; }

/// The paper's design and a scratch directory per test (test/cli_test.hpp).
class Cli : public ft::CliTest {
 protected:
  Cli() : CliTest("fivebar_test_cli") {}
};

std::vector<std::vector<std::string>> parse_csv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream ls(line);
    while (std::getline(ls, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    rows.push_back(cells);
  }
  return rows;
}

const std::vector<std::string> kIndexLowerArgs{"--station", "index", "--mechanism", "lower"};

std::vector<std::string> args(std::initializer_list<std::string> head, const std::vector<std::string>& target,
                              std::initializer_list<std::string> tail) {
  std::vector<std::string> out(head);
  out.insert(out.end(), target.begin(), target.end());
  out.insert(out.end(), tail);
  return out;
}

// --- General --------------------------------------------------------------------------------------

TEST_F(Cli, VersionAndHelp) {
  const Outcome v = run({"--version"});
  EXPECT_EQ(v.code, 0);
  EXPECT_THAT(v.out, MatchesRegex("fivebar [0-9]+\\.[0-9]+\\.[0-9]+\n"));

  const Outcome h = run({"--help"});
  EXPECT_EQ(h.code, 0);
  EXPECT_THAT(h.out, AllOf(HasSubstr("fk"), HasSubstr("ik"), HasSubstr("run"), HasSubstr("Exit status")));
  for (const char* cmd : {"fk", "ik", "run"}) {
    const Outcome sub = run({cmd, "--help"});
    EXPECT_EQ(sub.code, 0) << cmd;
    EXPECT_THAT(sub.out, HasSubstr("Usage: fivebar " + std::string(cmd))) << cmd;
  }
  EXPECT_THAT(run({"fk", "--help"}).out, AllOf(HasSubstr("degrees"), HasSubstr("--theta-file")));
  EXPECT_THAT(run({"ik", "--help"}).out, AllOf(HasSubstr("mm"), HasSubstr("--point-file"), HasSubstr("--all")));
}

TEST_F(Cli, UsageErrorsExitTwoWithAMessageOnStderr) {
  const std::vector<std::vector<std::string>> cases{
      {},
      {"frobnicate"},
      {"fk"},
      {"fk", kDesign, "--frobnicate"},
      {"fk", kDesign, "-s", "index", "-m", "middle", "--theta", "1,2"},
      {"fk", kDesign, "-s", "index", "-m", "lower", "--theta", "1,2", "--theta-file", "x.csv"},
      {"fk", kDesign, "-s", "index", "-m", "lower", "--theta-file", "x.csv", "--json"},
      {"fk", kDesign, "-s", "index", "-m", "lower", "--branch", "up", "--theta", "1,2"},
      {"fk", kDesign, "-s", "index", "-m", "lower"},
      {"ik", kDesign, "-s", "index", "-m", "lower", "--point", "1,2", "--mode", "+"},
      {"ik", kDesign, "-s", "index", "-m", "lower", "--point", "1,2", "--all", "--mode", "+-"},
      {"ik", kDesign, "-s", "index", "-m", "lower", "--point", "1,2", "--output", "x.csv"},
      {"run"},
  };
  for (const auto& c : cases) {
    std::string line;
    for (const auto& a : c) line += a + " ";
    SCOPED_TRACE("fivebar " + line);
    const Outcome r = run(c);
    EXPECT_EQ(r.code, 2);
    EXPECT_THAT(r.out, IsEmpty());
    EXPECT_FALSE(r.err.empty());
  }
  EXPECT_TRUE(tree(dir_).empty()) << "usage errors write nothing";
}

// --- fk -------------------------------------------------------------------------------------------

TEST_F(Cli, FkJsonMatchesTheGeometryAndHasTheContractKeys) {
  const double t1 = 100.0, t2 = 80.0;
  const Outcome r = run(args({"fk", kDesign}, kIndexLowerArgs, {"--theta", "100,80", "--json"}));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, IsEmpty());
  const json j = parse(r);
  for (const char* key : {"status", "point_mm", "theta_deg", "elbows_mm", "mode", "assembly", "jacobian", "lci",
                          "force_capability", "transmission_deg", "singularity", "closure_error_mm",
                          "within_joint_limits"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  for (const char* key : {"type1_sin", "type2_sin", "type1_distance_mm"}) EXPECT_TRUE(j["singularity"].contains(key));
  EXPECT_EQ(j["status"], "ok");
  EXPECT_EQ(j["assembly"], "+");
  EXPECT_EQ(j["mode"], "-+");
  EXPECT_NEAR(j["theta_deg"][0].get<double>(), t1, 1e-12);
  EXPECT_NEAR(j["theta_deg"][1].get<double>(), t2, 1e-12);

  // Independent check: P is L3 from A1 and L4 from A2, above the line A1A2 (assembly "+").
  const P2 P = xy(j["point_mm"]);
  const P2 A1 = elbow(kIndexLower.O1, kIndexLower.L[0], t1);
  const P2 A2 = elbow(kIndexLower.O2, kIndexLower.L[1], t2);
  EXPECT_NEAR(dist(P, A1), 15.0, 1e-12);
  EXPECT_NEAR(dist(P, A2), 15.0, 1e-12);
  EXPECT_GT(cross(A1, A2, P), 0.0);
  EXPECT_NEAR(xy(j["elbows_mm"][0])[0], A1[0], 1e-12);
  EXPECT_NEAR(xy(j["elbows_mm"][1])[1], A2[1], 1e-12);
  // Symmetric angles put P on the symmetry axis x = 6.25, at h = sqrt(L3^2 - (d/2)^2) above the elbows.
  const double half = (A2[0] - A1[0]) / 2;
  EXPECT_NEAR(P[0], 6.25, 1e-12);
  EXPECT_NEAR(P[1], A1[1] + std::sqrt(15.0 * 15.0 - half * half), 1e-12);
  // LCI in [0, 1]; transmission angles in degrees.
  EXPECT_GT(j["lci"].get<double>(), 0.0);
  EXPECT_LE(j["lci"].get<double>(), 1.0);
  for (const auto& a : j["transmission_deg"]) {
    EXPECT_GT(a.get<double>(), 0.0);
    EXPECT_LT(a.get<double>(), 180.0);
  }
}

TEST_F(Cli, FkJacobianMatchesCentralDifferencesOfFk) {
  const auto point = [&](double t1, double t2) {
    char theta[64];
    std::snprintf(theta, sizeof theta, "%.17g,%.17g", t1, t2);
    const Outcome r = run(args({"fk", kDesign}, kIndexLowerArgs, {"--theta", theta, "--json"}));
    EXPECT_EQ(r.code, 0) << r.err;
    return json::parse(r.out);
  };
  const double t1 = 115.0, t2 = 70.0;
  const json j = point(t1, t2);
  ASSERT_FALSE(j["jacobian"].is_null());
  const double h_deg = 1e-4;  // central difference error ~h^2, rounding ~eps*L/h: both << 1e-6
  const double h_rad = h_deg * kDeg;
  for (int col = 0; col < 2; ++col) {
    const json plus = point(t1 + (col == 0 ? h_deg : 0), t2 + (col == 1 ? h_deg : 0));
    const json minus = point(t1 - (col == 0 ? h_deg : 0), t2 - (col == 1 ? h_deg : 0));
    for (int row = 0; row < 2; ++row) {
      const double fd = (plus["point_mm"][row].get<double>() - minus["point_mm"][row].get<double>()) / (2 * h_rad);
      EXPECT_NEAR(j["jacobian"][row][col].get<double>(), fd, 1e-6 * 15.0) << "J(" << row << "," << col << ")";
    }
  }
}

TEST_F(Cli, FkTableForHumans) {
  const Outcome r = run(args({"fk", kDesign}, kIndexLowerArgs, {"--theta", "100,80"}));
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, AllOf(HasSubstr("index/lower"), HasSubstr("status"), HasSubstr("ok"), HasSubstr("6.2500"),
                           HasSubstr("LCI"), HasSubstr("(mm)"), HasSubstr("(deg)")));
}

TEST_F(Cli, FkBranchesAndNegativeAngles) {
  // Upper mechanism, angles below its base line: negative values right after the option.
  const Outcome r = run({"fk", kDesign, "-s", "index", "-m", "upper", "--theta", "-100,-80", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = parse(r);
  const P2 A1 = elbow(kIndexUpper.O1, 9.0, -100.0);
  const P2 A2 = elbow(kIndexUpper.O2, 9.0, -80.0);
  const P2 P = xy(j["point_mm"]);
  EXPECT_NEAR(dist(P, A1), 15.0, 1e-12);
  EXPECT_NEAR(dist(P, A2), 15.0, 1e-12);
  EXPECT_LT(cross(A1, A2, P), 0.0) << "upper mechanism: assembly '-' (below A1A2)";

  const Outcome all = run({"fk", kDesign, "-s", "index", "-m", "upper", "--theta", "-100,-80", "--all", "--json"});
  ASSERT_EQ(all.code, 0) << all.err;
  const json b = parse(all);
  ASSERT_EQ(b["branches"].size(), 2u);
  EXPECT_EQ(b["branches"][0]["assembly"], "+");
  EXPECT_EQ(b["branches"][1]["assembly"], "-");
  EXPECT_EQ(b["branches"][1]["point_mm"], j["point_mm"]);

  const Outcome minus = run({"fk", kDesign, "-s", "index", "-m", "upper", "--theta", "-100,-80", "--branch", "+", "--json"});
  ASSERT_EQ(minus.code, 0) << minus.err;
  EXPECT_EQ(json::parse(minus.out)["point_mm"], b["branches"][0]["point_mm"]);
}

TEST_F(Cli, FkWithoutConfigurationExitsOne) {
  // theta = (180, 0) puts the elbows 30.5 mm apart: more than L3 + L4 = 30.
  const Outcome r = run(args({"fk", kDesign}, kIndexLowerArgs, {"--theta", "180,0", "--json"}));
  EXPECT_EQ(r.code, 1);
  const json j = parse(r);
  EXPECT_EQ(j["status"], "unreachable");
  EXPECT_TRUE(j["point_mm"].is_null());
  EXPECT_FALSE(r.err.empty());
}

TEST_F(Cli, BadThetaSyntaxExitsTwoNamingTheOption) {
  for (const char* theta : {"100", "a,b", "1,2,3", "nan,1", "1,inf", "1;2", ",", "1e999,0"}) {
    SCOPED_TRACE(theta);
    const Outcome r = run(args({"fk", kDesign}, kIndexLowerArgs, {"--theta", theta}));
    EXPECT_EQ(r.code, 2);
    EXPECT_THAT(r.out, IsEmpty());
    EXPECT_THAT(r.err, HasSubstr("--theta"));
  }
}

// --- station / mechanism choice --------------------------------------------------------------------

TEST_F(Cli, StationAndMechanismChoices) {
  const Outcome unknown = run({"fk", kDesign, "--station", "pinky", "--mechanism", "lower", "--theta", "100,80"});
  EXPECT_EQ(unknown.code, 2);
  EXPECT_THAT(unknown.err, AllOf(HasSubstr("pinky"), HasSubstr("index"), HasSubstr("thumb")));

  const Outcome ambiguous = run({"fk", kDesign, "--theta", "100,80"});
  EXPECT_EQ(ambiguous.code, 2);
  EXPECT_THAT(ambiguous.err, AllOf(HasSubstr("--station"), HasSubstr("index"), HasSubstr("thumb")));

  const Outcome no_mech = run({"fk", kDesign, "--station", "thumb", "--theta", "100,80"});
  EXPECT_EQ(no_mech.code, 2);
  EXPECT_THAT(no_mech.err, AllOf(HasSubstr("--mechanism"), HasSubstr("lower"), HasSubstr("upper")));

  // A design with one station and one mechanism needs neither option.
  const fs::path single = write("single.yaml",
                                "name: single\n"
                                "stations:\n"
                                "  index:\n"
                                "    target: {center: [6.25, 15.5], axes: [15, 12], angle: 0}\n"
                                "    mechanisms:\n"
                                "      lower:\n"
                                "        bases: [[0, 0], [12.5, 0]]\n"
                                "        links: [9, 9, 15, 15]\n"
                                "        working_mode: \"-+\"\n"
                                "        assembly_mode: \"+\"\n");
  const Outcome ok = run({"ik", single.string(), "--point", "6.25,15.5", "--json"});
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_EQ(json::parse(ok.out)["mechanism"], "lower");
  const Outcome absent = run({"ik", single.string(), "--mechanism", "upper", "--point", "6.25,15.5"});
  EXPECT_EQ(absent.code, 2);
  EXPECT_THAT(absent.err, AllOf(HasSubstr("upper"), HasSubstr("lower")));
}

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

// --- design errors --------------------------------------------------------------------------------

TEST_F(Cli, MalformedDesignExitsTwoNamingTheKeyAndWritesNothing) {
  const fs::path bad = design_with("bad.yaml", "links: [9, 9, 15, 15]", "links: [9, 9, -15, 15]");
  for (const auto& cmd : std::vector<std::vector<std::string>>{
           {"fk", bad.string(), "-s", "index", "-m", "lower", "--theta", "100,80"},
           {"ik", bad.string(), "-s", "index", "-m", "lower", "--point", "6,15", "--json"},
           {"run", bad.string(), "--out", (dir_ / "out").string()}}) {
    SCOPED_TRACE(cmd[0]);
    const Outcome r = run(cmd);
    EXPECT_EQ(r.code, 2);
    EXPECT_THAT(r.out, IsEmpty());
    EXPECT_THAT(r.err, AllOf(HasSubstr("bad.yaml"), HasSubstr("links[2]")));
  }
  EXPECT_FALSE(fs::exists(dir_ / "out")) << "no output for a bad design";

  const Outcome missing = run({"run", (dir_ / "nope.yaml").string(), "--out", (dir_ / "out").string()});
  EXPECT_EQ(missing.code, 2);
  EXPECT_THAT(missing.err, HasSubstr("nope.yaml"));
  EXPECT_FALSE(fs::exists(dir_ / "out"));
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

// --- run ------------------------------------------------------------------------------------------

TEST_F(Cli, RunWritesTheTwoSummariesAndNothingElse) {
  const fs::path out = dir_ / "out";
  // Only kinematics, which writes no files of its own (other products write theirs beside).
  const Outcome r = run({"run", kDesign, "--out", out.string(), "--products", "kinematics"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, AllOf(HasSubstr("kinematics"), HasSubstr("summary.md")));

  const json s = json::parse(slurp(out / "iros2022" / "summary.json"));
  EXPECT_EQ(s["design"]["name"], "iros2022");
  EXPECT_TRUE(s["ok"].get<bool>());
  ASSERT_GE(s["built"].size(), 1u);
  EXPECT_EQ(s["built"][0]["name"], "kinematics");
  // Nothing but the summaries and the files the built products list (and their folders).
  std::set<std::string> expected{"iros2022", "iros2022/summary.json", "iros2022/summary.md"};
  for (const auto& product : s["built"]) {
    for (const auto& f : product["files"]) {
      for (fs::path p = fs::path("iros2022") / f.get<std::string>(); p != "iros2022"; p = p.parent_path()) {
        expected.insert(p.generic_string());
      }
    }
  }
  EXPECT_EQ(tree(out), std::vector<std::string>(expected.begin(), expected.end()));
  const json& stations = s["results"]["kinematics"]["stations"];
  ASSERT_EQ(stations.size(), 2u);
  // The summary's centre pose agrees with `fivebar ik` at the same point.
  const json& lower = stations[0]["mechanisms"][0];
  EXPECT_EQ(lower["mechanism"]["name"], "lower");
  const Outcome ik = run(args({"ik", kDesign}, kIndexLowerArgs, {"--point", "6.25,15.5", "--json"}));
  EXPECT_EQ(lower["centre"]["ik"]["theta_deg"], json::parse(ik.out)["theta_deg"]);
  EXPECT_EQ(lower["axis_ends"].size(), 4u);

  const std::string md = slurp(out / "iros2022" / "summary.md");
  EXPECT_THAT(md, AllOf(HasSubstr("# fivebar scene `iros2022`"), HasSubstr("| `kinematics` | built"),
                        HasSubstr("θ1 (deg)"), HasSubstr("Station `thumb`")));
}

TEST_F(Cli, RunJsonAndDefaultOutputRoot) {
  // Default root is outputs/ relative to the working directory.
  const Outcome r = run({"run", kDesign, "--json", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, IsEmpty());
  const json j = parse(r);
  EXPECT_EQ(j["built"][0]["name"], "kinematics");
  EXPECT_EQ(j["summary_md"], "outputs/iros2022/summary.md");
  EXPECT_TRUE(fs::exists(dir_ / "outputs" / "iros2022" / "summary.json"));
}

TEST_F(Cli, RunProductsOptionAndSceneList) {
  const fs::path out = dir_ / "out";
  const Outcome bogus = run({"run", kDesign, "--out", out.string(), "--products", "kinematics,teleport"});
  EXPECT_EQ(bogus.code, 2);
  EXPECT_THAT(bogus.err, AllOf(HasSubstr("teleport"), HasSubstr("kinematics")));
  EXPECT_FALSE(fs::exists(out));

  const Outcome listed = run({"run", kDesign, "--out", out.string(), "--products", "kinematics", "--json"});
  ASSERT_EQ(listed.code, 0) << listed.err;
  EXPECT_THAT(listed.err, IsEmpty());  // stderr is a file, not a terminal: no progress lines even without --quiet
  const json j = parse(listed);
  EXPECT_TRUE(j["products_listed"].get<bool>());
  EXPECT_TRUE(j["built"][0]["requested"].get<bool>());

  const fs::path scene = design_with("scene.yaml", "name: iros2022", "name: scene\nproducts: [kinematics]");
  const Outcome from_file = run({"run", scene.string(), "--out", out.string(), "--json"});
  ASSERT_EQ(from_file.code, 0) << from_file.err;
  EXPECT_TRUE(json::parse(from_file.out)["products_listed"].get<bool>());
  EXPECT_TRUE(fs::exists(out / "scene" / "summary.md"));
}

TEST_F(Cli, RunIntoAnUnusableOutputRootFailsWithoutPartialFiles) {
  const fs::path file = write("occupied", "not a directory\n");
  const Outcome r = run({"run", kDesign, "--out", file.string()});
  EXPECT_EQ(r.code, 3);
  EXPECT_THAT(r.err, HasSubstr("occupied"));
  EXPECT_EQ(slurp(file), "not a directory\n");
}

}  // namespace
