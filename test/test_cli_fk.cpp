// End-to-end tests of `fivebar fk`: expected values are derived here from the geometry of the
// paper's device (Table 1, test/cli_geometry.hpp), independently of the library.
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

}  // namespace
