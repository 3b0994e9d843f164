// Manufacturing tolerance of a five-bar: closed-form first-order sensitivity and a Monte Carlo
// reference (derivation in fivebar/tolerance.hpp).
#include "fivebar/format.hpp"
#include "fivebar/tolerance.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace fivebar {
namespace {

double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

bool finite(const Eigen::Ref<const Eigen::MatrixXd>& x) { return x.allFinite(); }

}  // namespace

const std::array<const char*, kToleranceParameters>& tolerance_parameter_names() {
  static const std::array<const char*, kToleranceParameters> names{"L1",  "L2",  "L3",  "L4",     "O1x",
                                                                   "O1y", "O2x", "O2y", "theta1", "theta2"};
  return names;
}

// --- ParameterSpread --------------------------------------------------------------------------------

ParameterCovariance CalibratedUncertainty::at(double theta1, double theta2) const {
  // dq = T dp: the geometry as it is, dtheta_j = (theta_j / k_j) dk_j - k_j dV0_j.
  Eigen::Matrix<double, static_cast<int>(kToleranceParameters), 12> T = Eigen::Matrix<double, static_cast<int>(kToleranceParameters), 12>::Zero();
  for (int i = 0; i < 8; ++i) T(i, i) = 1.0;
  const std::array<double, 2> theta{theta1, theta2};
  for (int j = 0; j < 2; ++j) {
    const double k = rad_per_volt[static_cast<std::size_t>(j)];
    T(8 + j, 8 + 2 * j) = -k;
    T(8 + j, 9 + 2 * j) = theta[static_cast<std::size_t>(j)] / k;
  }
  ParameterCovariance c = T * covariance * T.transpose();
  c(8, 8) += angle_variance[0];
  c(9, 9) += angle_variance[1];
  return 0.5 * (c + c.transpose());
}

ParameterSpread::ParameterSpread(const ParameterSigmas& sigma) : sigma_(sigma) {
  for (std::size_t j = 0; j < kToleranceParameters; ++j) {
    const auto i = static_cast<Eigen::Index>(j);
    covariance_(i, i) = sigma[j] * sigma[j];
    factor_(i, i) = sigma[j];
  }
}

ParameterSpread::ParameterSpread(const ParameterCovariance& covariance) : correlated_(true), covariance_(covariance) { factorise(); }

ParameterSpread::ParameterSpread(const CalibratedUncertainty& calibrated)
    : correlated_(true), covariance_(calibrated.at(0.0, 0.0)), calibrated_(calibrated) {
  factorise();
}

void ParameterSpread::factorise() {
  covariance_ = 0.5 * (covariance_ + covariance_.transpose());
  const Eigen::SelfAdjointEigenSolver<ParameterCovariance> eig(covariance_);
  // A posterior covariance is positive semi-definite; rounding can leave tiny negative eigenvalues.
  const Eigen::Matrix<double, static_cast<int>(kToleranceParameters), 1> root = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  factor_ = eig.eigenvectors() * root.asDiagonal();
  for (std::size_t j = 0; j < kToleranceParameters; ++j) {
    sigma_[j] = std::sqrt(std::max(covariance_(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j)), 0.0));
  }
}

ParameterSpread ParameterSpread::at(double theta1, double theta2) const {
  if (!calibrated_) return *this;
  ParameterSpread out(calibrated_->at(theta1, theta2));
  out.calibrated_ = calibrated_;
  return out;
}

double ParameterSpread::variance(const std::array<double, kToleranceParameters>& g) const {
  double var = 0.0;
  if (!correlated_) {
    for (std::size_t j = 0; j < kToleranceParameters; ++j) var += g[j] * g[j] * sigma_[j] * sigma_[j];
    return var;
  }
  const Eigen::Map<const Eigen::Matrix<double, static_cast<int>(kToleranceParameters), 1>> v(g.data());
  return std::max(0.0, v.dot(covariance_ * v));
}

std::array<double, kToleranceParameters> ParameterSpread::draw(const std::array<double, kToleranceParameters>& z) const {
  std::array<double, kToleranceParameters> dq{};
  if (!correlated_) {
    for (std::size_t j = 0; j < kToleranceParameters; ++j) dq[j] = sigma_[j] * z[j];
    return dq;
  }
  for (std::size_t i = 0; i < kToleranceParameters; ++i) {
    for (std::size_t k = 0; k < kToleranceParameters; ++k) dq[i] += factor_(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) * z[k];
  }
  return dq;
}

std::array<double, kToleranceParameters> ParameterSpread::generator(std::size_t k) const {
  std::array<double, kToleranceParameters> g{};
  for (std::size_t i = 0; i < kToleranceParameters; ++i) g[i] = factor_(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k));
  return g;
}

ZonotopeExtreme zonotope_farthest(const std::vector<Vec2>& generators) {
  const std::size_t n = generators.size();
  ZonotopeExtreme out;
  out.signs.assign(n, 1);
  // Every generator into the upper half plane (angle in [0, pi)), remembering the flip.
  std::vector<Vec2> g(generators);
  std::vector<std::int8_t> flip(n, 1);
  for (std::size_t j = 0; j < n; ++j) {
    if (g[j].y() < 0.0 || (g[j].y() == 0.0 && g[j].x() < 0.0)) {
      g[j] = -g[j];
      flip[j] = -1;
    }
  }
  std::vector<std::size_t> order;  // zero generators stay out: they would break the ordering
  for (std::size_t j = 0; j < n; ++j)
    if (g[j].x() != 0.0 || g[j].y() != 0.0) order.push_back(j);
  // Sorting by angle in [0, pi) without atan2: a before b when cross(a, b) > 0.
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return cross(g[a], g[b]) > 0.0; });
  // Walk the lower chain from -sum g to +sum g: vertex k has the first k sorted generators at +1.
  Vec2 v{0.0, 0.0};
  for (const Vec2& x : g) v -= x;
  std::size_t best_k = 0;
  out.norm = v.norm();
  out.point = v;
  for (std::size_t k = 0; k < order.size(); ++k) {
    v += 2.0 * g[order[k]];
    if (v.norm() > out.norm) {
      out.norm = v.norm();
      out.point = v;
      best_k = k + 1;
    }
  }
  for (std::size_t k = 0; k < order.size(); ++k) out.signs[order[k]] = static_cast<std::int8_t>(flip[order[k]] * (k < best_k ? 1 : -1));
  return out;
}

Sensitivity tolerance_sensitivity(const Mechanism& m, const Vec2& P) {
  Sensitivity out;
  const Pose pose = ik(m, P);
  out.status = pose.status;
  if (pose.status != Status::ok) return out;
  // Unit distal directions u_i = (P - A_i) / |P - A_i| (|P - A_i| = L_{i+2} within closure).
  const Vec2 u1 = (pose.P - pose.A1).normalized();
  const Vec2 u2 = (pose.P - pose.A2).normalized();
  const Vec2 e1(std::cos(pose.theta1), std::sin(pose.theta1));
  const Vec2 e2(std::cos(pose.theta2), std::sin(pose.theta2));
  // Rows of R: leg 1 then leg 2; columns in ToleranceParameter order.
  Eigen::Matrix<double, 2, static_cast<int>(kToleranceParameters)> R =
      Eigen::Matrix<double, 2, static_cast<int>(kToleranceParameters)>::Zero();
  R(0, 0) = u1.dot(e1);             // L1
  R(1, 1) = u2.dot(e2);             // L2
  R(0, 2) = 1.0;                    // L3
  R(1, 3) = 1.0;                    // L4
  R(0, 4) = u1.x();                 // O1x
  R(0, 5) = u1.y();                 // O1y
  R(1, 6) = u2.x();                 // O2x
  R(1, 7) = u2.y();                 // O2y
  R(0, 8) = m.L[0] * cross(e1, u1);  // theta1
  R(1, 9) = m.L[1] * cross(e2, u2);  // theta2
  // M^{-1} = [u2y -u1y; -u2x u1x] / det, det = cross(u1, u2) (the type II sine, >= kSingularSin
  // here because ik() reported ok).
  const double det = cross(u1, u2);
  Eigen::Matrix2d inv;
  inv << u2.y(), -u1.y(), -u2.x(), u1.x();
  inv /= det;
  out.S = inv * R;
  if (!finite(out.S)) {
    out = Sensitivity{};
    out.status = Status::singular_type2;
    return out;
  }
  out.pose = pose;
  return out;
}

ParameterSigmas parameter_sigmas(const ToleranceSettings& t) {
  const double link = std::sqrt(t.link_sigma_mm * t.link_sigma_mm + 2.0 * t.pin_sigma_mm * t.pin_sigma_mm);
  const double angle = t.angle_sigma_deg * format::kRadPerDeg;
  const double base = t.base_sigma_mm;
  return {link, link, link, link, base, base, base, base, angle, angle};
}

double major_3sigma_mm(const Eigen::Matrix2d& C) {
  const double mid = 0.5 * (C(0, 0) + C(1, 1));
  return 3.0 * std::sqrt(std::max(0.0, mid + std::hypot(0.5 * (C(0, 0) - C(1, 1)), C(0, 1))));
}

double angle_per_count(int bits) {
  return 2.0 * std::numbers::pi / std::ldexp(1.0, std::clamp(bits, 1, 32));
}

ToleranceEstimate tolerance_first_order(const Mechanism& m, const Vec2& P, const ParameterSpread& spread_any,
                                        double rad_per_count) {
  ToleranceEstimate out;
  const Sensitivity s = tolerance_sensitivity(m, P);
  out.status = s.status;
  if (s.status != Status::ok) return out;
  const ParameterSpread spread = spread_any.at(s.pose.theta1, s.pose.theta2);
  const ParameterSigmas& sigma = spread.sigma();
  if (spread.correlated()) {
    out.covariance = s.S * spread.covariance() * s.S.transpose();
  } else {
    Eigen::Matrix<double, static_cast<int>(kToleranceParameters), 1> var;
    for (std::size_t j = 0; j < kToleranceParameters; ++j) var(static_cast<Eigen::Index>(j)) = sigma[j] * sigma[j];
    out.covariance = s.S * var.asDiagonal() * s.S.transpose();
  }
  const double a = out.covariance(0, 0);
  const double b = out.covariance(0, 1);
  const double c = out.covariance(1, 1);
  const double mid = 0.5 * (a + c);
  const double rad = std::hypot(0.5 * (a - c), b);
  out.ellipse_semi_axes = {3.0 * std::sqrt(std::max(0.0, mid + rad)), 3.0 * std::sqrt(std::max(0.0, mid - rad))};
  out.ellipse_angle = (rad > 0.0) ? 0.5 * std::atan2(2.0 * b, a - c) : 0.0;
  double worst = 0.0;
  std::vector<Vec2> generators(kToleranceParameters);
  for (std::size_t j = 0; j < kToleranceParameters; ++j) {
    if (spread.correlated()) {  // the principal components' +-3 sigma
      const auto g = spread.generator(j);
      generators[j] = s.S * Eigen::Map<const Eigen::Matrix<double, static_cast<int>(kToleranceParameters), 1>>(g.data()) * 3.0;
    } else {
      generators[j] = s.S.col(static_cast<Eigen::Index>(j)) * (3.0 * sigma[j]);
    }
    worst += generators[j].norm();
  }
  const ZonotopeExtreme z = zonotope_farthest(generators);
  out.worst_case_mm = z.norm;
  if (spread.correlated()) {  // the sign of each parameter's displacement at that vertex
    std::array<double, kToleranceParameters> dq{};
    for (std::size_t k = 0; k < kToleranceParameters; ++k) {
      const auto g = spread.generator(k);
      for (std::size_t j = 0; j < kToleranceParameters; ++j) dq[j] += z.signs[k] * g[j];
    }
    for (std::size_t j = 0; j < kToleranceParameters; ++j) out.worst_corner[j] = dq[j] < 0.0 ? -1 : 1;
  } else {
    std::copy(z.signs.begin(), z.signs.end(), out.worst_corner.begin());
  }
  out.sum_of_effects_mm = worst;
  out.near_singular = worst > 0.25 * std::min(m.L[2], m.L[3]) * s.pose.type2_sin;
  const double step = std::max(s.pose.J.col(0).norm(), s.pose.J.col(1).norm()) * rad_per_count;
  out.resolution_um = 1000.0 * step;
  if (!out.covariance.allFinite() || !std::isfinite(worst) || !std::isfinite(out.resolution_um)) {
    out = ToleranceEstimate{};
    out.status = Status::singular_type2;
  }
  return out;
}

MonteCarloTolerance tolerance_monte_carlo(const Mechanism& m, const Vec2& P, const ParameterSpread& spread_any,
                                          std::size_t samples, std::uint64_t seed) {
  MonteCarloTolerance out;
  const Pose nominal = ik(m, P);
  out.status = nominal.status;
  if (nominal.status != Status::ok) return out;
  const ParameterSpread spread = spread_any.at(nominal.theta1, nominal.theta2);
  Mechanism printed = m;
  printed.joint_limits.reset();  // a device off its limits still puts its tactor somewhere
  printed.assembly_mode = nominal.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  // Welford's running mean and co-moment: one pass, no cancellation.
  Vec2 mean{0.0, 0.0};
  Eigen::Matrix2d comoment = Eigen::Matrix2d::Zero();
  std::array<double, kToleranceParameters> z{};
  for (std::size_t k = 0; k < samples; ++k) {
    for (std::size_t j = 0; j < kToleranceParameters; ++j) z[j] = normal(rng);
    const std::array<double, kToleranceParameters> dq = spread.draw(z);
    for (std::size_t i = 0; i < 4; ++i) printed.L[i] = m.L[i] + dq[i];
    printed.O1 = m.O1 + Vec2(dq[4], dq[5]);
    printed.O2 = m.O2 + Vec2(dq[6], dq[7]);
    const bool lengths_ok = std::all_of(printed.L.begin(), printed.L.end(), [](double l) { return l > 0.0; });
    const PointResult r = lengths_ok ? fk_point(printed, nominal.theta1 + dq[8], nominal.theta2 + dq[9])
                                     : PointResult{};
    if (r.status != Status::ok) {
      ++out.failed;
      continue;
    }
    const Vec2 err = r.P - P;
    ++out.used;
    const Vec2 delta = err - mean;
    mean += delta / static_cast<double>(out.used);
    comoment += delta * (err - mean).transpose();
  }
  out.mean_error = mean;
  if (out.used > 1) {
    out.covariance = comoment / static_cast<double>(out.used - 1);
    out.covariance(0, 1) = out.covariance(1, 0) = 0.5 * (out.covariance(0, 1) + out.covariance(1, 0));
  }
  return out;
}

std::vector<MonteCarloTolerance> tolerance_monte_carlo(const Mechanism& m, const std::vector<Vec2>& points,
                                                       const ParameterSpread& spread, std::size_t samples,
                                                       std::uint64_t seed) {
  // One table of draws for every point (common random numbers), in tolerance_monte_carlo()'s order.
  std::vector<double> draws(samples * kToleranceParameters);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (std::size_t k = 0; k < samples; ++k)
    for (std::size_t j = 0; j < kToleranceParameters; ++j) draws[k * kToleranceParameters + j] = normal(rng);
  std::vector<MonteCarloTolerance> out(points.size());
  const auto n = static_cast<std::ptrdiff_t>(points.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const Vec2& P = points[static_cast<std::size_t>(i)];
    MonteCarloTolerance& r = out[static_cast<std::size_t>(i)];
    const Pose nominal = ik(m, P);
    r.status = nominal.status;
    if (nominal.status != Status::ok) continue;
    Mechanism printed = m;
    printed.joint_limits.reset();
    printed.assembly_mode = nominal.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
    const ParameterSpread at = spread.at(nominal.theta1, nominal.theta2);
    Vec2 mean{0.0, 0.0};
    Eigen::Matrix2d comoment = Eigen::Matrix2d::Zero();
    for (std::size_t k = 0; k < samples; ++k) {
      std::array<double, kToleranceParameters> z{};
      std::copy_n(&draws[k * kToleranceParameters], kToleranceParameters, z.begin());
      const std::array<double, kToleranceParameters> dq = at.draw(z);
      for (std::size_t l = 0; l < 4; ++l) printed.L[l] = m.L[l] + dq[l];
      printed.O1 = m.O1 + Vec2(dq[4], dq[5]);
      printed.O2 = m.O2 + Vec2(dq[6], dq[7]);
      const bool lengths_ok = std::all_of(printed.L.begin(), printed.L.end(), [](double l) { return l > 0.0; });
      const PointResult p = lengths_ok ? fk_point(printed, nominal.theta1 + dq[8], nominal.theta2 + dq[9]) : PointResult{};
      if (p.status != Status::ok) {
        ++r.failed;
        continue;
      }
      const Vec2 err = p.P - P;
      ++r.used;
      const Vec2 delta = err - mean;
      mean += delta / static_cast<double>(r.used);
      comoment += delta * (err - mean).transpose();
    }
    r.mean_error = mean;
    if (r.used > 1) {
      r.covariance = comoment / static_cast<double>(r.used - 1);
      r.covariance(0, 1) = r.covariance(1, 0) = 0.5 * (r.covariance(0, 1) + r.covariance(1, 0));
    }
  }
  return out;
}

}  // namespace fivebar
