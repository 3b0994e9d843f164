// Calibration pose planning (fivebar/calibrate/plan.hpp).
#include "fivebar/calibrate/plan.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "fivebar/calibrate/fit.hpp"
#include "fivebar/error.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/sections/controller.hpp"

namespace fivebar::calibrate {

namespace {

using Rows = Eigen::Matrix<double, 2, kMechanismParameters>;
using Info = Eigen::Matrix<double, kMechanismParameters, kMechanismParameters>;

double log_det(const Info& M) {
  Eigen::LDLT<Info> ldlt(M);
  const auto d = ldlt.vectorD();
  double s = 0.0;
  for (int i = 0; i < d.size(); ++i) s += std::log(std::max(d[i], 1e-300));
  return s;
}

double observability(const std::vector<Rows>& rows, const std::vector<int>& chosen) {
  Eigen::MatrixXd J(2 * static_cast<Eigen::Index>(chosen.size()), kMechanismParameters);
  for (std::size_t i = 0; i < chosen.size(); ++i) J.block<2, kMechanismParameters>(2 * static_cast<Eigen::Index>(i), 0) = rows[static_cast<std::size_t>(chosen[i])];
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(J).singularValues();
  double s = 0.0;
  for (int i = 0; i < sv.size(); ++i) s += std::log(std::max(sv[i], 1e-300));
  return std::exp(s / static_cast<double>(sv.size())) / std::sqrt(static_cast<double>(chosen.size()));
}

/// trace(A M^{-1}): the I-criterion (mean predicted tactor variance over the target, scaled units).
double i_value(const Info& A, const Info& M) { return (Eigen::LDLT<Info>(M).solve(A)).trace(); }

/// How much adding the rows R lowers trace(A M^{-1}) (Woodbury: M^{-1} R^T (I + R M^{-1} R^T)^{-1} R M^{-1}).
double i_gain(const Info& A, const Info& Minv, const Rows& R) {
  const Eigen::Matrix<double, kMechanismParameters, 2> U = Minv * R.transpose();
  const Eigen::Matrix2d S = Eigen::Matrix2d::Identity() + R * U;
  return (S.inverse() * (U.transpose() * A * U)).trace();
}

double d_gain(const Info& Minv, const Rows& R) { return (Eigen::Matrix2d::Identity() + R * Minv * R.transpose()).determinant(); }

/// The candidate's margins (plan.hpp): each leg at least `ext` from full extension and folding,
/// the tactor at least `base` from the base line O1 O2 on the side of `side` (the target centre).
bool within_margins(const Mechanism& m, const Vec2& P, const Vec2& side, double ext, double base) {
  for (int i = 0; i < 2; ++i) {
    const Vec2& O = i == 0 ? m.O1 : m.O2;
    const double L = m.L[static_cast<std::size_t>(i)], D = m.L[static_cast<std::size_t>(i + 2)];
    const double r = (P - O).norm();
    if (r > L + D - ext || r < std::abs(L - D) + ext) return false;
  }
  const Vec2 u = (m.O2 - m.O1).normalized();
  const auto signed_distance = [&](const Vec2& x) { return u.x() * (x - m.O1).y() - u.y() * (x - m.O1).x(); };
  const double s = signed_distance(side) >= 0.0 ? 1.0 : -1.0;
  return s * signed_distance(P) >= base;
}

/// True when every one of `samples` devices drawn uniformly within 4 prior sigmas (a margin over the
/// 3-sigma box the plan promises) of each of the
/// twelve parameters assembles the candidate's readings in the design's working mode.
bool reachable_by_perturbed(const Mechanism& m, const MechanismVector& q, const PlannedPose& p, int samples, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-4.0, 4.0);  // a margin over the 3-sigma box
  for (int k = 0; k < samples; ++k) {
    MechanismVector d = q;
    for (int i = 0; i < kMechanismParameters; ++i) d[i] += u(rng) * prior_sigma(i, q);
    const auto th = joint_angles(d, p.volts1, p.volts2);
    const Pose pose = fk(with_geometry(m, d), th[0], th[1]);
    if (pose.status != Status::ok || !(pose.mode == m.working_mode)) return false;
  }
  return true;
}

Info scaled_information(const Mechanism& m, const MechanismVector& q, const std::vector<PlannedPose>& poses, bool& ok) {
  Info M = Info::Zero();
  Eigen::Matrix<double, kMechanismParameters, 1> s;
  for (int k = 0; k < kMechanismParameters; ++k) s[k] = parameter_scale(k, q);
  ok = true;
  for (const PlannedPose& p : poses) {
    const Prediction pr = predict(m, q, FrameVector::Zero(), p.volts1, p.volts2);
    if (pr.status != Status::ok) {
      ok = false;
      continue;
    }
    const Rows R = pr.dq * s.asDiagonal();
    M += R.transpose() * R;
  }
  return M;
}

/// Greedy choice of n rows by `gain` (of adding a candidate's rows to M, given M^{-1}), then
/// exchanges while `value` (of M, larger is better) grows.
template <class Gain, class Value>
std::vector<int> choose_poses(const std::vector<Rows>& rows, int n, const Gain& gain, const Value& value) {
  const double ridge = 1e-6;
  Info M = Info::Identity() * ridge;
  std::vector<int> chosen;
  std::vector<bool> used(rows.size(), false);
  for (int k = 0; k < n; ++k) {
    const Info Minv = Eigen::LDLT<Info>(M).solve(Info::Identity());
    int best = -1;
    double best_gain = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < rows.size(); ++i) {
      if (used[i]) continue;
      const double g = gain(Minv, rows[i]);
      if (g > best_gain) best_gain = g, best = static_cast<int>(i);
    }
    used[static_cast<std::size_t>(best)] = true;
    chosen.push_back(best);
    M += rows[static_cast<std::size_t>(best)].transpose() * rows[static_cast<std::size_t>(best)];
  }
  for (int pass = 0; pass < 3; ++pass) {
    bool improved = false;
    for (std::size_t k = 0; k < chosen.size(); ++k) {
      const Rows& out_rows = rows[static_cast<std::size_t>(chosen[k])];
      const Info without = M - out_rows.transpose() * out_rows;
      const Info Minv = Eigen::LDLT<Info>(without).solve(Info::Identity());
      int best = -1;
      double best_gain = gain(Minv, out_rows);
      for (std::size_t i = 0; i < rows.size(); ++i) {
        if (used[i]) continue;
        const double g = gain(Minv, rows[i]);
        if (g > best_gain * (1.0 + 1e-9)) best_gain = g, best = static_cast<int>(i);
      }
      if (best < 0) continue;
      const Info trial = without + rows[static_cast<std::size_t>(best)].transpose() * rows[static_cast<std::size_t>(best)];
      if (!(value(trial) > value(M))) continue;
      used[static_cast<std::size_t>(chosen[k])] = false;
      used[static_cast<std::size_t>(best)] = true;
      M = trial;
      chosen[k] = best;
      improved = true;
    }
    if (!improved) break;
  }
  return chosen;
}

}  // namespace

std::vector<PlannedPose> target_points(const Design& design, const Station& st, const Mechanism& m, int n) {
  const ControllerSettings* c = design.get<ControllerSettings>();
  const Potentiometer p1 = c ? c->joint(st.name, m.name, 1).potentiometer : Potentiometer{};
  const Potentiometer p2 = c ? c->joint(st.name, m.name, 2).potentiometer : Potentiometer{};
  const Ellipse& e = st.target;
  const double ca = std::cos(e.angle), sa = std::sin(e.angle);
  std::vector<PlannedPose> out;
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < n; ++b) {
      const double x = (a + 0.5) / n * 2.0 - 1.0, y = (b + 0.5) / n * 2.0 - 1.0;
      if (x * x + y * y > 1.0) continue;
      const Vec2 local(x * e.axes.x() / 2, y * e.axes.y() / 2);
      PlannedPose p;
      p.point = e.center + Vec2(ca * local.x() - sa * local.y(), sa * local.x() + ca * local.y());
      const Pose pose = ik(m, p.point);
      if (pose.status != Status::ok) continue;
      p.theta1 = pose.theta1;
      p.theta2 = pose.theta2;
      p.volts1 = p1.volts_at_zero + p.theta1 / p1.rad_per_volt;
      p.volts2 = p2.volts_at_zero + p.theta2 / p2.rad_per_volt;
      out.push_back(p);
    }
  }
  return out;
}

double predicted_target_error(const Mechanism& m, const MechanismVector& q, const std::vector<PlannedPose>& poses,
                              const std::vector<PlannedPose>& targets, double sigma_mm) {
  bool ok = true;
  const Info M = scaled_information(m, q, poses, ok);
  Eigen::SelfAdjointEigenSolver<Info> eig(M);
  if (!ok || targets.empty() || !(eig.eigenvalues()[0] > kUnidentifiableRel * kUnidentifiableRel * eig.eigenvalues()[kMechanismParameters - 1])) {
    return std::numeric_limits<double>::infinity();
  }
  const Info C = eig.eigenvectors() * eig.eigenvalues().cwiseInverse().asDiagonal() * eig.eigenvectors().transpose();
  bool tok = true;
  const Info A = scaled_information(m, q, targets, tok);
  return sigma_mm * std::sqrt((C * A).trace() / static_cast<double>(targets.size()));
}

std::vector<double> posterior_sigma(const Mechanism& m, const MechanismVector& q, const std::vector<PlannedPose>& poses,
                                    double sigma_mm) {
  Eigen::MatrixXd J(2 * static_cast<Eigen::Index>(poses.size()), kMechanismParameters);
  Eigen::VectorXd s(kMechanismParameters);
  for (int k = 0; k < kMechanismParameters; ++k) s[k] = parameter_scale(k, q);
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const Prediction p = predict(m, q, FrameVector::Zero(), poses[i].volts1, poses[i].volts2);
    J.block<2, kMechanismParameters>(2 * static_cast<Eigen::Index>(i), 0) = p.dq * s.asDiagonal();
  }
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(J, Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  std::vector<double> out(kMechanismParameters);
  const bool full = sv.size() == kMechanismParameters && sv[kMechanismParameters - 1] > kUnidentifiableRel * sv[0];
  for (int k = 0; k < kMechanismParameters; ++k) {
    if (!full) {
      out[static_cast<std::size_t>(k)] = std::numeric_limits<double>::infinity();
      continue;
    }
    double v = 0.0;
    for (int i = 0; i < sv.size(); ++i) v += std::pow(svd.matrixV()(k, i) / sv[i], 2);
    out[static_cast<std::size_t>(k)] = sigma_mm * std::sqrt(v) * s[k];
  }
  return out;
}

std::vector<MechanismPlan> plan_poses(const Design& design, const std::string& station_name, const std::string& mechanism,
                                      const PlanOptions& opt) {
  if (opt.poses < kMechanismParameters / 2) {
    throw InputError("plan = " + std::to_string(opt.poses) + " poses: at least " + std::to_string(kMechanismParameters / 2) +
                     " are needed for the twelve parameters of a mechanism");
  }
  if (!(opt.sigma_mm > 0.0)) throw InputError("plan: the measurement sigma must be > 0 mm");
  const Station& st = design.require_station(station_name);
  const ControllerSettings* c = design.get<ControllerSettings>();
  std::vector<MechanismPlan> out;
  for (const Mechanism* m : st.mechanisms()) {
    if (!mechanism.empty() && m->name != mechanism) continue;
    MechanismPlan plan;
    plan.station = st.name;
    plan.mechanism = m->name;
    for (const auto& n : mechanism_parameter_names()) plan.names.push_back(n);
    const Potentiometer p1 = c ? c->joint(st.name, m->name, 1).potentiometer : Potentiometer{};
    const Potentiometer p2 = c ? c->joint(st.name, m->name, 2).potentiometer : Potentiometer{};
    const MechanismVector q = mechanism_vector(*m, p1.volts_at_zero, p1.rad_per_volt, p2.volts_at_zero, p2.rad_per_volt);
    Eigen::Matrix<double, kMechanismParameters, 1> s;
    for (int k = 0; k < kMechanismParameters; ++k) s[k] = parameter_scale(k, q);
    const auto ranges = usable_ranges(design, st, *m);
    std::array<std::pair<double, double>, 2> span;
    for (int j = 0; j < 2; ++j) {
      const UsableRange& r = ranges[static_cast<std::size_t>(j)];
      if (!r.usable) {
        plan.problem = "joint " + r.joint + " has no usable range: " + r.problem;
        break;
      }
      span[static_cast<std::size_t>(j)] = r.limited ? std::pair{r.lo, r.hi} : std::pair{r.reference - 3.14159265358979, r.reference + 3.14159265358979};
    }
    std::vector<PlannedPose> cand;
    std::vector<Rows> rows;
    std::mt19937_64 reach_rng(opt.seed + 1);
    if (plan.problem.empty()) {
      const double min_lci = std::max(opt.min_lci, m->min_lci);
      for (int a = 0; a < opt.grid; ++a) {
        for (int b = 0; b < opt.grid; ++b) {
          PlannedPose p;
          p.theta1 = span[0].first + (span[0].second - span[0].first) * (a + 0.5) / opt.grid;
          p.theta2 = span[1].first + (span[1].second - span[1].first) * (b + 0.5) / opt.grid;
          const Pose pose = fk(*m, p.theta1, p.theta2);
          if (pose.status != Status::ok || pose.lci < min_lci) continue;
          if (m->assembly_mode == AssemblyMode::Any && !(pose.mode == m->working_mode)) continue;
          if (!(pose.mode == m->working_mode)) continue;
          p.volts1 = p1.volts_at_zero + p.theta1 / p1.rad_per_volt;
          p.volts2 = p2.volts_at_zero + p.theta2 / p2.rad_per_volt;
          p.point = pose.P;
          const Prediction pr = predict(*m, q, FrameVector::Zero(), p.volts1, p.volts2);
          if (pr.status != Status::ok) continue;
          if (!within_margins(*m, pose.P, st.target.center, opt.extension_margin_mm, opt.base_margin_mm)) continue;
          if (!reachable_by_perturbed(*m, q, p, opt.reach_samples, reach_rng)) continue;
          cand.push_back(p);
          rows.push_back(pr.dq * s.asDiagonal());
        }
      }
      plan.candidates = static_cast<int>(cand.size());
      if (plan.candidates < opt.poses) {
        plan.problem = std::to_string(plan.candidates) + " candidate poses in the usable ranges with LCI >= " +
                       std::to_string(min_lci) + ", the margins and reachable by every sampled device, fewer than the " +
                       std::to_string(opt.poses) + " asked";
      }
    }
    if (!plan.problem.empty()) {
      out.push_back(std::move(plan));
      continue;
    }
    // Greedy, then exchanges; a small ridge keeps M invertible until it has rank.
    const std::vector<PlannedPose> targets = target_points(design, st, *m);
    plan.target_points = static_cast<int>(targets.size());
    bool targets_ok = true;  // every target point comes from IK: assembles
    Info A = scaled_information(*m, q, targets, targets_ok) / std::max<double>(1.0, static_cast<double>(targets.size()));
    const bool i_opt = opt.criterion == PlanCriterion::i_optimal && !targets.empty();
    const auto gain = [&](const Info& Minv, const Rows& R) { return i_opt ? i_gain(A, Minv, R) : d_gain(Minv, R); };
    const auto value = [&](const Info& M) { return i_opt ? -i_value(A, M) : log_det(M); };  // larger is better
    (void)targets_ok;
    const std::vector<int> chosen = choose_poses(rows, opt.poses, gain, value);
    for (int i : chosen) plan.poses.push_back(cand[static_cast<std::size_t>(i)]);
    plan.observability_index = observability(rows, chosen);
    plan.expected_sigma = posterior_sigma(*m, q, plan.poses, opt.sigma_mm);
    plan.predicted_target_error_mm = predicted_target_error(*m, q, plan.poses, targets, opt.sigma_mm);
    // N random candidates, many times: the median of each figure.
    std::mt19937_64 rng(opt.seed);
    std::vector<double> oi, te;
    std::vector<std::vector<double>> sig(kMechanismParameters);
    for (int t = 0; t < opt.random_trials; ++t) {
      std::vector<int> pick(cand.size());
      for (std::size_t i = 0; i < cand.size(); ++i) pick[i] = static_cast<int>(i);
      for (int i = 0; i < opt.poses; ++i) {
        std::uniform_int_distribution<std::size_t> u(static_cast<std::size_t>(i), cand.size() - 1);
        std::swap(pick[static_cast<std::size_t>(i)], pick[u(rng)]);
      }
      pick.resize(static_cast<std::size_t>(opt.poses));
      oi.push_back(observability(rows, pick));
      std::vector<PlannedPose> ps;
      for (int i : pick) ps.push_back(cand[static_cast<std::size_t>(i)]);
      const auto sg = posterior_sigma(*m, q, ps, opt.sigma_mm);
      te.push_back(predicted_target_error(*m, q, ps, targets, opt.sigma_mm));
      for (int k = 0; k < kMechanismParameters; ++k) sig[static_cast<std::size_t>(k)].push_back(sg[static_cast<std::size_t>(k)]);
    }
    const auto median = [](std::vector<double> v) {
      std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
      return v[v.size() / 2];
    };
    plan.random_observability_index = median(oi);
    plan.random_target_error_mm = median(te);
    for (int k = 0; k < kMechanismParameters; ++k) plan.random_sigma.push_back(median(sig[static_cast<std::size_t>(k)]));
    out.push_back(std::move(plan));
  }
  if (out.empty()) throw InputError("station " + station_name + " has no mechanism '" + mechanism + "'");
  return out;
}

}  // namespace fivebar::calibrate
