// `fivebar report`: the __float128 reference checked against long double and against its own
// central differences; the work-precision series converge at the orders their methods have; the
// stability catalogue passes on the paper's stations and on random geometries, with no NaN; the
// output (JSON, text, plots), the `report` product and the CLI end to end.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <random>
#include <sstream>

#include "cli_test.hpp"
#include "fivebar/coverage/coverage.hpp"
#include "fivebar/report.hpp"
#include "fivebar/scene.hpp"
#include "fivebar/workspace/region.hpp"
#include "report/precision.hpp"
#include "report/quad.hpp"

namespace fivebar {
namespace {

namespace fs = std::filesystem;
namespace ft = ::fivebar::testing;
using ft::Outcome;
using ft::slurp;
using ::testing::AllOf;
using ::testing::HasSubstr;
using quadref::quad;
using LD = long double;

constexpr double kPi = std::numbers::pi;
constexpr double kEps = std::numeric_limits<double>::epsilon();

std::uint64_t test_seed() {
  if (const char* s = std::getenv("FIVEBAR_TEST_SEED")) return std::strtoull(s, nullptr, 10);
  return 20220923;
}

/// Paper Table 1.
Mechanism paper(const std::string& station, const std::string& which) {
  Mechanism m;
  m.name = which;
  const double distal = station == "index" ? 15.0 : 17.5;
  const double y = which == "lower" ? 0.0 : (station == "index" ? 31.0 : 35.0);
  m.O1 = {0.0, y};
  m.O2 = {12.5, y};
  m.L = {9.0, 9.0, distal, distal};
  m.working_mode = which == "lower" ? WorkingMode{-1, +1} : WorkingMode{+1, -1};
  m.assembly_mode = which == "lower" ? AssemblyMode::Plus : AssemblyMode::Minus;
  return m;
}

Ellipse index_target() {
  Ellipse e;
  e.center = {6.25, 15.5};
  e.axes = {15.0, 12.0};
  return e;
}

std::string describe(const Mechanism& m) {
  std::ostringstream s;
  s.precision(17);
  s << "O1 (" << m.O1.x() << ", " << m.O1.y() << ") O2 (" << m.O2.x() << ", " << m.O2.y() << ") L " << m.L[0] << " "
    << m.L[1] << " " << m.L[2] << " " << m.L[3] << " mode " << to_string(m.working_mode) << " assembly "
    << to_string(m.assembly_mode);
  return s.str();
}

// --- long double references written here (law of cosines with acos; easy cases only) ------------

struct LdPoint {
  bool ok = false;
  LD x = 0, y = 0;
};

LdPoint ld_fk(const Mechanism& m, double t1, double t2, int side) {
  const LD a1x = LD(m.O1.x()) + LD(m.L[0]) * std::cos(LD(t1)), a1y = LD(m.O1.y()) + LD(m.L[0]) * std::sin(LD(t1));
  const LD a2x = LD(m.O2.x()) + LD(m.L[1]) * std::cos(LD(t2)), a2y = LD(m.O2.y()) + LD(m.L[1]) * std::sin(LD(t2));
  const LD d = std::hypot(a2x - a1x, a2y - a1y), L3 = m.L[2], L4 = m.L[3];
  const LD c = (d * d + L3 * L3 - L4 * L4) / (2 * d * L3);
  if (c < -1 || c > 1) return {};
  const LD phi = std::atan2(a2y - a1y, a2x - a1x) + side * std::acos(c);
  return {true, a1x + L3 * std::cos(phi), a1y + L3 * std::sin(phi)};
}

std::array<LD, 2> ld_ik(const Mechanism& m, double px, double py) {
  std::array<LD, 2> out{};
  for (int i = 0; i < 2; ++i) {
    const Vec2& O = i == 0 ? m.O1 : m.O2;
    const LD dx = LD(px) - LD(O.x()), dy = LD(py) - LD(O.y()), D = std::hypot(dx, dy);
    const LD Lp = m.L[i], Ld = m.L[i + 2];
    const LD beta = std::acos((D * D + Lp * Lp - Ld * Ld) / (2 * D * Lp));
    const int sigma = i == 0 ? m.working_mode.sign1 : m.working_mode.sign2;
    out[i] = std::atan2(dy, dx) - sigma * beta;
  }
  return out;
}

/// Joint angles of m with every |sin| >= 0.2 (quad reference), from a seeded generator; with
/// `in_mode`, only configurations in m's working mode (so that IK returns to them).
std::vector<std::array<double, 2>> regular_angles(const Mechanism& m, int side, std::mt19937_64& rng, int count,
                                                  bool in_mode = false) {
  std::uniform_real_distribution<double> u(-kPi, kPi);
  const quadref::QMechanism qm(m);
  std::vector<std::array<double, 2>> out;
  for (int tries = 0; tries < 100000 && int(out.size()) < count; ++tries) {
    const double t1 = u(rng), t2 = u(rng);
    const quadref::QPose p = quadref::fk(qm, t1, t2, side);
    if (!p.reachable) continue;
    if (std::min({p.type1_sin[0], p.type1_sin[1], p.type2_sin}) < quad(0.2)) continue;
    if (in_mode) {
      const quad c1 = quadref::cross(p.A1 - qm.O1, p.P - p.A1), c2 = quadref::cross(p.A2 - qm.O2, p.P - p.A2);
      if ((c1 > 0 ? 1 : -1) != m.working_mode.sign1 || (c2 > 0 ? 1 : -1) != m.working_mode.sign2) continue;
    }
    out.push_back({t1, t2});
  }
  return out;
}

// --- the quad reference ----------------------------------------------------------------------------

TEST(QuadReference, FkAgreesWithLongDoubleOnRegularPoses) {
  std::mt19937_64 rng(test_seed());
  for (const auto& [station, which] : {std::pair{"index", "lower"}, {"thumb", "upper"}}) {
    const Mechanism m = paper(station, which);
    const int side = m.assembly_mode == AssemblyMode::Minus ? -1 : 1;
    const precision::MechanismT<LD> mt(m);
    const auto angles = regular_angles(m, side, rng, 200);
    ASSERT_EQ(angles.size(), 200u);
    for (const auto& [t1, t2] : angles) {
      SCOPED_TRACE(::testing::Message() << station << "/" << which << " theta " << t1 << ", " << t2);
      const quadref::QPose q = quadref::fk(quadref::QMechanism(m), t1, t2, side);
      // Independent long double forms: the chord form and the acos form. |sin| >= 0.2 bounds
      // their rounding by ~5 * a few eps_ld * 30 mm; the quad value must sit within that.
      const double tol = 64 * double(std::numeric_limits<LD>::epsilon()) * 30.0 / 0.2;
      LD px, py;
      ASSERT_TRUE(precision::fk(mt, LD(t1), LD(t2), side, px, py));
      EXPECT_LT(double(hypotq(quad(px) - q.P.x, quad(py) - q.P.y)), tol);
      const LdPoint a = ld_fk(m, t1, t2, side);
      ASSERT_TRUE(a.ok);
      EXPECT_LT(double(hypotq(quad(a.x) - q.P.x, quad(a.y) - q.P.y)), tol);
      // The quad point closes the loop to quad precision.
      EXPECT_LT(double(quadref::qabs(quadref::norm(q.P - q.A1) - quad(m.L[2]))), 1e-28);
      EXPECT_LT(double(quadref::qabs(quadref::norm(q.P - q.A2) - quad(m.L[3]))), 1e-28);
    }
  }
}

TEST(QuadReference, IkAgreesWithLongDoubleAndFkOfItReturns) {
  std::mt19937_64 rng(test_seed() + 1);
  const Mechanism m = paper("index", "lower");
  const precision::MechanismT<LD> mt(m);
  const auto angles = regular_angles(m, 1, rng, 200, true);
  ASSERT_EQ(angles.size(), 200u);
  for (const auto& [t1, t2] : angles) {
    const quadref::QPose f = quadref::fk(quadref::QMechanism(m), t1, t2, 1);
    const double px = double(f.P.x), py = double(f.P.y);
    const quadref::QPose q = quadref::ik(quadref::QMechanism(m), {px, py}, m.working_mode.sign1, m.working_mode.sign2);
    ASSERT_TRUE(q.reachable);
    SCOPED_TRACE(::testing::Message() << "P " << px << ", " << py);
    const double tol = 64 * double(std::numeric_limits<LD>::epsilon()) / 0.1;  // rad; elbow |sin| >= ~0.2
    LD a, b;
    ASSERT_TRUE(precision::ik(mt, LD(px), LD(py), a, b));
    EXPECT_LT(double(quadref::qabs(remainderq(quad(a) - q.theta1, 2 * quadref::kQuadPi))), tol);
    EXPECT_LT(double(quadref::qabs(remainderq(quad(b) - q.theta2, 2 * quadref::kQuadPi))), tol);
    const auto c = ld_ik(m, px, py);
    EXPECT_LT(double(quadref::qabs(remainderq(quad(c[0]) - q.theta1, 2 * quadref::kQuadPi))), tol);
    EXPECT_LT(double(quadref::qabs(remainderq(quad(c[1]) - q.theta2, 2 * quadref::kQuadPi))), tol);
    // The rounded P is within ~eps of FK's point, so IK returns the FK angles to ~eps / sin.
    EXPECT_LT(double(quadref::qabs(remainderq(q.theta1 - quad(t1), 2 * quadref::kQuadPi))), 1e-13);
    // Realised working-mode signs are the design's.
    const quad c1 = quadref::cross(q.A1 - quadref::q(m.O1), q.P - q.A1);
    const quad c2 = quadref::cross(q.A2 - quadref::q(m.O2), q.P - q.A2);
    EXPECT_EQ(c1 > 0 ? 1 : -1, m.working_mode.sign1);
    EXPECT_EQ(c2 > 0 ? 1 : -1, m.working_mode.sign2);
  }
}

TEST(QuadReference, JacobianMatchesQuadCentralDifferencesAndLciMatchesSvd) {
  std::mt19937_64 rng(test_seed() + 2);
  const Mechanism m = paper("thumb", "lower");
  const quadref::QMechanism qm(m);
  for (const auto& [t1, t2] : regular_angles(m, 1, rng, 50)) {
    const quadref::QPose p = quadref::fk(qm, t1, t2, 1);
    ASSERT_TRUE(p.jacobian_valid);
    const quad h = quad(1e-12);
    for (int j = 0; j < 2; ++j) {
      const quadref::QPose a = quadref::fk(qm, t1 + (j == 0 ? h : 0), t2 + (j == 1 ? h : 0), 1);
      const quadref::QPose b = quadref::fk(qm, t1 - (j == 0 ? h : 0), t2 - (j == 1 ? h : 0), 1);
      // Central difference: truncation ~h^2 |P'''| ~ 1e-24 * L, rounding ~eps_q L / h ~ 1e-21.
      EXPECT_LT(double(quadref::qabs((a.P.x - b.P.x) / (2 * h) - p.J[0][j])), 1e-18);
      EXPECT_LT(double(quadref::qabs((a.P.y - b.P.y) / (2 * h) - p.J[1][j])), 1e-18);
    }
    Eigen::Matrix<LD, 2, 2> J;
    J << LD(p.J[0][0]), LD(p.J[0][1]), LD(p.J[1][0]), LD(p.J[1][1]);
    const Eigen::JacobiSVD<Eigen::Matrix<LD, 2, 2>> svd(J);
    const LD lci = svd.singularValues()(1) / svd.singularValues()(0);
    EXPECT_NEAR(double(p.lci), double(lci), 1e-15);
  }
}

TEST(QuadReference, ClosedFormAreaAndMarginAgainstLongDoubleAndBruteForce) {
  for (const auto& [station, which] : {std::pair{"index", "lower"}, {"thumb", "lower"}}) {
    const Mechanism m = paper(station, which);
    // Lens areas in long double with acos (well-conditioned here: no tangent circles).
    auto lens = [](LD a, LD b, LD d) -> LD {
      if (d >= a + b) return 0;
      if (d <= std::fabs(a - b)) return std::numbers::pi_v<LD> * std::min(a, b) * std::min(a, b);
      const LD k = std::sqrt((-d + a + b) * (d + a - b) * (d - a + b) * (d + a + b));
      return a * a * std::acos((d * d + a * a - b * b) / (2 * d * a)) +
             b * b * std::acos((d * d + b * b - a * a) / (2 * d * b)) - k / 2;
    };
    const LD d = 12.5, R = 9 + LD(m.L[2]), r = LD(m.L[2]) - 9;
    const LD ld_area = lens(R, R, d) - 2 * lens(R, r, d) + lens(r, r, d);
    const quad q_area = quadref::annuli_area(quadref::QMechanism(m));
    EXPECT_NEAR(double(q_area), double(ld_area), 1e-16 * double(ld_area)) << station;
    // The exact (CGAL) region agrees with both to rounding.
    EXPECT_NEAR(reachable_region(m).area_mm2(), double(q_area), 1e-12 * double(q_area)) << station;

    // Margin: brute force over 2e5 boundary points and the filled ellipse's centre (the
    // distances' extremes lie on the boundary for base joints outside the ellipse).
    Ellipse e = index_target();
    e.angle = 0.3;
    double brute = INFINITY;
    for (int i = 0; i < 2; ++i) {
      const Vec2& O = i == 0 ? m.O1 : m.O2;
      LD dmin = INFINITY, dmax = 0;
      for (int k = 0; k < 200000; ++k) {
        const LD t = 2 * std::numbers::pi_v<LD> * k / 200000;
        const LD x = LD(7.5) * std::cos(t), y = LD(6) * std::sin(t);
        const LD c = std::cos(LD(0.3)), s = std::sin(LD(0.3));
        const LD dist = std::hypot(LD(6.25) + c * x - s * y - LD(O.x()), LD(15.5) + s * x + c * y - LD(O.y()));
        dmin = std::min(dmin, dist);
        dmax = std::max(dmax, dist);
      }
      brute = std::min({brute, double(R - dmax), double(dmin - r)});
    }
    const double qm = double(quadref::annuli_margin(quadref::QMechanism(m), e));
    // Sampling misses an extreme by at most ~R (pi / 2e5)^2 / 2 ~ 3e-9 mm.
    EXPECT_NEAR(qm, brute, 1e-8) << station;
    EXPECT_LE(qm, brute + 1e-15) << station;  // the exact extreme is never beaten by samples
  }
}

TEST(QuadReference, ContinuaAndMissesAreFlagged) {
  Mechanism m = paper("index", "lower");
  // Coincident elbows with L3 = L4: A2 = A1 at theta2 chosen so.
  m.O2 = m.O1;
  const quadref::QPose coincident = quadref::fk(quadref::QMechanism(m), 0.7, 0.7, 1);
  EXPECT_TRUE(coincident.reachable);
  EXPECT_TRUE(coincident.continuum);
  EXPECT_EQ(double(coincident.type2_sin), 0.0);
  // Distal links 30 mm long cannot bridge 40 mm.
  Mechanism far = paper("index", "lower");
  far.O2 = {58.0, 0.0};
  EXPECT_FALSE(quadref::fk(quadref::QMechanism(far), kPi, 0.0, 1).reachable);
  EXPECT_GT(double(quadref::fk_gap(quadref::QMechanism(far), kPi, 0.0)), 0.0);
  // P on O1 with L1 = L3: any theta1.
  Mechanism eq = paper("index", "lower");
  eq.L = {9, 9, 9, 9};
  const quadref::QPose on_base = quadref::ik(quadref::QMechanism(eq), quadref::q(eq.O1), -1, 1);
  EXPECT_TRUE(on_base.reachable);
  EXPECT_TRUE(on_base.continuum);
}

// --- fits ------------------------------------------------------------------------------------------

TEST(FitLogSlope, RecoversPowerLawsAndIgnoresFloorsAndZeros) {
  EXPECT_NEAR(*fit_log_slope({1, 0.5, 0.25, 0.125}, {3, 0.75, 0.1875, 0.046875}), 2.0, 1e-12);
  EXPECT_NEAR(*fit_log_slope({10, 100, 1000}, {1, 0.1, 0.01}), -1.0, 1e-12);
  // Points at or below the floor and non-positive values are left out.
  EXPECT_NEAR(*fit_log_slope({1, 0.5, 0.25, 0.125}, {1, 0.5, 1e-16, 0.0}, 1e-12), 1.0, 1e-12);
  EXPECT_FALSE(fit_log_slope({1.0}, {1.0}).has_value());
  EXPECT_FALSE(fit_log_slope({1, 1}, {1, 2}).has_value());  // no spread in x
}

// --- work-precision series -------------------------------------------------------------------------

void expect_finite(const Json& j, const std::string& where = "$");

const MechanismAccuracy& index_lower_accuracy() {
  static const MechanismAccuracy a = [] {
    AccuracyOptions o;
    o.quick = true;
    return mechanism_accuracy(paper("index", "lower"), index_target(), o);
  }();
  return a;
}

const WorkSeries& series(const std::vector<WorkSeries>& list, const std::string& method) {
  for (const WorkSeries& s : list)
    if (s.method == method) return s;
  throw std::runtime_error("no series " + method);
}

TEST(Accuracy, AreaErrorsShrinkAtTheMethodsOrders) {
  const MechanismAccuracy& a = index_lower_accuracy();
  const Region region = reachable_region(paper("index", "lower"));
  EXPECT_DOUBLE_EQ(a.exact_area_mm2, region.area_mm2());
  ASSERT_TRUE(a.quad_area_mm2 && a.closed_form_area_mm2);
  EXPECT_NEAR(a.exact_area_mm2, *a.quad_area_mm2, 1e-12 * a.exact_area_mm2);

  // Marching squares with refined crossings: a polygon with vertices on the boundary, error
  // ~ h^2 (chord sagitta) once h resolves the corners and holes.
  const WorkSeries& ms = series(a.area, "marching squares");
  ASSERT_GE(ms.points.size(), 4u);
  ASSERT_TRUE(ms.order);
  EXPECT_GT(*ms.order, 1.6);
  EXPECT_LT(*ms.order, 2.6);
  EXPECT_LT(ms.points.back().error, 0.02);
  for (std::size_t k = 1; k < ms.points.size(); ++k) EXPECT_NEAR(ms.points[k].resolution, 0.5 * ms.points[k - 1].resolution, 1e-12);

  // Cell counting: only cells within h/sqrt(2) of the boundary can be misclassified, so the
  // error is at most sqrt(2) h times the perimeter; order about 1 (fluctuating: lattice points).
  const WorkSeries& cc = series(a.area, "cell counting");
  for (const WorkPoint& p : cc.points)
    EXPECT_LE(p.error, std::sqrt(2.0) * p.resolution * region.perimeter_mm() + 4 * p.resolution * p.resolution)
        << "h " << p.resolution;
  ASSERT_TRUE(cc.order);
  EXPECT_GT(*cc.order, 0.8);
  EXPECT_LT(*cc.order, 3.5);
  EXPECT_LT(cc.points.back().error, cc.points.front().error / 8);
  // Times grow with resolution (quadratically in 2D; allow noise of a shared machine).
  EXPECT_GT(ms.points.back().time_s, ms.points.front().time_s);
  ASSERT_TRUE(ms.time_slope);
  EXPECT_LT(*ms.time_slope, 0.0);
}

TEST(Accuracy, DynamicsErrorFallsWithTheToleranceAndExplicitRkPaysForStiffness) {
  AccuracyOptions o;
  o.quick = true;
  const DynamicsAccuracy d = dynamics_accuracy(load_design(ft::CliTest::kDesign), o);
  ASSERT_TRUE(d.skipped.empty()) << d.skipped;
  ASSERT_EQ(d.series.size(), 6u);  // BDF, ERK x averaged S = 1e2, averaged S = 1e4, switched S = 1e2
  for (const DynamicsSeries& s : d.series) {
    SCOPED_TRACE(s.integrator + " " + s.pwm + " S = " + std::to_string(s.stiffness_ratio));
    ASSERT_GE(s.points.size(), 3u);
    for (const DynamicsPoint& p : s.points) EXPECT_EQ(p.status, "ok");
    // Against BDF at rtol 1e-12: six decades of tolerance buy at least four of error.
    EXPECT_LT(s.points.back().error_mm, 1e-4 * s.points.front().error_mm + 1e-9);
    EXPECT_GT(s.points.back().steps, s.points.front().steps);
  }
  // BDF's steps per simulated second stay within a factor 3 from S = 1e2 to 1e6; the explicit
  // method's grow at least 100-fold (stability, not accuracy, sets its step), and overtake BDF's.
  ASSERT_GE(d.stiffness.size(), 5u);
  double bdf_lo = 1e300, bdf_hi = 0.0;
  for (const StiffnessPoint& p : d.stiffness) {
    bdf_lo = std::min(bdf_lo, p.steps_per_s[0]);
    bdf_hi = std::max(bdf_hi, p.steps_per_s[0]);
    EXPECT_EQ(p.status[0], "ok");
  }
  EXPECT_LT(bdf_hi, 3.0 * bdf_lo);
  EXPECT_GT(d.stiffness.back().steps_per_s[1], 100.0 * d.stiffness.front().steps_per_s[1]);
  ASSERT_TRUE(d.crossover_ratio);
  EXPECT_GE(*d.crossover_ratio, d.stiffness.front().stiffness_ratio);
  EXPECT_LT(*d.crossover_ratio, d.stiffness.back().stiffness_ratio);
  EXPECT_NEAR(d.stiffness.front().stiffness_ratio, 100.0, 1e-9);  // the showcase's motors
}

TEST(Accuracy, CoverageSamplingConvergesToTheExactValues) {
  const MechanismAccuracy& a = index_lower_accuracy();
  const Mechanism m = paper("index", "lower");
  const double exact = double(quadref::annuli_margin(quadref::QMechanism(m), index_target()));
  ASSERT_TRUE(a.margin_quad_mm);
  EXPECT_NEAR(*a.margin_quad_mm, exact, 1e-15);
  EXPECT_NEAR(a.margin_mm, exact, 64 * kEps * 30);
  // The minimum of a smooth distance over N samples misses by ~(perimeter / N)^2: order 2; the
  // sampled minimum never undercuts the exact one.
  const WorkSeries& margin = series(a.coverage, "sampled margin");
  ASSERT_TRUE(margin.order);
  EXPECT_GT(*margin.order, 1.3);
  EXPECT_LT(*margin.order, 3.0);
  for (const WorkPoint& p : margin.points) EXPECT_GE(p.value, a.margin_mm - 1e-12);
  EXPECT_LT(margin.points.back().error, 1e-4);
  // Min LCI: smooth field, minimum on the boundary or inside: order 2 in the ring spacing.
  const WorkSeries& lci = series(a.coverage, "sampled min LCI");
  ASSERT_TRUE(lci.order);
  EXPECT_GT(*lci.order, 1.5);
  EXPECT_LT(*lci.order, 2.5);
  for (const WorkPoint& p : lci.points) EXPECT_GE(p.value, a.min_lci_reference - 1e-12);
  EXPECT_LE(a.min_lci_reference, a.min_lci + 1e-15);
  // The refined minimum is attained inside the ellipse (a real LCI, not an extrapolation).
  EXPECT_GT(a.min_lci_reference, 0.0);
}

TEST(Accuracy, RestrictedAreasAgainstTheSixteenTimesFinerGrid) {
  const MechanismAccuracy& a = index_lower_accuracy();
  EXPECT_FALSE(a.lci_threshold_from_design);  // the paper sets no min_lci
  EXPECT_DOUBLE_EQ(a.lci_threshold, 0.25);
  // The reference grid is 16x finer than the finest of the series.
  const WorkSeries& as = series(a.restricted, "assembly-restricted area");
  const WorkSeries& ls = series(a.restricted, "LCI-restricted area");
  EXPECT_NEAR(a.reference_spacing_mm, as.points.back().resolution / 16, 1e-12);
  // Restricting can only remove area: LCI >= 0.25 inside assembly-restricted inside reachable.
  EXPECT_LT(a.lci_area_reference_mm2, a.assembly_area_reference_mm2);
  EXPECT_LT(a.assembly_area_reference_mm2, a.exact_area_mm2);
  for (const WorkSeries* s : {&as, &ls}) {
    SCOPED_TRACE(s->method);
    // Converging: the estimate shrinks with h, and the finest is within 1e-4 of the area (the
    // errors themselves need not fall monotonically: corners of the region cancel or add by luck).
    ASSERT_TRUE(s->points.back().estimate && s->points.front().estimate);
    EXPECT_LT(*s->points.back().estimate, *s->points.front().estimate / 2);
    EXPECT_LT(s->points.back().error, 1e-4 * (s == &as ? a.assembly_area_reference_mm2 : a.lci_area_reference_mm2));
    // restricted_area's own estimate bounds the measured error on these regions at the quick
    // spacings (<= 3 mm; at 5.8 mm, in the default run, it does not).
    for (const WorkPoint& p : s->points) {
      ASSERT_TRUE(p.estimate);
      EXPECT_LE(p.error, *p.estimate) << "h " << p.resolution;
    }
  }
}

// The upper mechanism of each paper station is the lower one reflected across the target's
// centre line (y = 15.5 mm, 17.5 mm for the thumb), and the report takes a mirror image's figures
// from its twin. The rule compares every number exactly; the figures are checked against the
// upper mechanism's own region, coverage and restricted areas, computed here on its coordinates.
TEST(Accuracy, AMirrorImageIsDetectedExactlyAndHasItsTwinsFigures) {
  const Mechanism lower = paper("index", "lower"), upper = paper("index", "upper");
  const Ellipse t = index_target();
  EXPECT_EQ(mirror_line(lower, t, upper, t), 15.5);
  EXPECT_EQ(mirror_line(upper, t, lower, t), 15.5);
  Ellipse tt = t;
  tt.center = {6.25, 17.5};
  tt.axes = {15.0, 14.0};
  EXPECT_EQ(mirror_line(paper("thumb", "lower"), tt, paper("thumb", "upper"), tt), 17.5);
  EXPECT_FALSE(mirror_line(lower, t, paper("thumb", "upper"), t));  // other links and line
  Mechanism b = upper;
  b.O2.y() = std::nextafter(31.0, 32.0);
  EXPECT_FALSE(mirror_line(lower, t, b, t));
  b = upper;
  b.working_mode = lower.working_mode;  // not reflected
  EXPECT_FALSE(mirror_line(lower, t, b, t));
  b = upper;
  b.assembly_mode = AssemblyMode::Any;
  EXPECT_FALSE(mirror_line(lower, t, b, t));
  Ellipse moved = t;
  moved.center.y() += 0.1;
  EXPECT_FALSE(mirror_line(lower, t, upper, moved));
  Ellipse turned = t;
  turned.angle = 0.2;
  EXPECT_FALSE(mirror_line(lower, turned, upper, turned));
  Ellipse reflected = turned;
  reflected.angle = -0.2;
  EXPECT_EQ(mirror_line(lower, turned, upper, reflected), 15.5);
  Mechanism la = lower, ub = upper;  // joint arcs: theta -> -theta reverses each arc
  la.joint_limits = std::array<JointRange, 2>{JointRange{0.5, 3.0}, JointRange{-1.0, 1.5}};
  ub.joint_limits = std::array<JointRange, 2>{JointRange{-3.0, -0.5}, JointRange{-1.5, 1.0}};
  EXPECT_EQ(mirror_line(la, t, ub, t), 15.5);
  ub.joint_limits = la.joint_limits;
  EXPECT_FALSE(mirror_line(la, t, ub, t));

  // The twin's figures hold for the upper mechanism measured on its own coordinates.
  const MechanismAccuracy& a = index_lower_accuracy();
  EXPECT_NEAR(reachable_region(upper).area_mm2(), a.exact_area_mm2, 1e-12 * a.exact_area_mm2);
  const CoverageResult c = coverage(upper, t);
  EXPECT_NEAR(c.margin_mm, a.margin_mm, 1e-12);
  EXPECT_NEAR(c.min_lci, a.min_lci, 1e-9);
  Mechanism ul = upper;
  ul.min_lci = a.lci_threshold;
  const auto bb = reachable_region(upper).bounds();
  for (const char* method : {"assembly-restricted area", "LCI-restricted area"}) {
    const WorkPoint& p = series(a.restricted, method).points.back();
    const Restriction r = std::string(method) == "LCI-restricted area" ? Restriction::lci : Restriction::assembly;
    const double mine = restricted_area(ul, r, Grid::covering(bb, p.resolution, p.resolution)).area_mm2;
    EXPECT_NEAR(mine, p.value, 1e-6 * p.value) << method;
  }
}

TEST(Accuracy, ToleranceEstimatesAgainstManyDevicesAndTheExactPlaySet) {
  const MechanismAccuracy& a = index_lower_accuracy();
  ASSERT_GT(a.tolerance_reference_samples, 0u);
  const double ref = a.tolerance_reference_3sigma_mm;
  const double ref_se = ref / std::sqrt(2.0 * double(a.tolerance_reference_samples));
  // The first order agrees with 2e5 devices to their sampling error plus the linearisation's
  // second-order term (0.05 mm on 9-15 mm links: well under 1 %).
  const WorkSeries& fo = series(a.tolerance, "first-order 3-sigma");
  ASSERT_EQ(fo.points.size(), 1u);
  EXPECT_LT(fo.points[0].error, 4.0 * ref_se + 0.005 * ref);
  // The Monte Carlo's error falls like N^-1/2 and its own estimate tracks it.
  const WorkSeries& mc = series(a.tolerance, "Monte Carlo 3-sigma");
  ASSERT_GE(mc.points.size(), 3u);
  for (const WorkPoint& p : mc.points) {
    ASSERT_TRUE(p.estimate);
    EXPECT_LT(p.error, 4.0 * *p.estimate + 4.0 * ref_se) << p.resolution;
  }
  // Sampled devices never leave the exact play set and creep up on its extent; the first-order
  // parallelogram is close to the exact set for 0.1 mm of play far from singularities.
  const WorkSeries& sampled = series(a.tolerance, "play: sampled devices");
  for (const WorkPoint& p : sampled.points) EXPECT_LE(p.value, a.play_extent_mm * (1.0 + 1e-12)) << p.resolution;
  EXPECT_LT(sampled.points.back().error, sampled.points.front().error);
  const WorkSeries& lin = series(a.tolerance, "play: first order");
  EXPECT_LT(lin.points[0].error, 0.02 * a.play_extent_mm);
}

TEST(Accuracy, JointLimitsUseTheExactRegionAndNoQuadShortcut) {
  Mechanism m = paper("index", "lower");
  m.joint_limits = std::array<JointRange, 2>{JointRange{kPi / 3, 2.6}, JointRange{0.0, 2.6}};
  AccuracyOptions o;
  o.quick = true;
  const MechanismAccuracy a = mechanism_accuracy(m, index_target(), o);
  // No closed form with limits: the exact region is the reference, and it is smaller.
  EXPECT_FALSE(a.quad_area_mm2.has_value());
  EXPECT_FALSE(a.closed_form_area_mm2.has_value());
  EXPECT_FALSE(a.margin_quad_mm.has_value());
  EXPECT_LT(a.exact_area_mm2, annuli_intersection_area(paper("index", "lower")));
  EXPECT_DOUBLE_EQ(a.exact_area_mm2, reachable_region(m).area_mm2());
  EXPECT_THROW((void)series(a.area, "closed form (double)"), std::runtime_error);
  const WorkSeries& ms = series(a.area, "marching squares");
  EXPECT_LT(ms.points.back().error, ms.points.front().error);
  EXPECT_TRUE(series(a.coverage, "coverage()").points.empty());
  AccuracyReport r;
  r.mechanisms.push_back(a);
  const Json j = to_json(r);
  expect_finite(j);
  EXPECT_TRUE(j["mechanisms"][0]["area"]["quad_closed_form_mm2"].is_null());
}

TEST(Precision, StrataArePopulatedAndErrorsFollowTheConditioning) {
  AccuracyOptions o;
  o.quick = true;
  o.seed = test_seed();
  const Mechanism lower = paper("index", "lower"), upper = paper("thumb", "upper");
  for (const char* problem : {"fk", "ik"}) {
    SCOPED_TRACE(problem);
    const PrecisionStudy st = precision_study({&lower, &upper}, problem, o);
    ASSERT_EQ(st.strata.size(), 5u);
    ASSERT_EQ(st.methods.size(), 6u);
    for (std::size_t i = 0; i < st.strata.size(); ++i) {
      SCOPED_TRACE(i);
      // Even the smallest stratum (|sin| < 1e-9) is reached, through the shifted frames.
      EXPECT_GE(st.methods[1].cells[i].samples, 100u);
      for (const PrecisionMethod& m : st.methods) {
        const PrecisionCell& c = m.cells[i];
        EXPECT_TRUE(std::isfinite(c.max_error_mm) && std::isfinite(c.rms_error_mm) && std::isfinite(c.ns_per_call));
        EXPECT_EQ(c.failed, 0u) << m.name;
        EXPECT_GT(c.ns_per_call, 0.0) << m.name;
        EXPECT_LE(c.rms_error_mm, c.max_error_mm) << m.name;
      }
      // Error bound of the circle intersection: ~16 eps S / |sin| + a sqrt(eps) floor
      // (S = 17.5 + 9 + 12.5 here); the library paths are the double formulas.
      const double s_lo = std::max(st.strata[i][0], 0.0);
      const double bound = 2 * 16 * kEps * 39.0 * (s_lo > 0 ? 1 / s_lo : INFINITY);
      const double floor = 4 * std::sqrt(2 * 17.5 * 16 * kEps * 39.0) + 32 * kEps * 39;
      for (int k : {1, 3, 4, 5}) EXPECT_LE(st.methods[k].cells[i].max_error_mm, std::min(bound, floor)) << st.methods[k].name;
      // float < double < long double in accuracy wherever rounding (not the cap) dominates.
      if (i < 2) {
        EXPECT_GT(st.methods[0].cells[i].rms_error_mm, 1e6 * st.methods[1].cells[i].rms_error_mm);
        EXPECT_GT(st.methods[1].cells[i].rms_error_mm, 100 * st.methods[2].cells[i].rms_error_mm);
      }
    }
    // error ~ eps / sin while sin >> sqrt(eps): order 1 in eps; near tangency ~ sqrt(eps).
    ASSERT_TRUE(st.order[0] && st.order[1] && st.order[4]);
    EXPECT_NEAR(*st.order[0], 1.0, 0.1);
    EXPECT_NEAR(*st.order[1], 1.0, 0.1);
    EXPECT_NEAR(*st.order[4], 0.5, 0.15);
  }
}

// --- stability -------------------------------------------------------------------------------------

void expect_all_pass(const StabilityReport& r) {
  ASSERT_FALSE(r.cases.empty());
  for (const StabilityCase& c : r.cases) {
    // No NaN or infinity anywhere.
    EXPECT_TRUE(c.finite) << c.mechanism << " " << c.group << " " << c.name << " " << c.operation;
    if (c.error) EXPECT_TRUE(std::isfinite(*c.error)) << c.name;
    if (c.bound) EXPECT_TRUE(std::isfinite(*c.bound)) << c.name;
    EXPECT_TRUE(std::isfinite(c.parameter) && std::isfinite(c.conditioning)) << c.name;
    EXPECT_TRUE(c.passed) << c.mechanism << " | " << c.group << " | " << c.name << " | " << c.operation << ": "
                          << c.status << " (expected " << c.expected << "): " << c.explanation;
    if (c.ill_conditioned) EXPECT_FALSE(c.explanation.empty()) << c.name;
  }
  EXPECT_EQ(r.failed(), 0u);
}

const StabilityCase* find_case(const StabilityReport& r, const std::string& group, const std::string& name,
                               const std::string& op) {
  for (const StabilityCase& c : r.cases)
    if (c.group == group && c.name == name && c.operation == op) return &c;
  return nullptr;
}

TEST(Stability, EveryCasePassesOnThePaperStations) {
  const StabilityReport r = stability_report(load_design(ft::CliTest::kDesign));
  expect_all_pass(r);
  // Every group of the catalogue is there, for every mechanism.
  for (const char* mech : {"index/lower", "index/upper", "thumb/lower", "thumb/upper"}) {
    for (const char* group : {"type I distance", "type II distance", "link ratio", "scale", "coincident base joints",
                              "equal links", "ill-conditioned Jacobian", "tangent ellipse"}) {
      EXPECT_TRUE(std::any_of(r.cases.begin(), r.cases.end(),
                              [&](const StabilityCase& c) { return c.mechanism == mech && c.group == group; }))
          << mech << " " << group;
    }
  }
  // The dynamic cases of each station: five simulations at the extremes, each finished and finite.
  for (const char* station : {"index", "thumb"}) {
    std::size_t n = 0;
    for (const StabilityCase& c : r.cases) {
      if (c.mechanism != station || c.group != "dynamics") continue;
      ++n;
      EXPECT_EQ(c.operation, "simulate");
      EXPECT_TRUE(c.status == "ok" || c.status == "singular") << c.name << ": " << c.explanation;
      EXPECT_NE(c.explanation.find(" s simulated in "), std::string::npos) << c.explanation;
    }
    EXPECT_EQ(n, 5u) << station;
  }
  const StabilityCase* stiff = find_case(r, "dynamics", "stiffness ratio 1e8 (L/R = 1e-10 s), 1 mm step", "simulate");
  ASSERT_NE(stiff, nullptr);
  EXPECT_EQ(stiff->status, "ok");
  // Exactly singular inputs are reported singular with the exact answer.
  const StabilityCase* t1 = find_case(r, "type I distance", "leg 1 stretched, distance 0", "ik");
  ASSERT_NE(t1, nullptr);
  EXPECT_EQ(t1->status, "singular_type1");
  EXPECT_EQ(t1->conditioning, 0.0);
  EXPECT_LT(*t1->error, 1e-13);
  const StabilityCase* t2 = find_case(r, "type II distance", "distal links stretched, distance 0", "fk");
  ASSERT_NE(t2, nullptr);
  EXPECT_EQ(t2->status, "singular_type2");
  EXPECT_EQ(t2->conditioning, 0.0);
  // Far from singularities the status is ok and the error a few ulps of the scale.
  const StabilityCase* easy = find_case(r, "type I distance", "leg 1 stretched, distance 1e-01", "ik");
  ASSERT_NE(easy, nullptr);
  EXPECT_EQ(easy->status, "ok");
  EXPECT_FALSE(easy->ill_conditioned);
  EXPECT_LT(*easy->error, 64 * kEps * 24);
  // The stiff end: condition numbers up to 1e14 through both singularity types, flagged.
  for (const char* name : {"via type I, cond(J) = 1e+14", "via type II, cond(J) = 1e+14"}) {
    const StabilityCase* c = find_case(r, "ill-conditioned Jacobian", name, "lci");
    ASSERT_NE(c, nullptr) << name;
    EXPECT_GT(c->parameter, 5e13) << name;
    EXPECT_LT(c->parameter, 2e14) << name;
    EXPECT_TRUE(c->ill_conditioned) << name;
  }
  // Tangent ellipses: inside when clear, not inside when clearly outside, never inside when
  // outside; within rounding of tangency undecided and flagged.
  const StabilityCase* in = find_case(r, "tangent ellipse", "outer circle of leg 1, margin 1e-06 x scale", "coverage verdict");
  const StabilityCase* out = find_case(r, "tangent ellipse", "outer circle of leg 1, margin -1e-15 x scale", "coverage verdict");
  const StabilityCase* touch = find_case(r, "tangent ellipse", "outer circle of leg 1, margin 0 x scale", "coverage verdict");
  const StabilityCase* clear_out =
      find_case(r, "tangent ellipse", "outer circle of leg 1, margin -1e-09 x scale", "coverage verdict");
  ASSERT_TRUE(in && out && touch && clear_out);
  EXPECT_EQ(in->status, "inside");
  EXPECT_NE(out->status, "inside");
  EXPECT_EQ(clear_out->status, "not inside");
  EXPECT_TRUE(touch->ill_conditioned);
  // Scales: position errors relative to the scale stay at rounding level from 1e-3 to 1e6 mm.
  for (const char* s : {"x 1e-03", "x 1e+06"}) {
    const StabilityCase* c = find_case(r, "scale", s, "fk");
    ASSERT_NE(c, nullptr) << s;
    EXPECT_EQ(c->status, "ok") << s;
  }
}

Mechanism random_mechanism(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (;;) {
    Mechanism m;
    m.name = "random";
    m.O1 = {-5 + 10 * u(rng), -5 + 10 * u(rng)};
    const double b = 3 + 17 * u(rng), phi = 2 * kPi * u(rng);
    m.O2 = m.O1 + b * Vec2(std::cos(phi), std::sin(phi));
    m.L = {4 + 12 * u(rng), 4 + 12 * u(rng), 8 + 17 * u(rng), 8 + 17 * u(rng)};
    const auto modes = all_working_modes();
    m.working_mode = modes[std::size_t(u(rng) * 4) % 4];
    const double a = u(rng);
    m.assembly_mode = a < 0.4 ? AssemblyMode::Plus : a < 0.8 ? AssemblyMode::Minus : AssemblyMode::Any;
    if (annuli_intersection_area(m) > 20.0) return m;
  }
}

TEST(Stability, EveryCasePassesOnRandomGeometries) {
  std::mt19937_64 rng(test_seed() + 5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 5; ++k) {
    const Mechanism m = random_mechanism(rng);
    // A target around a reachable point of it (centre of a leg-1 circle intersection).
    Ellipse e;
    const double rho1 = std::fabs(m.L[0] - m.L[2]) + (0.3 + 0.4 * u(rng)) * 2 * std::min(m.L[0], m.L[2]);
    const CircleIntersection x = intersect_circles(m.O1, rho1, m.O2, 0.5 * (m.L[1] + m.L[3] + std::fabs(m.L[1] - m.L[3])), 1);
    e.center = x.status == Status::unreachable ? m.O1 + Vec2(rho1, 0.0) : x.point;
    e.axes = {1 + 4 * u(rng), 1 + 4 * u(rng)};
    e.angle = 2 * kPi * u(rng);
    SCOPED_TRACE(describe(m) + " (FIVEBAR_TEST_SEED=" + std::to_string(test_seed()) + ")");
    expect_all_pass(stability_catalogue(m, e, "random " + std::to_string(k)));
  }
}

TEST(Stability, TextAndJsonReportAFailureWithItsReason) {
  StabilityReport r;
  r.design = "made-up";
  StabilityCase ok;
  ok.mechanism = "a/b";
  ok.group = "scale";
  ok.name = "x 1e+00";
  ok.operation = "fk";
  ok.status = "ok";
  ok.expected = "ok";
  ok.error = 1e-15;
  ok.bound = 1e-12;
  ok.unit = "mm";
  StabilityCase bad = ok;
  bad.name = "x 1e+03";
  bad.error = 1e-3;
  bad.passed = false;
  bad.explanation = "error 1.0e-03 exceeds the bound 1.0e-12";
  r.cases = {ok, bad};
  EXPECT_EQ(r.failed(), 1u);
  EXPECT_FALSE(r.passed());
  const std::string text = to_text(r);
  EXPECT_THAT(text, AllOf(HasSubstr("FAIL"), HasSubstr("exceeds the bound"), HasSubstr("1 case(s) FAILED")));
  const Json j = to_json(r);
  EXPECT_FALSE(j["passed"].get<bool>());
  EXPECT_EQ(j["failed"], 1);
  EXPECT_EQ(j["cases"][1]["error"].get<double>(), 1e-3);
}

// --- output ----------------------------------------------------------------------------------------

/// Every number in the document is finite.
void expect_finite(const Json& j, const std::string& where) {
  if (j.is_number_float()) {
    EXPECT_TRUE(std::isfinite(j.get<double>())) << where;
  } else if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) expect_finite(it.value(), where + "." + it.key());
  } else if (j.is_array()) {
    for (std::size_t i = 0; i < j.size(); ++i) expect_finite(j[i], where + "[" + std::to_string(i) + "]");
  }
}

/// The paper's design and a scratch directory per test; ReportCli also runs the binary in it (test/cli_test.hpp).
class ReportTest : public ft::CliTest {
 protected:
  ReportTest() : CliTest("fivebar_test_report") {}
};

using Output = ReportTest;

TEST_F(Output, JsonTextAndPlotsOfTheAccuracyReport) {
  AccuracyReport r;
  r.design = "paper";
  r.quick = true;
  MechanismAccuracy m = index_lower_accuracy();
  m.station = "index";
  r.mechanisms.push_back(m);
  AccuracyOptions o;
  o.quick = true;
  const Mechanism lower = paper("index", "lower");
  r.fk = precision_study({&lower}, "fk", o);
  r.ik = precision_study({&lower}, "ik", o);

  const Json j = to_json(r);
  expect_finite(j);
  EXPECT_EQ(j["command"], "report accuracy");
  const Json& area = j["mechanisms"][0]["area"];
  EXPECT_EQ(area["series"][0]["method"], "cell counting");
  EXPECT_TRUE(area["series"][0]["points"][0].contains("h_mm"));
  EXPECT_TRUE(area["series"][0]["points"][0].contains("error_mm2"));
  EXPECT_TRUE(j["mechanisms"][0]["coverage"].contains("margin_mm"));
  EXPECT_EQ(j["fk"]["strata"].size(), 5u);
  EXPECT_TRUE(j["ik"]["strata"][0]["methods"][0].contains("max_error_ulp"));

  const std::string text = to_text(r);
  EXPECT_THAT(text, AllOf(HasSubstr("== index/lower =="), HasSubstr("marching squares"), HasSubstr("fitted order"),
                          HasSubstr("long double"), HasSubstr("ik_batch()")));

  const auto files = write_accuracy_plots(r, dir_ / "plots");
  ASSERT_EQ(files.size(), 14u);  // area, margin, min LCI, restricted, tolerance for index; FK; IK; SVG + PNG each
  for (const auto& f : files) {
    std::ifstream in(dir_ / "plots" / f, std::ios::binary);
    std::string head(8, '\0');
    in.read(head.data(), 8);
    if (f.extension() == ".png") {
      EXPECT_EQ(head, std::string("\x89PNG\r\n\x1a\n", 8)) << f;
    } else {
      EXPECT_THAT(head, HasSubstr("<?xml")) << f;
    }
  }
  // Atomic writes leave no temporaries behind.
  for (const auto& e : fs::directory_iterator(dir_ / "plots")) EXPECT_EQ(e.path().filename().string()[0] != '.', true);
}

TEST_F(Output, TheReportProductStatesTheAccuracyOfTheMainNumbers) {
  Design d = load_design(kDesign);
  d.stations.resize(1);  // index only: keeps the test short
  SceneOptions o;
  o.out_root = dir_;
  o.products = std::vector<std::string>{"report"};
  const SceneReport r = run_scene(d, o);
  ASSERT_TRUE(r.ok());
  const ProductOutcome* p = nullptr;
  for (const auto& x : r.products)
    if (x.name == "report") p = &x;
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->state, ProductOutcome::State::built);
  EXPECT_TRUE(p->passed);
  EXPECT_THAT(p->check, HasSubstr("stability cases passed"));
  EXPECT_THAT(p->markdown, AllOf(HasSubstr("Accuracy of the main numbers"), HasSubstr(" ± "),
                                 HasSubstr("exact region"), HasSubstr("Stability catalogue")));
  EXPECT_TRUE(fs::exists(r.out_dir / "report" / "accuracy.json"));
  EXPECT_TRUE(fs::exists(r.out_dir / "report" / "stability.json"));
  EXPECT_TRUE(fs::exists(r.out_dir / "report" / "accuracy_fk.png"));
  const Json& res = p->result;
  expect_finite(res);
  ASSERT_EQ(res["mechanisms"].size(), 2u);
  const Json& m0 = res["mechanisms"][0];
  // index/upper is index/lower's mirror image: measured once, said so.
  EXPECT_TRUE(m0["mirror_of"].is_null());
  EXPECT_EQ(res["mechanisms"][1]["mirror_of"], "index/lower");
  EXPECT_THAT(p->markdown, HasSubstr("(mirror image of `index/lower`)"));
  // The coverage margin and its error against the quad margin.
  EXPECT_LT(m0["coverage_margin"]["error_mm"].get<double>(), 1e-12);
  EXPECT_GT(m0["assembly_restricted_area"]["error_mm2"].get<double>(), 0.0);
  EXPECT_EQ(res["stability"]["failed"], 0);
}

}  // namespace
}  // namespace fivebar
