// Tests of the joint limits from the hardware (fivebar/device/joint_limits.hpp): the blocked half-angle of
// a hard stop against hand-computed cases and against a bisection on the collision module's exact
// capsule clearance (a second formulation), the potentiometer window by hand, the usable ranges of
// the showcase, their intersection with declared limits, the margin check against an independent
// dense sampling of the target, and the design keys (round trip, file:line:key errors).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <string>

#include "fivebar/collision.hpp"
#include "fivebar/design.hpp"
#include "fivebar/error.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"

namespace fivebar {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::ThrowsMessage;

const fs::path kSource = FIVEBAR_SOURCE_DIR;
constexpr double kPi = std::numbers::pi;
double deg(double d) { return d * kPi / 180.0; }
double in_deg(double r) { return r * 180.0 / kPi; }

Design paper() { return load_design(kSource / "designs" / "iros2022.yaml"); }

/// The link (axis at the origin, length L, segment radius r, end disks re) at angle a overlaps the
/// disk (d, 0) of radius ro, by the collision module's capsule clearance.
bool overlaps(double a, double d, double L, double r, double re, double ro) {
  const Vec2 A(L * std::cos(a), L * std::sin(a));
  const Capsule obstacle{Vec2(d, 0.0), Vec2(d, 0.0), ro};
  const double c = std::min({capsule_clearance(Capsule{Vec2(0, 0), A, r}, obstacle),
                             capsule_clearance(Capsule{A, A, re}, obstacle),
                             capsule_clearance(Capsule{Vec2(0, 0), Vec2(0, 0), re}, obstacle)});
  return c < 0.0;
}

/// The blocked half-angle by bisection on overlaps() (it holds at 0 and fails at pi).
double bisected(double d, double L, double r, double re, double ro) {
  double in = 0.0, out = kPi;
  for (int i = 0; i < 80; ++i) {
    const double mid = 0.5 * (in + out);
    (overlaps(mid, d, L, r, re, ro) ? in : out) = mid;
  }
  return 0.5 * (in + out);
}

TEST(HardStop, EndDiskCaseByHandAndByClearance) {
  // The showcase's proximal link (9 mm, 4 mm wide, 5 mm bosses) against the other motor's boss
  // 12.5 mm away: |A - O2| = 2.5 + 2.5 at cos a = (12.5^2 + 9^2 - 5^2) / (2 12.5 9) = 212.25 / 225.
  const double a = hard_stop_half_angle(12.5, 9.0, 2.0, 2.5, 2.5);
  EXPECT_NEAR(in_deg(a), 19.3809, 1e-3);  // acos(0.943333...) by hand
  EXPECT_NEAR(a, bisected(12.5, 9.0, 2.0, 2.5, 2.5), 1e-9);
}

TEST(HardStop, SegmentCaseByHandAndByClearance) {
  // A 20 mm link passes over the obstacle: the segment's side touches first, at
  // sin a = (2 + 2.5) / 12.5 (the perpendicular's foot at 11.66 mm <= 20 mm lies on the link).
  const double a = hard_stop_half_angle(12.5, 20.0, 2.0, 2.5, 2.5);
  EXPECT_NEAR(a, std::asin(4.5 / 12.5), 1e-15);
  EXPECT_NEAR(in_deg(a), 21.1002, 1e-3);
  EXPECT_NEAR(a, bisected(12.5, 20.0, 2.0, 2.5, 2.5), 1e-9);
  // A narrow link with a wide boss: the end disk decides even for a long link.
  EXPECT_NEAR(hard_stop_half_angle(12.5, 11.0, 0.5, 3.0, 2.5), bisected(12.5, 11.0, 0.5, 3.0, 2.5), 1e-9);
}

TEST(HardStop, NeverAndAlways) {
  EXPECT_EQ(hard_stop_half_angle(30.0, 9.0, 2.0, 2.5, 2.5), 0.0);  // out of reach
  EXPECT_EQ(hard_stop_half_angle(4.0, 9.0, 2.0, 2.5, 2.5), kPi);  // overlaps the link's own boss
}

TEST(HardStop, TheShowcaseStopsAreTheOtherMotorsOfTheSamePlane) {
  const Design d = paper();
  const Station& s = *d.station("index");
  const auto stops = hard_stops(s, *s.lower, 1, *d.get<Geometry>());
  // Lower O2 (12.5 mm, 0 deg), upper O1 (31 mm: out of reach), upper O2.
  ASSERT_EQ(stops.size(), 3u);
  EXPECT_EQ(stops[0].obstacle, "lower O2");
  EXPECT_EQ(stops[0].direction, 0.0);
  EXPECT_NEAR(stops[0].half_angle, std::acos(212.25 / 225.0), 1e-12);
  EXPECT_EQ(stops[1].obstacle, "upper O1");
  EXPECT_EQ(stops[1].half_angle, 0.0);
}

TEST(PotentiometerWindow, ByHand) {
  Potentiometer p;
  EXPECT_FALSE(potentiometer_window(p).has_value());  // no travel: endless
  // The showcase's lower theta1: 60 deg/V, 0.25 V at theta = 0, 300 deg over 0 ... 5 V.
  p.rad_per_volt = deg(60), p.volts_at_zero = 0.25, p.travel = deg(300);
  auto w = potentiometer_window(p);
  ASSERT_TRUE(w.has_value());
  EXPECT_NEAR(in_deg(w->lo), -15.0, 1e-12);
  EXPECT_NEAR(in_deg(w->hi), 285.0, 1e-12);
  // Wired reversed: 0 V at +150 deg, 5 V at -150 deg.
  p.rad_per_volt = -deg(60), p.volts_at_zero = 2.5;
  w = potentiometer_window(p);
  EXPECT_NEAR(in_deg(w->lo), -150.0, 1e-12);
  EXPECT_NEAR(in_deg(w->hi), 150.0, 1e-12);
}

TEST(UsableRanges, TheShowcaseByHand) {
  const Design d = paper();
  const Station& s = *d.station("index");
  const double stop = in_deg(std::acos(212.25 / 225.0));  // 19.38 deg
  const auto lower = usable_ranges(d, s, *s.lower);
  // theta1: the boss of O2 at 0 deg below, the potentiometer's end (0.25 V offset) above.
  EXPECT_TRUE(lower[0].usable && lower[0].limited);
  EXPECT_EQ(lower[0].joint, "index_lower_theta1");
  EXPECT_NEAR(in_deg(lower[0].lo), stop, 1e-9);
  EXPECT_NEAR(in_deg(lower[0].hi), 285.0, 1e-9);
  EXPECT_EQ(lower[0].lo_by, "hard stop at lower O2");
  EXPECT_EQ(lower[0].hi_by, "potentiometer travel");
  // theta2: the potentiometer (1.75 V offset: -105 deg) below, the boss of O1 at 180 deg above.
  EXPECT_NEAR(in_deg(lower[1].lo), -105.0, 1e-9);
  EXPECT_NEAR(in_deg(lower[1].hi), 180.0 - stop, 1e-9);
  // The upper mechanism mirrored.
  const auto upper = usable_ranges(d, s, *s.upper);
  EXPECT_NEAR(in_deg(upper[0].lo), -285.0, 1e-9);
  EXPECT_NEAR(in_deg(upper[0].hi), -stop, 1e-9);
  EXPECT_NEAR(in_deg(upper[1].lo), -180.0 + stop, 1e-9);
  EXPECT_NEAR(in_deg(upper[1].hi), 105.0, 1e-9);
  // The reference (the target centre's angle) lies inside.
  for (const auto& r : {lower[0], lower[1], upper[0], upper[1]}) {
    EXPECT_LT(r.lo, r.reference);
    EXPECT_GT(r.hi, r.reference);
  }
}

TEST(UsableRanges, DeclaredLimitsIntersectAndAnExcludedCentreIsAStatus) {
  Design d = paper();
  Station& s = d.stations[0];
  s.lower->joint_limits = std::array<JointRange, 2>{JointRange{deg(0), deg(250)}, JointRange{deg(-30), deg(120)}};
  auto r = usable_ranges(d, s, *s.lower);
  EXPECT_NEAR(in_deg(r[0].lo), in_deg(std::acos(212.25 / 225.0)), 1e-9);  // the stop is tighter than 0
  EXPECT_NEAR(in_deg(r[0].hi), 250.0, 1e-9);
  EXPECT_EQ(r[0].hi_by, "joint_limits");
  EXPECT_NEAR(in_deg(r[1].lo), -30.0, 1e-9);
  EXPECT_NEAR(in_deg(r[1].hi), 120.0, 1e-9);
  // with_usable_limits() hands these ranges to the rest of the tool.
  const Station limited = with_usable_limits(d, s);
  EXPECT_NEAR(in_deg((*limited.lower->joint_limits)[0].lo), in_deg(r[0].lo), 1e-9);
  EXPECT_NEAR((*limited.lower->joint_limits)[0].span(), r[0].span(), 1e-12);
  // A potentiometer whose travel misses the centre's angle (about 131 deg): no usable range.
  d.get<ControllerSettings>()->potentiometer.travel = deg(100);
  d.get<ControllerSettings>()->overrides.clear();  // 2.5 V at 0 deg: reads [-150, -50] deg
  r = usable_ranges(d, s, *s.lower);
  EXPECT_FALSE(r[0].usable);
  EXPECT_THAT(r[0].problem, HasSubstr("outside the potentiometer travel"));
  EXPECT_THAT(describe(r[0]), HasSubstr("outside the potentiometer travel"));
}

TEST(UsableRanges, WithoutTravelGeometryOrLimitsEveryAngle) {
  Design d = paper();
  d.reset<Geometry>();
  d.get<ControllerSettings>()->potentiometer.travel.reset();
  const Station& s = *d.station("index");
  const auto r = usable_ranges(d, s, *s.lower);
  EXPECT_FALSE(r[0].limited);
  EXPECT_EQ(describe(r[0]), "every angle");
  EXPECT_FALSE(with_usable_limits(d, s).lower->joint_limits.has_value());
}

TEST(RangeMargin, InsideAndOutside) {
  UsableRange r;
  r.limited = true, r.lo = deg(20), r.hi = deg(280);
  EXPECT_NEAR(in_deg(range_margin(r, deg(30))), 10.0, 1e-12);
  EXPECT_NEAR(in_deg(range_margin(r, deg(270))), 10.0, 1e-12);
  EXPECT_NEAR(in_deg(range_margin(r, deg(-85))), 5.0, 1e-12);   // 275 deg: 5 inside
  EXPECT_NEAR(in_deg(range_margin(r, deg(-75))), -5.0, 1e-12);  // 285 deg: 5 beyond hi
  EXPECT_NEAR(in_deg(range_margin(r, deg(10))), -10.0, 1e-12);  // 10 below lo
  EXPECT_NEAR(in_deg(range_margin(r, deg(300))), -20.0, 1e-12); // nearer hi than lo (+360)
}

TEST(JointMargins, AgreeWithAnIndependentDenseSampling) {
  Design d = paper();
  const Station& s = *d.station("index");
  const auto checks = check_joint_margins(d, s);
  // index/lower, index/upper, then the four patterns.
  ASSERT_EQ(checks.size(), 6u);
  EXPECT_EQ(checks[0].subject, "index/lower");
  EXPECT_EQ(checks[2].subject, "index stretch");
  for (const auto& c : checks) EXPECT_TRUE(c.passed) << c.subject << ": " << c.detail;
  // The worst margin of the lower mechanism: its angles over a dense sampling of the boundary
  // (the extremes lie there, away from singularities) against the ranges by hand.
  const double stop = std::acos(212.25 / 225.0);
  double worst = 1e9;
  for (int k = 0; k < 20000; ++k) {
    const Pose p = ik(*s.lower, s.target.boundary_point(2.0 * kPi * k / 20000));
    ASSERT_NE(p.status, Status::unreachable);
    double t1 = std::remainder(p.theta1 - deg(130), 2 * kPi) + deg(130);
    double t2 = std::remainder(p.theta2, 2 * kPi);
    worst = std::min({worst, t1 - stop, deg(285) - t1, t2 + deg(105), (kPi - stop) - t2});
  }
  EXPECT_NEAR(checks[0].worst_margin, worst, deg(0.1));
  // Proximal links vs the other leg's: the two base bosses, 12.5 - 2.5 - 2.5 mm apart, are the closest.
  EXPECT_NEAR(checks[0].min_link_clearance_mm, 7.5, 1e-12);
  // A margin beyond the worst fails the target check, and says where.
  d.get<ControllerSettings>()->joint_margin = worst + deg(1);
  const auto tight = check_joint_margins(d, s);
  EXPECT_FALSE(tight[0].passed);
  EXPECT_THAT(tight[0].detail, HasSubstr("below the margin"));
}

TEST(JointMargins, ExportGateReportsThemAndWritesTheRangesAsPositionLimits) {
  const Design d = paper();
  const ExportGate gate = export_gate(d, {});
  int hardware = 0, margins = 0;
  for (const GateCheck& c : gate.checks) {
    hardware += c.kind == "hardware_limits";
    margins += c.kind == "joint_margin";
    EXPECT_TRUE(c.passed) << c.subject << " " << c.kind << ": " << c.detail;
  }
  EXPECT_EQ(hardware, 4);      // two stations x two mechanisms
  EXPECT_EQ(margins, 4 + 8);   // and four patterns per station
  const Json tree = controller_parameters(d, {});
  const Json& lim = tree.begin().value().at("ros__parameters").at("joint_limits");
  const Json& l1 = lim.at("index_lower_theta1");
  EXPECT_EQ(l1.at("has_position_limits"), true);
  EXPECT_NEAR(l1.at("min_position").get<double>(), std::acos(212.25 / 225.0), 1e-12);
  EXPECT_NEAR(l1.at("max_position").get<double>(), deg(285), 1e-12);
  const Json& u2 = lim.at("thumb_upper_theta2");
  EXPECT_NEAR(u2.at("min_position").get<double>(), -kPi + std::acos(212.25 / 225.0), 1e-12);
  EXPECT_NEAR(u2.at("max_position").get<double>(), deg(105), 1e-12);
}

// --- Design keys ---------------------------------------------------------------------------------

const std::string kStations = R"(stations:
  index:
    target: {center: [6.25, 15.5], axes: [15, 12]}
    mechanisms:
      lower: {bases: [[0, 0], [12.5, 0]], links: [9, 9, 15, 15], working_mode: "-+"}
)";

TEST(Keys, TravelIsScopedAndRoundTrips) {
  const Design d = load_design_from_string("name: k\n" + kStations + R"(controller:
  joint_margin_deg: 7.5
  potentiometer: {travel_deg: 300}
  mechanisms:
    lower: {theta2: {potentiometer: {travel_deg: 340}}}
)",
                                           "<test>");
  const ControllerSettings& c = *d.get<ControllerSettings>();
  EXPECT_DOUBLE_EQ(c.joint_margin, deg(7.5));
  EXPECT_DOUBLE_EQ(*c.joint("index", "lower", 1).potentiometer.travel, deg(300));
  EXPECT_DOUBLE_EQ(*c.joint("index", "lower", 2).potentiometer.travel, deg(340));
  const Design back = load_design_from_string(to_yaml(d), "<to_yaml>");
  EXPECT_EQ(to_yaml(back), to_yaml(d));
  EXPECT_EQ(*back.get<ControllerSettings>()->joint("index", "lower", 2).potentiometer.travel,
            *c.joint("index", "lower", 2).potentiometer.travel);
  EXPECT_EQ(back.get<ControllerSettings>()->joint_margin, c.joint_margin);
}

TEST(Keys, BadValuesNameFileLineAndKey) {
  const auto fails = [](const std::string& controller, const std::string& message) {
    EXPECT_THAT([&] { load_design_from_string("name: k\n" + kStations + "controller:\n" + controller, "<test>"); },
                ThrowsMessage<InputError>(HasSubstr(message)))
        << controller;
  };
  fails("  potentiometer: {travel_deg: 400}\n", "<test>:8: controller.potentiometer.travel_deg = 400 deg: must be in (0, 360]");
  fails("  potentiometer: {travel_deg: 0}\n", "<test>:8: controller.potentiometer.travel_deg = 0 deg: must be in (0, 360]");
  fails("  mechanisms:\n    lower: {theta1: {potentiometer: {travel_deg: -5}}}\n",
        "<test>:9: controller.mechanisms.lower.theta1.potentiometer.travel_deg = -5 deg");
  fails("  potentiometer: {travel_deg: .nan}\n", "<test>:8: controller.potentiometer.travel_deg = .nan: must be a finite number");
  fails("  joint_margin_deg: -1\n", "<test>:8: controller.joint_margin_deg = -1 deg: must be >= 0");
  fails("  joint_margin_deg: 200\n", "<test>:8: controller.joint_margin_deg = 200 deg");
  // 360 deg (an endless potentiometer) is accepted.
  EXPECT_NO_THROW(load_design_from_string("name: k\n" + kStations + "controller:\n  potentiometer: {travel_deg: 360}\n", "<t>"));
}

}  // namespace
}  // namespace fivebar
