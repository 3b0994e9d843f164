// Calibration pose planning (fivebar/calibrate/plan.hpp).
#include "fivebar/calibrate/plan.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "fivebar/calibrate/fit.hpp"
#include "fivebar/error.hpp"
#include "fivebar/export/joint_limits.hpp"
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

}  // namespace

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
          cand.push_back(p);
          rows.push_back(pr.dq * s.asDiagonal());
        }
      }
      plan.candidates = static_cast<int>(cand.size());
      if (plan.candidates < opt.poses) {
        plan.problem = std::to_string(plan.candidates) + " candidate poses in the usable ranges with LCI >= " +
                       std::to_string(min_lci) + ", fewer than the " + std::to_string(opt.poses) + " asked";
      }
    }
    if (!plan.problem.empty()) {
      out.push_back(std::move(plan));
      continue;
    }
    // Greedy D-optimal, then exchanges; a small ridge keeps M invertible until it has rank.
    const double ridge = 1e-6;
    Info M = Info::Identity() * ridge;
    std::vector<int> chosen;
    std::vector<bool> used(cand.size(), false);
    for (int n = 0; n < opt.poses; ++n) {
      const Eigen::LDLT<Info> ldlt(M);
      int best = -1;
      double best_gain = -1.0;
      for (std::size_t i = 0; i < cand.size(); ++i) {
        if (used[i]) continue;
        const Eigen::Matrix2d G = Eigen::Matrix2d::Identity() + rows[i] * ldlt.solve(rows[i].transpose());
        if (G.determinant() > best_gain) best_gain = G.determinant(), best = static_cast<int>(i);
      }
      used[static_cast<std::size_t>(best)] = true;
      chosen.push_back(best);
      M += rows[static_cast<std::size_t>(best)].transpose() * rows[static_cast<std::size_t>(best)];
    }
    for (int pass = 0; pass < 2; ++pass) {
      bool improved = false;
      for (std::size_t k = 0; k < chosen.size(); ++k) {
        const Rows& out_rows = rows[static_cast<std::size_t>(chosen[k])];
        const Info without = M - out_rows.transpose() * out_rows;
        const double base = log_det(M);
        const double base_without = log_det(without);
        const Eigen::LDLT<Info> ldlt(without);
        int best = -1;
        double best_ld = base + 1e-9;
        for (std::size_t i = 0; i < cand.size(); ++i) {
          if (used[i]) continue;
          const Eigen::Matrix2d G = Eigen::Matrix2d::Identity() + rows[i] * ldlt.solve(rows[i].transpose());
          const double ld = base_without + std::log(std::max(G.determinant(), 1e-300));
          if (ld > best_ld) best_ld = ld, best = static_cast<int>(i);
        }
        if (best >= 0) {
          used[static_cast<std::size_t>(chosen[k])] = false;
          used[static_cast<std::size_t>(best)] = true;
          M = without + rows[static_cast<std::size_t>(best)].transpose() * rows[static_cast<std::size_t>(best)];
          chosen[k] = best;
          improved = true;
        }
      }
      if (!improved) break;
    }
    for (int i : chosen) plan.poses.push_back(cand[static_cast<std::size_t>(i)]);
    plan.observability_index = observability(rows, chosen);
    plan.expected_sigma = posterior_sigma(*m, q, plan.poses, opt.sigma_mm);
    // N random candidates, many times: the median of each figure.
    std::mt19937_64 rng(opt.seed);
    std::vector<double> oi;
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
      for (int k = 0; k < kMechanismParameters; ++k) sig[static_cast<std::size_t>(k)].push_back(sg[static_cast<std::size_t>(k)]);
    }
    const auto median = [](std::vector<double> v) {
      std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
      return v[v.size() / 2];
    };
    plan.random_observability_index = median(oi);
    for (int k = 0; k < kMechanismParameters; ++k) plan.random_sigma.push_back(median(sig[static_cast<std::size_t>(k)]));
    out.push_back(std::move(plan));
  }
  if (out.empty()) throw InputError("station " + station_name + " has no mechanism '" + mechanism + "'");
  return out;
}

}  // namespace fivebar::calibrate
