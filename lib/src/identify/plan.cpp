// Excitation planning (fivebar/identify/plan.hpp).

#include "fivebar/identify/plan.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/identify/filter.hpp"

namespace fivebar::identify {

namespace {

void require(bool ok, const std::string& flag, const std::string& rule) {
  if (!ok) throw InputError(flag + ": " + rule);
}

/// The fade window and its time derivatives: the quintic smoothstep 10 x^3 - 15 x^4 + 6 x^5 over
/// [0, fade] and mirrored over [end - fade, end], 1 between (zero speed and acceleration at both
/// ends, so the excitation starts and ends at rest).
struct Fade {
  double w = 1.0, dw = 0.0, ddw = 0.0;
};
Fade fade(double t, double end, double length) {
  Fade f;
  if (!(length > 0.0)) return f;
  double x = t / length, sign = 1.0;
  if (end - t < t) {
    x = (end - t) / length;
    sign = -1.0;
  }
  if (x >= 1.0) return f;
  x = std::max(0.0, x);
  f.w = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x);
  f.dw = sign * 30.0 * x * x * (1.0 - x) * (1.0 - x) / length;
  f.ddw = 60.0 * x * (1.0 - x) * (1.0 - 2.0 * x) / (length * length);
  return f;
}

/// Variance of the fit's equation error per unit variance of white noise on the angle: the angle
/// through the pipeline of identify (zero-phase Butterworth, central differences, the decimation
/// filter), weighted as the inertia and the viscous friction weigh acceleration and speed.
double angle_noise_gain(double J, double b, double fs, int R) {
  const double fc = fs / 10.0, dt = 1.0 / fs;
  const auto low = butterworth_lowpass(4, fc, fs);
  const int half = 4 * (settling_samples(low, 1e-9) + decimation_settling_samples(R, 1e-9)) + 16;
  std::vector<double> x(static_cast<std::size_t>(2 * half + 1), 0.0);
  x[static_cast<std::size_t>(half)] = 1.0;
  const std::vector<double> v = derivative(filtfilt(low, x), dt);
  const std::vector<double> a = derivative(v, dt);
  std::vector<double> e(x.size());
  for (std::size_t i = 0; i < e.size(); ++i) e[i] = J * a[i] + b * v[i];
  if (R > 1) e = filtfilt(decimation_filter(R), e);
  double s = 0.0;
  for (double v2 : e) s += v2 * v2;
  return s;
}

}  // namespace

ExcitationPlan plan_excitation(const JointPrior& prior, const PlanOptions& o) {
  require(o.duration_s > 0.0 && o.duration_s <= 3600.0, "--plan-duration", "must be in (0, 3600] s");
  require(o.sample_rate_hz > 0.0 && o.sample_rate_hz <= 1e5, "--plan-rate", "must be in (0, 100000] Hz");
  require(o.f_min_hz > 0.0 && o.f_max_hz > o.f_min_hz, "--plan-band", "needs 0 < f_min < f_max");
  require(o.f_max_hz < 0.1 * o.sample_rate_hz, "--plan-band", "f_max must be below a tenth of the sample rate");
  require(o.range_hi > o.range_lo, "joint range", "empty");
  require(o.max_speed > 0.0 && o.current_limit > 0.0 && o.drive_noise > 0.0, "limits", "speed, current and noise must be > 0");
  require(o.angle_quantum >= 0.0 && o.fade_s >= 0.0, "limits", "the angle quantum and the fade must be >= 0");
  const MotorParams& m = prior.motor;
  const double K = m.gearbox_efficiency * m.gear_ratio * m.torque_constant();
  const double J = m.gear_ratio * m.gear_ratio * m.rotor_inertia() + prior.load_inertia;
  const double b = m.viscous_friction(), c = m.coulomb_friction();
  // Unit multisine with Schroeder phases over harmonics kmin ... kmax of f_min.
  const int kmax = static_cast<int>(std::floor(o.f_max_hz / o.f_min_hz + 1e-9));
  const int K_h = kmax;
  const double w0 = 2.0 * std::numbers::pi * o.f_min_hz;
  const std::size_t n = static_cast<std::size_t>(std::floor(o.duration_s * o.sample_rate_hz)) + 1;
  require(n >= 100, "--plan-duration", "gives fewer than 100 samples");
  ExcitationPlan p;
  p.time.resize(n);
  p.fade_s = std::min(o.fade_s, 0.25 * o.duration_s);
  std::vector<double> u(n), du(n), ddu(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) / o.sample_rate_hz;
    p.time[i] = t;
    double s = 0.0, ds = 0.0, dds = 0.0;
    for (int k = 1; k <= K_h; ++k) {
      const double phi = -std::numbers::pi * k * (k - 1) / K_h;
      const double wk = k * w0;
      // Equal velocity amplitude per harmonic: position amplitude 1 / k keeps the speed spread.
      const double a = 1.0 / k;
      s += a * std::sin(wk * t + phi);
      ds += a * wk * std::cos(wk * t + phi);
      dds += -a * wk * wk * std::sin(wk * t + phi);
    }
    const Fade f = fade(t, p.time.size() > 1 ? static_cast<double>(n - 1) / o.sample_rate_hz : 0.0, p.fade_s);
    u[i] = f.w * s;
    du[i] = f.dw * s + f.w * ds;
    ddu[i] = f.ddw * s + 2.0 * f.dw * ds + f.w * dds;
  }
  double umax = 0.0, dumax = 0.0, tmax = 0.0, rms = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    umax = std::max(umax, std::abs(u[i]));
    dumax = std::max(dumax, std::abs(du[i]));
    tmax = std::max(tmax, J * std::abs(ddu[i]) + b * std::abs(du[i]));
    rms += du[i] * du[i];
  }
  rms = std::sqrt(rms / static_cast<double>(n));
  p.crest_factor = dumax / rms;
  // 90 % of each limit (a margin for the tracking error of the controller that plays it).
  const double half_range = 0.5 * (o.range_hi - o.range_lo);
  const double by_range = 0.9 * half_range / umax;
  const double by_speed = 0.9 * o.max_speed / dumax;
  const double torque_room = 0.9 * K * o.current_limit - c;
  require(torque_room > 0.0, "current limit", "the prior Coulomb friction alone needs more than 90 % of the current limit");
  const double by_current = torque_room / tmax;
  p.scale = std::min({by_range, by_speed, by_current});
  p.limited_by = p.scale == by_range ? "range" : p.scale == by_speed ? "speed" : "current";
  const double centre = 0.5 * (o.range_hi + o.range_lo);
  p.position.resize(n);
  p.velocity.resize(n);
  p.acceleration.resize(n);
  p.current.resize(n);
  p.duty.resize(n);
  const double emf = m.back_emf_constant() * m.gear_ratio;
  for (std::size_t i = 0; i < n; ++i) {
    p.position[i] = centre + p.scale * u[i];
    p.velocity[i] = p.scale * du[i];
    p.acceleration[i] = p.scale * ddu[i];
    const double w = p.velocity[i];
    const double tau = J * p.acceleration[i] + b * w + c * std::tanh(w / 1e-3);
    p.current[i] = tau / K;
    p.duty[i] = std::clamp((m.resistance() * p.current[i] + emf * w) / m.supply_voltage_V, -1.0, 1.0);
  }
  // Expected sigmas: the regressor at the decimated rate over the rows identify keeps (clear of the
  // filters' settling at both ends), cov = s^2 (W^T W)^-1 with s^2 the residual variance below.
  p.names = mechanical_names(o.per_direction, false);
  const int np = static_cast<int>(p.names.size());
  const int R = std::max(1, o.decimation);
  p.edge_samples = edge_samples(4, o.sample_rate_hz / 10.0, o.sample_rate_hz, R);
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < n; i += static_cast<std::size_t>(R)) {
    if (i >= static_cast<std::size_t>(p.edge_samples) && i + static_cast<std::size_t>(p.edge_samples) < n) kept.push_back(i);
  }
  require(static_cast<int>(kept.size()) >= 2 * np + 4, "--plan-duration", "too short for the filters' settling at both ends");
  Eigen::MatrixXd W(static_cast<Eigen::Index>(kept.size()), np);
  for (std::size_t r = 0; r < kept.size(); ++r) {
    const std::size_t i = kept[r];
    const double w = p.velocity[i];
    Eigen::Index c0 = 0;
    W(static_cast<Eigen::Index>(r), c0++) = p.acceleration[i];
    if (o.per_direction) {
      W(static_cast<Eigen::Index>(r), c0++) = w > 0.0 ? w : 0.0;
      W(static_cast<Eigen::Index>(r), c0++) = w < 0.0 ? w : 0.0;
    } else {
      W(static_cast<Eigen::Index>(r), c0++) = w;
    }
    W(static_cast<Eigen::Index>(r), c0++) = w > 0.0 ? 1.0 : w < 0.0 ? -1.0 : 0.0;
    W(static_cast<Eigen::Index>(r), c0++) = 1.0;
  }
  // The fit's residual variance: the drive noise through the decimation filter, and the reading's
  // rounding (uniform, q^2 / 12) through the filters and differences that make the acceleration
  // and speed columns.
  const double drive_var = o.drive_noise * o.drive_noise * decimation_noise_gain(R);
  const double angle_var = o.angle_quantum * o.angle_quantum / 12.0 * angle_noise_gain(J, b, o.sample_rate_hz, R);
  const double s2 = drive_var + angle_var;
  p.expected_residual = std::sqrt(s2);
  p.quantisation_share = s2 > 0.0 ? angle_var / s2 : 0.0;
  const Eigen::MatrixXd info = W.transpose() * W / s2;
  const Eigen::MatrixXd cov = info.ldlt().solve(Eigen::MatrixXd::Identity(np, np));
  p.expected_sigma = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  p.truth.resize(np);
  p.truth[0] = J;
  for (int k = 1; k < np - 2; ++k) p.truth[k] = b;
  p.truth[np - 2] = c;
  p.truth[np - 1] = 0.0;
  return p;
}

}  // namespace fivebar::identify
