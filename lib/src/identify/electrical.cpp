// The electrical side of a voltage or duty drive (lib/src/identify/detail.hpp): the current a
// zero-order-held voltage drives through the winding's first-order lag L/R, over each sample, and
// the fit of the winding from a sampled current.

#include <cmath>

#include "fivebar/format.hpp"
#include "identify/detail.hpp"

namespace fivebar::identify_detail {

ElectricalLag electrical_lag(double tau, double dt) {
  ElectricalLag l;
  if (!(tau > 0.0) || !(dt > 0.0)) return l;  // the current follows the voltage at once
  const double r = dt / tau;
  l.a = std::exp(-r);
  l.phi = (1.0 - l.a) / r;
  // Mean position (0: start, 1: end of the sample) of the weight exp(-(dt - u) / tau) / tau that the
  // current at the end of a sample gives the speed over it (the mean of a truncated exponential).
  l.lambda = 1.0 - 1.0 / r + (l.a > 0.0 ? l.a / (1.0 - l.a) : 0.0);
  return l;
}

std::vector<double> lagged_mean(const std::vector<double>& x, const ElectricalLag& lag) {
  std::vector<double> out(x.size());
  if (x.empty()) return out;
  double z = x.front();  // from steady state
  for (std::size_t k = 0; k < x.size(); ++k) {
    out[k] = x[k] + (z - x[k]) * lag.phi;
    z = lag.a * z + (1.0 - lag.a) * x[k];
  }
  return out;
}

std::vector<double> sampled_current_mean(const std::vector<double>& i, const ElectricalLag& lag) {
  std::vector<double> out(i);
  for (std::size_t k = 0; k + 1 < i.size(); ++k) {
    const double s = (i[k + 1] - lag.a * i[k]) / (1.0 - lag.a);  // the current the sample's voltage tends to
    out[k] = s + (i[k] - s) * lag.phi;
  }
  return out;
}

identify::Estimate winding_estimate(const identify::Estimate& arx, double dt, bool a_free, double a_held,
                                    const std::string& held_note) {
  // arx: i_k+1 = a i_k + b V_k - c w_k over (a, b, c); (R, L, k_e N) = ((1 - a) / b, -dt R / ln a, c / b).
  identify::Estimate e;
  e.names = {"resistance_ohm", "inductance_H", "back_emf_V_s_per_rad_output"};
  e.value = Eigen::Vector3d::Zero();
  e.sigma = Eigen::Vector3d::Zero();
  e.covariance = Eigen::Matrix3d::Zero();
  e.correlation = Eigen::Matrix3d::Identity();
  e.identified = {false, false, false};
  e.notes = {"", held_note, ""};
  e.residual_sigma = arx.residual_sigma;
  e.rows = arx.rows;
  const double a = a_free ? arx.value[0] : a_held, b = arx.value[1], c = arx.value[2];
  if (!arx.identified[1] || !(b > 0.0)) {
    e.notes[0] = e.notes[2] = "the voltage does not explain the current in this log; held at its prior";
    return e;
  }
  const double R = (1.0 - a) / b, keN = c / b;
  // Jacobian of (R, L, keN) with respect to (a, b, c).
  Eigen::Matrix3d G = Eigen::Matrix3d::Zero();
  G(0, 0) = a_free ? -1.0 / b : 0.0;
  G(0, 1) = -(1.0 - a) / (b * b);
  G(2, 1) = -c / (b * b);
  G(2, 2) = 1.0 / b;
  e.value[0] = R;
  e.value[2] = keN;
  e.identified[0] = true;
  e.identified[2] = arx.identified[2];
  if (a_free) {
    const double la = std::log(a);
    e.value[1] = -dt * (1.0 - a) / (b * la);
    G(1, 0) = -dt / b * (-la - (1.0 - a) / a) / (la * la);
    G(1, 1) = dt * (1.0 - a) / (b * b * la);
    e.identified[1] = true;
    e.notes[1] = "";
  }
  Eigen::Matrix3d C = arx.covariance.topLeftCorner(3, 3);
  if (!a_free) C.row(0).setZero(), C.col(0).setZero();
  e.covariance = G * C * G.transpose();
  for (int k = 0; k < 3; ++k) {
    if (!e.identified[static_cast<std::size_t>(k)]) e.covariance.row(k).setZero(), e.covariance.col(k).setZero();
  }
  e.sigma = e.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  for (int p = 0; p < 3; ++p) {
    for (int q = 0; q < 3; ++q) {
      if (e.sigma[p] > 0.0 && e.sigma[q] > 0.0) e.correlation(p, q) = e.covariance(p, q) / (e.sigma[p] * e.sigma[q]);
    }
  }
  return e;
}

}  // namespace fivebar::identify_detail
