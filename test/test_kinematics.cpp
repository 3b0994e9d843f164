// Kinematics: properties over regimes (paper stations, random geometries), extreme cases near
// type I / II singularities, scale and ratio extremes, and the batch kernels against the scalar
// path. Expected values come from independent computations (law of cosines, the paper's arccos
// form in long double, central differences, Eigen's SVD), never from the code under test.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <cstdlib>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "fivebar/detail/fastmath.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/numerics.hpp"
#include "paper.hpp"

namespace fivebar {
namespace {

using ::fivebar::testing::paper_mechanism;
using ::fivebar::testing::test_seed;

constexpr double kPi = std::numbers::pi;
constexpr double kEps = tol::kEps;

double deg(double d) { return d * kPi / 180.0; }

bool finite_pose(const Pose& p) {
  bool ok = std::isfinite(p.theta1) && std::isfinite(p.theta2) && p.A1.allFinite() &&
            p.A2.allFinite() && p.P.allFinite() && p.J.allFinite() && std::isfinite(p.lci) &&
            std::isfinite(p.force_capability) && std::isfinite(p.type2_sin) &&
            std::isfinite(p.type1_distance_mm) && std::isfinite(p.closure_error_mm);
  for (double v : p.transmission) ok = ok && std::isfinite(v);
  for (double v : p.type1_sin) ok = ok && std::isfinite(v);
  return ok;
}

Mechanism random_mechanism(std::mt19937_64& rng, double scale = 10.0) {
  std::uniform_real_distribution<double> len(0.3, 3.0), base(0.0, 2.0), sign(0.0, 1.0);
  Mechanism m;
  m.name = "random";
  m.O1 = {0.0, 0.0};
  m.O2 = {base(rng) * scale, 0.0};
  m.L = {len(rng) * scale, len(rng) * scale, len(rng) * scale, len(rng) * scale};
  m.working_mode = {std::int8_t(sign(rng) < 0.5 ? -1 : 1), std::int8_t(sign(rng) < 0.5 ? -1 : 1)};
  m.assembly_mode = AssemblyMode::Any;
  return m;
}

Mechanism scaled(Mechanism m, double s) {
  m.O1 *= s;
  m.O2 *= s;
  for (double& l : m.L) l *= s;
  return m;
}

double min_sin(const Pose& p) { return std::min({p.type1_sin[0], p.type1_sin[1], p.type2_sin}); }

/// Independent FK: the paper's eq. (2) with alpha from the law of cosines, in long double.
Vec2 fk_paper_long(const Mechanism& m, double t1, double t2, int assembly) {
  using LD = long double;
  const LD a1x = LD(m.O1.x()) + LD(m.L[0]) * std::cos(LD(t1));
  const LD a1y = LD(m.O1.y()) + LD(m.L[0]) * std::sin(LD(t1));
  const LD a2x = LD(m.O2.x()) + LD(m.L[1]) * std::cos(LD(t2));
  const LD a2y = LD(m.O2.y()) + LD(m.L[1]) * std::sin(LD(t2));
  const LD dx = a2x - a1x, dy = a2y - a1y, d = std::sqrt(dx * dx + dy * dy);
  const LD L3 = m.L[2], L4 = m.L[3];
  const LD alpha = std::acos((L3 * L3 - L4 * L4 + d * d) / (2 * L3 * d));
  const LD phi = std::atan2(dy, dx) + LD(assembly) * alpha;
  return {double(a1x + L3 * std::cos(phi)), double(a1y + L3 * std::sin(phi))};
}

// --- fast math kernels -------------------------------------------------------------------------

double ulp_of(long double v) {
  const double d = double(std::fabs(v));
  return std::nextafter(d, INFINITY) - d;
}

TEST(FastMath, SinCosWithinThreeUlpForAnglesInRange) {
  std::mt19937_64 rng(test_seed());
  std::uniform_real_distribution<double> small(-8.0, 8.0), big(-detail::kFastTrigMax, detail::kFastTrigMax);
  double worst_small = 0.0, worst_big = 0.0;
  for (int k = 0; k < 400000; ++k) {
    const bool is_big = k % 4 == 0;
    const double x = is_big ? big(rng) : small(rng);
    double s, c;
    detail::fast_sincos(x, s, c);
    const long double ts = std::sin((long double)x), tc = std::cos((long double)x);
    SCOPED_TRACE(x);
    if (!is_big) {
      // Relative to the result's own ulp: exact for every angle a design file can hold.
      worst_small = std::max({worst_small, double(std::fabs(s - ts) / ulp_of(ts)),
                              double(std::fabs(c - tc) / ulp_of(tc))});
    } else {
      // Far from zero the reduction's absolute error (|x| * 1e-32) is what is left.
      worst_big = std::max({worst_big, double(std::fabs(s - ts) / std::max(ulp_of(ts), kEps / 4)),
                            double(std::fabs(c - tc) / std::max(ulp_of(tc), kEps / 4))});
    }
  }
  EXPECT_LE(worst_small, 3.0);
  EXPECT_LE(worst_big, 3.0);
}

TEST(FastMath, SinCosAtQuadrantBoundaries) {
  for (int q = -16; q <= 16; ++q) {
    for (double dx : {-1e-9, 0.0, 1e-9}) {
      const double x = q * kPi / 4 + dx;
      double s, c;
      detail::fast_sincos(x, s, c);
      EXPECT_NEAR(s, std::sin(x), 2 * kEps) << x;
      EXPECT_NEAR(c, std::cos(x), 2 * kEps) << x;
    }
  }
}

TEST(FastMath, Atan2WithinThreeUlpInEveryOctant) {
  std::mt19937_64 rng(test_seed() + 1);
  std::uniform_real_distribution<double> u(-1.0, 1.0), e(-30.0, 30.0);
  double worst = 0.0;
  for (int k = 0; k < 400000; ++k) {
    const double y = u(rng) * std::pow(10.0, e(rng) / 10), x = u(rng) * std::pow(10.0, e(rng) / 10);
    const long double t = std::atan2((long double)y, (long double)x);
    const double got = detail::fast_atan2(y, x);
    worst = std::max(worst, double(std::fabs(got - t) / ulp_of(t)));
  }
  EXPECT_LE(worst, 3.0);
  EXPECT_EQ(detail::fast_atan2(0.0, 1.0), 0.0);
  EXPECT_DOUBLE_EQ(detail::fast_atan2(0.0, -1.0), kPi);
  EXPECT_DOUBLE_EQ(detail::fast_atan2(1.0, 0.0), kPi / 2);
  EXPECT_DOUBLE_EQ(detail::fast_atan2(-1.0, 0.0), -kPi / 2);
  EXPECT_DOUBLE_EQ(detail::fast_atan2(-1.0, -1.0), -3 * kPi / 4);
  EXPECT_EQ(detail::fast_atan2(0.0, 0.0), 0.0);
}

TEST(FastMath, AngleOfAVectorOfKnownLengthWithinThreeUlp) {
  // Vectors r (cos a, sin a) rounded from long double, so sqrt(x^2 + y^2) = r to within an ulp; the
  // reference is the long-double atan2 of the rounded components. Every octant, lengths 1e-6 to
  // 1e6, and the octant boundaries (|x| = |y|, an axis) where the fold changes branch.
  std::mt19937_64 rng(test_seed() + 2);
  std::uniform_real_distribution<long double> angle(-kPi, kPi);
  std::uniform_real_distribution<double> e(-6.0, 6.0);
  double worst = 0.0;
  const auto check = [&](long double a, double r) {
    const double x = double(r * std::cos(a)), y = double(r * std::sin(a));
    const long double t = std::atan2((long double)y, (long double)x);
    worst = std::max(worst, double(std::fabs(detail::fast_angle(y, x, r) - t) / ulp_of(t)));
  };
  for (int k = 0; k < 400000; ++k) check(angle(rng), std::pow(10.0, e(rng)));
  for (int q = -8; q <= 8; ++q) {
    for (long double da : {-1e-12L, 0.0L, 1e-12L}) check(q * (long double)kPi / 4 + da, 9.0);
  }
  EXPECT_LE(worst, 3.0);
  EXPECT_EQ(detail::fast_angle(0.0, 9.0, 9.0), 0.0);
  EXPECT_DOUBLE_EQ(detail::fast_angle(0.0, -9.0, 9.0), kPi);
  EXPECT_DOUBLE_EQ(detail::fast_angle(9.0, 0.0, 9.0), kPi / 2);
  EXPECT_DOUBLE_EQ(detail::fast_angle(-9.0, 0.0, 9.0), -kPi / 2);
  // A length off by delta (relative) moves the angle by at most 0.42 delta rad: the bound the
  // batch IK relies on when the elbow offset's length is the link's only to the reach slack.
  for (double delta : {1e-12, -1e-12, 16 * kEps}) {
    for (int k = 0; k < 64; ++k) {
      const double a = -kPi + 2 * kPi * (k + 0.5) / 64, x = 9.0 * std::cos(a), y = 9.0 * std::sin(a);
      EXPECT_NEAR(detail::fast_angle(y, x, 9.0 * (1 + delta)), std::atan2(y, x), 0.42 * std::fabs(delta) + 4 * kEps)
          << a;
    }
  }
}

// --- circle intersection -----------------------------------------------------------------------

TEST(CircleIntersection, HandWorkedCases) {
  // 3-4-5 triangle: circles (0,0) r=5 and (6,0) r=5 meet at (3, +-4).
  auto up = intersect_circles({0, 0}, 5, {6, 0}, 5, +1);
  ASSERT_EQ(up.status, Status::ok);
  EXPECT_NEAR(up.point.x(), 3.0, 4 * kEps * 6);
  EXPECT_NEAR(up.point.y(), 4.0, 4 * kEps * 6);
  auto down = intersect_circles({0, 0}, 5, {6, 0}, 5, -1);
  EXPECT_NEAR(down.point.y(), -4.0, 4 * kEps * 6);
  // Exact external tangency: one point, h = 0, no NaN.
  auto tangent = intersect_circles({0, 0}, 2, {5, 0}, 3, +1);
  ASSERT_EQ(tangent.status, Status::ok);
  EXPECT_EQ(tangent.h, 0.0);
  EXPECT_DOUBLE_EQ(tangent.point.x(), 2.0);
  // Apart, nested and concentric circles do not meet.
  EXPECT_EQ(intersect_circles({0, 0}, 1, {5, 0}, 1, 1).status, Status::unreachable);
  EXPECT_EQ(intersect_circles({0, 0}, 5, {1, 0}, 1, 1).status, Status::unreachable);
  EXPECT_EQ(intersect_circles({0, 0}, 5, {0, 0}, 4, 1).status, Status::unreachable);
}

TEST(CircleIntersection, TangencyWithinRoundingIsClampedNotNaN) {
  // 0.1 + 0.2 != 0.3 in binary: tangent circles whose radii sum misses d by an ulp.
  for (double d : {0.3, 0.30000000000000004, 0.29999999999999993}) {
    auto x = intersect_circles({0, 0}, 0.1, {d, 0}, 0.2, +1);
    EXPECT_EQ(x.status, Status::ok) << d;
    EXPECT_TRUE(x.point.allFinite());
    EXPECT_LE(x.h, 1e-7);
  }
}

/// Against an independent reference in long double: the law of cosines for the foot and Heron's
/// product K = (d+r1+r2)(-d+r1+r2)(d-r1+r2)(d+r1-r2) = (2 d h)^2 for the height. For exact inputs
/// the intersection is a problem of conditioning 1/sin(gamma), gamma the angle at which the circles
/// cross (sin gamma = d h / (r1 r2)), so the error may reach eps * scale * (1 + 1/sin gamma).
TEST(CircleIntersection, AgreesWithLongDoubleHeronAtRadiusRatiosUpTo1e8) {
  std::mt19937_64 rng(test_seed() + 3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  using LD = long double;
  double worst = 0.0;
  for (int k = 0; k < 200000; ++k) {
    const double r1 = std::pow(10.0, 8 * u(rng) - 4), r2 = std::pow(10.0, 8 * u(rng) - 4);
    const double d = std::fabs(r1 - r2) + 2 * std::min(r1, r2) * u(rng);
    const double ang = 2 * kPi * u(rng);
    const Vec2 c1(3 * r1 * (u(rng) - 0.5), 3 * r2 * (u(rng) - 0.5));
    const Vec2 c2 = c1 + d * Vec2(std::cos(ang), std::sin(ang));
    const int side = u(rng) < 0.5 ? 1 : -1;
    const CircleIntersection x = intersect_circles(c1, r1, c2, r2, side);
    // The centres actually posed, exactly.
    const LD dx = LD(c2.x()) - LD(c1.x()), dy = LD(c2.y()) - LD(c1.y()), R1 = r1, R2 = r2;
    const LD D = std::sqrt(dx * dx + dy * dy);
    const LD K = (D + R1 + R2) * (-D + R1 + R2) * (D - R1 + R2) * (D + R1 - R2);
    if (K < 0) {  // the rounding of c2 moved the circles apart: allowed either way, only by rounding
      EXPECT_TRUE(x.status == Status::unreachable || x.h <= 1e-6 * std::max(r1, r2));
      continue;
    }
    ASSERT_EQ(x.status, Status::ok) << r1 << " " << r2 << " " << d;
    const LD h = std::sqrt(K) / (2 * D), a = (D * D + R1 * R1 - R2 * R2) / (2 * D);
    const LD ox = (a * dx - side * h * dy) / D, oy = (a * dy + side * h * dx) / D;
    const double sin_gamma = double(D * h / (R1 * R2));
    const double scale = std::max({r1, r2, d, std::fabs(c1.x()), std::fabs(c1.y())});
    const double err = double(std::hypot(LD(x.offset.x()) - ox, LD(x.offset.y()) - oy));
    ASSERT_TRUE(std::isfinite(err));
    worst = std::max(worst, err / (kEps * scale * (1.0 + 1.0 / std::max(sin_gamma, 1e-300))));
  }
  EXPECT_LE(worst, 4.0);
}

/// Scaling every length by a power of two scales the intersection exactly (no rounding changes)
/// as long as nothing over- or underflows: the chord's fourth-power product is rescaled by an exact
/// power of 4, so lengths from 2^-480 to 2^480 (~1e-144 ... 1e144) give bit-for-bit the same point.
TEST(CircleIntersection, ScalesExactlyByPowersOfTwoFrom1em144To1e144) {
  std::mt19937_64 rng(test_seed() + 5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int checked = 0;
  for (int k = 0; k < 2000; ++k) {
    const double r1 = 0.1 + 10 * u(rng), r2 = 0.1 + 10 * u(rng);
    const Vec2 c1(20 * u(rng) - 10, 20 * u(rng) - 10);
    const double d = std::fabs(r1 - r2) + 2 * std::min(r1, r2) * u(rng), ang = 2 * kPi * u(rng);
    const Vec2 c2 = c1 + d * Vec2(std::cos(ang), std::sin(ang));
    const CircleIntersection ref = intersect_circles(c1, r1, c2, r2, +1);
    if (ref.status != Status::ok) continue;
    ++checked;
    for (int e : {-480, -200, -40, 40, 200, 480}) {
      const double s = std::ldexp(1.0, e);
      const CircleIntersection x = intersect_circles(s * c1, s * r1, s * c2, s * r2, +1);
      ASSERT_EQ(x.status, Status::ok) << e;
      EXPECT_EQ(x.offset.x(), s * ref.offset.x()) << e;
      EXPECT_EQ(x.offset.y(), s * ref.offset.y()) << e;
      EXPECT_EQ(x.h, s * ref.h) << e;
    }
  }
  EXPECT_GT(checked, 1500);
}

// --- regimes -----------------------------------------------------------------------------------

struct Regime {
  std::string name;
  Mechanism m;
  friend void PrintTo(const Regime& r, std::ostream* os) {
    *os << r.name << " O1 " << r.m.O1.transpose() << " O2 " << r.m.O2.transpose() << " L " << r.m.L[0]
        << " " << r.m.L[1] << " " << r.m.L[2] << " " << r.m.L[3] << " mode " << to_string(r.m.working_mode);
  }
};

std::vector<Regime> regimes() {
  std::vector<Regime> out;
  for (const char* s : {"index", "thumb"})
    for (const char* w : {"lower", "upper"}) out.push_back({std::string(s) + "_" + w, paper_mechanism(s, w)});
  std::mt19937_64 rng(test_seed() + 7);
  for (int k = 0; k < 12; ++k) out.push_back({"random" + std::to_string(k), random_mechanism(rng)});
  return out;
}

class KinematicsRegime : public ::testing::TestWithParam<Regime> {};

/// Random joint angles whose FK (in the mechanism's working-mode branch) is regular.
std::vector<Pose> regular_poses(const Mechanism& m, std::uint64_t seed, int count, double min_s = 1e-2) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> ang(-kPi, kPi);
  std::vector<Pose> out;
  for (int tries = 0; tries < 200 * count && int(out.size()) < count; ++tries) {
    for (const Pose& p : fk_all(m, ang(rng), ang(rng))) {
      if (p.status == Status::ok && min_sin(p) > min_s) out.push_back(p);
    }
  }
  return out;
}

TEST_P(KinematicsRegime, IkOfFkReturnsTheAnglesAndFkOfIkReturnsThePoint) {
  const Mechanism& m = GetParam().m;
  const double scale = m.length_scale();
  const auto poses = regular_poses(m, test_seed() + 11, 300);
  ASSERT_GT(poses.size(), 50u);
  for (const Pose& p : poses) {
    SCOPED_TRACE(::testing::Message() << "theta = " << p.theta1 << ", " << p.theta2 << " seed " << test_seed());
    const double s = min_sin(p);
    // Every FK point is exact to a few ulps of the scale divided by the conditioning (sin).
    const Vec2 ref = fk_paper_long(m, p.theta1, p.theta2, p.assembly);
    EXPECT_LE((p.P - ref).norm(), 8 * kEps * scale / s);
    const Pose q = ik(m, p.P, p.mode);
    ASSERT_EQ(q.status, Status::ok);
    EXPECT_EQ(q.mode, p.mode);
    EXPECT_NEAR(std::remainder(q.theta1 - p.theta1, 2 * kPi), 0.0, 8 * kEps / s * 4);
    EXPECT_NEAR(std::remainder(q.theta2 - p.theta2, 2 * kPi), 0.0, 8 * kEps / s * 4);
    const Pose back = fk(m, q.theta1, q.theta2, p.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus);
    ASSERT_EQ(back.status, Status::ok);
    EXPECT_LE((back.P - p.P).norm(), 8 * kEps * scale / s);
    EXPECT_LE(q.closure_error_mm, tol::kClosureRel * scale);
  }
}

TEST_P(KinematicsRegime, IkSatisfiesTheLoopConstraintsAndModeSigns) {
  const Mechanism& m = GetParam().m;
  const double scale = m.length_scale();
  for (const Pose& p : regular_poses(m, test_seed() + 13, 100)) {
    for (WorkingMode mode : all_working_modes()) {
      const Pose q = ik(m, p.P, mode);
      ASSERT_NE(q.status, Status::unreachable);
      ASSERT_TRUE(finite_pose(q));
      EXPECT_NEAR((q.A1 - m.O1).norm(), m.L[0], 8 * kEps * scale);
      EXPECT_NEAR((q.A2 - m.O2).norm(), m.L[1], 8 * kEps * scale);
      EXPECT_NEAR((q.P - q.A1).norm(), m.L[2], 8 * kEps * scale);
      EXPECT_NEAR((q.P - q.A2).norm(), m.L[3], 8 * kEps * scale);
      const double c1 = (q.A1 - m.O1).x() * (q.P - q.A1).y() - (q.A1 - m.O1).y() * (q.P - q.A1).x();
      const double c2 = (q.A2 - m.O2).x() * (q.P - q.A2).y() - (q.A2 - m.O2).y() * (q.P - q.A2).x();
      if (q.status == Status::ok) {
        EXPECT_EQ(c1 > 0 ? 1 : -1, mode.sign1);
        EXPECT_EQ(c2 > 0 ? 1 : -1, mode.sign2);
      }
    }
  }
}

TEST_P(KinematicsRegime, JacobianMatchesCentralDifferences) {
  const Mechanism& m = GetParam().m;
  for (const Pose& p : regular_poses(m, test_seed() + 17, 100, 5e-2)) {
    const AssemblyMode br = p.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
    // Step well inside the pose's conditioning: derivatives of order k grow like 1/s^k.
    const double s = min_sin(p);
    const double h = std::cbrt(kEps) * s;
    Eigen::Matrix2d num;
    for (int j = 0; j < 2; ++j) {
      const double dt1 = j == 0 ? h : 0.0, dt2 = j == 1 ? h : 0.0;
      const Pose a = fk(m, p.theta1 + dt1, p.theta2 + dt2, br);
      const Pose b = fk(m, p.theta1 - dt1, p.theta2 - dt2, br);
      ASSERT_EQ(a.status, Status::ok);
      ASSERT_EQ(b.status, Status::ok);
      num.col(j) = (a.P - b.P) / (2 * h);
    }
    ASSERT_TRUE(p.jacobian_valid);
    // Truncation error ~ (h/s)^2 / s^2 relative, rounding ~ eps / h: 1e-6 / s^2 covers both.
    EXPECT_LE((num - p.J).norm(), 1e-6 * p.J.norm() / (s * s)) << "J =\n" << p.J << "\nnum =\n" << num;
    // LCI and force capability from Eigen's SVD of the same J.
    Eigen::JacobiSVD<Eigen::Matrix2d> svd(p.J);
    const auto sv = svd.singularValues();
    EXPECT_NEAR(p.lci, sv(1) / sv(0), 1e-12);
    EXPECT_NEAR(p.force_capability, 1.0 / sv(0), 1e-12 / sv(0));
  }
}

TEST_P(KinematicsRegime, ScaleChangesLengthsOnly) {
  const Mechanism& m = GetParam().m;
  for (const Pose& p : regular_poses(m, test_seed() + 19, 40)) {
    for (double s : {1e-3, 1e-1, 7.0, 1e3, 1e6}) {
      SCOPED_TRACE(s);
      const Mechanism ms = scaled(m, s);
      const Pose q = ik(ms, p.P * s, p.mode);
      ASSERT_EQ(q.status, Status::ok);
      const double tol_angle = 64 * kEps / min_sin(p);
      EXPECT_NEAR(std::remainder(q.theta1 - p.theta1, 2 * kPi), 0.0, tol_angle);
      EXPECT_NEAR(std::remainder(q.theta2 - p.theta2, 2 * kPi), 0.0, tol_angle);
      EXPECT_NEAR(q.lci, p.lci, 1e-9);
      EXPECT_NEAR(q.transmission[2], p.transmission[2], tol_angle);
      EXPECT_NEAR(q.J.norm(), p.J.norm() * s, 1e-9 * p.J.norm() * s);
      EXPECT_NEAR(q.force_capability, p.force_capability / s, 1e-9 * p.force_capability / s);
    }
  }
}

TEST_P(KinematicsRegime, BatchAgreesWithScalar) {
  const Mechanism& m = GetParam().m;
  const double scale = m.length_scale();
  std::mt19937_64 rng(test_seed() + 23);
  std::uniform_real_distribution<double> ang(-4.0, 4.0);
  const std::size_t n = 5000;
  std::vector<double> t1(n), t2(n), px(n), py(n), u1(n), u2(n), l(n);
  std::vector<Status> st(n), st2(n), st3(n);
  for (std::size_t k = 0; k < n; ++k) {
    t1[k] = ang(rng);
    t2[k] = ang(rng);
  }
  fk_batch(m, t1, t2, px, py, st);
  std::size_t ok = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const Pose p = fk(m, t1[k], t2[k]);
    SCOPED_TRACE(::testing::Message() << "theta " << t1[k] << ", " << t2[k]);
    ASSERT_TRUE(std::isfinite(px[k]) && std::isfinite(py[k]));
    if (p.status == Status::ok && min_sin(p) > 1e-6) {
      ASSERT_EQ(st[k], Status::ok);
      EXPECT_LE(std::hypot(px[k] - p.P.x(), py[k] - p.P.y()), 16 * kEps * scale / min_sin(p));
      ++ok;
    } else if (p.status == Status::unreachable) {
      EXPECT_TRUE(st[k] == Status::unreachable || std::fabs(p.type2_sin) < 1e-6);
    }
  }
  EXPECT_GT(ok, n / 10);
  // The lean scalar forms give the full forms' point and angles to the last bit (same arithmetic,
  // same libm).
  for (std::size_t k = 0; k < n; ++k) {
    const Pose p = fk(m, t1[k], t2[k]);
    const PointResult r = fk_point(m, t1[k], t2[k]);
    if (p.status == Status::ok && min_sin(p) > 1e-6) {
      ASSERT_EQ(r.status, Status::ok);
      EXPECT_EQ(r.P, p.P);
      const Pose q = ik(m, p.P);
      const AnglesResult a = ik_angles(m, p.P);
      if (q.status != Status::ok || min_sin(q) < 1e-6) continue;
      ASSERT_EQ(a.status, Status::ok);
      EXPECT_EQ(a.theta1, q.theta1);
      EXPECT_EQ(a.theta2, q.theta2);
      EXPECT_LE(a.closure_error_mm, tol::kClosureRel * scale);
    }
  }
  // IK batch of the FK points, verified by FK (loop closure), and LCI batch against scalar.
  ik_batch(m, px, py, u1, u2, st2);
  lci_batch(m, px, py, l, st3);
  for (std::size_t k = 0; k < n; ++k) {
    if (st[k] != Status::ok) continue;
    const Pose q = ik(m, {px[k], py[k]});
    SCOPED_TRACE(::testing::Message() << "P " << px[k] << ", " << py[k]);
    ASSERT_TRUE(std::isfinite(u1[k]) && std::isfinite(u2[k]) && std::isfinite(l[k]));
    if (q.status != Status::ok || min_sin(q) < 1e-6) continue;
    ASSERT_EQ(st2[k], Status::ok);
    ASSERT_EQ(st3[k], Status::ok);
    EXPECT_NEAR(u1[k], q.theta1, 8 * kEps);
    EXPECT_NEAR(u2[k], q.theta2, 8 * kEps);
    EXPECT_NEAR(l[k], q.lci, 1e-12);
    const Vec2 A1 = m.O1 + m.L[0] * Vec2(std::cos(u1[k]), std::sin(u1[k]));
    const Vec2 A2 = m.O2 + m.L[1] * Vec2(std::cos(u2[k]), std::sin(u2[k]));
    EXPECT_LE(std::fabs((Vec2(px[k], py[k]) - A1).norm() - m.L[2]), tol::kClosureRel * scale);
    EXPECT_LE(std::fabs((Vec2(px[k], py[k]) - A2).norm() - m.L[3]), tol::kClosureRel * scale);
  }
}

INSTANTIATE_TEST_SUITE_P(Regimes, KinematicsRegime, ::testing::ValuesIn(regimes()),
                         [](const auto& info) { return info.param.name; });

// --- paper stations: hand-checkable facts ------------------------------------------------------

TEST(PaperStation, SymmetricPoseAtEllipseCentre) {
  // Index lower, P on the symmetry line x = 6.25 at y = 15.5: the two legs mirror each other,
  // so theta2 = pi - theta1 and the elbows point outward (A1.x < 0 < 12.5 < A2.x).
  const Mechanism m = paper_mechanism("index", "lower");
  const Pose p = ik(m, {6.25, 15.5});
  ASSERT_EQ(p.status, Status::ok);
  EXPECT_NEAR(p.theta2, kPi - p.theta1, 1e-14);
  EXPECT_LT(p.A1.x(), 0.0);
  EXPECT_GT(p.A2.x(), 12.5);
  // Law of cosines for leg 1: |P - O1| = D, angle of O1P plus the angle at O1 opposite L3.
  const double D = std::hypot(6.25, 15.5);
  const double at_O1 = std::acos((81.0 + D * D - 225.0) / (2 * 9.0 * D));
  EXPECT_NEAR(p.theta1, std::atan2(15.5, 6.25) + at_O1, 1e-13);
  EXPECT_EQ(p.mode, (WorkingMode{-1, +1}));
  EXPECT_EQ(p.assembly, 1);
  EXPECT_GT(p.lci, 0.0);
  EXPECT_LE(p.lci, 1.0);
}

TEST(PaperStation, IkAllGivesFourDistinctVerifiedBranches) {
  const Mechanism m = paper_mechanism("thumb", "upper");
  const auto all = ik_all(m, {6.25, 17.5});
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(all[i].status, Status::ok);
    EXPECT_EQ(all[i].mode, all_working_modes()[i]);
    for (std::size_t j = 0; j < i; ++j)
      EXPECT_GT(std::hypot(all[i].theta1 - all[j].theta1, all[i].theta2 - all[j].theta2), 1e-3);
  }
}

TEST(PaperStation, UnreachablePointIsAStatusNotAnException) {
  const Mechanism m = paper_mechanism("index", "lower");
  const Pose p = ik(m, {6.25, 40.0});  // beyond L1 + L3 = 24 from both bases
  EXPECT_EQ(p.status, Status::unreachable);
  EXPECT_TRUE(finite_pose(p));
  const Pose q = fk(m, kPi, 0.0);  // elbows at (-9, 0) and (21.5, 0): 30.5 mm > L3 + L4 = 30
  EXPECT_EQ(q.status, Status::unreachable);
  EXPECT_TRUE(finite_pose(q));
}

TEST(PaperStation, FkAnyPicksTheWorkingModeBranch) {
  Mechanism m = paper_mechanism("index", "lower");
  const Pose ref = ik(m, {5.0, 14.0});
  m.assembly_mode = AssemblyMode::Any;
  const Pose p = fk(m, ref.theta1, ref.theta2);
  EXPECT_EQ(p.mode, m.working_mode);
  EXPECT_NEAR((p.P - Vec2(5.0, 14.0)).norm(), 0.0, 1e-13);
}

// --- extreme cases -----------------------------------------------------------------------------

/// Type I: P on the line from O1 at distance D = (L1 + L3)(1 - delta) (stretched) or
/// |L1 - L3|(1 + delta) (folded). Expected elbow |sin| from the law of cosines in long double.
TEST(Extreme, TypeOneTangencyFromOneTenthToExact) {
  Mechanism m = paper_mechanism("index", "lower");
  m.L = {9.0, 9.0, 15.0, 15.0};
  const double dir = deg(70.0);
  for (bool stretched : {true, false}) {
    for (int k = 1; k <= 17; ++k) {
      const double delta = k == 17 ? 0.0 : std::pow(10.0, -k);
      const double D0 = stretched ? m.L[0] + m.L[2] : std::fabs(m.L[0] - m.L[2]);
      const double D = stretched ? D0 * (1 - delta) : D0 * (1 + delta);
      const Vec2 P = m.O1 + D * Vec2(std::cos(dir), std::sin(dir));
      SCOPED_TRACE(::testing::Message() << (stretched ? "stretched" : "folded") << " delta " << delta);
      const Pose p = ik(m, P);
      ASSERT_TRUE(finite_pose(p));
      using LD = long double;
      const LD Dl = std::hypot(LD(P.x()), LD(P.y()));  // the distance actually posed
      const LD cg = (LD(81) + LD(225) - Dl * Dl) / (2 * LD(9) * LD(15));
      const double expected_sin = double(std::sqrt(std::max<LD>(0, 1 - cg * cg)));
      if (cg > 1 + 1e-15L || cg < -1 - 1e-15L) {
        EXPECT_TRUE(p.status == Status::unreachable || p.status == Status::singular_type1);
        continue;
      }
      ASSERT_NE(p.status, Status::unreachable) << expected_sin;
      if (expected_sin > 4 * tol::kSingularSin) {
        EXPECT_NE(p.status, Status::singular_type1);
        // The angle error the conditioning allows: eps / sin.
        EXPECT_NEAR(p.type1_sin[0], expected_sin, 64 * kEps / expected_sin + 1e-12);
      } else if (expected_sin < tol::kSingularSin / 4) {
        EXPECT_EQ(p.status, Status::singular_type1);
        EXPECT_LT(p.lci, 1e-6);
      }
      EXPECT_LE(p.closure_error_mm, tol::kClosureRel * m.length_scale());
      // Distance to the nearest type I circle (both legs, stretched and folded), independently.
      double nearest = std::fabs(double(Dl) - D0);
      const double D2 = std::hypot(P.x() - m.O2.x(), P.y() - m.O2.y());
      for (double r : {m.L[0] + m.L[2], std::fabs(m.L[0] - m.L[2])}) nearest = std::min(nearest, std::fabs(double(Dl) - r));
      for (double r : {m.L[1] + m.L[3], std::fabs(m.L[1] - m.L[3])}) nearest = std::min(nearest, std::fabs(D2 - r));
      EXPECT_NEAR(p.type1_distance_mm, nearest, 8 * kEps * D0);
    }
  }
}

/// Type II: elbows placed so that |A2 - A1| = (L3 + L4)(1 - delta): distal links nearly collinear.
TEST(Extreme, TypeTwoTangencyFromOneTenthToExact) {
  const Mechanism m = paper_mechanism("index", "lower");
  const double t1 = deg(150.0);
  using LD = long double;
  for (int k = 1; k <= 17; ++k) {
    const double delta = k == 17 ? 0.0 : std::pow(10.0, -k);
    // A2 on circle (O2, L2) at distance D from A1: intersect in long double, take theta2.
    const LD a1x = LD(m.L[0]) * std::cos(LD(t1)), a1y = LD(m.L[0]) * std::sin(LD(t1));
    const LD D = LD(m.L[2] + m.L[3]) * (1 - LD(delta));
    const LD dx = LD(12.5) - a1x, dy = -a1y, d = std::sqrt(dx * dx + dy * dy);
    const LD a = (d * d + LD(81) - D * D) / (2 * d);  // from O2 towards A1
    const LD h = std::sqrt(std::max<LD>(0, LD(81) - a * a));
    const LD ux = -dx / d, uy = -dy / d;
    const LD ex = a * ux - h * uy, ey = a * uy + h * ux;
    const double t2 = double(std::atan2(ey, ex));
    SCOPED_TRACE(::testing::Message() << "delta " << delta << " theta2 " << t2);
    const Pose p = fk(m, t1, t2, AssemblyMode::Plus);
    ASSERT_TRUE(finite_pose(p));
    // The |sin| at the tactor for the angles actually posed, in long double.
    const LD b1x = LD(m.L[0]) * std::cos(LD(t1)), b1y = LD(m.L[0]) * std::sin(LD(t1));
    const LD b2x = LD(12.5) + LD(m.L[1]) * std::cos(LD(t2)), b2y = LD(m.L[1]) * std::sin(LD(t2));
    const LD dd = std::hypot(b2x - b1x, b2y - b1y);
    const LD cm = (LD(225) + LD(225) - dd * dd) / (2 * LD(225));
    if (cm < -1) {
      EXPECT_TRUE(p.status == Status::unreachable || p.status == Status::singular_type2);
      continue;
    }
    const double expected_sin = double(std::sqrt(std::max<LD>(0, 1 - cm * cm)));
    if (expected_sin > 4 * tol::kSingularSin) {
      EXPECT_EQ(p.status, Status::ok) << expected_sin;
      EXPECT_TRUE(p.jacobian_valid);
      EXPECT_NEAR(p.type2_sin, expected_sin, 64 * kEps / expected_sin + 1e-12);
    } else if (expected_sin < tol::kSingularSin / 4) {
      EXPECT_TRUE(p.status == Status::singular_type2 || p.status == Status::unreachable);
      EXPECT_FALSE(p.jacobian_valid);
      EXPECT_EQ(p.lci, 0.0);
    }
  }
}

TEST(Extreme, LinkRatiosFromTenThousandthToTenThousand) {
  for (double r : {1e-4, 1e-3, 1e-2, 1e-1, 1.0, 1e1, 1e2, 1e3, 1e4}) {
    Mechanism m;
    m.O1 = {0, 0};
    m.O2 = {1.0, 0};
    // Proximal links r times the distal ones; the base distance is kept reachable.
    m.L = {r, r, 1.0, 1.0};
    m.working_mode = {-1, +1};
    m.assembly_mode = AssemblyMode::Any;
    SCOPED_TRACE(r);
    const auto poses = regular_poses(m, test_seed() + 29, 50, 1e-3);
    ASSERT_FALSE(poses.empty());
    for (const Pose& p : poses) {
      const Pose q = ik(m, p.P, p.mode);
      ASSERT_TRUE(finite_pose(q));
      ASSERT_NE(q.status, Status::unreachable);
      EXPECT_LE(q.closure_error_mm, tol::kClosureRel * m.length_scale());
      EXPECT_NEAR((q.A1 - m.O1).norm(), m.L[0], 16 * kEps * m.length_scale());
    }
  }
}

TEST(Extreme, EqualProximalAndDistalLinksIkCircleThroughTheBase) {
  Mechanism m = paper_mechanism("index", "lower");
  m.L = {9.0, 9.0, 9.0, 9.0};
  // At P = O1 leg 1 is folded onto itself: any theta1 closes the loop; the status says singular.
  const Pose at_base = ik(m, m.O1);
  EXPECT_EQ(at_base.status, Status::singular_type1);
  EXPECT_TRUE(finite_pose(at_base));
  EXPECT_LE(at_base.closure_error_mm, tol::kClosureRel * m.length_scale());
  // Near the base the legs are nearly folded: |sin| ~ D / (2 L): reported, finite, closed.
  for (double D : {1e-1, 1e-4, 1e-8, 1e-12}) {
    const Pose p = ik(m, {D * 0.6, D * 0.8});
    ASSERT_TRUE(finite_pose(p)) << D;
    ASSERT_NE(p.status, Status::unreachable) << D;
    EXPECT_NEAR(p.type1_sin[0], D / 9.0 * std::sqrt(1 - D * D / 324.0), 1e-6 * D + 64 * kEps);
  }
}

TEST(Extreme, CoincidentBaseJoints) {
  Mechanism m = paper_mechanism("index", "lower");
  m.O2 = m.O1;
  for (const Pose& p : regular_poses(m, test_seed() + 31, 50, 1e-3)) {
    const Pose q = ik(m, p.P, p.mode);
    ASSERT_TRUE(finite_pose(q));
    EXPECT_EQ(q.status, Status::ok);
    EXPECT_LE(q.closure_error_mm, tol::kClosureRel * m.length_scale());
  }
  // Both elbows coincide with equal distal links: FK has a continuum; flagged type II.
  Mechanism n = m;
  n.L = {9, 9, 15, 15};
  const Pose p = fk(n, 0.3, 0.3, AssemblyMode::Plus);
  EXPECT_TRUE(finite_pose(p));
  EXPECT_EQ(p.status, Status::singular_type2);
}

/// A tactor a subnormal distance from a base (d^2 below the smallest normal double, so 1/d^2 would
/// overflow) with equal proximal and distal links (the IK circle passes through the base, so the
/// inner tangency d^2 = 0 does not exclude it): every batch output stays finite.
TEST(Extreme, SubnormalDistanceFromABaseNeverProducesNaN) {
  Mechanism m = paper_mechanism("index", "lower");
  m.L = {9.0, 9.0, 9.0, 9.0};
  const std::vector<double> px = {m.O1.x(), m.O1.x() + 1e-160, m.O1.x() + 3e-155, m.O2.x()};
  const std::vector<double> py = {m.O1.y() + 1e-160, m.O1.y(), m.O1.y() + 1e-170, m.O2.y() + 1e-162};
  const std::size_t n = px.size();
  std::vector<double> t1(n), t2(n), l(n), f(n);
  std::vector<Status> st(n), st2(n), st3(n);
  std::vector<std::int8_t> as(n);
  ik_batch(m, px, py, t1, t2, st);
  lci_batch(m, px, py, l, st2);
  conditioning_batch(m, px, py, l, f, as, st3);
  for (std::size_t k = 0; k < n; ++k) {
    SCOPED_TRACE(k);
    EXPECT_TRUE(std::isfinite(t1[k]) && std::isfinite(t2[k]) && std::isfinite(l[k]) && std::isfinite(f[k]));
    const AnglesResult a = ik_angles(m, {px[k], py[k]});
    EXPECT_TRUE(std::isfinite(a.theta1) && std::isfinite(a.theta2) && std::isfinite(a.closure_error_mm));
    EXPECT_TRUE(finite_pose(ik(m, {px[k], py[k]})));
  }
  // The full path's intersection at that scale: circles of radius 1e-160 whose centres are 1e-160
  // apart (d^2 subnormal) are treated as concentric, not divided through.
  const CircleIntersection x = intersect_circles({0, 0}, 1e-160, {1e-160, 0}, 1e-160, +1);
  EXPECT_TRUE(x.point.allFinite() && std::isfinite(x.h));
}

TEST(Extreme, NonFiniteAndHugeAnglesNeverProduceNaN) {
  const Mechanism m = paper_mechanism("index", "lower");
  // Spread over several of fk_batch's blocks (256 points), and the last element, so that a flag
  // lost between blocks would leave a fast-path result for one of them.
  std::vector<double> t1(700, 0.5), t2(700, 2.0);
  const double bad[] = {1e7, -3e9, 1e300, std::nan(""), INFINITY, -INFINITY};
  const std::size_t where[] = {0, 255, 256, 400, 513, 699};
  for (int i = 0; i < 6; ++i) t1[where[i]] = bad[i];
  std::vector<double> px(t1.size()), py(t1.size());
  std::vector<Status> st(t1.size());
  fk_batch(m, t1, t2, px, py, st);
  for (std::size_t k = 0; k < t1.size(); ++k) {
    EXPECT_TRUE(std::isfinite(px[k]) && std::isfinite(py[k])) << k;
    if (std::isfinite(t1[k])) {
      const Pose p = fk(m, t1[k], t2[k]);
      EXPECT_EQ(st[k], p.status);
      EXPECT_EQ(px[k], p.P.x());
    } else {
      EXPECT_EQ(st[k], Status::unreachable);
    }
  }
}

TEST(Lci, ClosedFormAgainstSvd) {
  std::mt19937_64 rng(test_seed() + 37);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < 1000; ++k) {
    Eigen::Matrix2d J;
    J << u(rng), u(rng), u(rng), u(rng);
    Eigen::JacobiSVD<Eigen::Matrix2d> svd(J);
    EXPECT_NEAR(lci(J), svd.singularValues()(1) / svd.singularValues()(0), 1e-13);
  }
  EXPECT_EQ(lci(Eigen::Matrix2d::Zero()), 0.0);
  EXPECT_EQ(lci(Eigen::Matrix2d::Identity() * 3), 1.0);
  Eigen::Matrix2d rank1;
  rank1 << 1, 2, 2, 4;
  EXPECT_EQ(lci(rank1), 0.0);
  // Condition number 1e14 (the stiff end): still resolved.
  Eigen::Matrix2d stiff;
  stiff << 1e7, 0, 0, 1e-7;
  EXPECT_NEAR(lci(stiff), 1e-14, 1e-27);
}

}  // namespace
}  // namespace fivebar
