// Kinematic calibration (fivebar/calibrate.hpp) against known synthetic truth: measurements made by
// a "true" device whose parameters differ from the design's, with noise and effects the model does
// not have (ADC quantisation, a small compliance), fitted back.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <set>
#include <string>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "fivebar/calibrate.hpp"
#include "fivebar/design.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/format.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/provenance.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/provenance.hpp"
#include "fivebar/sha256.hpp"
#include "fivebar/tolerance.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <numbers>

namespace fivebar::calibrate {
namespace {

const Design& paper() {
  static const Design d = load_design(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  return d;
}

std::uint64_t base_seed() {
  const char* s = std::getenv("FIVEBAR_TEST_SEED");
  return s != nullptr ? std::strtoull(s, nullptr, 10) : 1;
}

#if defined(FIVEBAR_SANITIZE)
constexpr int kSeeds = 12;
#else
constexpr int kSeeds = 120;
#endif

/// A true device: the design's parameters perturbed; measurements of it at `poses` random joint
/// targets over the target ellipse.
struct Truth {
  MechanismVector q;
  FrameVector frame = FrameVector::Zero();
};

MechanismVector design_q(const std::string& mech) {
  const Design& d = paper();
  const Mechanism& m = *d.station("index")->mechanism(mech);
  const auto* c = d.get<ControllerSettings>();
  const auto p1 = c->joint("index", mech, 1).potentiometer, p2 = c->joint("index", mech, 2).potentiometer;
  return mechanism_vector(m, p1.volts_at_zero, p1.rad_per_volt, p2.volts_at_zero, p2.rad_per_volt);
}

Truth perturbed(const std::string& mech, std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Truth t;
  t.q = design_q(mech);
  for (int i = 0; i < 8; ++i) t.q[i] += 0.1 * n(rng);
  t.q[8] += 0.03 * n(rng);
  t.q[10] += 0.03 * n(rng);
  t.q[9] *= 1.0 + 0.02 * n(rng);
  t.q[11] *= 1.0 + 0.02 * n(rng);
  return t;
}

struct Synthetic {
  double noise_mm = 0.02;
  bool quantise = true;      ///< 16-bit ADC over +-10 V
  double compliance = 0.002; ///< mm of tactor deflection per unit of cos(theta1 - theta2) (unmodelled)
};

std::vector<Measurement> measure(const std::string& mech, const Truth& t, int n, std::mt19937_64& rng, const Synthetic& s = {}) {
  const Design& d = paper();
  const Mechanism& m = *d.station("index")->mechanism(mech);
  const Mechanism truth = with_geometry(m, t.q);
  const Ellipse& e = d.station("index")->target;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, s.noise_mm);
  std::vector<Measurement> out;
  while (static_cast<int>(out.size()) < n) {
    const Vec2 p = e.center + Vec2(u(rng) * e.axes.x() / 2, u(rng) * e.axes.y() / 2);
    const Pose ik_pose = ik(truth, p);
    if (ik_pose.status != Status::ok || ik_pose.lci < 0.1) continue;
    Measurement r;
    r.station = "index";
    r.mechanism = mech;
    r.volts1 = t.q[8] + ik_pose.theta1 / t.q[9];
    r.volts2 = t.q[10] + ik_pose.theta2 / t.q[11];
    if (s.quantise) {
      const double q = 20.0 / 65536.0;
      r.volts1 = -10.0 + std::floor((r.volts1 + 10.0) / q) * q;
      r.volts2 = -10.0 + std::floor((r.volts2 + 10.0) / q) * q;
    }
    const Pose pose = fk(truth, t.q[9] * (r.volts1 - t.q[8]), t.q[11] * (r.volts2 - t.q[10]));
    if (pose.status != Status::ok) continue;
    const double c = std::cos(pose.theta1 - pose.theta2);
    const Vec2 bend = s.compliance * c * Vec2(1.0, 0.5);
    const double ct = std::cos(t.frame[0]), st = std::sin(t.frame[0]);
    const Vec2 P = pose.P + bend;
    r.point = Vec2(ct * P.x() - st * P.y(), st * P.x() + ct * P.y()) + t.frame.tail<2>() + Vec2(noise(rng), noise(rng));
    r.line = static_cast<int>(out.size()) + 2;
    out.push_back(r);
  }
  return out;
}

/// The true value of a result parameter, in its file unit.
double true_value(const Parameter& p, const MechanismVector& q) {
  const auto& names = mechanism_parameter_names();
  const auto i = std::find(names.begin(), names.end(), p.name) - names.begin();
  if (i == 6) return q[4] + q[6];
  if (i == 7) return q[5] + q[7];
  return q[i];
}

TEST(CalibrateModel, AnalyticJacobianMatchesCentralDifferences) {
  std::mt19937_64 rng(base_seed());
  for (const std::string mech : {"lower", "upper"}) {
    const Mechanism& m = *paper().station("index")->mechanism(mech);
    const Truth t = perturbed(mech, rng);
    FrameVector frame(0.03, 0.4, -0.2);
    for (const Measurement& r : measure(mech, t, 20, rng)) {
      SCOPED_TRACE(mech + " pose at line " + std::to_string(r.line));
      const Prediction p = predict(m, t.q, frame, r.volts1, r.volts2);
      ASSERT_EQ(p.status, Status::ok);
      for (int k = 0; k < kMechanismParameters + kFrameParameters; ++k) {
        MechanismVector qp = t.q, qm = t.q;
        FrameVector fp = frame, fm = frame;
        const double base = k < kMechanismParameters ? t.q[k] : frame[k - kMechanismParameters];
        const double h = 1e-6 * std::max(1.0, std::abs(base));
        if (k < kMechanismParameters) qp[k] += h, qm[k] -= h;
        else fp[k - kMechanismParameters] += h, fm[k - kMechanismParameters] -= h;
        const Vec2 numeric = (predict(m, qp, fp, r.volts1, r.volts2).y - predict(m, qm, fm, r.volts1, r.volts2).y) / (2 * h);
        const Vec2 analytic = k < kMechanismParameters ? Vec2(p.dq.col(k)) : Vec2(p.dframe.col(k - kMechanismParameters));
        EXPECT_NEAR((numeric - analytic).norm(), 0.0, 1e-6 * std::max(1.0, analytic.norm())) << "parameter " << k;
      }
    }
  }
}

TEST(Calibrate, RecoversTheTruthWithinItsThreeSigmaOverManySeeds) {
  int inside = 0, cases = 0;
  double rms_ratio_sum = 0.0;
  for (int seed = 0; seed < kSeeds; ++seed) {
    std::mt19937_64 rng(base_seed() * 1000003 + static_cast<std::uint64_t>(seed));
    const Truth t = perturbed("lower", rng);
    const Synthetic s;
    const auto rows = measure("lower", t, 60, rng, s);
    CalibrateOptions o;
    o.mechanisms = {"lower"};
    const CalibrationResult r = calibrate(paper(), rows, o, "synthetic");
    ASSERT_TRUE(r.unidentifiable.empty()) << "seed " << seed;
    for (const Parameter& p : r.parameters) {
      ASSERT_TRUE(p.identified) << p.key;
      ASSERT_GT(p.sigma, 0.0) << p.key;
      ++cases;
      if (std::abs(p.value - true_value(p, t.q)) <= 3.0 * p.sigma) ++inside;
    }
    // Residuals at the noise level: RMS of |r| over 2D residuals is sqrt(2) sigma per axis.
    rms_ratio_sum += r.after.rms_mm / (std::sqrt(2.0) * s.noise_mm);
    EXPECT_LT(r.after.rms_mm, r.before.rms_mm);
  }
  const double coverage = static_cast<double>(inside) / cases;
  const double mean_ratio = rms_ratio_sum / kSeeds;
  std::printf("[calibrate] 3-sigma coverage %d / %d = %.4f over %d seeds; residual RMS / noise = %.4f\n", inside, cases, coverage,
              kSeeds, mean_ratio);
  EXPECT_GE(coverage, 0.97);
  EXPECT_NEAR(mean_ratio, 1.0, 0.1);
}

TEST(Calibrate, FrameFitNamesO1AndTheFrameTranslationAsOneCombination) {
  std::mt19937_64 rng(base_seed());
  Truth lower = perturbed("lower", rng), upper = perturbed("upper", rng);
  lower.frame = upper.frame = FrameVector(0.01, 0.3, -0.4);
  auto rows = measure("lower", lower, 40, rng);
  for (const auto& r : measure("upper", upper, 40, rng)) rows.push_back(r);
  CalibrateOptions o;
  o.fit_frame = true;
  const CalibrationResult r = calibrate(paper(), rows, o, "synthetic");
  std::vector<std::string> names;
  for (const auto& u : r.unidentifiable) names.push_back(u.parameter);
  // Translating the instrument is translating both mechanisms (both O1 together): one O1 is held,
  // the lower's (the station frame's origin); its rotation is held by the lower O2 - O1 y.
  EXPECT_THAT(names, ::testing::UnorderedElementsAre("lower.O1x", "lower.O1y", "lower.O2y"));
  for (const auto& u : r.unidentifiable) {
    if (u.parameter == "lower.O1x") {
      EXPECT_THAT(u.combination, ::testing::HasSubstr("frame.x"));
      EXPECT_THAT(u.combination, ::testing::HasSubstr("upper.O1x"));
    }
    if (u.parameter == "lower.O2y") EXPECT_THAT(u.combination, ::testing::HasSubstr("frame.rotation"));
  }
  // The upper O1 is then known relative to the lower one: within 3 sigma of the truth's offset.
  for (const Parameter& p : r.parameters) {
    if (p.mechanism == "upper" && p.name == "O1x") {
      ASSERT_TRUE(p.identified);
      const double truth = upper.q[4] - lower.q[4];  // the lower O1 held at the design's x = 0
      EXPECT_NEAR(p.value - paper().station("index")->lower->O1.x(), truth, 3.0 * p.sigma + 1e-3);
    }
  }
  EXPECT_FALSE(r.requested_unidentifiable);
  // Asking for them by name is a failed check.
  o.fit = {"L1", "O1x", "frame.x"};
  o.fit_given = true;
  EXPECT_TRUE(calibrate(paper(), rows, o, "synthetic").requested_unidentifiable);
}

TEST(Calibrate, HoldoutErrorIsAtTheNoiseLevelAndRobustLossResistsOutliers) {
  std::mt19937_64 rng(base_seed() + 7);
  const Truth t = perturbed("lower", rng);
  auto rows = measure("lower", t, 80, rng);
  CalibrateOptions o;
  o.holdout = 10;
  const CalibrationResult r = calibrate(paper(), rows, o, "synthetic");
  EXPECT_EQ(r.poses, 70);
  EXPECT_EQ(r.holdout_poses, 10);
  EXPECT_LT(r.holdout_after.rms_mm, 2.0 * std::sqrt(2.0) * 0.02);
  EXPECT_GT(r.holdout_before.rms_mm, 3.0 * r.holdout_after.rms_mm);
  // Five gross outliers (2 mm): least squares is pulled, Huber is not.
  const auto measure_clean = rows;
  for (int i = 0; i < 5; ++i) rows[static_cast<std::size_t>(i * 13)].point.x() += 2.0;
  CalibrateOptions plain, huber;
  huber.loss = Loss::huber;
  const auto err = [&](const CalibrationResult& res) {
    double e = 0.0;
    for (const Parameter& p : res.parameters) {
      if (p.unit == "mm") e = std::max(e, std::abs(p.value - true_value(p, t.q)));
    }
    return e;
  };
  const double e_plain = err(calibrate(paper(), rows, plain, "synthetic"));
  const double e_huber = err(calibrate(paper(), rows, huber, "synthetic"));
  const double e_clean = err(calibrate(paper(), measure_clean, plain, "synthetic"));
  std::printf("[calibrate] largest length error: clean %.4f mm, 5 outliers least squares %.4f mm, Huber %.4f mm\n", e_clean, e_plain, e_huber);
  EXPECT_LT(e_huber, 0.25 * e_plain);
  EXPECT_LT(e_huber, 3.0 * e_clean);
}

TEST(Calibrate, BadRequestsNameTheProblem) {
  std::mt19937_64 rng(base_seed());
  const auto rows = measure("lower", perturbed("lower", rng), 5, rng);
  CalibrateOptions o;
  EXPECT_THAT([&] { calibrate(paper(), rows, o, "m.csv"); }, ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("10 equations for 12 unknowns")));
  o.fit = {"L9"};
  o.fit_given = true;
  EXPECT_THAT([&] { calibrate(paper(), rows, o, "m.csv"); }, ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("unknown parameter 'L9'")));
}

TEST(CalibratePlan, PlannedPosesBeatRandomPosesInPosteriorSigma) {
  PlanOptions o;
  o.criterion = PlanCriterion::d_optimal;  // the option that optimises the parameters themselves
  o.poses = 20;
  o.random_trials = 30;
  const auto plans = plan_poses(paper(), "index", "", o);
  ASSERT_EQ(plans.size(), 2u);
  for (const MechanismPlan& p : plans) {
    SCOPED_TRACE(p.mechanism);
    ASSERT_TRUE(p.problem.empty()) << p.problem;
    ASSERT_EQ(p.poses.size(), 20u);
    EXPECT_GT(p.observability_index, p.random_observability_index);
    // An independent check of the claim: the posterior sigmas of the plan against fresh random sets
    // drawn from the target ellipse by IK (not the planner's candidates).
    double planned = 0.0, random = 0.0;
    for (std::size_t k = 0; k < p.expected_sigma.size(); ++k) planned += std::log(p.expected_sigma[k]);
    std::mt19937_64 rng(base_seed());
    const Mechanism& m = *paper().station("index")->mechanism(p.mechanism);
    const MechanismVector q = design_q(p.mechanism);
    std::vector<PlannedPose> rnd;
    for (const Measurement& r : measure(p.mechanism, Truth{q}, 20, rng)) rnd.push_back({0, 0, r.volts1, r.volts2, r.point});
    for (double s : posterior_sigma(m, q, rnd, o.sigma_mm)) random += std::log(s);
    EXPECT_LT(planned, random);
    // Every planned pose lies in the usable ranges and reaches its point.
    for (const PlannedPose& pose : p.poses) {
      const Pose f = fk(m, pose.theta1, pose.theta2);
      EXPECT_EQ(f.status, Status::ok);
      EXPECT_NEAR((f.P - pose.point).norm(), 0.0, 1e-9);
    }
  }
}

// The default plan minimises the predicted tactor error over the target (I-optimal). Reference,
// computed here apart from the planner: the first-order tactor covariance G C G^T after a fit with
// C = sigma^2 (J^T J)^{-1} (unscaled J), averaged over random points of the target ellipse reached
// by IK, against sets of as many random joint-space poses (uniform over the usable ranges, any
// that assemble). Every planned pose keeps the margins and is reached by devices drawn within
// 3 prior sigmas of each parameter.
TEST(CalibratePlan, PlanBeatsRandomJointSpacePosesOnTheTargetErrorAndIsReachable) {
  const Design& d = paper();
  const Station& st = *d.station("index");
  std::mt19937_64 rng(base_seed() + 21);
  for (const int n : {12, 20}) {
    PlanOptions o;
    o.poses = n;
    o.random_trials = 5;
    for (const MechanismPlan& p : plan_poses(d, "index", "", o)) {
      SCOPED_TRACE(p.mechanism + " " + std::to_string(n) + " poses");
      ASSERT_TRUE(p.problem.empty()) << p.problem;
      const Mechanism& m = *st.mechanism(p.mechanism);
      const MechanismVector q = design_q(p.mechanism);
      std::vector<Vec2> points;
      std::uniform_real_distribution<double> u(-1.0, 1.0);
      while (points.size() < 200) {
        const Vec2 x(u(rng), u(rng));
        if (x.squaredNorm() > 1.0) continue;
        const Vec2 P = st.target.center + Vec2(x.x() * st.target.axes.x() / 2, x.y() * st.target.axes.y() / 2);  // angle 0
        if (ik(m, P).status == Status::ok) points.push_back(P);
      }
      const auto target_error = [&](const std::vector<std::pair<double, double>>& volts) {
        Eigen::MatrixXd J(2 * static_cast<Eigen::Index>(volts.size()), kMechanismParameters);
        for (std::size_t i = 0; i < volts.size(); ++i) {
          const Prediction pr = predict(m, q, FrameVector::Zero(), volts[i].first, volts[i].second);
          if (pr.status != Status::ok) return std::numeric_limits<double>::infinity();
          J.block<2, kMechanismParameters>(2 * static_cast<Eigen::Index>(i), 0) = pr.dq;
        }
        const Eigen::MatrixXd JtJ = J.transpose() * J;
        Eigen::FullPivLU<Eigen::MatrixXd> lu(JtJ);
        if (lu.rank() < kMechanismParameters) return std::numeric_limits<double>::infinity();
        const Eigen::MatrixXd C = 0.02 * 0.02 * lu.inverse();
        double sum = 0.0;
        for (const Vec2& P : points) {
          const Pose pose = ik(m, P);
          const Prediction g = predict(m, q, FrameVector::Zero(), q[8] + pose.theta1 / q[9], q[10] + pose.theta2 / q[11]);
          sum += (g.dq * C * g.dq.transpose()).trace();
        }
        return std::sqrt(sum / static_cast<double>(points.size()));
      };
      std::vector<std::pair<double, double>> planned;
      for (const PlannedPose& pose : p.poses) planned.emplace_back(pose.volts1, pose.volts2);
      const double plan_error = target_error(planned);
      const auto ranges = usable_ranges(d, st, m);
      std::vector<double> random;
      for (int t = 0; t < 40; ++t) {
        std::vector<std::pair<double, double>> v;
        while (static_cast<int>(v.size()) < n) {
          double th[2];
          for (int j = 0; j < 2; ++j) {
            const UsableRange& r = ranges[static_cast<std::size_t>(j)];
            th[j] = r.limited ? r.lo + (r.hi - r.lo) * (u(rng) + 1.0) / 2.0 : r.reference + std::numbers::pi * u(rng);
          }
          const Pose f = fk(m, th[0], th[1]);
          if (f.status != Status::ok || !(f.mode == m.working_mode)) continue;
          v.emplace_back(q[8] + th[0] / q[9], q[10] + th[1] / q[11]);
        }
        random.push_back(target_error(v));
      }
      std::nth_element(random.begin(), random.begin() + 20, random.end());
      std::printf("[calibrate] plan %s, %d poses: predicted target RMS error %.2f um (planner's own figure %.2f um), "
                  "random joint-space median %.2f um\n", p.mechanism.c_str(), n, plan_error * 1e3, p.predicted_target_error_mm * 1e3,
                  random[20] * 1e3);
      EXPECT_LT(plan_error, random[20]);
      EXPECT_NEAR(p.predicted_target_error_mm, plan_error, 0.05 * plan_error);
      // Margins and reachability of every planned pose.
      std::uniform_real_distribution<double> box(-3.0, 3.0);
      int unreachable = 0;
      for (const PlannedPose& pose : p.poses) {
        const Pose f = fk(m, pose.theta1, pose.theta2);
        for (int i = 0; i < 2; ++i) {
          const double r = (f.P - (i == 0 ? m.O1 : m.O2)).norm();
          EXPECT_LE(r, m.L[static_cast<std::size_t>(i)] + m.L[static_cast<std::size_t>(i + 2)] - o.extension_margin_mm);
        }
        const double side = p.mechanism == "lower" ? f.P.y() - m.O1.y() : m.O1.y() - f.P.y();  // base lines are horizontal here
        EXPECT_GE(side, o.base_margin_mm);
        for (int k = 0; k < 100; ++k) {
          MechanismVector dq = q;
          for (int i = 0; i < kMechanismParameters; ++i) dq[i] += box(rng) * (i < 8 ? 0.1 : i % 2 == 0 ? (std::numbers::pi / 180) / std::abs(q[i + 1]) : 0.01 * std::abs(q[i]));
          const Pose g = fk(with_geometry(m, dq), dq[9] * (pose.volts1 - dq[8]), dq[11] * (pose.volts2 - dq[10]));
          if (g.status != Status::ok || !(g.mode == m.working_mode)) ++unreachable;
        }
      }
      EXPECT_EQ(unreachable, 0);
    }
  }
}

TEST(CalibratePatch, PatchedDesignCarriesTheEstimatesAndTheirProvenance) {
  std::mt19937_64 rng(base_seed());
  const Truth t = perturbed("lower", rng);
  const auto rows = measure("lower", t, 60, rng);
  const CalibrationResult r = calibrate(paper(), rows, {}, "synthetic");
  ASSERT_TRUE(r.gate.passed) << ::testing::PrintToString(r.gate.refusal_lines());
  Source src{"bench/m.csv", sha256_hex("x"), "2026-11-26"};
  const Design d = with_provenance(patched_design(paper(), r), r, src);
  const Design back = load_design_from_string(to_yaml(d), "patched");
  for (const Parameter& p : r.parameters) {
    EXPECT_NEAR(design_number(back, p.key), p.value, 1e-12 * std::max(1.0, std::abs(p.value))) << p.key;
    EXPECT_TRUE(is_measured(back, p.key)) << p.key;
  }
  // The other mechanism stays assumed; the potentiometer group too (upper joints).
  EXPECT_FALSE(is_measured(back, "stations.index.mechanisms.upper.links[0]"));
  const auto assumed = assumed_values(back, "potentiometer");
  EXPECT_THAT(assumed, ::testing::Contains(::testing::HasSubstr("upper")));
  EXPECT_THAT(assumed, ::testing::Not(::testing::Contains(::testing::HasSubstr("stations.index.lower"))));
  EXPECT_THAT(assumed_groups(back), ::testing::Contains("kinematics"));
  // The posterior covariance survives the file: sigmas and correlations read back give it again,
  // its diagonal is each parameter's reported sigma squared (computed separately in fit.cpp, O2 with
  // O1's share), and the correlations are real (the links and bases of a mechanism are not
  // independent after a fit).
  const ProvenanceCovariance pc = provenance_covariance(back, r.key_covariance_keys);
  ASSERT_EQ(pc.covariance.rows(), r.key_covariance.rows());
  ASSERT_EQ(r.key_covariance_keys.size(), 12u);
  EXPECT_EQ(pc.sources, std::vector<std::string>{"bench/m.csv"});
  double largest = 0.0;
  for (Eigen::Index a = 0; a < pc.covariance.rows(); ++a) {
    const auto p = std::find_if(r.parameters.begin(), r.parameters.end(),
                                [&](const Parameter& q) { return q.key == r.key_covariance_keys[static_cast<std::size_t>(a)]; });
    EXPECT_NEAR(r.key_covariance(a, a), p->sigma * p->sigma, 1e-12 * p->sigma * p->sigma) << p->key;
    for (Eigen::Index b = 0; b < pc.covariance.cols(); ++b) {
      const double scale = std::sqrt(r.key_covariance(a, a) * r.key_covariance(b, b));
      EXPECT_NEAR(pc.covariance(a, b), r.key_covariance(a, b), 1e-12 * scale) << a << "," << b;
      if (a != b) largest = std::max(largest, std::abs(r.key_covariance(a, b)) / scale);
    }
  }
  EXPECT_GT(largest, 0.3);
  // A later measurement of one key supersedes its entry and drops its correlations.
  const Design again = with_measured_values(back, {{r.key_covariance_keys[0], 0.5}}, {"other.csv", sha256_hex("y"), "2026-11-27", "by hand"});
  const ProvenanceCovariance pc2 = provenance_covariance(again, r.key_covariance_keys);
  EXPECT_DOUBLE_EQ(pc2.covariance(0, 0), 0.25);
  for (Eigen::Index b = 1; b < pc2.covariance.cols(); ++b) EXPECT_EQ(pc2.covariance(0, b), 0.0);
  EXPECT_NEAR(pc2.covariance(1, 2), r.key_covariance(1, 2), 1e-12 * std::sqrt(r.key_covariance(1, 1) * r.key_covariance(2, 2)));
}

// The calibration's posterior covariance replaces the tolerance: sigmas it covers. Reference: a
// Monte Carlo over the twelve calibration parameters drawn from the fit's own key covariance (Cholesky
// in the test), each sampled device driven by the controller to the potentiometer voltages it
// believes put the tactor at the target centre (theta_j = k_j (V_j - V0_j) with the device's true
// k and V0, plus the potentiometer's linearity as a uniform error), its tactor by FK.
TEST(CalibratedTolerance, PosteriorCovarianceReplacesTheSigmasAndMatchesAMonteCarloOfTheParameters) {
  std::mt19937_64 rng(base_seed() + 7);
  const Truth t = perturbed("lower", rng);
  const auto rows = measure("lower", t, 30, rng);
  const CalibrationResult r = calibrate(paper(), rows, {}, "synthetic");
  const Design back = load_design_from_string(
      to_yaml(with_provenance(patched_design(paper(), r), r, {"bench/m.csv", sha256_hex("x"), "2026-11-26"})), "patched");
  const Station& st = *back.station("index");
  const Mechanism& m = *st.mechanism("lower");
  const ToleranceSources src = tolerance_sources(back, st, m);
  ASSERT_TRUE(src.calibrated.has_value());
  EXPECT_THAT(src.spread_source, ::testing::HasSubstr("calibration posterior covariance (bench/m.csv)"));
  EXPECT_TRUE(src.spread().calibrated());
  const auto keys = calibration_keys(back, "index", "lower");
  ASSERT_EQ(std::vector<std::string>(keys.begin(), keys.end()), r.key_covariance_keys);
  // The other mechanism keeps the tolerance: sigmas.
  EXPECT_FALSE(tolerance_sources(back, st, *st.mechanism("upper")).calibrated.has_value());

  // Nominal (calibrated) values the controller uses.
  const auto* c = back.get<ControllerSettings>();
  const Potentiometer p1 = c->joint("index", "lower", 1).potentiometer, p2 = c->joint("index", "lower", 2).potentiometer;
  const Vec2 P = st.target.center;
  const Pose nominal = ik(m, P);
  ASSERT_EQ(nominal.status, Status::ok);
  const double V1 = p1.volts_at_zero + nominal.theta1 / p1.rad_per_volt, V2 = p2.volts_at_zero + nominal.theta2 / p2.rad_per_volt;
  const ToleranceSettings tol = back.get<ToleranceSettings>() ? *back.get<ToleranceSettings>() : ToleranceSettings{};
  const double a = tol.linearity_percent / 100.0 * tol.pot_travel_deg * std::numbers::pi / 180.0;  // half band, rad
  const Eigen::MatrixXd L = Eigen::LLT<Eigen::MatrixXd>(r.key_covariance).matrixL();
#if defined(FIVEBAR_SANITIZE)
  const int n = 4000;
  const double tol_rel = 0.12;
#else
  const int n = 40000;
  const double tol_rel = 0.04;
#endif
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> lin(-a, a);
  Mechanism printed = m;
  printed.joint_limits.reset();
  printed.assembly_mode = nominal.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  Eigen::Matrix2d second = Eigen::Matrix2d::Zero();
  int used = 0;
  for (int k = 0; k < n; ++k) {
    Eigen::VectorXd z(12);
    for (int i = 0; i < 12; ++i) z[i] = normal(rng);
    const Eigen::VectorXd dp = L * z;
    for (int i = 0; i < 4; ++i) printed.L[static_cast<std::size_t>(i)] = m.L[static_cast<std::size_t>(i)] + dp[i];
    printed.O1 = m.O1 + Vec2(dp[4], dp[5]);
    printed.O2 = m.O2 + Vec2(dp[6], dp[7]);
    const double th1 = (p1.rad_per_volt + dp[9]) * (V1 - p1.volts_at_zero - dp[8]) + lin(rng);
    const double th2 = (p2.rad_per_volt + dp[11]) * (V2 - p2.volts_at_zero - dp[10]) + lin(rng);
    const PointResult f = fk_point(printed, th1, th2);
    if (f.status != Status::ok) continue;
    const Eigen::Vector2d e = f.P - P;
    ++used;
    mean += e;
    second += e * e.transpose();
  }
  ASSERT_GT(used, n * 99 / 100);
  mean /= used;
  const Eigen::Matrix2d mc = second / used - mean * mean.transpose();
  const ToleranceEstimate first = tolerance_first_order(m, P, src.spread(), src.rad_per_count[0]);
  ASSERT_EQ(first.status, Status::ok);
  const double rel = (first.covariance - mc).norm() / mc.norm();
  EXPECT_LT(rel, tol_rel) << "first order\n" << first.covariance << "\nMonte Carlo\n" << mc;
  EXPECT_NEAR(first.ellipse_semi_axes.x(), major_3sigma_mm(mc), 0.5 * tol_rel * major_3sigma_mm(mc));
  // The same sigmas taken as independent miss the correlations the fit left.
  const ParameterSpread at = src.spread().at(nominal.theta1, nominal.theta2);
  const ToleranceEstimate independent = tolerance_first_order(m, P, at.sigma(), src.rad_per_count[0]);
  const double rel_independent = (independent.covariance - mc).norm() / mc.norm();
  std::printf("[calibrate] tactor covariance at the target centre vs Monte Carlo of the parameters: full %.3f, "
              "independent %.3f (relative Frobenius); 3-sigma %.4f mm (Monte Carlo %.4f, tolerance: only %.4f)\n",
              rel, rel_independent, first.ellipse_semi_axes.x(), major_3sigma_mm(mc),
              tolerance_first_order(m, P, src.sigma, src.rad_per_count[0]).ellipse_semi_axes.x());
  EXPECT_GT(rel_independent, 0.5);
  // A calibrated device is known better than the tolerance: section's assumptions say.
  EXPECT_LT(first.ellipse_semi_axes.x(), tolerance_first_order(m, P, src.sigma, src.rad_per_count[0]).ellipse_semi_axes.x());

  // Robust coverage uses the covariance too: its sigma is sqrt(g^T C g) over the geometry block.
  const RobustCoverage rc = robust_coverage(m, st.target, src.spread(), 0.997, 0, 1);
  EXPECT_TRUE(rc.calibrated);
  Eigen::VectorXd g(8);
  for (int i = 0; i < 8; ++i) g[i] = rc.gradient[static_cast<std::size_t>(i)];
  EXPECT_NEAR(rc.sigma_mm, std::sqrt(g.dot(r.key_covariance.topLeftCorner(8, 8) * g)), 1e-9);
}

TEST(CalibratePatch, CorrelationsThatBreakTheRulesAreRefusedNamingTheKey) {
  const std::string head = to_yaml(paper());
  const std::string entry = "{source: m.csv, sha256: " + sha256_hex("x") + ", date: \"2026-11-26\", method: fit, sigma: 0.01";
  const auto load = [&](const std::string& extra) {
    return load_design_from_string(head + "provenance:\n  \"stations.index.mechanisms.lower.links[0]\": " + entry + extra +
                                       "}\n  \"stations.index.mechanisms.lower.links[1]\": " + entry + "}\n",
                                   "bad.yaml");
  };
  EXPECT_NO_THROW(load(", correlation: {\"stations.index.mechanisms.lower.links[1]\": -0.4}"));
  try {
    load(", correlation: {\"stations.index.mechanisms.lower.links[1]\": 1.5}");
    ADD_FAILURE() << "a correlation of 1.5 was accepted";
  } catch (const std::exception& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("correlation"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("[-1, 1]"));
  }
  try {
    load(", correlation: {\"stations.index.mechanisms.lower.links[2]\": 0.5}");
    ADD_FAILURE() << "a correlation with an unmeasured key was accepted";
  } catch (const std::exception& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("links[2]"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("without its own provenance entry"));
  }
}

// Provenance is validated as a whole (issue 45): dates of the calendar, and correlations that some
// covariance has. For three keys with rho01 = rho02 = a and rho12 = b the matrix is positive
// semi-definite iff 1 + 2 a^2 b - 2 a^2 - b^2 >= 0 (its determinant; the 2 x 2 minors are 1 - rho^2
// >= 0): a = 0.99, b = -0.99 gives -2.88 (refused), a = b = 0.5 gives 0.5 (accepted).
TEST(CalibratePatch, ProvenanceDatesAndCorrelationMatricesAreValidated) {
  const std::string head = to_yaml(paper());
  const auto entry = [](const std::string& date, const std::string& corr) {
    return "{source: m.csv, sha256: " + sha256_hex("x") + ", date: \"" + date + "\", method: fit, sigma: 0.01" +
           (corr.empty() ? "" : ", correlation: {" + corr + "}") + "}";
  };
  const std::string L = "stations.index.mechanisms.lower.links";
  const auto load_three = [&](double a, double b) {
    return load_design_from_string(head + "provenance:\n  \"" + L + "[0]\": " +
                                       entry("2026-11-26", "\"" + L + "[1]\": " + std::to_string(a) + ", \"" + L + "[2]\": " + std::to_string(a)) +
                                       "\n  \"" + L + "[1]\": " + entry("2026-11-26", "\"" + L + "[2]\": " + std::to_string(b)) +
                                       "\n  \"" + L + "[2]\": " + entry("2026-11-26", "") + "\n",
                                   "bad.yaml");
  };
  const auto det = [](double a, double b) { return 1 + 2 * a * a * b - 2 * a * a - b * b; };
  ASSERT_GT(det(0.5, 0.5), 0.0);
  ASSERT_LT(det(0.99, -0.99), 0.0);
  EXPECT_NO_THROW(load_three(0.5, 0.5));
  try {
    load_three(0.99, -0.99);
    ADD_FAILURE() << "correlations that no covariance has were accepted";
  } catch (const std::exception& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("bad.yaml:"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("not positive semi-definite"));
  }
  const auto load_date = [&](const std::string& date) {
    return load_design_from_string(head + "provenance:\n  \"" + L + "[0]\": " + entry(date, "") + "\n", "bad.yaml");
  };
  EXPECT_NO_THROW(load_date("2024-02-29"));  // a leap year
  for (const std::string bad : {"2024-13-45", "2023-02-29", "2100-02-29", "2026-04-31", "2026-00-10", "2026-01-00"}) {
    try {
      load_date(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const std::exception& e) {
      EXPECT_THAT(e.what(), ::testing::HasSubstr("date = " + bad + ": not a date of the calendar"));
    }
  }
}

TEST(CalibrateHardStops, OffsetsFromTwoStopsRecoverTheTruth) {
  // The paper design has hard stops where a proximal link meets the other motor's round end.
  const Design& d = paper();
  const Station& st = *d.station("index");
  std::string csv = "station,mechanism,joint,stop,volts\n";
  // A joint with both stops gets V0 and k; with one, V0 at the design's k.
  const double v0 = 0.31, k_true = 1.0 / 0.93;
  const double k_design = d.get<ControllerSettings>()->joint("index", "lower", 1).potentiometer.rad_per_volt;
  std::array<double, 2> k_used{};
  int stops = 0;
  for (int j = 1; j <= 2; ++j) {
    const auto range = usable_ranges(d, st, *st.lower)[static_cast<std::size_t>(j - 1)];
    const bool lo = range.lo_by.rfind("hard stop", 0) == 0, hi = range.hi_by.rfind("hard stop", 0) == 0;
    const double k = lo && hi ? k_true : k_design;
    k_used[static_cast<std::size_t>(j - 1)] = k;
    if (lo) csv += "index,lower," + std::to_string(j) + ",lo," + format::shortest(v0 + range.lo / k) + "\n", ++stops;
    if (hi) csv += "index,lower," + std::to_string(j) + ",hi," + format::shortest(v0 + range.hi / k) + "\n", ++stops;
  }
  if (stops == 0) GTEST_SKIP() << "no hard stop in the paper design";
  const CalibrationResult r = hard_stop_calibration(d, csv, "stops.csv");
  bool any = false;
  for (const Parameter& p : r.parameters) {
    const std::size_t j = p.name.starts_with("theta1") ? 0 : 1;
    if (p.unit == "V") {
      any = true;
      EXPECT_TRUE(p.identified);
      EXPECT_NEAR(p.value, v0, 1e-9) << p.key;
    } else {
      EXPECT_NEAR(p.value, k_used[j], 1e-9 * k_used[j]) << p.key;
    }
  }
  EXPECT_TRUE(any);
  EXPECT_THAT([&] { hard_stop_calibration(d, "station,mechanism,joint,stop,volts\nindex,lower,3,lo,1\n", "s.csv"); },
              ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("s.csv:2: column 'joint'")));
}


// The quality gate (fivebar/provenance/gate.hpp) on a fit that cannot determine its parameters:
// every pose on one horizontal line of the target. Nothing may be written as measured, and each
// refused value says why.
TEST(CalibrateGate, PosesOnALineAreRefusedWithReasonsPerParameter) {
  std::mt19937_64 rng(base_seed() + 3);
  const Truth t = perturbed("lower", rng);
  const Design& d = paper();
  const Mechanism truth = with_geometry(*d.station("index")->lower, t.q);
  const Ellipse& e = d.station("index")->target;
  std::normal_distribution<double> noise(0.0, 0.02);
  std::vector<Measurement> rows;
  for (int k = 0; k < 30; ++k) {
    const Vec2 p = e.center + Vec2((k / 29.0 - 0.5) * 0.8 * e.axes.x(), 0.0);
    const Pose pose = ik(truth, p);
    ASSERT_EQ(pose.status, Status::ok);
    Measurement r;
    r.station = "index";
    r.mechanism = "lower";
    r.volts1 = t.q[8] + pose.theta1 / t.q[9];
    r.volts2 = t.q[10] + pose.theta2 / t.q[11];
    r.point = p + Vec2(noise(rng), noise(rng));
    r.line = k + 2;
    rows.push_back(r);
  }
  const CalibrationResult r = calibrate(d, rows, {}, "line.csv");
  std::printf("[calibrate] poses on a line: solver %s, gate %s\n", r.termination.c_str(), r.gate.passed ? "passed" : "refused");
  EXPECT_FALSE(r.gate.passed);
  const auto lines = r.gate.refusal_lines();
  ASSERT_FALSE(lines.empty());
  for (const std::string& l : lines) std::printf("  %s\n", l.c_str());
  // Each refused value names its key and a reason: the solver's verdict or a sigma beyond its prior.
  for (const std::string& l : lines) {
    EXPECT_THAT(l, ::testing::AnyOf(::testing::HasSubstr("did not converge"), ::testing::HasSubstr("its prior")));
    EXPECT_THAT(l, ::testing::HasSubstr("stations.index."));
  }
  if (!r.converged) EXPECT_THAT(lines.front(), ::testing::HasSubstr("(" + r.termination + ")"));
  // The writer refuses a refused fit.
  EXPECT_THROW(with_provenance(patched_design(d, r), r, {"line.csv", sha256_hex("x"), "2026-11-26"}), std::logic_error);
}

// A good fit passes: with the sigma stated, by its chi-square test (the unmodelled compliance of the
// synthetic device is a tenth of the noise), and the patched design's entries record the gate.
TEST(CalibrateGate, AGoodFitPassesAndItsEntriesRecordTheGate) {
  std::mt19937_64 rng(base_seed() + 5);
  const Truth t = perturbed("lower", rng);
  auto rows = measure("lower", t, 60, rng);
  for (Measurement& m : rows) m.sigma_mm = 0.02;
  const CalibrationResult r = calibrate(paper(), rows, {}, "good.csv");
  ASSERT_TRUE(r.gate.passed) << (r.gate.refusal_lines().empty() ? "" : r.gate.refusal_lines().front());
  EXPECT_EQ(r.termination, "CONVERGENCE");
  ASSERT_EQ(r.gate.tests.size(), 1u);
  EXPECT_EQ(r.gate.tests[0].name, "chi-square");
  EXPECT_EQ(r.gate.parameters.size(), 12u);
  const Design back = load_design_from_string(
      to_yaml(with_provenance(patched_design(paper(), r), r, {"good.csv", sha256_hex("x"), "2026-11-26"})), "patched");
  const auto* entry = &back.get<ProvenanceSettings>()->entries.at("stations.index.mechanisms.lower.links[2]");
  ASSERT_TRUE(entry->gate.has_value());
  EXPECT_TRUE(entry->gate->passed);
  EXPECT_EQ(entry->gate->solver, "CONVERGENCE");
  EXPECT_THAT(entry->gate->tests, ::testing::HasSubstr("chi-square"));
  ASSERT_TRUE(entry->gate->sigma_ratio.has_value());
  EXPECT_LT(*entry->gate->sigma_ratio, 1.0);
  EXPECT_TRUE(untrusted_values(back, "kinematics", {"index"}, "lower").empty());
  // A sigma stated ten times too small: the chi-square test refuses the fit.
  for (Measurement& m : rows) m.sigma_mm = 0.002;
  const CalibrationResult small = calibrate(paper(), rows, {}, "good.csv");
  EXPECT_FALSE(small.gate.passed);
  EXPECT_THAT(small.gate.reasons.front(), ::testing::HasSubstr("larger than the stated measurement sigma"));
}

// Honest sigmas under a robust loss: 5 % of the poses carry a 1-mm blunder. The robust fit names
// them, and the estimate and covariance are least squares over the other poses: the truth lies
// within 3 sigma in at least 95 % of (parameter, seed) cases, and the blunders are the poses named.
TEST(CalibrateRobust, SigmasStayHonestWithFivePercentBlunders) {
  int inside = 0, cases = 0, named = 0, blunders = 0, wrongly = 0;
  for (const Loss loss : {Loss::huber, Loss::cauchy}) {
    for (int seed = 0; seed < 20; ++seed) {
      std::mt19937_64 rng(base_seed() * 7919 + static_cast<std::uint64_t>(seed));
      const Truth t = perturbed("lower", rng);
      auto rows = measure("lower", t, 60, rng);
      std::uniform_real_distribution<double> angle(0.0, 2.0 * std::numbers::pi);
      std::set<int> bad;
      for (int k = 0; k < 3; ++k) {  // 5 % of 60
        Measurement& m = rows[static_cast<std::size_t>(7 + 19 * k)];
        const double a = angle(rng);
        m.point += Vec2(std::cos(a), std::sin(a));
        bad.insert(m.line);
      }
      CalibrateOptions o;
      o.loss = loss;
      const CalibrationResult r = calibrate(paper(), rows, o, "blunders.csv");
      for (const ExcludedPose& e : r.outliers) (bad.count(e.line) != 0 ? named : wrongly) += 1;
      blunders += static_cast<int>(bad.size());
      for (const Parameter& p : r.parameters) {
        ++cases;
        if (std::abs(p.value - true_value(p, t.q)) <= 3.0 * p.sigma) ++inside;
      }
      EXPECT_TRUE(r.gate.passed) << "seed " << seed << ": " << ::testing::PrintToString(r.gate.refusal_lines());
    }
  }
  const double coverage = static_cast<double>(inside) / cases;
  std::printf("[calibrate] robust loss, 5%% 1-mm blunders: 3-sigma coverage %d / %d = %.4f; blunders named %d / %d, "
              "clean poses named %d\n", inside, cases, coverage, named, blunders, wrongly);
  EXPECT_GE(coverage, 0.95);
  EXPECT_EQ(named, blunders);
  EXPECT_LE(wrongly, blunders / 10);
}

// A pose the design's nominal model cannot assemble (the device reached it) is skipped and named;
// the fit goes on. Too few poses left is bad input naming the skipped lines.
TEST(Calibrate, APoseTheNominalModelCannotAssembleIsSkippedAndNamed) {
  std::mt19937_64 rng(base_seed() + 9);
  const Truth t = perturbed("lower", rng);
  auto rows = measure("lower", t, 40, rng);
  Measurement odd = rows.front();
  const MechanismVector q = design_q("lower");
  odd.volts1 = q[8] + std::numbers::pi / q[9];  // theta1 = 180 deg, theta2 = 0: A1 and A2 30.5 mm apart, L3 + L4 = 30
  odd.volts2 = q[10];
  odd.line = 99;
  ASSERT_NE(predict(*paper().station("index")->lower, q, FrameVector::Zero(), odd.volts1, odd.volts2).status, Status::ok);
  rows.push_back(odd);
  const CalibrationResult r = calibrate(paper(), rows, {}, "m.csv");
  ASSERT_EQ(r.skipped.size(), 1u);
  EXPECT_EQ(r.skipped[0].line, 99);
  EXPECT_THAT(r.skipped[0].reason, ::testing::HasSubstr("cannot assemble"));
  EXPECT_EQ(r.poses, 40);
  EXPECT_TRUE(r.gate.passed);
  std::vector<Measurement> few(rows.begin(), rows.begin() + 5);
  few.push_back(odd);
  EXPECT_THAT([&] { calibrate(paper(), few, {}, "m.csv"); },
              ::testing::ThrowsMessage<InputError>(::testing::HasSubstr("skipped: the design's model cannot assemble line 99")));
}

// Hard stops: one stop per joint holds the slope at the design's value, whose prior (1 % of k)
// enters V0's sigma (dV0/dk = theta_stop / k^2): with a true slope 1 % off, V0 stays within 3 sigma.
// One reading per stop gives no sigma: refused.
TEST(CalibrateHardStops, OneStopCarriesTheSlopePriorAndOneReadingIsRefused) {
  const Design& d = paper();
  const Station& st = *d.station("index");
  const double k_design = d.get<ControllerSettings>()->joint("index", "lower", 1).potentiometer.rad_per_volt;
  const double k_true = 1.01 * k_design, v0 = 0.31;
  std::string once = "station,mechanism,joint,stop,volts\n", twice = once;
  std::vector<double> theta;
  for (int j = 1; j <= 2; ++j) {
    const auto range = usable_ranges(d, st, *st.lower)[static_cast<std::size_t>(j - 1)];
    const bool lo = range.lo_by.rfind("hard stop", 0) == 0;
    if (!lo && range.hi_by.rfind("hard stop", 0) != 0) continue;
    const double th = lo ? range.lo : range.hi;
    const std::string row = "index,lower," + std::to_string(j) + "," + (lo ? "lo," : "hi,");
    once += row + format::shortest(v0 + th / k_true) + "\n";
    twice += row + format::shortest(v0 + th / k_true - 1e-4) + "\n" + row + format::shortest(v0 + th / k_true + 1e-4) + "\n";
    theta.push_back(th);
  }
  if (theta.empty()) GTEST_SKIP() << "no hard stop in the paper design";
  const CalibrationResult one = hard_stop_calibration(d, once, "once.csv");
  EXPECT_FALSE(one.gate.passed);
  EXPECT_THAT(one.gate.reasons.front(), ::testing::HasSubstr("read once"));
  const CalibrationResult two = hard_stop_calibration(d, twice, "twice.csv");
  std::size_t n = 0;
  for (const Parameter& p : two.parameters) {
    if (p.unit != "V") continue;
    const double th = theta[std::min(n++, theta.size() - 1)];
    // The slope's share of the sigma (the readings' spread is 1e-4 V / sqrt(2) ... ).
    EXPECT_GT(p.sigma, 0.9 * std::abs(th) / (k_design * k_design) * 0.01 * k_design) << p.key;
    EXPECT_LE(std::abs(p.value - v0), 3.0 * p.sigma) << p.key;
  }
}

TEST(Sha256, KnownAnswers) {
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(sha256_hex(std::string(1000000, 'a')), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

// The file is hashed streaming, 64 KiB at a time (docs/reliability.md "Resource bounds"): the FIPS
// 180-2 answer for a million 'a', and at every length around a chunk and a block boundary the
// digest of the whole text in one piece (whose known answers are above); past the bound, refused.
TEST(Sha256, AFileIsHashedStreamingAndBounded) {
  const std::filesystem::path file = std::filesystem::temp_directory_path() / ("fivebar_sha256_" + std::to_string(::getpid()));
  const auto write = [&](const std::string& text) { std::ofstream(file, std::ios::binary) << text; };
  write(std::string(1000000, 'a'));
  EXPECT_EQ(sha256_file(file), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  std::mt19937 rng(7);
  for (const std::size_t n : {0u, 1u, 55u, 56u, 63u, 64u, 65u, 119u, 120u, 65535u, 65536u, 65537u, 131071u, 131072u, 131135u}) {
    std::string text(n, '\0');
    for (char& c : text) c = static_cast<char>(rng() & 0xff);
    write(text);
    EXPECT_EQ(sha256_file(file), sha256_hex(text)) << n << " bytes";
  }
  write(std::string(101, 'x'));
  EXPECT_EQ(sha256_file(file, 101), sha256_hex(std::string(101, 'x')));
  EXPECT_THROW((void)sha256_file(file, 100), InputError);
  EXPECT_THROW((void)sha256_file("/dev/zero", std::uintmax_t{1} << 20), InputError);
  std::filesystem::remove(file);
}

}  // namespace
}  // namespace fivebar::calibrate
