// Tolerance module (fivebar/tolerance.hpp): the closed-form sensitivity against central finite
// differences of fk() on perturbed mechanisms, the first-order covariance against Monte Carlo at
// small tolerances, determinism for a seed, and a status on a type II singularity.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <string>

#include "fivebar/error.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/sections/tolerance.hpp"
#include "fivebar/tolerance.hpp"
#include "paper.hpp"

namespace fivebar {
namespace {

using testing::paper_mechanism;
using testing::test_seed;

/// The mechanism with parameter j moved by h (mm or rad); the angle offsets move the joint angles.
Vec2 perturbed_fk(const Mechanism& m, const Pose& nominal, std::size_t j, double h) {
  Mechanism p = m;
  p.joint_limits.reset();
  p.assembly_mode = nominal.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
  double t1 = nominal.theta1;
  double t2 = nominal.theta2;
  switch (j) {
    case 0: case 1: case 2: case 3: p.L[j] += h; break;
    case 4: p.O1.x() += h; break;
    case 5: p.O1.y() += h; break;
    case 6: p.O2.x() += h; break;
    case 7: p.O2.y() += h; break;
    case 8: t1 += h; break;
    default: t2 += h; break;
  }
  const Pose q = fk(p, t1, t2);
  EXPECT_EQ(q.status, Status::ok);
  return q.P;
}

/// A random regular pose of m: joint angles drawn until FK is ok, well away from singularities.
Pose random_regular_pose(const Mechanism& m, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  for (;;) {
    const Pose q = fk(m, angle(rng), angle(rng));
    if (q.status != Status::ok) continue;
    if (q.type2_sin < 0.2 || q.type1_sin[0] < 0.1 || q.type1_sin[1] < 0.1) continue;
    if (q.mode != m.working_mode) continue;
    return q;
  }
}

std::string describe(const Mechanism& m, const Pose& q) {
  std::ostringstream s;
  s.precision(17);
  s << m.name << " L=" << m.L[0] << "," << m.L[1] << "," << m.L[2] << "," << m.L[3] << " theta=" << q.theta1
    << "," << q.theta2 << " P=" << q.P.x() << "," << q.P.y();
  return s.str();
}

TEST(Tolerance, SensitivityMatchesCentralFiniteDifferencesOfFk) {
  const std::uint64_t seed = test_seed();
  SCOPED_TRACE("FIVEBAR_TEST_SEED=" + std::to_string(seed));
  std::mt19937_64 rng(seed);
  for (const char* station : {"index", "thumb"}) {
    for (const char* which : {"lower", "upper"}) {
      const Mechanism m = paper_mechanism(station, which);
      for (int k = 0; k < 25; ++k) {
        const Pose q = random_regular_pose(m, rng);
        SCOPED_TRACE(describe(m, q));
        const Sensitivity s = tolerance_sensitivity(m, q.P);
        ASSERT_EQ(s.status, Status::ok);
        const Pose nominal = ik(m, q.P);
        const double h = 1e-5;  // mm or rad: truncation ~h^2, rounding ~eps * 30 mm / h, both < 1e-9
        for (std::size_t j = 0; j < kToleranceParameters; ++j) {
          SCOPED_TRACE(tolerance_parameter_names()[j]);
          const Vec2 fd = (perturbed_fk(m, nominal, j, h) - perturbed_fk(m, nominal, j, -h)) / (2.0 * h);
          const Vec2 col = s.S.col(static_cast<Eigen::Index>(j));
          EXPECT_LE((col - fd).norm(), 1e-6 * std::max(1.0, fd.norm())) << "closed " << col.transpose()
                                                                         << " fd " << fd.transpose();
        }
      }
    }
  }
}

ParameterSigmas uniform_sigmas(double mm, double rad) {
  return {mm, mm, mm, mm, mm, mm, mm, mm, rad, rad};
}

TEST(Tolerance, ZeroTolerancesGiveZeroErrorAndSmallOnesScaleLinearly) {
  const Mechanism m = paper_mechanism("index", "lower");
  const Vec2 P(6.25, 18.0);
  const ToleranceEstimate zero = tolerance_first_order(m, P, ParameterSigmas{}, angle_per_count(16));
  ASSERT_EQ(zero.status, Status::ok);
  EXPECT_EQ(zero.covariance.norm(), 0.0);
  EXPECT_EQ(zero.worst_case_mm, 0.0);
  const ToleranceEstimate a = tolerance_first_order(m, P, uniform_sigmas(0.01, 1e-3), angle_per_count(16));
  const ToleranceEstimate b = tolerance_first_order(m, P, uniform_sigmas(0.03, 3e-3), angle_per_count(16));
  EXPECT_NEAR(b.worst_case_mm, 3.0 * a.worst_case_mm, 1e-12);
  EXPECT_NEAR(b.ellipse_semi_axes.x(), 3.0 * a.ellipse_semi_axes.x(), 1e-12);
  EXPECT_NEAR((b.covariance - 9.0 * a.covariance).norm(), 0.0, 1e-15);
  // The worst case bounds the 3-sigma ellipse's major semi-axis (triangle inequality).
  EXPECT_GE(a.worst_case_mm, a.ellipse_semi_axes.x());
  EXPECT_GE(a.ellipse_semi_axes.x(), a.ellipse_semi_axes.y());
}

TEST(Tolerance, ResolutionIsOneCountOnTheWorseJointByFiniteDifferences) {
  const Mechanism m = paper_mechanism("thumb", "upper");
  const std::uint64_t seed = test_seed();
  SCOPED_TRACE("FIVEBAR_TEST_SEED=" + std::to_string(seed));
  std::mt19937_64 rng(seed);
  const Pose q = random_regular_pose(m, rng);
  SCOPED_TRACE(describe(m, q));
  const double per_count = angle_per_count(12);
  EXPECT_DOUBLE_EQ(per_count, 2.0 * std::numbers::pi / 4096.0);
  const ToleranceEstimate e = tolerance_first_order(m, q.P, ParameterSigmas{}, per_count);
  ASSERT_EQ(e.status, Status::ok);
  const Pose n = ik(m, q.P);
  const double h = 1e-6;
  const double step1 = ((perturbed_fk(m, n, 8, h) - perturbed_fk(m, n, 8, -h)) / (2.0 * h)).norm();
  const double step2 = ((perturbed_fk(m, n, 9, h) - perturbed_fk(m, n, 9, -h)) / (2.0 * h)).norm();
  EXPECT_NEAR(e.resolution_um, 1000.0 * std::max(step1, step2) * per_count, 1e-6 * e.resolution_um);
}

TEST(Tolerance, FirstOrderCovarianceAgreesWithMonteCarloAtSmallTolerances) {
  const std::uint64_t seed = test_seed();
  SCOPED_TRACE("FIVEBAR_TEST_SEED=" + std::to_string(seed));
  std::mt19937_64 rng(seed);
  const ParameterSigmas sigma{1e-3, 2e-3, 1.5e-3, 1e-3, 2e-3, 1e-3, 1e-3, 2e-3, 1e-4, 2e-4};
  const std::size_t n = 20000;
  for (const char* which : {"lower", "upper"}) {
    const Mechanism m = paper_mechanism("index", which);
    for (int k = 0; k < 3; ++k) {
      const Pose q = random_regular_pose(m, rng);
      SCOPED_TRACE(describe(m, q));
      const ToleranceEstimate fo = tolerance_first_order(m, q.P, sigma, angle_per_count(16));
      const MonteCarloTolerance mc = tolerance_monte_carlo(m, q.P, sigma, n, seed + std::uint64_t(k));
      ASSERT_EQ(fo.status, Status::ok);
      ASSERT_EQ(mc.status, Status::ok);
      EXPECT_EQ(mc.used, n);
      EXPECT_EQ(mc.failed, 0u);
      const Eigen::Matrix2d& C = fo.covariance;
      // Standard error of a sample covariance of normal data: sqrt((C_aa C_bb + C_ab^2) / n).
      for (int a = 0; a < 2; ++a) {
        for (int b = 0; b < 2; ++b) {
          const double se = std::sqrt((C(a, a) * C(b, b) + C(a, b) * C(a, b)) / double(n));
          EXPECT_NEAR(mc.covariance(a, b), C(a, b), 4.0 * se) << "element " << a << b;
        }
      }
      // The mean error is second order in sigma: far below one standard error of the mean.
      EXPECT_LT(mc.mean_error.norm(), 4.0 * std::sqrt(C.trace() / double(n)));
    }
  }
}

TEST(Tolerance, MonteCarloIsDeterministicForASeed) {
  const Mechanism m = paper_mechanism("thumb", "lower");
  const Vec2 P(6.25, 20.0);
  const ParameterSigmas sigma = uniform_sigmas(0.05, 0.01);
  const MonteCarloTolerance a = tolerance_monte_carlo(m, P, sigma, 2000, 7);
  const MonteCarloTolerance b = tolerance_monte_carlo(m, P, sigma, 2000, 7);
  const MonteCarloTolerance c = tolerance_monte_carlo(m, P, sigma, 2000, 8);
  ASSERT_EQ(a.status, Status::ok);
  EXPECT_EQ(a.used, b.used);
  EXPECT_EQ(a.covariance, b.covariance);
  EXPECT_EQ(a.mean_error, b.mean_error);
  EXPECT_NE(a.covariance, c.covariance);
}

TEST(Tolerance, TypeTwoSingularityGivesAStatusNotNaN) {
  // Index lower (bases 12.5 mm apart, links 9 and 15 mm), symmetric pose with both distal links
  // along one line: |A1 - A2| = L3 + L4 = 30 mm, i.e. 12.5 - 18 cos(theta1) = 30 with
  // theta2 = pi - theta1; the tactor is the midpoint of A1 A2.
  const Mechanism m = paper_mechanism("index", "lower");
  const double c = -17.5 / 18.0;
  const double s = std::sqrt(1.0 - c * c);
  const Vec2 A1(9.0 * c, 9.0 * s);
  const Vec2 A2(12.5 - 9.0 * c, 9.0 * s);
  ASSERT_NEAR((A2 - A1).norm(), 30.0, 1e-12);
  const Vec2 P = 0.5 * (A1 + A2);
  for (const Vec2& at : {P, Vec2(P + Vec2(0.0, 1e-12))}) {
    const ToleranceEstimate e = tolerance_first_order(m, at, uniform_sigmas(0.05, 0.01), angle_per_count(16));
    EXPECT_EQ(e.status, Status::singular_type2);
    EXPECT_TRUE(e.covariance.allFinite());
    EXPECT_TRUE(std::isfinite(e.worst_case_mm));
    EXPECT_EQ(e.worst_case_mm, 0.0);
    const Sensitivity sens = tolerance_sensitivity(m, at);
    EXPECT_EQ(sens.status, Status::singular_type2);
    EXPECT_TRUE(sens.S.allFinite());
    const MonteCarloTolerance mc = tolerance_monte_carlo(m, at, uniform_sigmas(0.05, 0.01), 100, 1);
    EXPECT_EQ(mc.status, Status::singular_type2);
    EXPECT_TRUE(mc.covariance.allFinite());
  }
  // Unreachable points carry their own status.
  EXPECT_EQ(tolerance_first_order(m, Vec2(6.25, 100.0), uniform_sigmas(0.05, 0.01), 1e-4).status,
            Status::unreachable);
}

// --- The `tolerance:` section -------------------------------------------------------------------

const char* const kStation = R"(name: tol
stations:
  index:
    target: {center: [6.25, 15.5], axes: [15, 12], angle: 0}
    mechanisms:
      lower: {bases: [[0, 0], [12.5, 0]], links: [9, 9, 15, 15], working_mode: "-+"}
)";

TEST(ToleranceSection, DefaultsRoundTripAndSigmas) {
  const Design bare = load_design_from_string(std::string(kStation), "bare.yaml");
  EXPECT_EQ(bare.get<ToleranceSettings>(), nullptr);
  const Design d = load_design_from_string(std::string(kStation) + "tolerance:\n", "defaults.yaml");
  const ToleranceSettings* t = d.get<ToleranceSettings>();
  ASSERT_NE(t, nullptr);
  EXPECT_EQ(t->adc_bits, 16);
  const Design given = load_design_from_string(
      std::string(kStation) +
          "tolerance: {link_sigma_mm: 0.03, pin_sigma_mm: 0.04, base_sigma_mm: 0.2, angle_sigma_deg: 1.5,\n"
          "            adc_bits: 12, samples: 500, seed: 9}\n",
      "given.yaml");
  const ToleranceSettings* g = given.get<ToleranceSettings>();
  ASSERT_NE(g, nullptr);
  EXPECT_EQ(g->adc_bits, 12);
  EXPECT_EQ(g->samples, 500u);
  EXPECT_EQ(g->seed, 9u);
  const Design again = load_design_from_string(to_yaml(given), "again.yaml");
  const ToleranceSettings* r = again.get<ToleranceSettings>();
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->link_sigma_mm, 0.03);
  EXPECT_EQ(r->pin_sigma_mm, 0.04);
  EXPECT_EQ(r->base_sigma_mm, 0.2);
  EXPECT_EQ(r->angle_sigma_deg, 1.5);
  EXPECT_EQ(r->adc_bits, 12);
  EXPECT_EQ(r->samples, 500u);
  EXPECT_EQ(r->seed, 9u);
  // Link length: 0.03 mm of length and two holes of 0.04 mm along it: sqrt(0.0009 + 0.0032).
  const ParameterSigmas s = parameter_sigmas(*g);
  EXPECT_NEAR(s[0], std::sqrt(0.0041), 1e-15);
  EXPECT_EQ(s[3], s[0]);
  EXPECT_EQ(s[4], 0.2);
  EXPECT_EQ(s[7], 0.2);
  EXPECT_NEAR(s[9], 1.5 * std::numbers::pi / 180.0, 1e-15);
}

TEST(ToleranceSection, BadValuesNameFileLineAndKey) {
  const struct {
    const char* text;
    const char* expect;
  } cases[] = {
      {"tolerance:\n  link_sigma_mm: -1\n", "bad.yaml:8: tolerance.link_sigma_mm"},
      {"tolerance:\n  angle_sigma_deg: 20\n", "bad.yaml:8: tolerance.angle_sigma_deg"},
      {"tolerance:\n  adc_bits: 40\n", "bad.yaml:8: tolerance.adc_bits"},
      {"tolerance:\n  samples: 1.5\n", "bad.yaml:8: tolerance.samples"},
      {"tolerance:\n  sigma: 1\n", "bad.yaml:8: tolerance.sigma"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.text);
    try {
      (void)load_design_from_string(std::string(kStation) + c.text, "bad.yaml");
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.expect), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace fivebar
