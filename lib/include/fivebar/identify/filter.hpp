#pragma once
/// Zero-phase filtering for the inverse dynamic model (docs/identify.md "IDIM-LS"): a digital
/// Butterworth low-pass in second-order sections (bilinear transform with pre-warping), run forward
/// and backward (filtfilt: odd-reflection padding and steady-state initial conditions, as SciPy's
/// sosfiltfilt does), central differences and decimation (Chebyshev low-pass at 0.8 of the new Nyquist
/// frequency, then every R-th sample).

#include <array>
#include <vector>

namespace fivebar::identify {

/// One biquad, a0 = 1: y = b0 x + b1 x1 + b2 x2 - a1 y1 - a2 y2.
struct Biquad {
  std::array<double, 3> b{1.0, 0.0, 0.0};
  std::array<double, 2> a{0.0, 0.0};
};

/// Butterworth low-pass of `order` (1 ... 16) with its -3 dB point at `cutoff_hz` < fs/2, unit DC gain.
/// std::invalid_argument outside those ranges.
std::vector<Biquad> butterworth_lowpass(int order, double cutoff_hz, double sample_rate_hz);
/// The filter's gain at `frequency_hz` (one pass).
double gain(const std::vector<Biquad>& sos, double frequency_hz, double sample_rate_hz);
/// One forward pass from rest.
std::vector<double> filter(const std::vector<Biquad>& sos, const std::vector<double>& x);
/// Forward and backward (zero phase, squared magnitude). Needs at least 2 samples.
std::vector<double> filtfilt(const std::vector<Biquad>& sos, const std::vector<double>& x);
/// Central differences (one-sided at the ends), uniform step `dt`.
std::vector<double> derivative(const std::vector<double>& x, double dt);
/// Low-pass (8th-order Chebyshev I, 0.05 dB, at 0.8 of fs / (2 factor), zero phase: the filter of
/// MATLAB's and SciPy's decimate) then every `factor`-th
/// sample from the first; `factor` 1 returns x.
std::vector<double> decimate(const std::vector<double>& x, int factor);

/// Samples after which the impulse response of `sos` (one pass, from rest) has decayed: the part
/// beyond them holds at most `tail_fraction` of its absolute sum. Within that many samples of either
/// end, a zero-phase filter's output depends on the padding at the end rather than on the data.
int settling_samples(const std::vector<Biquad>& sos, double tail_fraction);
/// settling_samples() of decimate()'s anti-aliasing filter at `factor`, in samples at the full rate
/// (0 for factor 1).
int decimation_settling_samples(int factor, double tail_fraction);
/// Sum of the squared impulse response of decimate()'s filter run forward and backward, at the full
/// rate: the variance a white unit noise keeps through it (about 0.8 / factor). 1 for factor 1.
double decimation_noise_gain(int factor);
/// The impulse response of `sos` run forward and backward (zero phase), centred: element k is the
/// response at lag k - half, half = (size - 1) / 2.
std::vector<double> zero_phase_impulse(const std::vector<Biquad>& sos, int half);
/// The share of a filter's impulse response (absolute sum) left beyond its settling length in
/// edge_samples().
inline constexpr double kEdgeTail = 1e-3;
/// Full-rate samples at each end of a log whose IDIM-LS rows depend on the filters' start-up rather
/// than on the data: the position low-pass's settling (Butterworth `order` at `cutoff_hz`), the two
/// samples of the one-sided differences, and the decimation filter's settling (kEdgeTail).
int edge_samples(int order, double cutoff_hz, double sample_rate_hz, int decimation);
/// Full-rate samples on each side of a reversal of the filtered speed within which a disturbance at
/// the reversal (the reading stalled in the backlash) weighs on the IDIM-LS rows: half the main lobe
/// of the position's low-pass (`cutoff_hz`) and of the decimation filter, and the two samples of the
/// one-sided differences (20 at 1 kHz, fs / 10, decimation 10).
int reversal_samples(double cutoff_hz, double sample_rate_hz, int decimation);
/// The sections of decimate()'s anti-aliasing filter at `factor` (>= 2), normalised frequency (fs 1).
std::vector<Biquad> decimation_filter(int factor);

}  // namespace fivebar::identify
