// Workspace: exact (CGAL) areas against closed forms derived here, scaling, topology, point
// queries against IK, and sampled (marching-squares) areas converging to the exact ones.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <random>

#include "fivebar/workspace/region.hpp"
#include "paper.hpp"

namespace fivebar {
namespace {

constexpr double kPi = std::numbers::pi;

using ::fivebar::testing::paper_mechanism;
using ::fivebar::testing::test_seed;

/// Lens area of two disks (radii a, b, centre distance d), written out here independently.
double lens(double a, double b, double d) {
  if (a <= 0 || b <= 0 || d >= a + b) return 0.0;
  if (d <= std::fabs(a - b)) return kPi * std::min(a, b) * std::min(a, b);
  const double alpha = std::acos((d * d + a * a - b * b) / (2 * d * a));  // half-angle at centre a
  const double beta = std::acos((d * d + b * b - a * a) / (2 * d * b));
  // Two circular segments: r^2 (phi - sin phi) / 2 with phi = 2 alpha, 2 beta.
  return 0.5 * a * a * (2 * alpha - std::sin(2 * alpha)) + 0.5 * b * b * (2 * beta - std::sin(2 * beta));
}

double annuli_area_reference(const Mechanism& m) {
  const double d = (m.O2 - m.O1).norm();
  const double R1 = m.L[0] + m.L[2], r1 = std::fabs(m.L[0] - m.L[2]);
  const double R2 = m.L[1] + m.L[3], r2 = std::fabs(m.L[1] - m.L[3]);
  return lens(R1, R2, d) - lens(R1, r2, d) - lens(r1, R2, d) + lens(r1, r2, d);
}

std::vector<Mechanism> geometries() {
  std::vector<Mechanism> out = {paper_mechanism("index", "lower"), paper_mechanism("index", "upper"), paper_mechanism("thumb", "lower"),
                                paper_mechanism("thumb", "upper")};
  std::mt19937_64 rng(test_seed());
  std::uniform_real_distribution<double> len(2.0, 25.0), base(0.0, 20.0);
  while (out.size() < 16) {
    Mechanism m = paper_mechanism("index", "lower");
    m.O2 = {base(rng), 0.5 * base(rng)};
    m.L = {len(rng), len(rng), len(rng), len(rng)};
    if (annuli_area_reference(m) < 1.0) continue;
    out.push_back(m);
  }
  return out;
}

TEST(ExactRegion, AreaEqualsClosedFormOfIntersectingAnnuli) {
  for (const Mechanism& m : geometries()) {
    SCOPED_TRACE(::testing::Message() << "O2 " << m.O2.transpose() << " L " << m.L[0] << " " << m.L[1] << " "
                                    << m.L[2] << " " << m.L[3]);
    const Region r = reachable_region(m);
    const double ref = annuli_area_reference(m);
    EXPECT_NEAR(r.area_mm2(), ref, 1e-9 * ref);
    EXPECT_NEAR(annuli_intersection_area(m), ref, 1e-9 * ref);
    EXPECT_GT(r.perimeter_mm(), 0.0);
  }
}

TEST(ExactRegion, AreaScalesWithTheSquareOfTheScale) {
  const Mechanism m = paper_mechanism("thumb", "upper");
  const double a1 = reachable_region(m).area_mm2();
  for (double s : {1e-3, 0.5, 3.0, 1e3}) {
    Mechanism ms = m;
    ms.O1 *= s;
    ms.O2 *= s;
    for (double& l : ms.L) l *= s;
    EXPECT_NEAR(reachable_region(ms).area_mm2(), a1 * s * s, 1e-9 * a1 * s * s) << s;
  }
}

TEST(ExactRegion, PaperIndexLowerHasOneComponentWithTwoHoles) {
  // Inner circles (radius |9 - 15| = 6) around O1 and O2 lie inside the other leg's annulus
  // (their points are 6.5 ... 18.5 mm from the other base, inside [6, 24]): two holes.
  const Region r = reachable_region(paper_mechanism("index", "lower"));
  EXPECT_EQ(r.components(), 1);
  EXPECT_EQ(r.holes(), 2);
  // Perimeter: two full hole circles plus the outer boundary (two arcs of radius 24 meeting at
  // x = 6.25): 2 * 2 pi 6 + 2 * 24 * 2 acos(6.25 / 24).
  EXPECT_NEAR(r.perimeter_mm(), 4 * kPi * 6 + 2 * 24 * 2 * std::acos(6.25 / 24), 1e-9 * r.perimeter_mm());
}

/// One leg with joint limits, the other leg a disk around the same base that contains it: the
/// region is the leg's curvilinear rectangle, whose area is the integral of the Jacobian
/// |det d(P)/d(theta, psi)| = L1 L3 |sin psi| over [lo, hi] x [0, pi]: 2 L1 L3 (hi - lo).
TEST(ExactRegion, JointLimitedLegAreaIsTwiceL1L3TimesTheSpan) {
  for (int sigma : {-1, 1}) {
    for (double span_deg : {10.0, 45.0, 90.0, 180.0, 300.0}) {
      for (double lo_deg : {-170.0, -20.0, 35.0, 120.0}) {
        Mechanism m;
        m.O1 = {1.0, 2.0};
        m.O2 = m.O1;
        m.L = {9.0, 24.0, 15.0, 24.0};  // leg 2: disk of radius 48 around the same base
        m.working_mode = {std::int8_t(sigma), 1};
        const double lo = lo_deg * kPi / 180, hi = (lo_deg + span_deg) * kPi / 180;
        m.joint_limits = std::array<JointRange, 2>{JointRange{lo, hi}, JointRange{-kPi, kPi}};
        SCOPED_TRACE(::testing::Message() << "sigma " << sigma << " lo " << lo_deg << " span " << span_deg);
        const Region r = reachable_region(m);
        EXPECT_NEAR(r.area_mm2(), 2 * 9.0 * 15.0 * (hi - lo), 1e-9 * 2 * 9 * 15 * (hi - lo));
        EXPECT_EQ(r.components(), 1);
      }
    }
  }
}

TEST(ExactRegion, MembershipAgreesWithIkAndJointLimits) {
  std::mt19937_64 rng(test_seed() + 1);
  std::vector<Mechanism> ms = geometries();
  Mechanism limited = paper_mechanism("index", "lower");
  limited.joint_limits = std::array<JointRange, 2>{JointRange{0.5, 2.9}, JointRange{-0.2, 2.0}};
  ms.push_back(limited);
  for (const Mechanism& m : ms) {
    const Region r = reachable_region(m);
    const auto b = r.bounds();
    std::uniform_real_distribution<double> ux(b[0] - 2, b[2] + 2), uy(b[1] - 2, b[3] + 2);
    int inside = 0;
    for (int k = 0; k < 2000; ++k) {
      const Vec2 p(ux(rng), uy(rng));
      const Pose pose = ik(m, p);
      const bool reach = pose.status != Status::unreachable && pose.within_joint_limits;
      if (r.boundary_distance(p) < 1e-9 * m.length_scale()) continue;  // undecidable in double
      EXPECT_EQ(r.contains(p), reach) << p.transpose();
      inside += reach;
    }
    EXPECT_GT(inside, 50);
  }
}

TEST(ExactRegion, BoundaryDistanceOfAnnuliRegionIsTheActiveConstraint) {
  const Mechanism m = paper_mechanism("index", "lower");
  const Region r = reachable_region(m);
  // On the symmetry line x = 6.25 both legs are alike: the boundary is the outer circle (24 mm)
  // or a hole (6 mm) around either base, whichever is nearer.
  for (double y : {8.0, 10.0, 15.5, 20.0, -12.0}) {
    const Vec2 p(6.25, y);
    EXPECT_NEAR(r.signed_distance(p), std::min(24.0 - p.norm(), p.norm() - 6.0), 1e-12) << y;
  }
  EXPECT_NEAR(r.signed_distance({0.0, 3.0}), -3.0, 1e-12);    // inside the hole around O1
  // Outside above: the nearest boundary point is the corner where the outer arcs meet.
  EXPECT_NEAR(r.signed_distance({6.25, 30.0}), -(30.0 - std::sqrt(24.0 * 24.0 - 6.25 * 6.25)), 1e-12);
}

TEST(SampledArea, ReachConvergesToTheExactAreaAsTheGridIsRefined) {
  Mechanism m = paper_mechanism("index", "lower");
  m.joint_limits = std::array<JointRange, 2>{JointRange{0.3, 3.0}, JointRange{0.1, 2.8}};
  const Region r = reachable_region(m);
  double last_error = INFINITY;
  for (double h : {0.8, 0.4, 0.2}) {
    const SampledArea s = restricted_area(m, Restriction::reach, Grid::covering(r.bounds(), h, 2 * h));
    const double err = std::fabs(s.area_mm2 - r.area_mm2());
    SCOPED_TRACE(h);
    EXPECT_LT(err, last_error);
    EXPECT_LT(err, s.error_mm2);  // the estimate is conservative
    EXPECT_GT(err, 0.05 * s.error_mm2);  // ... but of the right size
    last_error = err;
  }
  EXPECT_LT(last_error, 1e-3 * r.area_mm2());
}

TEST(SampledArea, AssemblyAndLciRegionsAreNestedInsideReach) {
  Mechanism m = paper_mechanism("thumb", "lower");
  m.min_lci = 0.3;
  const Region r = reachable_region(m);
  const Grid g = Grid::covering(r.bounds(), 0.25, 0.5);
  const double reach = restricted_area(m, Restriction::reach, g).area_mm2;
  const double assembly = restricted_area(m, Restriction::assembly, g).area_mm2;
  const double lci = restricted_area(m, Restriction::lci, g).area_mm2;
  EXPECT_LT(assembly, reach);
  EXPECT_LT(lci, assembly);
  EXPECT_GT(lci, 0.0);
}

// The margin of every restriction, written here from the full pose of ik() as the definition
// reads (the annuli in mm, the assembly side as cross(P - A1, P - A2) / (L3 + L4), the LCI
// shortfall times the length scale): restriction_margin() takes a leaner path without joint
// limits and must give the same double at every point, assembly mode any included.
TEST(SampledArea, MarginOfEachRestrictionEqualsTheOneFromTheFullPose) {
  std::mt19937_64 rng(test_seed());
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Mechanism> ms = geometries();
  ms[1].assembly_mode = AssemblyMode::Any;
  int inside = 0;
  for (Mechanism m : ms) {
    m.min_lci = 0.3;
    const auto b = reachable_region(m).bounds();
    for (int k = 0; k < 400; ++k) {
      const Vec2 p(b[0] - 1 + (b[2] - b[0] + 2) * u(rng), b[1] - 1 + (b[3] - b[1] + 2) * u(rng));
      double reach = std::numeric_limits<double>::infinity();
      for (int i = 0; i < 2; ++i) {
        const double d = (p - (i == 0 ? m.O1 : m.O2)).norm();
        reach = std::min(reach, m.L[i] + m.L[i + 2] - d);
        if (std::fabs(m.L[i] - m.L[i + 2]) > 0.0) reach = std::min(reach, d - std::fabs(m.L[i] - m.L[i + 2]));
      }
      const Pose pose = ik(m, p);
      double assembly = reach, lci = reach;
      if (!(reach < 0.0)) {
        if (pose.status == Status::unreachable) {
          reach = assembly = lci = std::min(reach, 0.0);
        } else {
          ++inside;
          const Vec2 f1 = pose.P - pose.A1, f2 = pose.P - pose.A2;
          if (m.assembly_mode != AssemblyMode::Any) {
            assembly = std::min(assembly, double(int(m.assembly_mode)) * (f1.x() * f2.y() - f1.y() * f2.x()) / (m.L[2] + m.L[3]));
          }
          lci = std::min(assembly, (pose.lci - m.min_lci) * m.length_scale());
        }
      }
      EXPECT_EQ(restriction_margin(m, Restriction::reach, p), reach);
      EXPECT_EQ(restriction_margin(m, Restriction::assembly, p), assembly);
      EXPECT_EQ(restriction_margin(m, Restriction::lci, p), lci) << p.transpose();
    }
  }
  EXPECT_GT(inside, 2000);
}

TEST(Field, SamplesMatchTheScalarKinematics) {
  const Mechanism m = paper_mechanism("index", "upper");
  const Region r = reachable_region(m);
  const WorkspaceField f = sample_field(m, Grid::covering(r.bounds(), 1.0, 1.0));
  int reach = 0;
  for (int j = 0; j < f.grid.ny; ++j) {
    for (int i = 0; i < f.grid.nx; ++i) {
      const std::size_t k = std::size_t(j) * f.grid.nx + i;
      const Vec2 p = f.grid.point(i, j);
      const Pose pose = ik(m, p);
      ASSERT_EQ(f.reach[k] != 0, pose.status != Status::unreachable);
      if (!f.reach[k]) continue;
      ++reach;
      EXPECT_EQ(f.lci[k], pose.lci);
      EXPECT_EQ(f.force_capability[k], pose.force_capability);
      if (r.boundary_distance(p) > 1e-9) EXPECT_TRUE(r.contains(p));
    }
  }
  EXPECT_GT(reach, 100);
}

}  // namespace
}  // namespace fivebar
