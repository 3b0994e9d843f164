// Zero-phase filtering (fivebar/identify/filter.hpp).

#include "fivebar/identify/filter.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>

namespace fivebar::identify {

namespace {

using Complex = std::complex<double>;

/// Low-pass sections from the analog prototype's left-half-plane poles (cutoff 1 rad/s, pairs listed
/// once with Im > 0, a real pole with Im = 0): scaled to the pre-warped cutoff, mapped by the bilinear
/// transform, zeros at z = -1, unit gain at DC.
std::vector<Biquad> lowpass_from_poles(const std::vector<Complex>& prototype, double cutoff_hz, double fs) {
  const double warped = 2.0 * fs * std::tan(std::numbers::pi * cutoff_hz / fs);
  std::vector<Biquad> sos;
  for (const Complex& s0 : prototype) {
    const Complex s = s0 * warped;
    const Complex z = (2.0 * fs + s) / (2.0 * fs - s);
    Biquad q;
    if (s0.imag() == 0.0) {
      const double p = z.real();
      const double g = (1.0 - p) / 2.0;
      q.b = {g, g, 0.0};
      q.a = {-p, 0.0};
    } else {
      const double a1 = -2.0 * z.real(), a2 = std::norm(z);
      const double g = (1.0 + a1 + a2) / 4.0;
      q.b = {g, 2.0 * g, g};
      q.a = {a1, a2};
    }
    sos.push_back(q);
  }
  return sos;
}

void check(int order, double cutoff_hz, double fs) {
  if (order < 1 || order > 16) throw std::invalid_argument("filter order must be 1 ... 16");
  if (!(fs > 0.0) || !(cutoff_hz > 0.0) || !(cutoff_hz < 0.5 * fs)) {
    throw std::invalid_argument("filter cutoff must be in (0, fs/2)");
  }
}

/// Chebyshev type I, ripple `ripple_db`, passband edge at cutoff (as scipy's cheby1), unit DC gain.
std::vector<Biquad> chebyshev1_lowpass(int order, double ripple_db, double cutoff_hz, double fs) {
  check(order, cutoff_hz, fs);
  const double eps = std::sqrt(std::pow(10.0, ripple_db / 10.0) - 1.0);
  const double mu = std::asinh(1.0 / eps) / order;
  std::vector<Complex> poles;
  for (int k = 0; k < order / 2; ++k) {
    const double th = std::numbers::pi * (2.0 * k + 1.0) / (2.0 * order);
    poles.emplace_back(-std::sinh(mu) * std::sin(th), std::cosh(mu) * std::cos(th));
  }
  if (order % 2 == 1) poles.emplace_back(-std::sinh(mu), 0.0);
  return lowpass_from_poles(poles, cutoff_hz, fs);
}

/// Steady-state states (transposed direct form II) of each section for a unit step input.
std::vector<std::array<double, 2>> step_states(const std::vector<Biquad>& sos) {
  std::vector<std::array<double, 2>> zi(sos.size());
  double x = 1.0;
  for (std::size_t i = 0; i < sos.size(); ++i) {
    const Biquad& q = sos[i];
    const double y = x * (q.b[0] + q.b[1] + q.b[2]) / (1.0 + q.a[0] + q.a[1]);
    const double z2 = q.b[2] * x - q.a[1] * y;
    const double z1 = q.b[1] * x - q.a[0] * y + z2;
    zi[i] = {z1, z2};
    x = y;
  }
  return zi;
}

void run(const std::vector<Biquad>& sos, std::vector<double>& x, std::vector<std::array<double, 2>> z) {
  for (std::size_t s = 0; s < sos.size(); ++s) {
    const Biquad& q = sos[s];
    double z1 = z[s][0], z2 = z[s][1];
    for (double& v : x) {
      const double in = v;
      const double y = q.b[0] * in + z1;
      z1 = q.b[1] * in - q.a[0] * y + z2;
      z2 = q.b[2] * in - q.a[1] * y;
      v = y;
    }
  }
}

std::vector<double> zero_phase(const std::vector<Biquad>& sos, const std::vector<double>& x) {
  if (x.size() < 2) throw std::invalid_argument("filtfilt needs at least 2 samples");
  std::size_t pad = 3 * (2 * sos.size() + 1);
  pad = std::min(pad, x.size() - 1);
  const std::size_t n = x.size();
  std::vector<double> e;
  e.reserve(n + 2 * pad);
  for (std::size_t i = pad; i >= 1; --i) e.push_back(2.0 * x[0] - x[i]);
  e.insert(e.end(), x.begin(), x.end());
  for (std::size_t i = 1; i <= pad; ++i) e.push_back(2.0 * x[n - 1] - x[n - 1 - i]);
  const auto zi = step_states(sos);
  auto scaled = [&](double v) {
    auto z = zi;
    for (auto& s : z) s = {s[0] * v, s[1] * v};
    return z;
  };
  run(sos, e, scaled(e.front()));
  std::reverse(e.begin(), e.end());
  run(sos, e, scaled(e.front()));
  std::reverse(e.begin(), e.end());
  return std::vector<double>(e.begin() + static_cast<std::ptrdiff_t>(pad), e.begin() + static_cast<std::ptrdiff_t>(pad + n));
}

}  // namespace

std::vector<Biquad> butterworth_lowpass(int order, double cutoff_hz, double fs) {
  check(order, cutoff_hz, fs);
  std::vector<Complex> poles;
  for (int k = 0; k < order / 2; ++k) {
    const double th = std::numbers::pi * (2.0 * k + 1.0) / (2.0 * order);
    poles.emplace_back(-std::sin(th), std::cos(th));
  }
  if (order % 2 == 1) poles.emplace_back(-1.0, 0.0);
  return lowpass_from_poles(poles, cutoff_hz, fs);
}

double gain(const std::vector<Biquad>& sos, double f, double fs) {
  const Complex z1 = std::exp(Complex(0.0, -2.0 * std::numbers::pi * f / fs));
  Complex h = 1.0;
  for (const Biquad& q : sos) h *= (q.b[0] + q.b[1] * z1 + q.b[2] * z1 * z1) / (1.0 + q.a[0] * z1 + q.a[1] * z1 * z1);
  return std::abs(h);
}

std::vector<double> filter(const std::vector<Biquad>& sos, const std::vector<double>& x) {
  std::vector<double> y = x;
  run(sos, y, std::vector<std::array<double, 2>>(sos.size(), {0.0, 0.0}));
  return y;
}

std::vector<double> filtfilt(const std::vector<Biquad>& sos, const std::vector<double>& x) { return zero_phase(sos, x); }

std::vector<double> derivative(const std::vector<double>& x, double dt) {
  const std::size_t n = x.size();
  std::vector<double> d(n, 0.0);
  if (n < 2) return d;
  d[0] = (x[1] - x[0]) / dt;
  d[n - 1] = (x[n - 1] - x[n - 2]) / dt;
  for (std::size_t i = 1; i + 1 < n; ++i) d[i] = (x[i + 1] - x[i - 1]) / (2.0 * dt);
  return d;
}

std::vector<double> decimate(const std::vector<double>& x, int factor) {
  if (factor < 1) throw std::invalid_argument("decimation factor must be >= 1");
  if (factor == 1) return x;
  // The anti-aliasing filter of MATLAB's and SciPy's decimate: Chebyshev I, order 8, 0.05 dB, at
  // 0.8 of the new Nyquist frequency, run forward and backward.
  const std::vector<double> y = zero_phase(decimation_filter(factor), x);
  std::vector<double> out;
  for (std::size_t i = 0; i < y.size(); i += static_cast<std::size_t>(factor)) out.push_back(y[i]);
  return out;
}

std::vector<Biquad> decimation_filter(int factor) {
  if (factor < 2) throw std::invalid_argument("decimation filter: factor must be >= 2");
  return chebyshev1_lowpass(8, 0.05, 0.8 / factor * 0.5, 1.0);
}

int settling_samples(const std::vector<Biquad>& sos, double tail_fraction) {
  // The response until it has stayed below 1e-14 of its peak for a long stretch (every section is
  // stable, so it decays geometrically), then the shortest head holding all but the tail fraction.
  std::vector<double> h(1, 1.0);
  const std::size_t max_len = 1u << 20;
  double peak = 0.0;
  std::size_t quiet = 0;
  for (std::size_t len = 1024; len <= max_len; len *= 2) {
    h.assign(len, 0.0);
    h[0] = 1.0;
    h = filter(sos, h);
    peak = 0.0;
    for (double v : h) peak = std::max(peak, std::abs(v));
    quiet = 0;
    for (std::size_t i = len; i-- > 0 && std::abs(h[i]) < 1e-14 * peak;) ++quiet;
    if (quiet > len / 4) break;
  }
  double total = 0.0;
  for (double v : h) total += std::abs(v);
  double tail = total;
  for (std::size_t i = 0; i < h.size(); ++i) {
    if (tail <= tail_fraction * total) return static_cast<int>(i);
    tail -= std::abs(h[i]);
  }
  return static_cast<int>(h.size());
}

int decimation_settling_samples(int factor, double tail_fraction) {
  return factor < 2 ? 0 : settling_samples(decimation_filter(factor), tail_fraction);
}

std::vector<double> zero_phase_impulse(const std::vector<Biquad>& sos, int half) {
  std::vector<double> x(static_cast<std::size_t>(2 * half + 1), 0.0);
  x[static_cast<std::size_t>(half)] = 1.0;
  x = filter(sos, x);
  std::reverse(x.begin(), x.end());
  x = filter(sos, x);
  std::reverse(x.begin(), x.end());
  return x;
}

int edge_samples(int order, double cutoff_hz, double fs, int decimation) {
  return settling_samples(butterworth_lowpass(order, cutoff_hz, fs), kEdgeTail) + 2 + decimation_settling_samples(decimation, kEdgeTail);
}

int reversal_samples(double cutoff_hz, double fs, int decimation) {
  // Half the main lobe of each low-pass, 1 / (2 f_c): the position's and, at 0.8 of fs / (2 R), the
  // decimation's; the two samples of the one-sided differences.
  const double lobe = 0.5 * fs / cutoff_hz + (decimation > 1 ? 0.5 * fs / (0.8 * fs / (2.0 * decimation)) : 0.0);
  return static_cast<int>(std::ceil(lobe)) + 2;
}

double decimation_noise_gain(int factor) {
  if (factor < 2) return 1.0;
  const auto sos = decimation_filter(factor);
  const auto h = zero_phase_impulse(sos, 2 * settling_samples(sos, 1e-9));
  double s = 0.0;
  for (double v : h) s += v * v;
  return s;
}

}  // namespace fivebar::identify
