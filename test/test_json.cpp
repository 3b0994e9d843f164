// JSON at the edges (fivebar/json.hpp): degrees normalised to (-180, 180], the contract keys of a
// pose, nulls where there is nothing to describe.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "fivebar/json.hpp"
#include "fivebar/kinematics.hpp"
#include "paper.hpp"

namespace fivebar {
namespace {

constexpr double kPi = std::numbers::pi;

using ::fivebar::testing::paper_mechanism;

TEST(AngleDeg, NormalisesToTheHalfOpenInterval) {
  EXPECT_EQ(angle_deg(0.0), 0.0);
  EXPECT_FALSE(std::signbit(angle_deg(-0.0)));
  EXPECT_FALSE(std::signbit(angle_deg(-2 * kPi)));
  EXPECT_DOUBLE_EQ(angle_deg(kPi), 180.0);
  EXPECT_DOUBLE_EQ(angle_deg(-kPi), 180.0);
  EXPECT_DOUBLE_EQ(angle_deg(7 * kPi), 180.0);
  EXPECT_DOUBLE_EQ(angle_deg(1.5 * kPi), -90.0);
  EXPECT_DOUBLE_EQ(angle_deg(kPi / 2), 90.0);
  EXPECT_NEAR(angle_deg(2 * kPi + 0.1), 0.1 * 180.0 / kPi, 1e-12);
}

TEST(AngleDeg, RandomAnglesLandInRangeAndKeepTheirDirection) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  for (int i = 0; i < 10000; ++i) {
    const double rad = u(rng);
    const double deg = angle_deg(rad);
    SCOPED_TRACE(rad);
    EXPECT_GT(deg, -180.0);
    EXPECT_LE(deg, 180.0);
    EXPECT_NEAR(std::cos(deg * kPi / 180.0), std::cos(rad), 1e-12);
    EXPECT_NEAR(std::sin(deg * kPi / 180.0), std::sin(rad), 1e-12);
  }
}

TEST(ModeString, PrintsRealisedSignsWithZero) {
  EXPECT_EQ(mode_string({-1, +1}), "-+");
  EXPECT_EQ(mode_string({+1, -1}), "+-");
  EXPECT_EQ(mode_string({0, +1}), "0+");
  EXPECT_EQ(mode_string({0, 0}), "00");
  EXPECT_EQ(sign_char(-3), '-');
}

TEST(PoseJson, HasTheContractKeysInMillimetresAndDegrees) {
  const Mechanism m = paper_mechanism("index", "lower");
  const Pose p = ik(m, Vec2(6.25, 15.5));
  ASSERT_EQ(p.status, Status::ok);
  const Json j = to_json(p);
  for (const char* key : {"status", "point_mm", "theta_deg", "elbows_mm", "mode", "assembly", "jacobian", "lci",
                          "force_capability", "transmission_deg", "singularity", "closure_error_mm",
                          "within_joint_limits"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j.begin().key(), "status") << "status comes first";
  EXPECT_EQ(j["status"], "ok");
  EXPECT_EQ(j["mode"], "-+");
  EXPECT_EQ(j["assembly"], "+");
  EXPECT_DOUBLE_EQ(j["theta_deg"][0].get<double>(), angle_deg(p.theta1));
  EXPECT_DOUBLE_EQ(j["theta_deg"][1].get<double>(), angle_deg(p.theta2));
  EXPECT_DOUBLE_EQ(j["point_mm"][0].get<double>(), p.P.x());
  EXPECT_DOUBLE_EQ(j["elbows_mm"][1][1].get<double>(), p.A2.y());
  EXPECT_DOUBLE_EQ(j["jacobian"][1][0].get<double>(), p.J(1, 0));
  EXPECT_DOUBLE_EQ(j["transmission_deg"][2].get<double>(), p.transmission[2] * 180.0 / kPi);
  EXPECT_DOUBLE_EQ(j["singularity"]["type1_sin"][0].get<double>(), p.type1_sin[0]);
  EXPECT_DOUBLE_EQ(j["singularity"]["type2_sin"].get<double>(), p.type2_sin);
  EXPECT_DOUBLE_EQ(j["singularity"]["type1_distance_mm"].get<double>(), p.type1_distance_mm);
  EXPECT_EQ(j["within_joint_limits"], true);
}

TEST(PoseJson, JacobianIsNullWhenInvalid) {
  Pose p = ik(paper_mechanism("index", "lower"), Vec2(6.25, 15.5));
  p.jacobian_valid = false;
  EXPECT_TRUE(to_json(p)["jacobian"].is_null());
  p.mode = {0, +1};
  p.assembly = 0;
  EXPECT_EQ(to_json(p)["mode"], "0+");
  EXPECT_EQ(to_json(p)["assembly"], "0");
}

TEST(PoseJson, UnreachablePoseHasNullGeometry) {
  const Pose p = ik(paper_mechanism("index", "lower"), Vec2(100.0, 100.0));
  ASSERT_EQ(p.status, Status::unreachable);
  const Json j = to_json(p);
  EXPECT_EQ(j["status"], "unreachable");
  for (const char* key : {"point_mm", "theta_deg", "elbows_mm", "mode", "assembly", "jacobian", "transmission_deg",
                          "singularity", "closure_error_mm", "within_joint_limits"}) {
    EXPECT_TRUE(j[key].is_null()) << key;
  }
  EXPECT_EQ(j["lci"], 0.0);
}

TEST(MechanismJson, LinksModesAndJointLimitsInDegrees) {
  Mechanism m = paper_mechanism("index", "lower");
  Json j = to_json(m);
  EXPECT_EQ(j["links_mm"], Json::array({9.0, 9.0, 15.0, 15.0}));
  EXPECT_EQ(j["bases_mm"][1], Json::array({12.5, 0.0}));
  EXPECT_EQ(j["working_mode"], "-+");
  EXPECT_EQ(j["assembly_mode"], "+");
  EXPECT_TRUE(j["joint_limits_deg"].is_null());
  // A counter-clockwise arc from 200 deg to 30 deg: lo wraps to -160, hi = lo + 190.
  m.joint_limits = std::array<JointRange, 2>{JointRange{200.0 * kPi / 180.0, 30.0 * kPi / 180.0},
                                             JointRange{-kPi / 2, kPi / 2}};
  j = to_json(m);
  EXPECT_NEAR(j["joint_limits_deg"][0][0].get<double>(), -160.0, 1e-9);
  EXPECT_NEAR(j["joint_limits_deg"][0][1].get<double>(), 30.0, 1e-9);
  EXPECT_NEAR(j["joint_limits_deg"][1][0].get<double>(), -90.0, 1e-9);
  EXPECT_NEAR(j["joint_limits_deg"][1][1].get<double>(), 90.0, 1e-9);
}

TEST(EllipseJson, CentreAxesAngle) {
  Ellipse e;
  e.center = {6.25, 15.5};
  e.axes = {15.0, 12.0};
  e.angle = kPi / 6;
  const Json j = to_json(e);
  EXPECT_EQ(j["center_mm"], Json::array({6.25, 15.5}));
  EXPECT_EQ(j["axes_mm"], Json::array({15.0, 12.0}));
  EXPECT_NEAR(j["angle_deg"].get<double>(), 30.0, 1e-12);
}

}  // namespace
}  // namespace fivebar
