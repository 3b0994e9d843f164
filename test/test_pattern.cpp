// Tests of fivebar/pattern.hpp: the four paths against their formulas (typed here independently),
// the per-sample checks on the paper's stations (the showcase patterns pass; others fail with the
// expected reason), and the trajectory CSV (FK of the written angles reproduces the written
// points; speeds recomputed from the written angles).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/design.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/pattern.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/motor.hpp"

namespace fivebar {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

constexpr double kPi = std::numbers::pi;
const fs::path kDesign = fs::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml";

PatternSpec spec(PatternKind kind, double amplitude_mm, double separation_mm, double duration_s = 1.0,
                 double rate_hz = 100.0) {
  PatternSpec s;
  s.kind = kind;
  s.amplitude_mm = amplitude_mm;
  s.separation_mm = separation_mm;
  s.duration_s = duration_s;
  s.rate_hz = rate_hz;
  return s;
}

/// The ramp of the paths, typed independently: 0 at rest, 1/2 at mid-time, 1 at the end.
double u(double t, double T) { return 0.5 - 0.5 * std::cos(kPi * t / T); }

// ---------------------------------------------------------------------------------------------
// Paths.

TEST(PatternPath, SamplesTimesAndCentre) {
  const PatternSpec s = spec(PatternKind::stretch, 3.0, 8.0, 1.0, 100.0);
  EXPECT_EQ(s.samples(), 101u);
  const PatternPath p = pattern_path(s, {6.25, 15.5});
  ASSERT_EQ(p.time_s.size(), 101u);
  EXPECT_EQ(p.time_s.front(), 0.0);
  EXPECT_DOUBLE_EQ(p.time_s.back(), 1.0);
  EXPECT_DOUBLE_EQ(p.time_s[37], 0.37);
  EXPECT_EQ(p.centre, Vec2(6.25, 15.5));
  PatternSpec moved = s;
  moved.centre = Vec2(5.0, 14.0);
  EXPECT_EQ(pattern_path(moved, {6.25, 15.5}).centre, Vec2(5.0, 14.0));
  // 0.5 s at 250 Hz: 125 intervals, 126 samples; 0.29 s at 100 Hz is 28.999999999999996 intervals
  // in doubles, and still 29 intervals.
  EXPECT_EQ(spec(PatternKind::slip, 1.0, 6.0, 0.5, 250.0).samples(), 126u);
  ASSERT_LT(0.29 * 100.0, 29.0);
  EXPECT_EQ(spec(PatternKind::slip, 1.0, 6.0, 0.29, 100.0).samples(), 30u);
  EXPECT_DOUBLE_EQ(pattern_path(spec(PatternKind::slip, 1.0, 6.0, 0.29, 100.0), {0, 0}).time_s.back(), 0.29);
}

TEST(PatternPath, StretchMovesApartHorizontally) {
  const Vec2 c(6.25, 15.5);
  const PatternPath p = pattern_path(spec(PatternKind::stretch, 3.0, 8.0), c);
  EXPECT_EQ(p.upper.front(), Vec2(6.25, 19.5));
  EXPECT_EQ(p.lower.front(), Vec2(6.25, 11.5));
  EXPECT_NEAR((p.upper.back() - Vec2(9.25, 19.5)).norm(), 0.0, 1e-14);
  EXPECT_NEAR((p.lower.back() - Vec2(3.25, 11.5)).norm(), 0.0, 1e-14);
  for (std::size_t k = 0; k < p.time_s.size(); ++k) {
    EXPECT_DOUBLE_EQ(p.upper[k].y(), 19.5);  // horizontal only
    EXPECT_DOUBLE_EQ(p.lower[k].y(), 11.5);
    EXPECT_NEAR(p.upper[k].x() - 6.25, 3.0 * u(p.time_s[k], 1.0), 1e-14);
    EXPECT_NEAR(p.upper[k].x() - 6.25, 6.25 - p.lower[k].x(), 1e-14);  // mirror images
  }
  EXPECT_NEAR(p.upper[50].x(), 6.25 + 1.5, 1e-14);
}

TEST(PatternPath, SlipMovesBothDownTogether) {
  const Vec2 c(6.25, 15.5);
  const PatternPath p = pattern_path(spec(PatternKind::slip, 4.0, 6.0), c);
  // Upper from c + (0, 3 + 2) to c + (0, 3 - 2); the lower 6 mm below it throughout.
  EXPECT_NEAR((p.upper.front() - Vec2(6.25, 20.5)).norm(), 0.0, 1e-14);
  EXPECT_NEAR((p.upper.back() - Vec2(6.25, 16.5)).norm(), 0.0, 1e-14);
  EXPECT_NEAR((p.lower.back() - Vec2(6.25, 10.5)).norm(), 0.0, 1e-14);
  for (std::size_t k = 0; k < p.time_s.size(); ++k) {
    EXPECT_NEAR((p.upper[k] - p.lower[k] - Vec2(0.0, 6.0)).norm(), 0.0, 1e-13);
    EXPECT_DOUBLE_EQ(p.upper[k].x(), 6.25);
  }
}

TEST(PatternPath, TwistTurnsAlongTheCircleByTheArcLength) {
  const Vec2 c(6.25, 15.5);
  const PatternPath p = pattern_path(spec(PatternKind::twist, 3.0, 8.0), c);
  for (std::size_t k = 0; k < p.time_s.size(); ++k) {
    EXPECT_NEAR((p.upper[k] - c).norm(), 4.0, 1e-13);  // on the circle of diameter 8
    EXPECT_NEAR((p.upper[k] + p.lower[k] - 2.0 * c).norm(), 0.0, 1e-13);  // diametrically opposite
  }
  EXPECT_NEAR((p.upper.front() - Vec2(6.25, 19.5)).norm(), 0.0, 1e-14);
  // 3 mm of arc at radius 4: 0.75 rad counter-clockwise from the top.
  const Vec2 end = c + 4.0 * Vec2(std::cos(kPi / 2 + 0.75), std::sin(kPi / 2 + 0.75));
  EXPECT_NEAR((p.upper.back() - end).norm(), 0.0, 1e-13);
}

TEST(PatternPath, PivotTracksTheRotatingContactPoints) {
  const Vec2 c(6.25, 15.5);
  PatternSpec s = spec(PatternKind::pivot, 0.0, 8.0, 2.0);
  s.pivot_amplitude = 20.0 * kPi / 180.0;
  s.pivot_frequency_hz = 0.5;
  const PatternPath p = pattern_path(s, c);
  ASSERT_EQ(p.time_s.size(), 201u);
  // Quarter period (t = 0.5 s): the object at +20 degrees.
  const double a = 20.0 * kPi / 180.0;
  EXPECT_NEAR((p.upper[50] - (c + 4.0 * Vec2(-std::sin(a), std::cos(a)))).norm(), 0.0, 1e-13);
  EXPECT_NEAR((p.lower[50] - (c + 4.0 * Vec2(std::sin(a), -std::cos(a)))).norm(), 0.0, 1e-13);
  // Half and full period: back at the start.
  EXPECT_NEAR((p.upper[100] - p.upper[0]).norm(), 0.0, 1e-13);
  EXPECT_NEAR((p.upper[200] - p.upper[0]).norm(), 0.0, 1e-13);

  // Contact points given explicitly keep their distance to the centre and their angle apart.
  s.contact_points = std::array<Vec2, 2>{Vec2(1.0, 3.0), Vec2(-2.0, -4.0)};
  const PatternPath q = pattern_path(s, c);
  for (std::size_t k = 0; k < q.time_s.size(); ++k) {
    EXPECT_NEAR((q.upper[k] - c).norm(), std::sqrt(10.0), 1e-13);
    EXPECT_NEAR((q.lower[k] - c).norm(), std::sqrt(20.0), 1e-13);
    EXPECT_NEAR((q.upper[k] - q.lower[k]).norm(), std::sqrt(9.0 + 49.0), 1e-13);
  }
  EXPECT_EQ(q.upper.front(), c + Vec2(1.0, 3.0));
}

TEST(PatternPath, StartsAndEndsAtRest) {
  // At rest at both ends: the first and last steps shrink like dt^2 (ten times the rate, a hundredth
  // of the step), where a step in mid-pattern shrinks like dt (a tenth).
  for (PatternKind kind : {PatternKind::stretch, PatternKind::slip, PatternKind::twist}) {
    SCOPED_TRACE(std::string(to_string(kind)));
    const PatternPath slow = pattern_path(spec(kind, 3.0, 8.0, 1.0, 100.0), {6.25, 15.5});
    const PatternPath fast = pattern_path(spec(kind, 3.0, 8.0, 1.0, 1000.0), {6.25, 15.5});
    const auto step = [](const PatternPath& p, std::size_t k) { return (p.upper[k + 1] - p.upper[k]).norm(); };
    EXPECT_NEAR(step(fast, 0) / step(slow, 0), 0.01, 0.0005);
    EXPECT_NEAR(step(fast, 999) / step(slow, 99), 0.01, 0.0005);
    EXPECT_NEAR(step(fast, 500) / step(slow, 50), 0.1, 0.005);
  }
}

// ---------------------------------------------------------------------------------------------
// Checks on the paper's stations.

class PaperPatterns : public ::testing::Test {
 protected:
  void SetUp() override { design_ = load_design(kDesign); }
  const Station& station(const char* name) const { return *design_.station(name); }
  const Geometry& geometry() const { return *design_.get<Geometry>(); }
  double max_speed() const { return design_.get<PatternSettings>()->max_joint_speed; }
  Design design_;
};

TEST_F(PaperPatterns, TheShowcasePatternsAllRender) {
  ASSERT_TRUE(design_.has<PatternSettings>());
  for (const Station& s : design_.stations) {
    const auto specs = design_.get<PatternSettings>()->for_station(s.name);
    ASSERT_EQ(specs.size(), 4u) << s.name;
    for (const PatternSpec& sp : specs) {
      SCOPED_TRACE(s.name + " " + std::string(to_string(sp.kind)));
      const PatternResult r = check_pattern(s, geometry(), sp, max_speed());
      EXPECT_TRUE(r.passed) << (r.first_failure ? r.first_failure->reason : "");
      EXPECT_EQ(r.samples.size(), sp.samples());
      EXPECT_EQ(r.status_counts[0], 2 * sp.samples());  // every sample of both tactors ok
      EXPECT_EQ(r.moved_samples, 0u);
      EXPECT_GE(r.min_clearance_mm, geometry().min_clearance);
      for (const PatternSample& sample : r.samples) {
        EXPECT_EQ(sample.lower.point, sample.lower.target);
        EXPECT_EQ(sample.upper.status, SampleStatus::ok);
      }
    }
  }
}

TEST_F(PaperPatterns, StretchKeepsThePinBossClearanceOfItsStart) {
  // Vertical start 8 mm apart: clearance 8 - 5 = 3 mm between the P bosses, growing as they part.
  const PatternResult r = check_pattern(station("index"), geometry(), spec(PatternKind::stretch, 3.0, 8.0), max_speed());
  EXPECT_NEAR(r.min_clearance_mm, 3.0, 1e-12);
  ASSERT_TRUE(r.samples.front().clearance_mm.has_value());
  EXPECT_NEAR(*r.samples.front().clearance_mm, 3.0, 1e-12);
  EXPECT_GT(*r.samples.back().clearance_mm, 3.0);
}

TEST_F(PaperPatterns, LongTwistOnTheIndexCollidesAndThePriorityRuleMovesTheLower) {
  // 6 mm of arc on the 8 mm circle turns the pair by 86 degrees: the lower tactor swings up beside
  // the upper one and its distal link L3 passes under the upper's tactor joint.
  const PatternResult r = check_pattern(station("index"), geometry(), spec(PatternKind::twist, 6.0, 8.0), max_speed());
  EXPECT_FALSE(r.passed);
  ASSERT_TRUE(r.first_failure.has_value());
  EXPECT_EQ(r.first_failure->mechanism, "lower");
  EXPECT_EQ(r.first_failure->status, SampleStatus::collision_moved);
  EXPECT_THAT(r.first_failure->reason, HasSubstr("priority rule moved it"));
  EXPECT_GT(r.moved_samples, 0u);
  EXPECT_LT(r.min_clearance_mm, geometry().min_clearance);
  std::size_t moved = 0;
  for (std::size_t k = 0; k < r.samples.size(); ++k) {
    const PatternSample& s = r.samples[k];
    SCOPED_TRACE(k);
    if (s.moved_mm > 0.0) {
      ++moved;
      EXPECT_EQ(s.lower.status, SampleStatus::collision_moved);
      EXPECT_LT(*s.clearance_mm, geometry().min_clearance);
      ASSERT_TRUE(s.commanded_clearance_mm.has_value());
      EXPECT_GE(*s.commanded_clearance_mm, geometry().min_clearance);  // the commanded pair is free
      EXPECT_NEAR((s.lower.point - s.lower.target).norm(), s.moved_mm, 1e-12);
      EXPECT_EQ(s.upper.point, s.upper.target);  // the upper has priority
    } else {
      EXPECT_EQ(s.lower.point, s.lower.target);
    }
  }
  EXPECT_EQ(moved, r.moved_samples);
  EXPECT_EQ(r.first_failure->index, [&] {
    for (std::size_t k = 0; k < r.samples.size(); ++k) {
      if (r.samples[k].moved_mm > 0.0) return k;
    }
    return r.samples.size();
  }());
}

TEST_F(PaperPatterns, StretchBeyondTheWorkspaceIsUnreachable) {
  // 20 mm: the upper tactor would reach (26.25, 19.5), 28.7 mm from its base joint O3 (0, 31),
  // beyond L1 + L3 = 24 mm.
  // Near the edge of the workspace a leg approaches full stretch and its motor speeds up without
  // bound: with the design's 360 deg/s that is the first failure, just before the edge.
  const PatternResult fast = check_pattern(station("index"), geometry(), spec(PatternKind::stretch, 20.0, 8.0), max_speed());
  ASSERT_FALSE(fast.passed);
  EXPECT_EQ(fast.first_failure->status, SampleStatus::too_fast);
  // With unlimited motors the edge itself fails.
  const PatternResult r = check_pattern(station("index"), geometry(), spec(PatternKind::stretch, 20.0, 8.0), 1e9);
  ASSERT_FALSE(r.passed);
  EXPECT_LT(fast.first_failure->index, r.first_failure->index);
  EXPECT_EQ(r.first_failure->status, SampleStatus::unreachable);
  const Vec2 p = r.samples[r.first_failure->index].upper.target;
  const Vec2 q = r.samples[r.first_failure->index].lower.target;
  EXPECT_TRUE((p - Vec2(0, 31)).norm() > 24.0 || (q - Vec2(12.5, 0)).norm() > 24.0);
  // The sample before it was still within both reaches.
  const std::size_t k = r.first_failure->index - 1;
  EXPECT_LE((r.samples[k].upper.target - Vec2(0, 31)).norm(), 24.0);
  EXPECT_THAT(r.first_failure->reason, HasSubstr("unreachable"));
}

TEST_F(PaperPatterns, FastPivotExceedsTheMotorSpeed) {
  PatternSpec s = spec(PatternKind::pivot, 0.0, 8.0, 0.5);
  s.pivot_amplitude = 30.0 * kPi / 180.0;
  s.pivot_frequency_hz = 8.0;
  const PatternResult r = check_pattern(station("index"), geometry(), s, max_speed());
  ASSERT_FALSE(r.passed);
  EXPECT_EQ(r.first_failure->status, SampleStatus::too_fast);
  EXPECT_GT(r.peak_joint_speed, max_speed());
  EXPECT_THAT(r.first_failure->reason, HasSubstr("deg/s"));
  // The same pattern against a limit above its peak passes.
  EXPECT_TRUE(check_pattern(station("index"), geometry(), s, 1.01 * r.peak_joint_speed).passed);
}

TEST_F(PaperPatterns, MinLciAndJointLimitsAreChecked) {
  Station s = station("index");
  s.upper->min_lci = 0.5;  // the stretch starts at LCI 0.464 (upper at 4 mm above the centre)
  const PatternResult lci = check_pattern(s, geometry(), spec(PatternKind::stretch, 3.0, 8.0), max_speed());
  ASSERT_FALSE(lci.passed);
  EXPECT_EQ(lci.first_failure->status, SampleStatus::low_lci);
  EXPECT_EQ(lci.first_failure->mechanism, "upper");
  EXPECT_EQ(lci.first_failure->index, 0u);

  Station lim = station("index");
  // The lower's first motor starts at 144.8 deg (stretch start) and turns outward as the tactor
  // moves left: allow only up to 146 deg.
  lim.lower->joint_limits = std::array<JointRange, 2>{JointRange{100.0 * kPi / 180, 146.0 * kPi / 180},
                                                      JointRange{-kPi, kPi - 1e-9}};
  const PatternResult jl = check_pattern(lim, geometry(), spec(PatternKind::stretch, 3.0, 8.0), max_speed());
  ASSERT_FALSE(jl.passed);
  EXPECT_EQ(jl.first_failure->status, SampleStatus::outside_joint_limits);
  EXPECT_EQ(jl.first_failure->mechanism, "lower");
  const double theta1 = jl.samples[jl.first_failure->index].lower.theta[0];
  EXPECT_GT(theta1 * 180.0 / kPi, 146.0);
}

TEST_F(PaperPatterns, NeedsBothMechanismsAndValidParameters) {
  Station one = station("index");
  one.upper.reset();
  EXPECT_THROW(check_pattern(one, geometry(), spec(PatternKind::stretch, 3.0, 8.0), max_speed()), InputError);
  EXPECT_THAT([&] { check_pattern(station("index"), geometry(), spec(PatternKind::stretch, -1.0, 8.0), max_speed()); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("amplitude_mm = -1 mm")));
  EXPECT_THROW(check_pattern(station("index"), geometry(), spec(PatternKind::twist, 3.0, 0.0), max_speed()), InputError);
  EXPECT_THROW(check_pattern(station("index"), geometry(), spec(PatternKind::slip, 3.0, 8.0), 0.0), InputError);
}

// ---------------------------------------------------------------------------------------------
// Trajectory CSV.

struct Row {
  double t;
  std::string station, mechanism;
  bool has_angles;
  double theta1_deg, theta2_deg, x, y;
  std::string status;
};

std::vector<Row> parse(const std::string& text, std::string* header) {
  std::istringstream in(text);
  std::string line;
  std::getline(in, *header);
  std::vector<Row> rows;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ls(line);
    std::string cell;
    while (std::getline(ls, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    EXPECT_EQ(cells.size(), 11u) << line;
    if (cells.size() < 11) continue;
    Row r;
    r.t = std::stod(cells[0]);
    r.station = cells[1];
    r.mechanism = cells[2];
    r.has_angles = !cells[3].empty();
    r.theta1_deg = r.has_angles ? std::stod(cells[3]) : 0.0;
    r.theta2_deg = r.has_angles ? std::stod(cells[4]) : 0.0;
    r.x = std::stod(cells[5]);
    r.y = std::stod(cells[6]);
    r.status = cells[7];
    rows.push_back(r);
  }
  return rows;
}

TEST_F(PaperPatterns, ForwardKinematicsOfTheWrittenAnglesReproducesTheWrittenPoints) {
  for (const char* name : {"index", "thumb"}) {
    const Station& s = station(name);
    for (PatternKind kind : all_pattern_kinds()) {
      SCOPED_TRACE(std::string(name) + " " + std::string(to_string(kind)));
      PatternSpec sp = spec(kind, 3.0, 8.0, kind == PatternKind::pivot ? 2.0 : 1.0);
      if (kind == PatternKind::twist) sp.amplitude_mm = 6.0;  // on the index: some samples moved
      const PatternResult r = check_pattern(s, geometry(), sp, max_speed());
      std::ostringstream out;
      write_trajectory_csv(out, r);
      std::string header;
      const auto rows = parse(out.str(), &header);
      EXPECT_EQ(header, "time_s,station,mechanism,theta1_deg,theta2_deg,x_mm,y_mm,status,target_x_mm,target_y_mm,lci");
      ASSERT_EQ(rows.size(), 2 * r.samples.size());
      for (std::size_t i = 0; i < rows.size(); ++i) {
        const Row& row = rows[i];
        EXPECT_EQ(row.station, name);
        EXPECT_EQ(row.mechanism, i % 2 == 0 ? "upper" : "lower");
        EXPECT_DOUBLE_EQ(row.t, r.samples[i / 2].time_s);
        ASSERT_TRUE(row.has_angles);
        const Mechanism& m = row.mechanism == "upper" ? *s.upper : *s.lower;
        const PointResult p = fk_point(m, row.theta1_deg * kPi / 180.0, row.theta2_deg * kPi / 180.0);
        ASSERT_EQ(p.status, Status::ok);
        EXPECT_NEAR(p.P.x(), row.x, 1e-9);
        EXPECT_NEAR(p.P.y(), row.y, 1e-9);
      }
    }
  }
}

TEST_F(PaperPatterns, WrittenAnglesAreContinuousAndGiveTheReportedPeakSpeed) {
  PatternSpec sp = spec(PatternKind::pivot, 0.0, 8.0, 2.0);
  sp.pivot_amplitude = 40.0 * kPi / 180.0;
  const PatternResult r = check_pattern(station("thumb"), geometry(), sp, max_speed());
  std::ostringstream out;
  write_trajectory_csv(out, r);
  std::string header;
  const auto rows = parse(out.str(), &header);
  double peak_deg_s = 0.0;
  for (std::size_t i = 2; i < rows.size(); ++i) {
    const Row& a = rows[i - 2];
    const Row& b = rows[i];
    const double dt = b.t - a.t;
    for (double d : {b.theta1_deg - a.theta1_deg, b.theta2_deg - a.theta2_deg}) {
      EXPECT_LT(std::fabs(d), 10.0) << "jump at row " << i;  // continuous, no 360-degree wraps
      peak_deg_s = std::max(peak_deg_s, std::fabs(d) / dt);
    }
  }
  EXPECT_NEAR(peak_deg_s, r.peak_joint_speed * 180.0 / kPi, 1e-6 * peak_deg_s);
}

TEST_F(PaperPatterns, JsonSummaryAndPicture) {
  const PatternResult r = check_pattern(station("index"), geometry(), spec(PatternKind::twist, 6.0, 8.0), max_speed());
  const Json j = to_json(r);
  EXPECT_EQ(j["pattern"], "twist");
  EXPECT_FALSE(j["passed"].get<bool>());
  EXPECT_EQ(j["first_failure"]["status"], "collision_moved");
  EXPECT_EQ(j["first_failure"]["index"], r.first_failure->index);
  EXPECT_EQ(j["worst"]["moved_samples"], r.moved_samples);
  EXPECT_FALSE(j.contains("samples"));
  EXPECT_EQ(to_json(r, true)["samples"].size(), r.samples.size());
  const RenderedPlot pic = plot_patterns(station("index"), geometry(), {r});
  EXPECT_EQ(pic.png.substr(0, 4), std::string("\x89PNG", 4));
  EXPECT_THAT(pic.svg, HasSubstr("<svg"));
}

// The one joint speed the pattern checks use (fivebar/device/joint_limits.hpp): the smaller of the
// controller's stated limit and the motors' steady speed; either alone; the patterns' own limit
// with neither section.
TEST(PatternSpeed, TheExportsJointSpeedOrThePatternsOwnWithoutAControllerOrMotor) {
  Design d = load_design(kDesign);
  const Station& index = d.require_station("index");
  double motor = std::numeric_limits<double>::infinity();
  for (const char* m : {"lower", "upper"}) {
    for (int j : {1, 2}) motor = std::min(motor, motor_free_speed(d.get<MotorSettings>()->joint("index", m, j)));
  }
  const double stated = d.get<ControllerSettings>()->max_velocity;
  ASSERT_LT(motor, stated);  // the showcase: 343.5 < 360 deg/s
  EXPECT_EQ(pattern_joint_speed_limit(d, index), motor);
  d.get<ControllerSettings>()->max_velocity = 0.5 * motor;
  EXPECT_EQ(pattern_joint_speed_limit(d, index), 0.5 * motor);
  d.reset<MotorSettings>();
  EXPECT_EQ(pattern_joint_speed_limit(d, index), 0.5 * motor);
  d.reset<ControllerSettings>();
  EXPECT_EQ(pattern_joint_speed_limit(d, index), d.get<PatternSettings>()->max_joint_speed);
  d.reset<PatternSettings>();
  EXPECT_EQ(pattern_joint_speed_limit(d, index), PatternSettings{}.max_joint_speed);
}

}  // namespace
}  // namespace fivebar
