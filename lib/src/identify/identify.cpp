// IDIM-LS and the fit figures (fivebar/identify/identify.hpp).

#include "fivebar/identify/identify.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/identify/filter.hpp"
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

/// The filtered motion and drive of one log, at full rate and decimated.
struct Prepared {
  std::vector<double> q, qf, v, a;      // full rate
  std::vector<double> d;                // raw drive (the mechanical one: the current when measured next to a voltage)
  std::vector<double> u;                // drive torque input alpha * d, raw (for the simulation)
  // decimated
  Eigen::MatrixXd W;
  Eigen::VectorXd Y;
  std::vector<double> d_dec, v_dec, t_dec;
  std::vector<double> known_dec;        // the known closed-chain torque, decimated (empty: none)
  // electrical regression (voltage drive with its current)
  Eigen::MatrixXd We;
  Eigen::VectorXd Ye;
};

struct Setup {
  double dt = 0.0, fc = 0.0;
  int R = 1;
  int order = 4;
  bool zoh = true;
  bool per_direction = false;
  bool electrical = false;   // voltage or duty drive with a logged current
  double alpha = 1.0, g = 0.0;  // mechanical drive map (after the electrical fit when any)
  double supply = 1.0;       // V per drive unit for the electrical equation (1 for voltage)
};

Eigen::VectorXd to_eigen(const std::vector<double>& v) { return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())); }

Prepared prepare(const JointLog& j, const std::vector<double>& time, const JointPrior& prior, const Setup& s) {
  Prepared p;
  p.q = joint_angle(j, prior);
  const auto sos = butterworth_lowpass(s.order, s.fc, 1.0 / s.dt);
  (void)time;
  p.qf = filtfilt(sos, p.q);
  p.v = derivative(p.qf, s.dt);
  p.a = derivative(p.v, s.dt);
  const bool use_current = s.electrical;
  p.d = use_current ? j.current : j.drive_values;
  // Parallel filtering (Gautier): the low-pass serves the derivatives of the position; the drive and
  // every column of the regressor then go through the same decimation filter. The drive itself is
  // only low-passed for the electrical equation's di/dt.
  // A logged drive command is held over its sample (a digital drive's zero-order hold, and the
  // convention of simulate_position); the central-difference acceleration at t_k sees the mean of
  // the commands over [t_k-1, t_k+1], so the regression takes (d_k-1 + d_k) / 2. A measured current
  // (next to a voltage drive) is an instantaneous value and is taken as it is.
  std::vector<double> df = p.d;
  if (s.zoh && !use_current) {
    for (std::size_t i = df.size() - 1; i >= 1; --i) df[i] = 0.5 * (p.d[i] + p.d[i - 1]);
  }
  std::vector<std::vector<double>> cols;
  cols.push_back(p.a);
  if (s.per_direction) {
    std::vector<double> vp(p.v.size()), vn(p.v.size());
    for (std::size_t i = 0; i < p.v.size(); ++i) {
      vp[i] = p.v[i] > 0.0 ? p.v[i] : 0.0;
      vn[i] = p.v[i] < 0.0 ? p.v[i] : 0.0;
    }
    cols.push_back(vp);
    cols.push_back(vn);
  } else {
    cols.push_back(p.v);
  }
  std::vector<double> sv(p.v.size());
  for (std::size_t i = 0; i < p.v.size(); ++i) sv[i] = sgn(p.v[i]);
  cols.push_back(sv);
  cols.push_back(std::vector<double>(p.v.size(), 1.0));
  std::vector<double> tau(p.v.size());
  for (std::size_t i = 0; i < tau.size(); ++i) tau[i] = s.alpha * df[i] - s.g * p.v[i];
  if (!prior.known_torque.empty()) {  // the closed chain's share (--rig mechanism)
    for (std::size_t i = 0; i < tau.size(); ++i) tau[i] -= prior.known_torque[i];
    p.known_dec = decimate(prior.known_torque, s.R);
  }
  const std::vector<double> Yd = decimate(tau, s.R);
  p.Y = to_eigen(Yd);
  p.W.resize(p.Y.size(), static_cast<Eigen::Index>(cols.size()));
  for (std::size_t c = 0; c < cols.size(); ++c) p.W.col(static_cast<Eigen::Index>(c)) = to_eigen(decimate(cols[c], s.R));
  p.d_dec = decimate(df, s.R);
  p.v_dec = decimate(p.v, s.R);
  for (std::size_t i = 0; i < time.size(); i += static_cast<std::size_t>(s.R)) p.t_dec.push_back(time[i]);
  p.u.resize(p.d.size());
  for (std::size_t i = 0; i < p.d.size(); ++i) p.u[i] = s.alpha * p.d[i];
  if (s.electrical) {
    // V = R i + L di/dt + k_e N w (output-shaft speed, so the third parameter is k_e N).
    std::vector<double> V = j.drive_values;
    for (double& x : V) x *= s.supply;
    const std::vector<double> di = derivative(filtfilt(sos, df), s.dt);
    p.Ye = to_eigen(decimate(V, s.R));
    p.We.resize(p.Ye.size(), 3);
    p.We.col(0) = to_eigen(p.d_dec);
    p.We.col(1) = to_eigen(decimate(di, s.R));
    p.We.col(2) = to_eigen(p.v_dec);
  }
  return p;
}

Fit fit_figures(const Prepared& p, const Eigen::VectorXd& theta, const Setup& s, const std::vector<double>& time,
                const IdentifyOptions& o, std::vector<double>* sim_out, std::vector<double>* drive_hat_out) {
  Fit f;
  const Eigen::VectorXd tau_hat = p.W * theta;
  std::vector<double> dhat(p.d_dec.size());
  for (std::size_t i = 0; i < dhat.size(); ++i) {
    const double known = p.known_dec.empty() ? 0.0 : p.known_dec[i];
    dhat[i] = (tau_hat[static_cast<Eigen::Index>(i)] + known + s.g * p.v_dec[i]) / s.alpha;
  }
  f.drive_fit_percent = fit_percent(p.d_dec, dhat);
  f.drive_relative_error_percent = relative_error_percent(p.d_dec, dhat);
  if (!p.known_dec.empty()) {  // one joint of a closed chain: its open-loop simulation alone means nothing
    if (sim_out) sim_out->clear();
    if (drive_hat_out) *drive_hat_out = dhat;
    return f;
  }
  const std::vector<double> sim =
      simulate_position(time, p.u, s.g, theta, s.per_direction, p.qf.front(), p.v.front(), o.coulomb_smoothing);
  bool finite = true;
  for (double x : sim) finite = finite && std::isfinite(x);
  if (finite) {
    f.simulated = true;
    f.position_fit_percent = fit_percent(p.q, sim);
    f.position_relative_error_percent = relative_error_percent(p.q, sim);
  }
  if (sim_out) *sim_out = finite ? sim : std::vector<double>();
  if (drive_hat_out) *drive_hat_out = dhat;
  return f;
}

Parameter record(std::string key, double value, double sigma, bool identified, std::string note) {
  return Parameter{std::move(key), value, sigma, identified, std::move(note)};
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
    const double a1 = f(w);
    const double a2 = f(w + 0.5 * h * a1);
    const double a3 = f(w + 0.5 * h * a2);
    const double a4 = f(w + h * a3);
    x += h / 6.0 * (w + 2.0 * (w + 0.5 * h * a1) + 2.0 * (w + 0.5 * h * a2) + (w + h * a3));
    w += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
    out[k + 1] = x;
  }
  return out;
}

JointIdentification identify_joint(const JointLog& joint, const std::vector<double>& time, const JointPrior& prior,
                                   const JointLog* validation, const std::vector<double>* validation_time,
                                   const IdentifyOptions& o) {
  JointIdentification r;
  r.joint = joint.prefix.empty() ? "motor" : joint.prefix;
  r.drive_column = joint.drive_column;
  r.reading_column = joint.reading_column;
  r.linear = joint.linear;
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
  const std::vector<std::string> names = mechanical_names(o.per_direction, joint.linear);
  const int p = static_cast<int>(names.size());
  s.R = o.decimation > 0 ? o.decimation : 10;
  if (o.decimation <= 0) {
    while (s.R > 1 && static_cast<int>(time.size()) / s.R < 50 * (p + 3)) --s.R;
  }
  if (static_cast<int>(time.size()) / s.R < 2 * p + 4) {
    throw InputError("the log has " + std::to_string(time.size()) + " rows; decimated by " + std::to_string(s.R) +
                     " that is fewer than twice the " + std::to_string(p) + " unknowns");
  }
  r.sample_time = s.dt;
  r.cutoff_hz = s.fc;
  r.decimation = s.R;
  const MotorParams& m = prior.motor;
  s.electrical = (joint.drive == DriveKind::voltage || joint.drive == DriveKind::duty) && !joint.current.empty();
  s.supply = joint.drive == DriveKind::duty ? m.supply_voltage_V : 1.0;
  const ReducedDrive rd = reduced_drive(s.electrical ? DriveKind::current : joint.drive, m);
  s.alpha = rd.alpha;
  s.g = rd.g;
  if (joint.linear && joint.drive != DriveKind::torque) {
    throw InputError("a linear axis (position_m) takes its drive as force_N");
  }

  // Electrical fit first: it sets k_t = k_e for the mechanical one.
  const Prepared first = prepare(joint, time, prior, s);
  Prepared est = first;
  if (s.electrical) {
    Eigen::Vector3d eprior(m.resistance(), m.inductance(), m.back_emf_constant() * m.gear_ratio);
    Estimate el = least_squares(first.We, first.Ye, {"resistance_ohm", "inductance_H", "back_emf_V_s_per_rad_output"}, eprior,
                                o.rank_tolerance);
    if (el.identified[2] && el.value[2] > 0.0) {
      const double ke_motor = el.value[2] / m.gear_ratio;  // V s / rad = N m / A at the motor shaft
      s.alpha = m.gearbox_efficiency * m.gear_ratio * ke_motor;
      est = prepare(joint, time, prior, s);
    }
    r.electrical = el;
  }
  Eigen::VectorXd mprior(p);
  if (joint.linear) {
    mprior.setZero();
  } else {
    mprior[0] = m.gear_ratio * m.gear_ratio * m.rotor_inertia() + prior.load_inertia;
    for (int k = 1; k < p - 2; ++k) mprior[k] = m.viscous_friction();
    mprior[p - 2] = m.coulomb_friction();
    mprior[p - 1] = 0.0;
  }
  r.idim = least_squares(est.W, est.Y, names, mprior, o.rank_tolerance);
  if (!r.idim.value.allFinite() || !r.idim.sigma.allFinite()) {
    throw InputError("the least-squares fit is not finite: the log's values are out of range for this model");
  }
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (!r.idim.identified[i]) r.unidentifiable.push_back(names[i]);
  }
  std::vector<double> sim, dhat;
  r.estimation_idim = fit_figures(est, r.idim.value, s, time, o, &sim, &dhat);
  r.series.time = time;
  r.series.position = est.q;
  r.series.position_idim = sim;
  r.series.drive_time = est.t_dec;
  r.series.drive = est.d_dec;
  r.series.drive_idim = dhat;

  std::optional<Prepared> val;
  if (validation != nullptr) {
    Setup sv = s;
    sv.dt = ((*validation_time).back() - (*validation_time).front()) / static_cast<double>(validation_time->size() - 1);
    if (std::abs(sv.dt - s.dt) > 0.05 * s.dt) {
      throw InputError("--validation: sample time " + format::shortest(sv.dt) + " s differs from the estimation log's " +
                       format::shortest(s.dt) + " s");
    }
    if (static_cast<int>(validation_time->size()) / s.R < 2 * p + 4) throw InputError("--validation: the log is too short");
    val = prepare(*validation, *validation_time, prior, sv);
    std::vector<double> vsim, vdhat;
    r.validation_idim = fit_figures(*val, r.idim.value, sv, *validation_time, o, &vsim, &vdhat);
    r.validation_series.time = *validation_time;
    r.validation_series.position = val->q;
    r.validation_series.position_idim = vsim;
    r.validation_series.drive_time = val->t_dec;
    r.validation_series.drive = val->d_dec;
    r.validation_series.drive_idim = vdhat;
  }

  if (o.output_error && !prior.known_torque.empty()) {
    r.output_error_status = "not run: one joint of a closed chain (--rig mechanism) is not simulated alone";
  } else if (o.output_error) {
    bool ok = r.idim.identified[0] && r.idim.value[0] > 0.0;
    if (!ok) {
      r.output_error_status = "not run: the inertia is not identified or not positive";
    } else {
      Estimate oe = identify_detail::output_error(time, est.u, s.g, est.q, r.idim, s.per_direction, est.qf.front(),
                                                  est.v.front(), o.coulomb_smoothing, r.output_error_status);
      r.output_error = oe;
      std::vector<double> osim;
      r.estimation_oe = fit_figures(est, oe.value, s, time, o, &osim, nullptr);
      r.series.position_oe = osim;
      if (val) {
        Setup sv = s;
        std::vector<double> vo;
        r.validation_oe = fit_figures(*val, oe.value, sv, *validation_time, o, &vo, nullptr);
        r.validation_series.position_oe = vo;
      }
    }
  } else {
    r.output_error_status = "not run (--no-output-error)";
  }

  // The records.
  const Estimate& fin = (o.use_output_error && r.output_error) ? *r.output_error : r.idim;
  const std::string method = (o.use_output_error && r.output_error) ? "output error" : "IDIM-LS";
  for (int i = 0; i < p; ++i) {
    const std::size_t ui = static_cast<std::size_t>(i);
    r.parameters.push_back(record(names[ui], fin.value[i], fin.sigma[i], fin.identified[ui],
                                  fin.identified[ui] ? method : r.idim.notes[ui]));
  }
  if (!joint.linear) {
    const std::string mk = prior.motor_key + ".";
    const double N2 = m.gear_ratio * m.gear_ratio;
    // Derived design keys (the design's units).
    r.parameters.push_back(record(mk + "rotor_inertia_g_cm2", (fin.value[0] - prior.load_inertia) / N2 * 1e7, fin.sigma[0] / N2 * 1e7,
                                  fin.identified[0],
                                  fin.identified[0] ? "(inertia_kg_m2 - load " + format::shortest(prior.load_inertia) +
                                                          " kg m^2) / gear_ratio^2, gear_ratio held at its prior"
                                                    : r.idim.notes[0]));
    if (!o.per_direction) {
      r.parameters.push_back(record(mk + "viscous_friction_mNm_s_per_rad", fin.value[1] * 1e3, fin.sigma[1] * 1e3, fin.identified[1],
                                    fin.identified[1] ? "viscous_Nm_s_per_rad" : r.idim.notes[1]));
    }
    const int c = p - 2;
    r.parameters.push_back(record(mk + "coulomb_friction_mNm", fin.value[c] * 1e3, fin.sigma[c] * 1e3,
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
      r.parameters.push_back(record(mk + "terminal_resistance_ohm", el.value[0], el.sigma[0], el.identified[0],
                                    el.identified[0] ? "IDIM-LS (electrical equation)" : el.notes[0]));
      r.parameters.push_back(record(mk + "inductance_mH", el.value[1] * 1e3, el.sigma[1] * 1e3, el.identified[1],
                                    el.identified[1] ? "IDIM-LS (electrical equation)" : el.notes[1]));
      const double ke = el.value[2] / m.gear_ratio, ske = el.sigma[2] / m.gear_ratio;
      r.parameters.push_back(record(mk + "back_emf_mV_per_rpm", ke * 1e3 / rpm, ske * 1e3 / rpm, el.identified[2],
                                    el.identified[2] ? "IDIM-LS (electrical equation), gear_ratio held at its prior" : el.notes[2]));
      r.parameters.push_back(record(mk + "torque_constant_mNm_per_A", ke * 1e3, ske * 1e3, el.identified[2],
                                    el.identified[2] ? "k_t = k_e (SI)" : el.notes[2]));
    } else {
      r.parameters.push_back(record(mk + "terminal_resistance_ohm", m.terminal_resistance_ohm, 0.0, false, why));
      r.parameters.push_back(record(mk + "inductance_mH", m.inductance_mH, 0.0, false,
                                    "held at its prior: the model neglects L/R against the mechanical time constant"));
      r.parameters.push_back(record(mk + "torque_constant_mNm_per_A", m.torque_constant_mNm_per_A, 0.0, false, why));
      r.parameters.push_back(record(mk + "back_emf_mV_per_rpm", m.back_emf_mV_per_rpm, 0.0, false, why));
    }
    r.parameters.push_back(record(mk + "gearbox_efficiency", m.gearbox_efficiency, 0.0, false,
                                  "held at its prior: it scales every torque, so a log cannot separate it from the friction and inertia"));
    r.parameters.push_back(record(mk + "gear_ratio", m.gear_ratio, 0.0, false, "held at its prior (a datasheet value)"));
  }
  return r;
}

}  // namespace fivebar::identify
