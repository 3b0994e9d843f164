// Coverage: point-ellipse extremes against brute force and circles; verdicts and margins against
// independent computations (dense sampling of the ellipse against the annuli inequalities or
// IK with joint limits), tangent and just-outside ellipses, rotated ellipses, holes.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <numbers>
#include <random>

#include "fivebar/coverage/coverage.hpp"
#include "paper.hpp"

namespace fivebar {
namespace {

constexpr double kPi = std::numbers::pi;

using ::fivebar::testing::paper_mechanism;
using ::fivebar::testing::test_seed;

Ellipse ellipse(double cx, double cy, double ax, double ay, double angle_deg = 0.0) {
  Ellipse e;
  e.center = {cx, cy};
  e.axes = {ax, ay};
  e.angle = angle_deg * kPi / 180.0;
  return e;
}

Vec2 on_ellipse(const Ellipse& e, double r, double t) {
  const double c = std::cos(e.angle), s = std::sin(e.angle);
  const double x = 0.5 * r * e.axes.x() * std::cos(t), y = 0.5 * r * e.axes.y() * std::sin(t);
  return e.center + Vec2(c * x - s * y, s * x + c * y);
}

/// Margin by brute force: the annuli inequalities at many points of the filled ellipse (the
/// boundary carries the extremes of a distance from a point outside, the interior those of a
/// point inside). Independent of coverage.cpp's root finder.
double brute_margin_annuli(const Mechanism& m, const Ellipse& e, int n = 200000) {
  double margin = INFINITY;
  for (int i = 0; i < 2; ++i) {
    const Vec2& O = i == 0 ? m.O1 : m.O2;
    const double outer = m.L[i] + m.L[i + 2], inner = std::fabs(m.L[i] - m.L[i + 2]);
    double dmax = 0.0, dmin = INFINITY;
    for (int k = 0; k < n; ++k) {
      const double d = (on_ellipse(e, 1.0, 2 * kPi * k / n) - O).norm();
      dmax = std::max(dmax, d);
      dmin = std::min(dmin, d);
    }
    const Vec2 q = O - e.center;
    const double c = std::cos(e.angle), s = std::sin(e.angle);
    const double lx = c * q.x() + s * q.y(), ly = -s * q.x() + c * q.y();
    const bool o_inside = std::pow(lx / (0.5 * e.axes.x()), 2) + std::pow(ly / (0.5 * e.axes.y()), 2) <= 1.0;
    margin = std::min(margin, outer - dmax);
    if (inner > 0) margin = std::min(margin, (o_inside ? 0.0 : dmin) - inner);
  }
  return margin;
}

TEST(EllipseExtremes, CircleHasClosedFormExtremes) {
  const Ellipse c = ellipse(1.0, -2.0, 6.0, 6.0);
  for (const Vec2& p : {Vec2(10, 3), Vec2(1.5, -2.2), Vec2(-30, 0), Vec2(1, 1)}) {
    const EllipseExtremes ex = ellipse_distance_extremes(c, p);
    const double d = (p - c.center).norm();
    EXPECT_NEAR(ex.min_distance, std::fabs(d - 3.0), 1e-12) << p.transpose();
    EXPECT_NEAR(ex.max_distance, d + 3.0, 1e-12) << p.transpose();
    EXPECT_EQ(ex.p_inside, d <= 3.0);
  }
}

TEST(EllipseExtremes, AgreeWithDenseSamplingIncludingNearTheEvolute) {
  std::mt19937_64 rng(test_seed());
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Ellipse e = ellipse(u(rng), u(rng), 4 + 20 * std::fabs(u(rng)), 1 + 10 * std::fabs(u(rng)), 180 * u(rng));
    // Points near the centre are the hard ones (up to four critical points, close together).
    const double spread = trial % 2 ? 0.5 : 15.0;
    const Vec2 p = e.center + spread * Vec2(u(rng), u(rng));
    const EllipseExtremes ex = ellipse_distance_extremes(e, p);
    double lo = INFINITY, hi = 0;
    for (int k = 0; k < 100000; ++k) {
      const double d = (on_ellipse(e, 1.0, 2 * kPi * k / 100000) - p).norm();
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    SCOPED_TRACE(trial);
    // Sampling over-estimates a minimum by at most ~ (step * max|q'|)^2 / (2 d).
    EXPECT_LE(ex.min_distance, lo + 1e-12);
    EXPECT_GE(ex.min_distance, lo - 1e-6);
    EXPECT_GE(ex.max_distance, hi - 1e-12);
    EXPECT_LE(ex.max_distance, hi + 1e-6);
    EXPECT_NEAR((ex.nearest - p).norm(), ex.min_distance, 1e-9);
  }
}

TEST(Coverage, PaperStationsCoverTheirTargets) {
  for (const char* s : {"index", "thumb"}) {
    const Ellipse target = std::string(s) == "index" ? ellipse(6.25, 15.5, 15, 12) : ellipse(6.25, 17.5, 15, 14);
    for (const char* w : {"lower", "upper"}) {
      SCOPED_TRACE(std::string(s) + " " + w);
      const Mechanism m = paper_mechanism(s, w);
      const CoverageResult c = coverage(m, target);
      EXPECT_TRUE(c.covered) << c.reason;
      EXPECT_TRUE(c.inside);
      EXPECT_NEAR(c.margin_mm, brute_margin_annuli(m, target), 1e-6);
      EXPECT_EQ(c.covered_fraction, 1.0);
      EXPECT_GT(c.min_lci, 0.0);
      EXPECT_TRUE(c.assembly_ok);
      EXPECT_GT(c.min_force_capability, 0.0);
      // min LCI over the filled ellipse is at most the LCI anywhere in it (centre, samples).
      EXPECT_LE(c.min_lci, ik(m, target.center).lci + 1e-15);
      for (int k = 0; k < 64; ++k) EXPECT_LE(c.min_lci, ik(m, on_ellipse(target, 1.0, 2 * kPi * k / 64)).lci + 1e-12);
    }
    const Station st{s, std::string(s) == "index" ? ellipse(6.25, 15.5, 15, 12) : ellipse(6.25, 17.5, 15, 14),
                     paper_mechanism(s, "lower"), paper_mechanism(s, "upper")};
    const StationCoverage sc = station_coverage(st);
    ASSERT_TRUE(sc.shared.has_value());
    EXPECT_TRUE(sc.covered());
    EXPECT_DOUBLE_EQ(sc.shared->margin_mm, std::min(sc.lower->margin_mm, sc.upper->margin_mm));
  }
}

/// A circle inside the outer circle of leg 1 at distance delta from it (delta > 0 inside, < 0
/// sticking out), away from every other constraint: margin = delta exactly.
TEST(Coverage, TangentAndJustOutsideByTensOfMicrometres) {
  const Mechanism m = paper_mechanism("index", "lower");
  const Vec2 dir = Vec2(0.3, 1.0).normalized();
  for (double delta : {50e-3, 20e-3, 1e-6, -1e-6, -20e-3, -50e-3}) {
    const double rho = 2.0;
    const Vec2 c = m.O1 + (24.0 - rho - delta) * dir;
    const Ellipse e = ellipse(c.x(), c.y(), 2 * rho, 2 * rho);
    SCOPED_TRACE(delta);
    const CoverageResult r = coverage(m, e);
    EXPECT_EQ(r.inside, delta > 0);
    EXPECT_NEAR(r.margin_mm, delta, 1e-11);
    EXPECT_NEAR((r.worst_point - m.O1).norm(), 24.0 - delta, 1e-9);
  }
}

TEST(Coverage, RotatedEllipsesAgreeWithBruteForce) {
  const Mechanism m = paper_mechanism("thumb", "upper");
  std::mt19937_64 rng(test_seed() + 3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int inside = 0, outside = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const Ellipse e = ellipse(6.25 + 6 * u(rng), 17.5 + 6 * u(rng), 10 + 8 * std::fabs(u(rng)),
                              6 + 8 * std::fabs(u(rng)), 90 * u(rng));
    const CoverageResult r = coverage(m, e);
    const double ref = brute_margin_annuli(m, e, 50000);
    SCOPED_TRACE(trial);
    EXPECT_NEAR(r.margin_mm, ref, 1e-5);
    if (std::fabs(ref) > 1e-4) EXPECT_EQ(r.inside, ref > 0);
    (r.inside ? inside : outside)++;
  }
  EXPECT_GT(inside, 5);
  EXPECT_GT(outside, 5);
}

TEST(Coverage, EllipseOverAHoleIsNotCovered) {
  // Index lower: the hole of radius 6 around O1 = (0, 0). An ellipse around (1, 2) holds it.
  const Mechanism m = paper_mechanism("index", "lower");
  const Ellipse e = ellipse(1.0, 2.0, 15, 12);
  const CoverageResult r = coverage(m, e);
  EXPECT_FALSE(r.covered);
  EXPECT_FALSE(r.inside);
  EXPECT_LE(r.margin_mm, -6.0 + 1e-12);  // O1 lies inside the ellipse: the whole hole radius
  EXPECT_GT(r.covered_fraction, 0.0);
  EXPECT_LT(r.covered_fraction, 1.0);
  EXPECT_FALSE(r.reason.empty());
}

TEST(Coverage, CoveredFractionMatchesSamplingWhenPartlyOutside) {
  const Mechanism m = paper_mechanism("index", "lower");
  const Ellipse e = ellipse(6.25, 22.0, 15, 12);  // sticks out above the outer arcs
  const CoverageResult r = coverage(m, e);
  EXPECT_FALSE(r.inside);
  int in = 0, total = 0;
  for (int i = 0; i < 400; ++i) {
    for (int j = 0; j < 400; ++j) {
      const double x = -1 + 2 * (i + 0.5) / 400, y = -1 + 2 * (j + 0.5) / 400;
      if (x * x + y * y > 1) continue;
      const Vec2 p = e.center + Vec2(7.5 * x, 6 * y);
      ++total;
      in += ik(m, p).status != Status::unreachable;
    }
  }
  EXPECT_NEAR(r.covered_fraction, double(in) / total, 2e-3);
}

TEST(Coverage, JointLimitsCutTheEllipseAndTheVerdictFollowsIk) {
  Mechanism m = paper_mechanism("index", "lower");
  const Ellipse e = ellipse(6.25, 15.5, 15, 12);
  // Measure the joint ranges the ellipse needs, then set limits just wider / just narrower.
  double lo1 = INFINITY, hi1 = -INFINITY, lo2 = INFINITY, hi2 = -INFINITY;
  for (int ring = 0; ring <= 20; ++ring) {
    for (int k = 0; k < 720; ++k) {
      const Pose p = ik(m, on_ellipse(e, ring / 20.0, 2 * kPi * k / 720));
      lo1 = std::min(lo1, p.theta1);
      hi1 = std::max(hi1, p.theta1);
      lo2 = std::min(lo2, p.theta2);
      hi2 = std::max(hi2, p.theta2);
    }
  }
  const double wide = 0.02, narrow = -0.02;  // rad
  for (double pad : {wide, narrow}) {
    Mechanism lim = m;
    lim.joint_limits = std::array<JointRange, 2>{JointRange{lo1 - pad, hi1 + pad}, JointRange{lo2 - pad, hi2 + pad}};
    const CoverageResult r = coverage(lim, e);
    SCOPED_TRACE(pad);
    EXPECT_EQ(r.inside, pad > 0) << r.method;
    if (pad > 0) {
      EXPECT_GT(r.margin_mm, 0.0);
      // The margin is at most the joint-angle slack times the longest lever (L1 + L3).
      EXPECT_LT(r.margin_mm, pad * 24.0);
    } else {
      EXPECT_LT(r.margin_mm, 0.0);
      EXPECT_LT(r.covered_fraction, 1.0);
    }
  }
}

TEST(Coverage, WithinRoundingOfTangencyTheVerdictIsUndecided) {
  const Mechanism m = paper_mechanism("index", "lower");
  const Vec2 dir = Vec2(0.3, 1.0).normalized();
  const double rho = 2.0;
  const Vec2 c = m.O1 + (24.0 - rho - 1e-12) * dir;  // 1e-12 mm inside: within rounding
  const CoverageResult r = coverage(m, ellipse(c.x(), c.y(), 2 * rho, 2 * rho));
  EXPECT_THAT(r.method, ::testing::HasSubstr("undecided within"));
  // No polygon around the ellipse fits in 1e-12 mm, and no point of it is outside.
  EXPECT_FALSE(r.decided);
  EXPECT_FALSE(r.covered);
  EXPECT_LE(std::fabs(r.margin_mm - 1e-12), r.margin_error_mm);
}

TEST(Coverage, LciThresholdAndAssemblySideEnterTheVerdict) {
  Mechanism m = paper_mechanism("index", "lower");
  const Ellipse e = ellipse(6.25, 15.5, 15, 12);
  const CoverageResult base = coverage(m, e);
  ASSERT_TRUE(base.covered);
  m.min_lci = base.min_lci + 0.01;
  const CoverageResult strict = coverage(m, e);
  EXPECT_TRUE(strict.inside);
  EXPECT_FALSE(strict.lci_ok);
  EXPECT_FALSE(strict.covered);
  EXPECT_THAT(strict.reason, ::testing::HasSubstr("LCI"));
  // Demanding the other assembly side fails over the whole ellipse.
  m.min_lci = 0.0;
  m.assembly_mode = AssemblyMode::Minus;
  EXPECT_FALSE(coverage(m, e).assembly_ok);
}

}  // namespace
}  // namespace fivebar
