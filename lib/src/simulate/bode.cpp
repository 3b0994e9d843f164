// Frequency response of a chirp run (fivebar/dynamics.hpp chirp_bode): the empirical transfer
// function estimate by direct DFTs of the commanded and the actual x displacement, its CSV and its
// log-log picture (lib/src/plot/work_precision_plot.hpp, the house style of the report plots).

#include <cmath>
#include <complex>
#include <numbers>
#include <ostream>

#include "fivebar/dynamics.hpp"
#include "fivebar/format.hpp"
#include "plot/work_precision_plot.hpp"

namespace fivebar {

namespace {

/// DFT of x at frequency f over the samples (t_k, x_k).
std::complex<double> dft(const std::vector<double>& t, const std::vector<double>& x, double f) {
  std::complex<double> sum(0.0, 0.0);
  for (std::size_t k = 0; k < t.size(); ++k) sum += x[k] * std::polar(1.0, -2.0 * std::numbers::pi * f * t[k]);
  return sum;
}

plot::PlotSpec bode_spec(const BodeResult& bode, const std::string& title) {
  plot::PlotSpec spec;
  spec.title = title;
  spec.x_label = "frequency (Hz)";
  spec.y_label = "|X / X_ref|, tactor x displacement per commanded";
  for (std::size_t m = 0; m < bode.mechanisms.size(); ++m) {
    plot::PlotSeries ps;
    ps.label = bode.mechanisms[m] + " tactor" +
               (bode.bandwidth_hz[m] ? ", -3 dB at " + format::fixed(*bode.bandwidth_hz[m], 2) + " Hz"
                                     : std::string(", no -3 dB crossing in the band"));
    for (std::size_t i = 0; i < bode.f_hz.size(); ++i) ps.points.push_back({bode.f_hz[i], bode.magnitude[m][i]});
    spec.series.push_back(std::move(ps));
  }
  if (!bode.f_hz.empty() && !bode.magnitude.empty()) {
    plot::PlotSeries line;
    line.label = "-3 dB of the lowest frequency's magnitude (" + bode.mechanisms.front() + ")";
    const double level = bode.magnitude.front().front() * std::pow(10.0, -3.0 / 20.0);
    line.points = {{bode.f_hz.front(), level}, {bode.f_hz.back(), level}};
    spec.series.push_back(std::move(line));
  }
  spec.footnote = bode.note;
  return spec;
}

}  // namespace

BodeResult chirp_bode(const SimulationInput& input, const SimulationResult& result, const SimulationRequest& request,
                      std::size_t points) {
  BodeResult bode;
  const double rate = input.controller.loop_rate_hz;
  const double f0 = request.chirp_f0_hz;
  const double f1 = request.chirp_f1_hz > 0.0 ? request.chirp_f1_hz : 0.25 * rate;
  const double lo = 1.25 * f0, hi = f1 / 1.25;
  for (std::size_t i = 0; i < points; ++i) {
    bode.f_hz.push_back(lo * std::pow(hi / lo, points > 1 ? double(i) / double(points - 1) : 0.0));
  }
  bode.note = "Chirp " + format::fixed(f0, 2) + " -> " + format::fixed(f1, 2) + " Hz over " +
              format::fixed(request.chirp_duration_s, 1) + " s, amplitude " + format::fixed(request.chirp_amplitude_mm, 3) +
              " mm along x; ratio of the DFTs of actual and commanded x displacement over the controller's samples.";
  if (!result.ok()) bode.note += " The run stopped early (" + std::string(to_string(result.status)) + ").";
  for (std::size_t m = 0; m < input.mechanisms.size(); ++m) {
    bode.mechanisms.push_back(input.mechanisms[m].name);
    std::vector<double> t, u, y;
    for (const TimeSample& s : result.samples) {
      if (m >= s.mechanisms.size()) continue;
      const MechanismSample& ms = s.mechanisms[m];
      const MechanismSample& first = result.samples.front().mechanisms[m];
      t.push_back(s.t);
      u.push_back(ms.P_ref_mm.x() - first.P_ref_mm.x());
      y.push_back(ms.P_mm.x() - first.P_mm.x());
    }
    std::vector<double> mag;
    for (const double f : bode.f_hz) {
      const std::complex<double> U = dft(t, u, f), Y = dft(t, y, f);
      mag.push_back(std::abs(U) > 0.0 ? std::abs(Y) / std::abs(U) : 0.0);
    }
    std::optional<double> bw;
    const double level = mag.empty() ? 0.0 : mag.front() * std::pow(10.0, -3.0 / 20.0);
    for (std::size_t i = 1; i < mag.size(); ++i) {
      if (mag[i] < level && mag[i - 1] >= level && mag[i] > 0.0) {
        const double a = std::log(mag[i - 1] / level), b = std::log(mag[i] / level);  // a >= 0 > b
        const double w = a / (a - b);
        bw = std::exp(std::log(bode.f_hz[i - 1]) + w * (std::log(bode.f_hz[i]) - std::log(bode.f_hz[i - 1])));
        break;
      }
    }
    bode.magnitude.push_back(std::move(mag));
    bode.bandwidth_hz.push_back(bw);
  }
  return bode;
}

void write_bode_csv(std::ostream& out, const BodeResult& bode) {
  out << "f_hz";
  for (const std::string& m : bode.mechanisms) out << "," << m << "_magnitude," << m << "_magnitude_db";
  out << "\n";
  for (std::size_t i = 0; i < bode.f_hz.size(); ++i) {
    out << format::shortest(bode.f_hz[i]);
    for (std::size_t m = 0; m < bode.mechanisms.size(); ++m) {
      const double g = bode.magnitude[m][i];
      out << "," << format::shortest(g) << "," << (g > 0.0 ? format::shortest(20.0 * std::log10(g)) : std::string());
    }
    out << "\n";
  }
}

std::string bode_svg(const BodeResult& bode, const std::string& title) { return plot::render_svg(bode_spec(bode, title)); }
std::string bode_png(const BodeResult& bode, const std::string& title) { return plot::render_png(bode_spec(bode, title)); }

}  // namespace fivebar
