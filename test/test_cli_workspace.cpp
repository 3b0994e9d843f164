// End-to-end tests of `fivebar workspace`, `fivebar coverage` and their `fivebar run` products:
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

#include "cli_test.hpp"

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

constexpr double kPi = std::numbers::pi;

// --- geometry of the paper's device, by hand ---------------------------------------------------

/// Area of the intersection of two disks of radii a and b whose centres are d apart.
double lens(double a, double b, double d) {
  if (d >= a + b) return 0.0;
  if (d <= std::fabs(a - b)) return kPi * std::min(a, b) * std::min(a, b);
  const double alpha = std::acos((d * d + a * a - b * b) / (2 * d * a));
  const double beta = std::acos((d * d + b * b - a * a) / (2 * d * b));
  return a * a * (alpha - std::sin(2 * alpha) / 2) + b * b * (beta - std::sin(2 * beta) / 2);
}
/// Two annuli r <= |P - O_i| <= R with centres d apart (inclusion-exclusion over the disks).
double annuli_area(double r, double R, double d) { return lens(R, R, d) - 2 * lens(R, r, d) + lens(r, r, d); }

/// Signed margin of a filled ellipse inside the two annuli about (ox1, oy) and (ox2, oy): the
/// smallest of R - max|p - O_i| and min|p - O_i| - r over the ellipse boundary (the centres are
/// outside the ellipse), by dense sampling of the boundary.
double annuli_margin(double r, double R, double ox1, double ox2, double oy, double cx, double cy, double a, double b) {
  double margin = 1e9;
  const int n = 400000;
  for (int k = 0; k < n; ++k) {
    const double t = 2 * kPi * k / n;
    const double x = cx + a * std::cos(t), y = cy + b * std::sin(t);
    for (double ox : {ox1, ox2}) {
      const double d = std::hypot(x - ox, y - oy);
      margin = std::min({margin, R - d, d - r});
    }
  }
  return margin;
}

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
      const json& mech = st["mechanisms"][m];
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

// --- coverage ---------------------------------------------------------------------------------

const std::vector<std::string> kResultKeys{"covered",          "inside",  "margin_mm", "covered_fraction",
                                           "worst_point_mm",   "min_lci", "min_lci_point_mm",
                                           "min_force_capability", "lci_ok", "assembly_ok", "method", "reason"};

/// Keys in document order (parse with nlohmann::ordered_json to keep it).
template <class J>
std::vector<std::string> keys(const J& j) {
  std::vector<std::string> out;
  for (auto it = j.begin(); it != j.end(); ++it) out.push_back(it.key());
  return out;
}

TEST_F(CliWorkspace, CoverageJsonHasExactlyTheDocumentedShapeAndIndependentMargins) {
  const Outcome r = run({"coverage", kDesign, "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const auto j = nlohmann::ordered_json::parse(r.out);
  EXPECT_EQ(keys(j), std::vector<std::string>{"stations"});
  EXPECT_EQ(keys(j["stations"]), (std::vector<std::string>{"index", "thumb"}));
  // Index: ellipse 15 x 12 at (6.25, 15.5); lower annuli 6..24 about (0,0), (12.5,0); upper about
  // y = 31. Thumb: 15 x 14 at (6.25, 17.5), annuli 8.5..26.5, upper at y = 35.
  struct Expect {
    const char* station;
    double r, R, upper_y, cx, cy, a, b;
  };
  for (const Expect& e : {Expect{"index", 6.0, 24.0, 31.0, 6.25, 15.5, 7.5, 6.0},
                          Expect{"thumb", 8.5, 26.5, 35.0, 6.25, 17.5, 7.5, 7.0}}) {
    SCOPED_TRACE(e.station);
    const auto& st = j["stations"][e.station];
    EXPECT_EQ(keys(st), (std::vector<std::string>{"lower", "upper", "shared"}));
    const double lower = annuli_margin(e.r, e.R, 0, 12.5, 0, e.cx, e.cy, e.a, e.b);
    const double upper = annuli_margin(e.r, e.R, 0, 12.5, e.upper_y, e.cx, e.cy, e.a, e.b);
    EXPECT_GT(lower, 0.5);
    for (const char* part : {"lower", "upper", "shared"}) {
      const auto& c = st[part];
      EXPECT_EQ(keys(c), kResultKeys) << part;
      EXPECT_TRUE(c["covered"].get<bool>()) << part;
      EXPECT_TRUE(c["inside"].get<bool>()) << part;
      EXPECT_EQ(c["covered_fraction"].get<double>(), 1.0) << part;
      EXPECT_EQ(c["reason"], "") << part;
      EXPECT_FALSE(c["method"].get<std::string>().empty()) << part;
      const double expected = std::string(part) == "lower" ? lower : std::string(part) == "upper" ? upper
                                                                                                   : std::min(lower, upper);
      EXPECT_NEAR(c["margin_mm"].get<double>(), expected, 1e-6) << part;
      // The worst point is on the ellipse.
      const double u = (c["worst_point_mm"][0].get<double>() - e.cx) / e.a;
      const double v = (c["worst_point_mm"][1].get<double>() - e.cy) / e.b;
      EXPECT_NEAR(u * u + v * v, 1.0, 1e-6) << part;
      EXPECT_GT(c["min_lci"].get<double>(), 0.0);
      EXPECT_LE(c["min_lci"].get<double>(), 1.0);
      EXPECT_GT(c["min_force_capability"].get<double>(), 0.0);
    }
  }
}

TEST_F(CliWorkspace, CoverageEllipseOverrideOutsideIsExitOneWithNegativeMargin) {
  // 40 mm wide at the index centre: x reaches -13.75 where |P - O2| = 26.25 > 24.
  const Outcome r = run({"coverage", kDesign, "--station", "index", "--ellipse", "6.25,15.5,40,12,0", "--json"});
  EXPECT_EQ(r.code, 1) << r.err;
  const json j = parse(r);
  EXPECT_EQ(keys(j["stations"]), std::vector<std::string>{"index"});
  for (const char* part : {"lower", "upper", "shared"}) {
    const json& c = j["stations"]["index"][part];
    EXPECT_FALSE(c["covered"].get<bool>()) << part;
    EXPECT_LT(c["margin_mm"].get<double>(), 0.0) << part;
    EXPECT_GT(c["covered_fraction"].get<double>(), 0.0) << part;
    EXPECT_LT(c["covered_fraction"].get<double>(), 1.0) << part;
    EXPECT_THAT(c["reason"].get<std::string>(), Not(IsEmpty())) << part;
  }
  // Independent margin of the lower mechanism against its annuli (negative: outside by that much).
  EXPECT_NEAR(j["stations"]["index"]["lower"]["margin_mm"].get<double>(),
              annuli_margin(6, 24, 0, 12.5, 0, 6.25, 15.5, 20, 6), 1e-6);

  const Outcome table = run({"coverage", kDesign, "--station", "index", "--ellipse", "6.25,15.5,40,12,0"});
  EXPECT_EQ(table.code, 1);
  EXPECT_THAT(table.out, AllOf(HasSubstr("NOT COVERED"), HasSubstr("(--ellipse)"), HasSubstr("margin")));

  // A negative centre coordinate is a value, not an option; a small circle there is covered.
  const Outcome negative = run({"coverage", kDesign, "--station", "index", "--ellipse", "-1,15.5,4,4,0", "--json"});
  EXPECT_EQ(negative.code, 0) << negative.err;
  EXPECT_TRUE(json::parse(negative.out)["stations"]["index"]["shared"]["covered"].get<bool>());
}

TEST_F(CliWorkspace, CoverageFailsOnTheDesignsLciThreshold) {
  // min_lci 0.9 on the index lower mechanism: inside, but conditioning too poor over the ellipse.
  const fs::path design =
      design_with("strict.yaml", "assembly_mode: \"+\"", "assembly_mode: \"+\"\n        min_lci: 0.9");
  const Outcome r = run({"coverage", design.string(), "--json"});
  EXPECT_EQ(r.code, 1) << r.err;
  const json j = parse(r);
  const json& lower = j["stations"]["index"]["lower"];
  EXPECT_TRUE(lower["inside"].get<bool>());
  EXPECT_FALSE(lower["lci_ok"].get<bool>());
  EXPECT_FALSE(lower["covered"].get<bool>());
  EXPECT_LT(lower["min_lci"].get<double>(), 0.9);
  EXPECT_TRUE(j["stations"]["index"]["upper"]["covered"].get<bool>());
  EXPECT_FALSE(j["stations"]["index"]["shared"]["covered"].get<bool>());
  EXPECT_TRUE(j["stations"]["thumb"]["shared"]["covered"].get<bool>());
}

TEST_F(CliWorkspace, CoverageOfOneMechanismJudgesItAloneWithoutTheSharedRegion) {
  // min_lci 0.9 on the index lower mechanism fails it; --mechanism upper does not look at it.
  const fs::path design =
      design_with("strict.yaml", "assembly_mode: \"+\"", "assembly_mode: \"+\"\n        min_lci: 0.9");
  const Outcome both = run({"coverage", design.string(), "--station", "index", "--json"});
  const Outcome upper = run({"coverage", design.string(), "--station", "index", "--mechanism", "upper", "--json"});
  const Outcome lower = run({"coverage", design.string(), "--station", "index", "-m", "lower", "--json"});
  EXPECT_EQ(both.code, 1) << both.err;
  EXPECT_EQ(upper.code, 0) << upper.err;
  EXPECT_EQ(lower.code, 1) << lower.err;
  const json jb = parse(both), ju = parse(upper), jl = parse(lower);
  // Only the chosen mechanism, no shared region, and the same numbers as the full run.
  EXPECT_FALSE(ju["stations"]["index"].contains("lower"));
  EXPECT_FALSE(ju["stations"]["index"].contains("shared"));
  EXPECT_EQ(ju["stations"]["index"]["upper"], jb["stations"]["index"]["upper"]);
  EXPECT_FALSE(jl["stations"]["index"].contains("upper"));
  EXPECT_EQ(jl["stations"]["index"]["lower"], jb["stations"]["index"]["lower"]);
  // A mechanism name that does not exist: exit 2 naming the option, nothing printed.
  const Outcome missing = run({"coverage", kDesign, "--mechanism", "middle"});
  EXPECT_EQ(missing.code, 2);
  EXPECT_THAT(missing.err, HasSubstr("--mechanism"));
  EXPECT_THAT(missing.out, IsEmpty());
}

TEST_F(CliWorkspace, CoverageBadEllipseIsExitTwoNamingTheOption) {
  for (const char* bad : {"1,2,3", "6,15,0,12,0", "6,15,-3,12,0", "a,b,c,d,e", "6,15,10,12,0,1", "6,15,10,12,nan",
                          "6,15,10,,0", ""}) {
    const Outcome r = run({"coverage", kDesign, "--ellipse", bad});
    SCOPED_TRACE(bad);
    EXPECT_EQ(r.code, 2) << r.out;
    EXPECT_THAT(r.err, HasSubstr("--ellipse"));
    EXPECT_THAT(r.out, IsEmpty());
  }
  const Outcome unknown = run({"coverage", kDesign, "--station", "pinky"});
  EXPECT_EQ(unknown.code, 2);
  EXPECT_THAT(unknown.err, AllOf(HasSubstr("pinky"), HasSubstr("index")));
  // Coverage writes no file at all.
  EXPECT_EQ(tree(dir_), std::vector<std::string>{});
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
  EXPECT_NEAR(s["results"]["workspace"]["stations"][0]["mechanisms"]["lower"]["area_mm2"].get<double>(), area, 1e-9 * area);

  const std::string md = slurp(scene / "summary.md");
  EXPECT_THAT(md, AllOf(HasSubstr("## Reachable workspace"), HasSubstr("## Target coverage"),
                        HasSubstr("![Station index workspace](workspace/index-workspace.png)"),
                        HasSubstr("| lower | ✓ covered |"), HasSubstr("exact area (mm²)")));
}

TEST_F(CliWorkspace, RunCoverageFailsForAStationThatIsNotCoveredAndOnlyScansTheSceneStations) {
  // A scene with the index station only, whose target is too wide for the lower mechanism.
  std::string text = slurp(kDesign);
  const auto thumb = text.find("  thumb:");
  const auto geometry = text.find("\ngeometry:");
  ASSERT_NE(thumb, std::string::npos);
  ASSERT_NE(geometry, std::string::npos);
  text.erase(thumb, geometry + 1 - thumb);
  // ... and the patterns' per-station entries, which name the thumb.
  const auto per_station = text.find("\n  stations:\n    thumb:");
  ASSERT_NE(per_station, std::string::npos);
  text.erase(per_station, text.find("\n\n", per_station + 1) - per_station);
  const std::string from = "axes: [15, 12]";
  text.replace(text.find(from), from.size(), "axes: [40, 12]");
  const fs::path design = dir_ / "wide.yaml";
  std::ofstream(design) << text;

  const fs::path out = dir_ / "out";
  const Outcome r = run({"run", design.string(), "--out", out.string(), "--products", "coverage", "--json", "--quiet"});
  EXPECT_EQ(r.code, 1) << r.err;
  const json j = parse(r);
  ASSERT_EQ(j["built"].size(), 1u);
  EXPECT_FALSE(j["built"][0]["passed"].get<bool>());
  EXPECT_EQ(keys(j["results"]["coverage"]["stations"]), std::vector<std::string>{"index"});
  const std::string md = slurp(out / "iros2022" / "summary.md");
  EXPECT_THAT(md, AllOf(HasSubstr("✗ **not covered**"), Not(HasSubstr("Station `thumb`"))));
  EXPECT_FALSE(fs::exists(out / "iros2022" / "workspace"));  // not asked for, not built
}

}  // namespace
