// IDIM-LS and the fit figures (fivebar/identify/identify.hpp).

#include "fivebar/identify/identify.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <numeric>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/identify/filter.hpp"
#include "fivebar/runtime/controller.hpp"
#include "identify/detail.hpp"

namespace fivebar::identify {

namespace {

double sgn(double v) { return v > 0.0 ? 1.0 : v < 0.0 ? -1.0 : 0.0; }

double norm(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x * x;
  return std::sqrt(s);
}

double relative_error_percent(const std::vector<double>& y, const std::vector<double>& yhat) {
  std::vector<double> d(y.size());
  for (std::size_t i = 0; i < y.size(); ++i) d[i] = y[i] - yhat[i];
  const double ny = norm(y);
  return ny > 0.0 ? 100.0 * norm(d) / ny : 0.0;
}

/// One RK4 step of x' = w, w' = f(w) (the reduced model's speed equation), the open-loop and the
/// closed-loop simulations' one integrator.
template <class F>
void rk4_step(double& x, double& w, double h, const F& f) {
  const double a1 = f(w);
  const double a2 = f(w + 0.5 * h * a1);
  const double a3 = f(w + 0.5 * h * a2);
  const double a4 = f(w + h * a3);
  x += h / 6.0 * (w + 2.0 * (w + 0.5 * h * a1) + 2.0 * (w + 0.5 * h * a2) + (w + h * a3));
  w += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
}

/// The filtered motion and drive of one log.
struct Prepared {
  std::vector<double> q, qf, v, a;      // full rate
  std::vector<double> d;                // raw drive (the mechanical one: the current's sample means when measured next to a voltage)
  std::vector<double> u;                // drive torque input alpha * d, raw (for the simulation)
  // decimated, the edge rows trimmed
  Eigen::MatrixXd W;
  Eigen::VectorXd Y;
  std::vector<double> d_dec, emf_dec, t_dec;  // the drive paired with each row, the speed its EMF term sees, the time
  std::vector<double> known_dec;        // the known closed-chain torque, decimated (empty: none)
  std::vector<std::size_t> rows;        // the decimated rows kept (kept_rows(), less the reversals')
  // electrical regression (voltage drive with its current): i_k+1 against i_k, V_k, -w
  Eigen::MatrixXd We;
  Eigen::VectorXd Ye;
};

struct Setup {
  double dt = 0.0, fc = 0.0;
  int R = 1;
  int order = 4;
  int trim = 0;              // full-rate samples dropped at each end: the filters' settling
  bool zoh = true;
  bool per_direction = false;
  bool electrical = false;   // voltage or duty drive with a logged current
  bool voltage = false;      // voltage or duty drive (the winding's lag applies)
  identify_detail::ElectricalLag lag;  // of the winding over one sample
  double emf_per_ohm = 0.0;  // k_e N / R, A per rad/s (a voltage drive with its current)
  double alpha = 1.0, g = 0.0;  // mechanical drive map (after the electrical fit when any)
  double supply = 1.0;       // V per drive unit for the electrical equation (1 for voltage)
  int reversal_window = 0;   // rows within this many samples of a reversal left out (IdentifyOptions::skip_reversals)
};

/// Rows r of the decimated series (sample r R of the full rate) clear of both ends by `trim` samples.
std::vector<std::size_t> kept_rows(std::size_t n, int R, int trim) {
  std::vector<std::size_t> rows;
  const std::size_t t = static_cast<std::size_t>(std::max(0, trim));
  for (std::size_t i = 0, r = 0; i < n; i += static_cast<std::size_t>(R), ++r) {
    if (i >= t && i + t < n) rows.push_back(r);
  }
  return rows;
}

/// Decimated (fivebar/identify/filter.hpp decimate()) and only the kept rows.
std::vector<double> decimate_kept(const std::vector<double>& x, int R, const std::vector<std::size_t>& rows) {
  const std::vector<double> d = decimate(x, R);
  std::vector<double> out;
  out.reserve(rows.size());
  for (std::size_t r : rows) out.push_back(d[r]);
  return out;
}

/// The drive held over each sample, as the acceleration at t_k sees it: that acceleration, two
/// central differences, is (q_k+2 - 2 q_k + q_k-2) / (4 dt^2), the true acceleration weighted by a
/// triangle over [t_k-2, t_k+2], which gives the samples from k-2 to k+1 the weights 1, 3, 3, 1 (/ 8).
std::vector<double> held_pair(const std::vector<double>& x) {
  const std::size_t n = x.size();
  std::vector<double> y = x;
  auto at = [&](std::ptrdiff_t i) { return x[static_cast<std::size_t>(std::clamp<std::ptrdiff_t>(i, 0, static_cast<std::ptrdiff_t>(n) - 1))]; };
  for (std::size_t i = 0; i < n; ++i) {
    const auto k = static_cast<std::ptrdiff_t>(i);
    y[i] = (at(k - 2) + 3.0 * at(k - 1) + 3.0 * at(k) + at(k + 1)) / 8.0;
  }
  return y;
}

Eigen::VectorXd to_eigen(const std::vector<double>& v) { return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())); }

/// The regression of the winding from the sampled current: i_k+1 = a i_k + b V_k - c w_k with w the
/// speed weighted as the lag weighs it (ElectricalLag::lambda).
void electrical_regression(Prepared& p, const JointLog& j, const Setup& s, const std::vector<std::size_t>& rows) {
  const std::size_t n = j.current.size();
  std::vector<double> next(n), now(n), V(n), w(n);
  for (std::size_t k = 0; k < n; ++k) {
    // --instant-drive: the voltage and the current are instantaneous values, V_k = R i_k + k_e N w_k.
    const std::size_t k1 = s.zoh ? std::min(k + 1, n - 1) : k;
    next[k] = j.current[k1];
    now[k] = j.current[k];
    V[k] = s.supply * j.drive_values[k];
    w[k] = -(s.zoh ? p.v[k] + s.lag.lambda * (p.v[k1] - p.v[k]) : p.v[k]);
  }
  p.Ye = to_eigen(decimate_kept(next, s.R, rows));
  p.We.resize(p.Ye.size(), 3);
  p.We.col(0) = to_eigen(decimate_kept(now, s.R, rows));
  p.We.col(1) = to_eigen(decimate_kept(V, s.R, rows));
  p.We.col(2) = to_eigen(decimate_kept(w, s.R, rows));
}

/// The mechanical regressor at the kept decimated rows: acceleration, speed (or its positive and
/// negative parts), sgn(speed), 1, each through the decimation filter (parallel filtering).
Eigen::MatrixXd regressor(const std::vector<double>& v, const std::vector<double>& a, const Setup& s,
                          const std::vector<std::size_t>& rows) {
  const std::size_t n = v.size();
  std::vector<std::vector<double>> cols;
  cols.push_back(a);
  if (s.per_direction) {
    std::vector<double> vp(n), vn(n);
    for (std::size_t i = 0; i < n; ++i) {
      vp[i] = v[i] > 0.0 ? v[i] : 0.0;
      vn[i] = v[i] < 0.0 ? v[i] : 0.0;
    }
    cols.push_back(vp);
    cols.push_back(vn);
  } else {
    cols.push_back(v);
  }
  std::vector<double> sv(n);
  for (std::size_t i = 0; i < n; ++i) sv[i] = sgn(v[i]);
  cols.push_back(sv);
  cols.push_back(std::vector<double>(n, 1.0));
  Eigen::MatrixXd W(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(cols.size()));
  for (std::size_t c = 0; c < cols.size(); ++c) W.col(static_cast<Eigen::Index>(c)) = to_eigen(decimate_kept(cols[c], s.R, rows));
  return W;
}

/// The regressor of a position at the log's rate, through the same filters as the log's own.
Eigen::MatrixXd regressor_of(const std::vector<double>& q, const Setup& s, const std::vector<std::size_t>& rows) {
  const auto sos = butterworth_lowpass(s.order, s.fc, 1.0 / s.dt);
  const std::vector<double> v = derivative(filtfilt(sos, q), s.dt);
  const std::vector<double> a = derivative(v, s.dt);
  return regressor(v, a, s, rows);
}

/// `rows` less those within `window` full-rate samples of a reversal of the filtered speed `v` (a
/// change of sign between two samples): IdentifyOptions::skip_reversals.
std::vector<std::size_t> without_reversals(const std::vector<std::size_t>& rows, const std::vector<double>& v, int R, int window) {
  if (window <= 0 || v.empty()) return rows;
  const auto n = static_cast<std::ptrdiff_t>(v.size());
  std::vector<bool> near(v.size(), false);
  for (std::ptrdiff_t k = 1; k < n; ++k) {
    if ((v[static_cast<std::size_t>(k)] > 0.0) == (v[static_cast<std::size_t>(k - 1)] > 0.0)) continue;
    for (std::ptrdiff_t i = std::max<std::ptrdiff_t>(0, k - window); i < std::min(n, k + window); ++i) near[static_cast<std::size_t>(i)] = true;
  }
  std::vector<std::size_t> out;
  for (std::size_t r : rows) {
    if (!near[r * static_cast<std::size_t>(R)]) out.push_back(r);
  }
  return out;
}

Prepared prepare(const JointLog& j, const std::vector<double>& time, const JointPrior& prior, const Setup& s) {
  Prepared p;
  p.q = joint_angle(j, prior);
  const auto sos = butterworth_lowpass(s.order, s.fc, 1.0 / s.dt);
  p.qf = filtfilt(sos, p.q);
  p.v = derivative(p.qf, s.dt);
  p.a = derivative(p.v, s.dt);
  const std::size_t n = p.v.size();
  p.rows = without_reversals(kept_rows(n, s.R, s.trim), p.v, s.R, s.reversal_window);
  const std::vector<std::size_t>& rows = p.rows;
  // Parallel filtering (Gautier): the low-pass serves the derivatives of the position; the drive and
  // every column of the regressor then go through the same decimation filter.
  // A logged drive command is held over its sample (a digital drive's zero-order hold, and the
  // convention of simulate_position); the central-difference acceleration at t_k sees the mean of
  // the drive torque over [t_k-1, t_k+1], so the regression takes the mean of the two samples' means.
  // A voltage drives the current through the winding's lag L/R: each sample's mean current is
  // taken from the sampled current when it is logged (sampled_current_mean), else from the voltage
  // and the speed through the lag of the priors (lagged_mean).
  std::vector<double> df, emf = p.v;
  if (s.electrical) {
    p.d = j.current;
    if (s.zoh) {
      // Over a sample with the speed a ramp w(t), the current is the steady current of w(t - tau)
      // plus the transient; sampled_current_mean() takes the steady part at the end's value, so the
      // sample's mean current gains k_e N / R [(w_end - w_mean) - phi (w_end - w_start)]: 3 % of the
      // inertia's torque with the design's motor. k_e N / R from the electrical fit (the priors
      // before it).
      p.d = identify_detail::sampled_current_mean(j.current, s.lag);
      for (std::size_t k = 0; k + 1 < n; ++k) {
        const double w_mean = (p.qf[k + 1] - p.qf[k]) / s.dt;
        p.d[k] += s.emf_per_ohm * ((p.v[k + 1] - w_mean) - s.lag.phi * (p.v[k + 1] - p.v[k]));
      }
    }
    df = s.zoh ? held_pair(p.d) : p.d;
  } else if (s.voltage && s.zoh) {
    std::vector<double> wbar(n);  // the mean speed over each sample
    for (std::size_t k = 0; k + 1 < n; ++k) wbar[k] = (p.qf[k + 1] - p.qf[k]) / s.dt;
    wbar[n - 1] = p.v[n - 1];
    p.d = j.drive_values;
    df = held_pair(identify_detail::lagged_mean(p.d, s.lag));
    emf = held_pair(identify_detail::lagged_mean(wbar, s.lag));
  } else {
    p.d = j.drive_values;
    df = s.zoh ? held_pair(p.d) : p.d;
  }
  std::vector<double> tau(n);
  for (std::size_t i = 0; i < n; ++i) tau[i] = s.alpha * df[i] - s.g * emf[i];
  if (!prior.known_torque.empty()) {  // the closed chain's share (--rig mechanism)
    for (std::size_t i = 0; i < n; ++i) tau[i] -= prior.known_torque[i];
    p.known_dec = decimate_kept(prior.known_torque, s.R, rows);
  }
  p.Y = to_eigen(decimate_kept(tau, s.R, rows));
  p.W = regressor(p.v, p.a, s, rows);
  p.d_dec = decimate_kept(df, s.R, rows);
  p.emf_dec = decimate_kept(emf, s.R, rows);
  for (std::size_t r : rows) p.t_dec.push_back(time[r * static_cast<std::size_t>(s.R)]);
  p.u.resize(n);
  for (std::size_t i = 0; i < n; ++i) p.u[i] = s.alpha * p.d[i];
  // The winding's regression keeps the reversals' rows: left out, its L came out 28 % high instead of
  // 14 % with L/R = 2 ms (InductanceIsIdentifiedWhenTheWindingLagsOverASample).
  if (s.electrical) electrical_regression(p, j, s, kept_rows(n, s.R, s.trim));
  return p;
}

/// R, L and k_e N from the sampled current (lib/src/identify/electrical.cpp). L is held at its prior
/// when the prior's L/R is below the sample period, or when the log does not resolve it (the share a
/// of the current carried over one sample not above three of its sigmas): the current then follows
/// each sample's voltage and the log carries no trace of L.
Estimate fit_winding(const Prepared& p, const Setup& s, const MotorParams& m, double tol) {
  const double tau = m.inductance() / m.resistance();
  std::string note;
  if (!s.zoh) {
    note = "held at its prior: --instant-drive takes the current as following the voltage at once";
  } else if (tau < s.dt) {
    note = "not resolvable: the prior L/R = " + format::shortest(tau * 1e3) + " ms is below the sample period " +
           format::shortest(s.dt * 1e3) + " ms (the current settles within each sample); held at its prior";
  } else {
    // The voltage and the speed first: a column nearly a combination of them is the carried-over current.
    Eigen::MatrixXd W(p.We.rows(), 3);
    W << p.We.col(1), p.We.col(2), p.We.col(0);
    const Estimate bca = least_squares(W, p.Ye, {"b", "c", "a"}, Eigen::Vector3d(0.0, 0.0, s.lag.a), tol);
    Eigen::PermutationMatrix<3> perm;
    perm.indices() << 1, 2, 0;  // b, c, a -> a, b, c
    Estimate arx = bca;
    arx.names = {"a", "b", "c"};
    arx.value = perm * bca.value;
    arx.sigma = perm * bca.sigma;
    arx.covariance = perm * bca.covariance * perm.transpose();
    arx.identified = {bca.identified[2], bca.identified[0], bca.identified[1]};
    const double a = arx.value[0];
    if (arx.identified[0] && a > 0.0 && a < 1.0 && a > 3.0 * arx.sigma[0]) {
      return identify_detail::winding_estimate(arx, s.dt, true, a, "");
    }
    note = "not resolved by this log: the current carried over one sample, " + format::shortest(a) + " +- " +
           format::shortest(arx.sigma[0]) + ", is not above three of its sigmas; held at its prior";
  }
  // a held: regress i_k+1 - a i_k on V_k and -w.
  const double a_held = s.zoh ? s.lag.a : 0.0;
  const Eigen::VectorXd y = p.Ye - a_held * p.We.col(0);
  const Eigen::MatrixXd W = p.We.rightCols(2);
  const Estimate bc = least_squares(W, y, {"b", "c"}, Eigen::Vector2d::Zero(), tol);
  Estimate arx;
  arx.names = {"a", "b", "c"};
  arx.value = Eigen::Vector3d(a_held, bc.value[0], bc.value[1]);
  arx.identified = {false, bc.identified[0], bc.identified[1]};
  arx.covariance = Eigen::Matrix3d::Zero();
  arx.covariance.bottomRightCorner(2, 2) = bc.covariance;
  arx.residual_sigma = bc.residual_sigma;
  arx.rows = bc.rows;
  Estimate e = identify_detail::winding_estimate(arx, s.dt, false, a_held, note);
  e.value[1] = m.inductance();
  return e;
}

/// The mechanical parameters scale with the drive's scale alpha (k_t from the electrical fit): its
/// relative variance adds theta theta^T var(alpha) / alpha^2 to their covariance (independent errors).
void add_scale_variance(Estimate& e, double relative_variance) {
  const Eigen::Index n = e.value.size();
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) {
      if (e.identified[static_cast<std::size_t>(i)] && e.identified[static_cast<std::size_t>(j)]) {
        e.covariance(i, j) += e.value[i] * e.value[j] * relative_variance;
      }
    }
  }
  for (Eigen::Index i = 0; i < n; ++i) e.sigma[i] = std::sqrt(std::max(0.0, e.covariance(i, i)));
  for (Eigen::Index i = 0; i < n; ++i) {
    for (Eigen::Index j = 0; j < n; ++j) {
      if (e.sigma[i] > 0.0 && e.sigma[j] > 0.0) e.correlation(i, j) = e.covariance(i, j) / (e.sigma[i] * e.sigma[j]);
    }
  }
}

Parameter record(std::string key, double value, double sigma, bool identified, std::string note) {
  return Parameter{std::move(key), value, sigma, identified, std::move(note)};
}

/// Every key of a joint's result: the mechanical parameters, the design keys derived from them,
/// the electrical keys (fitted or held) and the held gearbox.
std::vector<Parameter> records(const JointIdentification& r, const JointLog& joint, const JointPrior& prior,
                               const IdentifyOptions& o, int p) {
  std::vector<Parameter> out;
  const std::vector<std::string> names = mechanical_names(o.per_direction, joint.linear);
  const MotorParams& m = prior.motor;
  const Estimate& fin = r.iv ? *r.iv : (o.use_output_error && r.output_error) ? *r.output_error : r.idim;
  const std::string method = r.iv ? "IDIM-IV" : (o.use_output_error && r.output_error) ? "output error" : "IDIM-LS";
  for (int i = 0; i < p; ++i) {
    const std::size_t ui = static_cast<std::size_t>(i);
    out.push_back(record(names[ui], fin.value[i], fin.sigma[i], fin.identified[ui],
                         fin.identified[ui] ? method : r.idim.notes[ui]));
  }
  if (!joint.linear) {
    const std::string mk = prior.motor_key + ".";
    const double N2 = m.gear_ratio * m.gear_ratio;
    // Derived design keys (the design's units).
    out.push_back(record(mk + "rotor_inertia_g_cm2", (fin.value[0] - prior.load_inertia) / N2 * 1e7, fin.sigma[0] / N2 * 1e7,
                         fin.identified[0],
                         fin.identified[0] ? "(inertia_kg_m2 - load " + format::shortest(prior.load_inertia) +
                                                 " kg m^2) / gear_ratio^2, gear_ratio held at its prior"
                                           : r.idim.notes[0]));
    if (!o.per_direction) {
      out.push_back(record(mk + "viscous_friction_mNm_s_per_rad", fin.value[1] * 1e3, fin.sigma[1] * 1e3, fin.identified[1],
                           fin.identified[1] ? "viscous_Nm_s_per_rad" : r.idim.notes[1]));
    }
    const int c = p - 2;
    out.push_back(record(mk + "coulomb_friction_mNm", fin.value[c] * 1e3, fin.sigma[c] * 1e3,
                         fin.identified[static_cast<std::size_t>(c)],
                         fin.identified[static_cast<std::size_t>(c)] ? "coulomb_Nm" : r.idim.notes[static_cast<std::size_t>(c)]));
    const bool torque = joint.drive == DriveKind::torque;
    const bool current = joint.drive == DriveKind::current;
    const std::string why = torque ? "held at its prior: a torque drive does not involve it"
                            : current ? "held at its prior: with a current drive only ratios to eta N k_t are identifiable"
                                      : "held at its prior: the log has no current, so only ratios to k_t / R are identifiable";
    if (r.electrical) {
      const Estimate& el = *r.electrical;
      const double rpm = 60.0 / (2.0 * std::numbers::pi);
      out.push_back(record(mk + "terminal_resistance_ohm", el.value[0], el.sigma[0], el.identified[0],
                           el.identified[0] ? "IDIM-LS (electrical equation on the sampled current)" : el.notes[0]));
      out.push_back(record(mk + "inductance_mH", el.value[1] * 1e3, el.sigma[1] * 1e3, el.identified[1],
                           el.identified[1] ? "IDIM-LS (electrical equation on the sampled current)" : el.notes[1]));
      const double ke = el.value[2] / m.gear_ratio, ske = el.sigma[2] / m.gear_ratio;
      out.push_back(record(mk + "back_emf_mV_per_rpm", ke * 1e3 / rpm, ske * 1e3 / rpm, el.identified[2],
                           el.identified[2] ? "IDIM-LS (electrical equation on the sampled current), gear_ratio held at its prior" : el.notes[2]));
      out.push_back(record(mk + "torque_constant_mNm_per_A", ke * 1e3, ske * 1e3, el.identified[2],
                           el.identified[2] ? "k_t = k_e (SI)" : el.notes[2]));
    } else {
      out.push_back(record(mk + "terminal_resistance_ohm", m.terminal_resistance_ohm, 0.0, false, why));
      out.push_back(record(mk + "inductance_mH", m.inductance_mH, 0.0, false,
                           torque || current ? why
                                             : "held at its prior: the log has no current (the winding's lag L/R over each "
                                               "sample is the priors')"));
      out.push_back(record(mk + "torque_constant_mNm_per_A", m.torque_constant_mNm_per_A, 0.0, false, why));
      out.push_back(record(mk + "back_emf_mV_per_rpm", m.back_emf_mV_per_rpm, 0.0, false, why));
    }
    out.push_back(record(mk + "gearbox_efficiency", m.gearbox_efficiency, 0.0, false,
                         "held at its prior: it scales every torque, so a log cannot separate it from the friction and inertia"));
    out.push_back(record(mk + "gear_ratio", m.gear_ratio, 0.0, false, "held at its prior (a datasheet value)"));
  }
  return out;
}

}  // namespace

double fit_percent(const std::vector<double>& y, const std::vector<double>& yhat) {
  if (y.empty()) return 0.0;
  const double mean = std::accumulate(y.begin(), y.end(), 0.0) / static_cast<double>(y.size());
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    num += (y[i] - yhat[i]) * (y[i] - yhat[i]);
    den += (y[i] - mean) * (y[i] - mean);
  }
  return den > 0.0 ? 100.0 * (1.0 - std::sqrt(num / den)) : 0.0;
}

Estimate least_squares(const Eigen::MatrixXd& W, const Eigen::VectorXd& Y, const std::vector<std::string>& names,
                       const Eigen::VectorXd& prior, double tol) {
  const Eigen::Index p = W.cols();
  Estimate e;
  e.names = names;
  e.value = prior;
  e.sigma = Eigen::VectorXd::Zero(p);
  e.covariance = Eigen::MatrixXd::Zero(p, p);
  e.correlation = Eigen::MatrixXd::Identity(p, p);
  e.identified.assign(static_cast<std::size_t>(p), false);
  e.notes.assign(static_cast<std::size_t>(p), "");
  e.rows = static_cast<int>(W.rows());
  // Base parameters: columns taken in order; a column within `tol` (relative) of the span of the
  // columns already kept is a combination of them and its parameter is not separable.
  std::vector<Eigen::Index> kept;
  for (Eigen::Index c = 0; c < p; ++c) {
    const double nc = W.col(c).norm();
    if (!(nc > 0.0)) {
      e.notes[static_cast<std::size_t>(c)] = "not excited: its regressor column is zero in this log; held at its prior";
      continue;
    }
    if (!kept.empty()) {
      Eigen::MatrixXd B(W.rows(), static_cast<Eigen::Index>(kept.size()));
      for (std::size_t k = 0; k < kept.size(); ++k) B.col(static_cast<Eigen::Index>(k)) = W.col(kept[k]);
      const Eigen::VectorXd coef = B.colPivHouseholderQr().solve(W.col(c));
      const double dist = (W.col(c) - B * coef).norm() / nc;
      if (dist < tol) {
        std::vector<std::string> parts;
        for (std::size_t k = 0; k < kept.size(); ++k) {
          if (std::abs(coef[static_cast<Eigen::Index>(k)]) > 1e-6) {
            parts.push_back(format::fixed(coef[static_cast<Eigen::Index>(k)], 4) + " x " + names[static_cast<std::size_t>(kept[k])]);
          }
        }
        e.notes[static_cast<std::size_t>(c)] = "not separable in this log: its regressor column is " + format::join(parts, " + ") +
                                               " (relative distance " + format::shortest(dist) + "); held at its prior";
        continue;
      }
    }
    kept.push_back(c);
  }
  const Eigen::Index m = static_cast<Eigen::Index>(kept.size());
  if (m == 0) return e;
  Eigen::VectorXd y = Y;
  for (Eigen::Index c = 0; c < p; ++c) {
    if (std::find(kept.begin(), kept.end(), c) == kept.end()) y -= W.col(c) * prior[c];
  }
  Eigen::MatrixXd A(W.rows(), m);
  for (Eigen::Index k = 0; k < m; ++k) A.col(k) = W.col(kept[static_cast<std::size_t>(k)]);
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  const Eigen::VectorXd x = qr.solve(y);
  const double ssr = (y - A * x).squaredNorm();
  const double dof = static_cast<double>(W.rows() - m);
  const double s2 = dof > 0 ? ssr / dof : 0.0;
  e.residual_sigma = std::sqrt(s2);
  const Eigen::MatrixXd AtA = A.transpose() * A;
  const Eigen::MatrixXd cov = s2 * AtA.ldlt().solve(Eigen::MatrixXd::Identity(m, m));
  for (Eigen::Index a = 0; a < m; ++a) {
    const Eigen::Index ia = kept[static_cast<std::size_t>(a)];
    e.value[ia] = x[a];
    e.identified[static_cast<std::size_t>(ia)] = true;
    for (Eigen::Index b = 0; b < m; ++b) e.covariance(ia, kept[static_cast<std::size_t>(b)]) = cov(a, b);
  }
  for (Eigen::Index i = 0; i < p; ++i) e.sigma[i] = std::sqrt(std::max(0.0, e.covariance(i, i)));
  for (Eigen::Index a : kept) {
    for (Eigen::Index b : kept) {
      if (e.sigma[a] > 0.0 && e.sigma[b] > 0.0) e.correlation(a, b) = e.covariance(a, b) / (e.sigma[a] * e.sigma[b]);
    }
  }
  return e;
}

std::vector<double> simulate_position(const std::vector<double>& time, const std::vector<double>& u, double g,
                                      const Eigen::VectorXd& theta, bool per_direction, double q0, double w0, double ws) {
  std::vector<double> out(time.size());
  double x = q0, w = w0;
  const double* th = theta.data();
  out[0] = x;
  for (std::size_t k = 0; k + 1 < time.size(); ++k) {
    const double h = time[k + 1] - time[k];
    auto f = [&](double ww) { return acceleration(th, per_direction, g, u[k], ww, ws); };
    rk4_step(x, w, h, f);
    out[k + 1] = x;
  }
  return out;
}

namespace {

/// The device's PID as a LoopController.
class DevicePid final : public LoopController {
 public:
  DevicePid(std::vector<double> reference, const runtime::Gains& gains, double period, double scale)
      : reference_(std::move(reference)), gains_(gains), period_(period), scale_(scale) {}
  void reset() override { state_ = runtime::PidState{}; }
  double drive(std::size_t row, double angle) override {
    const double e = reference_[std::min(row, reference_.size() - 1)] - angle;
    return scale_ * runtime::pid_update(gains_, period_, state_, e);
  }

 private:
  std::vector<double> reference_;
  runtime::Gains gains_;
  double period_, scale_;
  runtime::PidState state_;
};

/// Rows of several prepared logs, one below the other.
Prepared stack(const std::vector<Prepared>& ps) {
  if (ps.size() == 1) return ps.front();
  Prepared out;
  Eigen::Index rows = 0, erows = 0;
  for (const Prepared& p : ps) {
    rows += p.W.rows();
    erows += p.We.rows();
  }
  out.W.resize(rows, ps.front().W.cols());
  out.Y.resize(rows);
  out.We.resize(erows, ps.front().We.cols());
  out.Ye.resize(erows);
  Eigen::Index r = 0, e = 0;
  for (const Prepared& p : ps) {
    out.W.middleRows(r, p.W.rows()) = p.W;
    out.Y.segment(r, p.Y.size()) = p.Y;
    r += p.W.rows();
    if (p.We.rows() > 0) {
      out.We.middleRows(e, p.We.rows()) = p.We;
      out.Ye.segment(e, p.Ye.size()) = p.Ye;
      e += p.We.rows();
    }
    out.d_dec.insert(out.d_dec.end(), p.d_dec.begin(), p.d_dec.end());
    out.emf_dec.insert(out.emf_dec.end(), p.emf_dec.begin(), p.emf_dec.end());
    out.known_dec.insert(out.known_dec.end(), p.known_dec.begin(), p.known_dec.end());
  }
  return out;
}

/// The logs of one fit, prepared.
struct Prepped {
  std::vector<Setup> setups;
  std::vector<Prepared> logs;
  Prepared all;  ///< stacked
};

Prepped prepare_all(const std::vector<LogSegment>& segs, const JointPrior& prior, const Setup& s) {
  Prepped out;
  for (const LogSegment& g : segs) {
    Setup sg = s;
    sg.dt = (g.time->back() - g.time->front()) / static_cast<double>(g.time->size() - 1);
    out.setups.push_back(sg);
    out.logs.push_back(prepare(*g.joint, *g.time, prior, sg));
  }
  out.all = stack(out.logs);
  return out;
}

/// The drive-to-torque map of the simulated loop: the controller commands the log's drive column
/// (duty or voltage when the current is only measured), not the current the mechanical regression reads.
struct LoopDrive {
  double alpha = 1.0, g = 0.0;
};

/// Fit figures over every log of a fit (the percentages over the logs' rows together); the series
/// of the first log for the plot. A closed-loop log's position is simulated in its loop.
Fit fit_logs(const Prepped& pp, const std::vector<LogSegment>& segs, const Eigen::VectorXd& theta, const LoopDrive& loop,
             const IdentifyOptions& o, std::vector<double>* sim_first, std::vector<double>* dhat_first) {
  Fit f;
  std::vector<double> d, dh, q, qs;
  bool simulated = pp.all.known_dec.empty();
  const Eigen::VectorXd tau_hat = pp.all.W * theta;
  for (std::size_t i = 0; i < pp.all.d_dec.size(); ++i) {
    const double known = pp.all.known_dec.empty() ? 0.0 : pp.all.known_dec[i];
    const Setup& s = pp.setups.front();
    dh.push_back((tau_hat[static_cast<Eigen::Index>(i)] + known + s.g * pp.all.emf_dec[i]) / s.alpha);
  }
  d = pp.all.d_dec;
  if (dhat_first) dhat_first->assign(dh.begin(), dh.begin() + static_cast<std::ptrdiff_t>(pp.logs.front().d_dec.size()));
  f.drive_fit_percent = fit_percent(d, dh);
  f.drive_relative_error_percent = relative_error_percent(d, dh);
  if (sim_first) sim_first->clear();
  if (!simulated) return f;  // one joint of a closed chain: its simulation alone means nothing
  for (std::size_t k = 0; k < segs.size(); ++k) {
    const Prepared& p = pp.logs[k];
    const Setup& s = pp.setups[k];
    std::vector<double> sim;
    if (segs[k].controller != nullptr) {
      sim = simulate_closed_loop(*segs[k].time, *segs[k].controller, loop.alpha, loop.g, theta, s.per_direction, p.qf.front(),
                                 p.v.front(), o.coulomb_smoothing);
    } else {
      sim = simulate_position(*segs[k].time, p.u, s.g, theta, s.per_direction, p.qf.front(), p.v.front(), o.coulomb_smoothing);
    }
    bool finite = sim.size() == p.q.size();
    for (double x : sim) finite = finite && std::isfinite(x);
    if (!finite) {
      simulated = false;
      break;
    }
    if (k == 0 && sim_first) *sim_first = sim;
    q.insert(q.end(), p.q.begin(), p.q.end());
    qs.insert(qs.end(), sim.begin(), sim.end());
  }
  if (simulated) {
    f.simulated = true;
    f.position_fit_percent = fit_percent(q, qs);
    f.position_relative_error_percent = relative_error_percent(q, qs);
  } else if (sim_first) {
    sim_first->clear();
  }
  return f;
}

/// One instrumental-variable solve: theta = (Z^T W)^-1 Z^T Y over the columns `ls` identified (the
/// others held at its values), covariance s^2 (Z^T W)^-1 Z^T Z (W^T Z)^-1 (Janot, Vandanjon, Gautier 2014).
Estimate iv_solve(const Eigen::MatrixXd& W, const Eigen::VectorXd& Y, const Eigen::MatrixXd& Z, const Estimate& ls) {
  Estimate e = ls;
  const Eigen::Index p = W.cols();
  std::vector<Eigen::Index> kept;
  Eigen::VectorXd y = Y;
  for (Eigen::Index c = 0; c < p; ++c) {
    if (ls.identified[static_cast<std::size_t>(c)]) {
      kept.push_back(c);
    } else {
      y -= W.col(c) * ls.value[c];
    }
  }
  const Eigen::Index m = static_cast<Eigen::Index>(kept.size());
  if (m == 0) return e;
  Eigen::MatrixXd A(W.rows(), m), B(W.rows(), m);
  for (Eigen::Index k = 0; k < m; ++k) {
    A.col(k) = W.col(kept[static_cast<std::size_t>(k)]);
    B.col(k) = Z.col(kept[static_cast<std::size_t>(k)]);
  }
  const Eigen::MatrixXd BtA = B.transpose() * A;
  const Eigen::FullPivLU<Eigen::MatrixXd> lu(BtA);
  const Eigen::VectorXd x = lu.solve(B.transpose() * y);
  const Eigen::MatrixXd inv = lu.inverse();
  const double dof = static_cast<double>(W.rows() - m);
  const double s2 = dof > 0 ? (y - A * x).squaredNorm() / dof : 0.0;
  const Eigen::MatrixXd cov = s2 * inv * (B.transpose() * B) * inv.transpose();
  e.residual_sigma = std::sqrt(s2);
  e.covariance.setZero();
  e.correlation.setIdentity();
  for (Eigen::Index a = 0; a < m; ++a) {
    e.value[kept[static_cast<std::size_t>(a)]] = x[a];
    for (Eigen::Index b = 0; b < m; ++b) e.covariance(kept[static_cast<std::size_t>(a)], kept[static_cast<std::size_t>(b)]) = cov(a, b);
  }
  for (Eigen::Index i = 0; i < p; ++i) e.sigma[i] = std::sqrt(std::max(0.0, e.covariance(i, i)));
  for (Eigen::Index a : kept) {
    for (Eigen::Index b : kept) {
      if (e.sigma[a] > 0.0 && e.sigma[b] > 0.0) e.correlation(a, b) = e.covariance(a, b) / (e.sigma[a] * e.sigma[b]);
    }
  }
  return e;
}

/// IDIM-IV from IDIM-LS: the loop simulated with the last estimate gives the instruments (the
/// regressor of the simulated, noise-free position), until no parameter moves by more than
/// iv_tolerance of its sigma.
void closed_loop_iv(JointIdentification& r, const Prepped& pp, const std::vector<LogSegment>& segs, const LoopDrive& loop,
                    const IdentifyOptions& o) {
  Estimate cur = r.idim;
  for (int it = 1; it <= o.iv_max_iterations; ++it) {
    if (!(cur.value[0] > 0.0)) {
      r.iv_status = "stopped at iteration " + std::to_string(it) + ": the inertia is not positive, the loop cannot be simulated";
      return;
    }
    Eigen::MatrixXd Z(pp.all.W.rows(), pp.all.W.cols());
    Eigen::Index row = 0;
    for (std::size_t k = 0; k < segs.size(); ++k) {
      const Prepared& p = pp.logs[k];
      const std::vector<double> qs = simulate_closed_loop(*segs[k].time, *segs[k].controller, loop.alpha, loop.g, cur.value,
                                                          o.per_direction, p.qf.front(), p.v.front(), o.coulomb_smoothing);
      bool finite = qs.size() == p.q.size();
      for (double x : qs) finite = finite && std::isfinite(x);
      if (!finite) {
        r.iv_status = "stopped at iteration " + std::to_string(it) + ": the simulated loop diverged";
        return;
      }
      Z.middleRows(row, p.W.rows()) = regressor_of(qs, pp.setups[k], p.rows);
      row += p.W.rows();
    }
    const Estimate next = iv_solve(pp.all.W, pp.all.Y, Z, r.idim);
    if (!next.value.allFinite() || !next.sigma.allFinite()) {
      r.iv_status = "stopped at iteration " + std::to_string(it) + ": the instruments are not independent (Z^T W singular)";
      return;
    }
    double step = 0.0;
    for (Eigen::Index i = 0; i < next.value.size(); ++i) {
      if (next.identified[static_cast<std::size_t>(i)] && next.sigma[i] > 0.0) step = std::max(step, std::abs(next.value[i] - cur.value[i]) / next.sigma[i]);
    }
    cur = next;
    r.iv_iterations = it;
    if (step <= o.iv_tolerance) {
      r.iv = cur;
      r.iv_converged = true;
      r.iv_status = "converged in " + std::to_string(it) + " iterations";
      return;
    }
  }
  r.iv = cur;
  r.iv_status = "not converged after " + std::to_string(o.iv_max_iterations) + " iterations";
}

/// The checks on the logs of a fit and the setup they share.
Setup setup_for(const std::vector<LogSegment>& logs, const IdentifyOptions& o, int p) {
  const std::vector<double>& time = *logs.front().time;
  Setup s;
  s.dt = (time.back() - time.front()) / static_cast<double>(time.size() - 1);
  const double fs = 1.0 / s.dt;
  s.fc = o.cutoff_hz > 0.0 ? o.cutoff_hz : fs / 10.0;
  if (!(s.fc < 0.5 * fs)) {
    throw InputError("--cutoff: " + format::shortest(s.fc) + " Hz is not below the log's Nyquist frequency " + format::shortest(0.5 * fs) + " Hz");
  }
  s.per_direction = o.per_direction;
  s.zoh = o.zero_order_hold;
  if (o.filter_order < 1 || o.filter_order > 16) throw InputError("--filter-order: must be 1 ... 16");
  s.order = o.filter_order;
  std::size_t shortest = time.size();
  for (const LogSegment& g : logs) shortest = std::min(shortest, g.time->size());
  s.R = o.decimation > 0 ? o.decimation : 10;
  if (o.decimation <= 0) {
    while (s.R > 1 && static_cast<int>(shortest) / s.R < 50 * (p + 3)) --s.R;
  }
  s.trim = edge_samples(s.order, s.fc, fs, s.R);
  for (std::size_t k = 0; k < logs.size(); ++k) {
    const std::vector<double>& t = *logs[k].time;
    const double dt = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
    const std::string which = logs.size() > 1 ? "log " + std::to_string(k + 1) + ": " : "";
    if (std::abs(dt - s.dt) > 0.05 * s.dt) {
      throw InputError(which + "sample time " + format::shortest(dt) + " s differs from the first log's " + format::shortest(s.dt) + " s");
    }
    const std::size_t kept = kept_rows(t.size(), s.R, s.trim).size();
    if (static_cast<int>(kept) < 2 * p + 4) {
      throw InputError(which + "the log has " + std::to_string(t.size()) + " rows; decimated by " + std::to_string(s.R) +
                       " and clear of the " + std::to_string(s.trim) + " samples at each end where the filters settle, " +
                       std::to_string(kept) + " rows remain: fewer than twice the " + std::to_string(p) + " unknowns and 4");
    }
    const JointLog& j = *logs[k].joint;
    const JointLog& j0 = *logs.front().joint;
    if (j.drive != j0.drive || j.reading != j0.reading || j.current.empty() != j0.current.empty() || j.linear != j0.linear) {
      throw InputError(which + "joint '" + (j.prefix.empty() ? std::string("motor") : j.prefix) + "' is logged with '" + j.drive_column +
                       "' and '" + j.reading_column + "'" + (j.current.empty() ? "" : " and its current") + ", the first log with '" +
                       j0.drive_column + "' and '" + j0.reading_column + "'" + (j0.current.empty() ? "" : " and its current") +
                       ": the logs of one fit record the same columns");
    }
  }
  return s;
}

/// The electrical fit (a voltage or duty drive with its current) and the mechanical drive map it
/// gives; the logs prepared again with it.
void fit_electrical(JointIdentification& r, Prepped& pp, Setup& s, const std::vector<LogSegment>& logs, const JointPrior& prior,
                    const IdentifyOptions& o, double& alpha_variance, MotorParams& fitted) {
  r.electrical = fit_winding(pp.all, s, prior.motor, o.rank_tolerance);
  const Estimate& el = *r.electrical;
  const MotorParams& m = prior.motor;
  if (el.identified[1]) s.lag = identify_detail::electrical_lag(el.value[1] / el.value[0], s.dt);
  if (el.identified[0] && el.identified[2]) s.emf_per_ohm = el.value[2] / el.value[0];
  if (el.identified[0] && el.value[0] > 0.0) fitted.terminal_resistance_ohm = el.value[0];
  if (el.identified[2] && el.value[2] > 0.0) {
    const double ke_motor = el.value[2] / m.gear_ratio;  // V s / rad = N m / A at the motor shaft
    s.alpha = m.gearbox_efficiency * m.gear_ratio * ke_motor;
    alpha_variance = (el.sigma[2] / el.value[2]) * (el.sigma[2] / el.value[2]);
    fitted.torque_constant_mNm_per_A = ke_motor * 1e3;
    fitted.back_emf_mV_per_rpm = ke_motor * 1e3 * 2.0 * std::numbers::pi / 60.0;
  }
  pp = prepare_all(logs, prior, s);
}

Eigen::VectorXd mechanical_prior(const JointPrior& prior, bool linear, int p) {
  Eigen::VectorXd mprior(p);
  const MotorParams& m = prior.motor;
  if (linear) {
    mprior.setZero();
  } else {
    mprior[0] = m.gear_ratio * m.gear_ratio * m.rotor_inertia() + prior.load_inertia;
    for (int k = 1; k < p - 2; ++k) mprior[k] = m.viscous_friction();
    mprior[p - 2] = m.coulomb_friction();
    mprior[p - 1] = 0.0;
  }
  return mprior;
}

/// The output-error refinement over the open-loop logs (the closed-loop ones are not simulated open loop).
void refine_output_error(JointIdentification& r, const Prepped& est, const std::optional<Prepped>& val,
                         const std::vector<LogSegment>& logs, const std::vector<LogSegment>& validation, const LoopDrive& loop,
                         const JointPrior& prior, const IdentifyOptions& o, bool closed) {
  if (!o.output_error) {
    r.output_error_status = "not run (--no-output-error)";
    return;
  }
  if (!prior.known_torque.empty()) {
    r.output_error_status = "not run: one joint of a closed chain (--rig mechanism) is not simulated alone";
    return;
  }
  if (closed) {
    r.output_error_status = "not run: a closed-loop log (an open-loop simulation of it drifts; IDIM-IV is the estimate under feedback)";
    return;
  }
  if (!(r.idim.identified[0] && r.idim.value[0] > 0.0)) {
    r.output_error_status = "not run: the inertia is not identified or not positive";
    return;
  }
  std::vector<identify_detail::Series> series;
  for (std::size_t k = 0; k < logs.size(); ++k) {
    const Prepared& p = est.logs[k];
    series.push_back({logs[k].time, &p.u, &p.q, p.qf.front(), p.v.front()});
  }
  const Setup& s = est.setups.front();
  Estimate oe = identify_detail::output_error(series, s.g, r.idim, s.per_direction, o.coulomb_smoothing, r.output_error_status);
  r.output_error = oe;
  std::vector<double> osim;
  r.estimation_oe = fit_logs(est, logs, oe.value, loop, o, &osim, nullptr);
  r.series.position_oe = osim;
  if (val) {
    std::vector<double> vo;
    r.validation_oe = fit_logs(*val, validation, oe.value, loop, o, &vo, nullptr);
    r.validation_series.position_oe = vo;
  }
}

}  // namespace

std::unique_ptr<LoopController> device_pid(std::vector<double> reference, const runtime::Gains& gains, double period_s, double scale) {
  if (reference.empty()) throw InputError("a closed-loop log needs its reference column");
  return std::make_unique<DevicePid>(std::move(reference), gains, period_s, scale);
}

std::vector<double> simulate_closed_loop(const std::vector<double>& time, LoopController& c, double alpha, double g,
                                         const Eigen::VectorXd& theta, bool per_direction, double q0, double w0, double ws,
                                         std::vector<double>* drive_out) {
  c.reset();
  std::vector<double> out(time.size(), std::numeric_limits<double>::quiet_NaN());
  if (drive_out) drive_out->assign(time.size(), 0.0);
  double x = q0, w = w0;
  const double* th = theta.data();
  // The smoothed Coulomb term's slope tau_c / (J w_s) makes the speed equation stiff: sub-steps keep
  // RK4 within its stability bound (h lambda <= 2).
  const std::size_t k_coulomb = per_direction ? 3 : 2;
  const double J = theta[0];
  double lambda = (std::abs(theta[static_cast<Eigen::Index>(k_coulomb)]) / ws + std::abs(g) + std::abs(theta[1])) / J;
  if (per_direction) lambda += std::abs(theta[2]) / J;
  for (std::size_t k = 0; k < time.size(); ++k) {
    out[k] = x;
    if (!std::isfinite(x) || !std::isfinite(w)) break;
    const double d = c.drive(k, x);
    if (drive_out) (*drive_out)[k] = d;
    if (k + 1 == time.size()) break;
    const double step = time[k + 1] - time[k];
    const int sub = static_cast<int>(std::clamp(std::ceil(step * lambda / 2.0), 1.0, 1000.0));
    const double h = step / sub;
    const double u = alpha * d;
    auto f = [&](double ww) { return acceleration(th, per_direction, g, u, ww, ws); };
    for (int i = 0; i < sub; ++i) {
      rk4_step(x, w, h, f);
    }
  }
  return out;
}

JointIdentification identify_joint(const JointLog& joint, const std::vector<double>& time, const JointPrior& prior,
                                   const JointLog* validation, const std::vector<double>* validation_time,
                                   const IdentifyOptions& o) {
  std::vector<LogSegment> val;
  if (validation != nullptr) val.push_back({validation, validation_time, nullptr});
  return identify_joint(std::vector<LogSegment>{{&joint, &time, nullptr}}, prior, val, o);
}

JointIdentification identify_joint(const std::vector<LogSegment>& logs, const JointPrior& prior,
                                   const std::vector<LogSegment>& validation, const IdentifyOptions& o) {
  if (logs.empty()) throw InputError("no log to identify");
  const JointLog& joint = *logs.front().joint;
  const bool closed = logs.front().controller != nullptr;
  for (const LogSegment& g : logs) {
    if ((g.controller != nullptr) != closed) throw InputError("the logs of one fit are all closed loop (with a reference) or all open loop");
  }
  if (logs.size() > 1 && !prior.known_torque.empty()) throw InputError("--rig mechanism: one log per fit");
  if (joint.linear && joint.drive != DriveKind::torque) throw InputError("a linear axis (position_m) takes its drive as force_N");
  JointIdentification r;
  r.joint = joint.prefix.empty() ? "motor" : joint.prefix;
  r.drive_column = joint.drive_column;
  r.reading_column = joint.reading_column;
  r.linear = joint.linear;
  r.logs = static_cast<int>(logs.size());
  const std::vector<std::string> names = mechanical_names(o.per_direction, joint.linear);
  const int p = static_cast<int>(names.size());
  Setup s = setup_for(logs, o, p);
  r.sample_time = s.dt;
  r.cutoff_hz = s.fc;
  r.decimation = s.R;
  r.edge_samples = s.trim;
  const MotorParams& m = prior.motor;
  s.voltage = joint.drive == DriveKind::voltage || joint.drive == DriveKind::duty;
  // Around a reversal the reading stalls in the gearbox's backlash while the motor, whose speed the
  // back-EMF sees, already turns: rows within the filters' main lobes of one are left out. Open loop
  // only: under the PID (IdentifyClosedLoop) IDIM-IV's inertia has a mean z of -0.05 over 20 logs
  // with every row and -0.51 with those rows left out.
  if (s.voltage && o.skip_reversals && !closed) s.reversal_window = reversal_samples(s.fc, 1.0 / s.dt, s.R);
  r.reversal_samples = s.reversal_window;
  s.electrical = s.voltage && !joint.current.empty();
  s.supply = joint.drive == DriveKind::duty ? m.supply_voltage_V : 1.0;
  s.lag = identify_detail::electrical_lag(m.inductance() / m.resistance(), s.dt);
  s.emf_per_ohm = m.back_emf_constant() * m.gear_ratio / m.resistance();
  const ReducedDrive rd = reduced_drive(s.electrical ? DriveKind::current : joint.drive, m);
  s.alpha = rd.alpha;
  s.g = rd.g;

  // Electrical fit first: it gives the lag for the current's sample means and k_t = k_e for the
  // mechanical one.
  Prepped est = prepare_all(logs, prior, s);
  for (std::size_t k = 0; k < logs.size(); ++k) {
    r.reversal_rows += static_cast<int>(kept_rows(est.logs[k].v.size(), s.R, s.trim).size() - est.logs[k].rows.size());
  }
  double alpha_variance = 0.0;  // relative, of the drive's scale (k_t from the electrical fit)
  MotorParams fitted = m;
  if (s.electrical) fit_electrical(r, est, s, logs, prior, o, alpha_variance, fitted);
  LoopDrive loop{s.alpha, s.g};
  if (s.electrical) {
    const ReducedDrive ld = reduced_drive(joint.drive, fitted);
    loop = {ld.alpha, ld.g};
  }
  r.idim = least_squares(est.all.W, est.all.Y, names, mechanical_prior(prior, joint.linear, p), o.rank_tolerance);
  if (!r.idim.value.allFinite() || !r.idim.sigma.allFinite()) {
    throw InputError("the least-squares fit is not finite: the log's values are out of range for this model");
  }
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (!r.idim.identified[i]) r.unidentifiable.push_back(names[i]);
  }
  if (closed) {
    closed_loop_iv(r, est, logs, loop, o);
    if (r.iv && alpha_variance > 0.0) add_scale_variance(*r.iv, alpha_variance);
  }
  if (alpha_variance > 0.0) add_scale_variance(r.idim, alpha_variance);
  const Estimate& reported = r.iv ? *r.iv : r.idim;
  std::vector<double> sim, dhat;
  r.estimation_idim = fit_logs(est, logs, reported.value, loop, o, &sim, &dhat);
  r.series.time = *logs.front().time;
  r.series.position = est.logs.front().q;
  r.series.position_idim = sim;
  r.series.drive_time = est.logs.front().t_dec;
  r.series.drive = est.logs.front().d_dec;
  r.series.drive_idim = dhat;

  std::optional<Prepped> val;
  if (!validation.empty()) {
    for (const LogSegment& g : validation) {
      const double dt = (g.time->back() - g.time->front()) / static_cast<double>(g.time->size() - 1);
      if (std::abs(dt - s.dt) > 0.05 * s.dt) {
        throw InputError("--validation: sample time " + format::shortest(dt) + " s differs from the estimation log's " +
                         format::shortest(s.dt) + " s");
      }
      if (static_cast<int>(g.time->size()) / s.R < 2 * p + 4) throw InputError("--validation: the log is too short");
    }
    val = prepare_all(validation, prior, s);
    std::vector<double> vsim, vdhat;
    r.validation_idim = fit_logs(*val, validation, reported.value, loop, o, &vsim, &vdhat);
    r.validation_series.time = *validation.front().time;
    r.validation_series.position = val->logs.front().q;
    r.validation_series.position_idim = vsim;
    r.validation_series.drive_time = val->logs.front().t_dec;
    r.validation_series.drive = val->logs.front().d_dec;
    r.validation_series.drive_idim = vdhat;
  }
  refine_output_error(r, est, val, logs, validation, loop, prior, o, closed);
  r.method = closed ? "IDIM-IV" : (o.use_output_error && r.output_error) ? "output error" : "IDIM-LS";
  r.parameters = records(r, joint, prior, o, p);
  return r;
}

}  // namespace fivebar::identify
