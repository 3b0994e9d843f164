// Output-error refinement of the motor-rig model by Ceres Solver (lib/src/identify/detail.hpp):
// the model is simulated with the same fixed-step RK4 as identify::simulate_position, in automatic
// differentiation, and the simulated position is fitted to the logged one.

#include <ceres/ceres.h>

#include <cmath>

#include "identify/detail.hpp"

namespace fivebar::identify_detail {

namespace {

constexpr int kMaxParameters = 5;

struct PositionResiduals {
  const std::vector<double>* time;
  const std::vector<double>* u;
  const std::vector<double>* q;
  double g, q0, w0, ws;
  bool per_direction;
  int count;  ///< parameters in use (4 or 5)

  template <class T>
  bool operator()(T const* const* blocks, T* residual) const {
    const T* theta_in = blocks[0];
    T theta[kMaxParameters];
    for (int i = 0; i < kMaxParameters; ++i) theta[i] = i < count ? theta_in[i] : T(0.0);
    T x = T(q0), w = T(w0);
    const std::size_t n = time->size();
    residual[0] = T((*q)[0]) - x;
    for (std::size_t k = 0; k + 1 < n; ++k) {
      const double h = (*time)[k + 1] - (*time)[k];
      const double uk = (*u)[k];
      auto f = [&](const T& ww) { return identify::acceleration(theta, per_direction, g, uk, ww, ws); };
      const T a1 = f(w);
      const T a2 = f(w + 0.5 * h * a1);
      const T a3 = f(w + 0.5 * h * a2);
      const T a4 = f(w + h * a3);
      const T w2 = w + 0.5 * h * a1, w3 = w + 0.5 * h * a2, w4 = w + h * a3;
      x = x + h / 6.0 * (w + 2.0 * w2 + 2.0 * w3 + w4);
      w = w + h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
      residual[k + 1] = T((*q)[k + 1]) - x;
    }
    return true;
  }
};

}  // namespace

identify::Estimate output_error(const std::vector<Series>& logs, double g, const identify::Estimate& start, bool per_direction,
                                double ws, std::string& status) {
  const int p = static_cast<int>(start.value.size());
  identify::Estimate e = start;
  std::vector<double> theta(start.value.data(), start.value.data() + p);
  ceres::Problem problem;
  for (const Series& s : logs) {
    auto* functor = new PositionResiduals{s.time, s.u, s.q, g, s.q0, s.w0, ws, per_direction, p};
    auto* cost = new ceres::DynamicAutoDiffCostFunction<PositionResiduals, 8>(functor);
    cost->AddParameterBlock(p);
    cost->SetNumResiduals(static_cast<int>(s.time->size()));
    problem.AddResidualBlock(cost, nullptr, theta.data());
  }
  std::vector<int> held;
  for (int i = 0; i < p; ++i) {
    if (!start.identified[static_cast<std::size_t>(i)]) held.push_back(i);
  }
  if (static_cast<int>(held.size()) == p) {
    status = "not run: no parameter identified";
    return e;
  }
  if (!held.empty()) problem.SetManifold(theta.data(), new ceres::SubsetManifold(p, held));
  // The inertia stays positive (the simulation divides by it).
  problem.SetParameterLowerBound(theta.data(), 0, 1e-3 * std::abs(start.value[0]) + 1e-300);
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 50;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (summary.termination_type != ceres::CONVERGENCE && summary.termination_type != ceres::NO_CONVERGENCE) {
    status = "failed: " + summary.message;
    return e;
  }
  status = summary.termination_type == ceres::CONVERGENCE ? "converged" : "stopped after " + std::to_string(summary.iterations.size()) + " iterations";
  // Covariance s^2 (J^T J)^-1 over the identified parameters, J from the problem at the optimum.
  double cost_value = 0.0;
  ceres::CRSMatrix jac;
  std::vector<double> residuals;
  problem.Evaluate(ceres::Problem::EvaluateOptions(), &cost_value, &residuals, nullptr, &jac);
  const int n = jac.num_rows;
  std::vector<int> free;
  for (int i = 0; i < p; ++i) {
    if (start.identified[static_cast<std::size_t>(i)]) free.push_back(i);
  }
  // The jacobian in the manifold's tangent space has only the free columns, in order.
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, jac.num_cols);
  for (int r = 0; r < n; ++r) {
    for (int k = jac.rows[static_cast<std::size_t>(r)]; k < jac.rows[static_cast<std::size_t>(r) + 1]; ++k) {
      J(r, jac.cols[static_cast<std::size_t>(k)]) = jac.values[static_cast<std::size_t>(k)];
    }
  }
  const int m = static_cast<int>(free.size());
  const double ssr = 2.0 * cost_value;
  const double s2 = n > m ? ssr / (n - m) : 0.0;
  Eigen::MatrixXd JtJ = J.transpose() * J;
  Eigen::MatrixXd cov_free = s2 * JtJ.ldlt().solve(Eigen::MatrixXd::Identity(JtJ.rows(), JtJ.cols()));
  e.value = Eigen::Map<Eigen::VectorXd>(theta.data(), p);
  e.covariance = Eigen::MatrixXd::Zero(p, p);
  e.sigma = Eigen::VectorXd::Zero(p);
  e.correlation = Eigen::MatrixXd::Identity(p, p);
  if (cov_free.rows() == m) {
    for (int a = 0; a < m; ++a) {
      for (int b = 0; b < m; ++b) e.covariance(free[a], free[b]) = cov_free(a, b);
    }
  }
  for (int i = 0; i < p; ++i) e.sigma[i] = std::sqrt(std::max(0.0, e.covariance(i, i)));
  for (int a : free) {
    for (int b : free) {
      if (e.sigma[a] > 0.0 && e.sigma[b] > 0.0) e.correlation(a, b) = e.covariance(a, b) / (e.sigma[a] * e.sigma[b]);
    }
  }
  e.residual_sigma = std::sqrt(s2);
  e.rows = n;
  return e;
}

}  // namespace fivebar::identify_detail
