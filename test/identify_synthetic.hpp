#pragma once
// Synthetic bench logs for the identify tests and benchmarks: a motor with known parameters driven
// by a logged current, simulated at ten times the log rate with effects the identified model does
// not have: a small compliance between the motor and the load (a second inertia on a spring, the
// reading taken on the load side), backlash in the reading (a play operator), ADC quantisation of
// the reading, and white noise on the logged current.

#include <cmath>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "fivebar/runtime/controller.hpp"

namespace fivebar::testing {

struct SyntheticTruth {
  double K = 0.7;             ///< N m per A at the output (eta N k_t of the design's defaults)
  double J = 2e-3;            ///< total inertia at the output, kg m^2 (motor side + load side)
  double load_share = 0.3;    ///< of J on the load side of the compliance
  double resonance_hz = 300;  ///< of the compliance (0: rigid)
  double b = 1e-3;            ///< N m s / rad
  double c = 5e-3;            ///< N m
  double offset = 1e-3;       ///< N m
  double current_noise = 2e-3;   ///< A, logged current
  double quantum = 2.0 * std::numbers::pi / 65536.0;  ///< reading quantum, rad (16-bit over a turn)
  double backlash = 2e-5;     ///< rad, play in the reading
  double amplitude = 0.06;    ///< A, multisine current
  double bias_current = 0.0;  ///< A added to the command (a constant drive keeps one direction)
  double duration = 10.0;     ///< s
  double rate = 1000.0;       ///< Hz
  // Voltage drive (a random-phase multisine voltage held over each sample).
  bool voltage_drive = false;
  double R = 5.0;             ///< ohm (the design's default motor)
  double L = 0.5e-3;          ///< H: L/R = 0.1 ms, a tenth of the sample period
  double keN = 1.0;           ///< V s / rad at the output (k_e N = K / eta with eta 0.7)
  double amplitude_V = 0.6;   ///< V, multisine voltage
  int substeps = 10;          ///< integration steps per sample
  // Closed loop: the device's PID (runtime::pid_update at the log's rate) follows a multisine
  // reference from the logged (noisy, quantised) reading; the duty x supply_V drives the winding.
  bool closed_loop = false;
  double supply_V = 6.0;
  double kp = 5.0, ki = 1.0, kd = 0.05, i_clamp = 0.2;  ///< duty per rad, per rad s, per rad/s
  double reference_amplitude = 0.4;  ///< rad, multisine reference
  double reading_noise = 0.0;        ///< rad, white noise on the reading before quantisation
};

struct SyntheticLog {
  std::vector<double> time, current, theta;
  std::vector<double> voltage;  ///< the held voltage of a voltage drive (empty: current drive)
  std::vector<double> duty, reference;  ///< closed loop: the PID's duty and its reference
  std::string csv(bool with_current = true) const {
    std::ostringstream o;
    o.precision(17);
    if (!duty.empty()) {
      o << (with_current ? "time_s,duty,current_A,theta_rad,theta_ref_rad\n" : "time_s,duty,theta_rad,theta_ref_rad\n");
      for (std::size_t i = 0; i < time.size(); ++i) {
        o << time[i] << "," << duty[i] << ",";
        if (with_current) o << current[i] << ",";
        o << theta[i] << "," << reference[i] << "\n";
      }
      return o.str();
    }
    o << (voltage.empty() ? "time_s,current_A,theta_rad\n" : "time_s,voltage_V,current_A,theta_rad\n");
    for (std::size_t i = 0; i < time.size(); ++i) {
      o << time[i] << ",";
      if (!voltage.empty()) o << voltage[i] << ",";
      o << current[i] << "," << theta[i] << "\n";
    }
    return o.str();
  }
};

inline SyntheticLog synthetic_log(const SyntheticTruth& t, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  // A random-phase multisine current, 0.3 ... 6 Hz.
  const int harmonics = 20;
  std::vector<double> ph(harmonics);
  for (double& p : ph) p = phase(rng);
  auto multisine = [&](double time) {
    double s = 0.0;
    for (int k = 1; k <= harmonics; ++k) s += std::sin(2.0 * std::numbers::pi * 0.3 * k * time + ph[static_cast<std::size_t>(k - 1)]);
    return s / std::sqrt(0.5 * harmonics);
  };
  auto command = [&](double time) { return (t.voltage_drive ? t.amplitude_V : t.amplitude) * multisine(time) + t.bias_current; };
  runtime::Gains gains{t.kp, t.ki, t.kd, t.i_clamp};
  runtime::PidState pid;
  const double Jl = t.J * t.load_share, Jm = t.J - Jl;
  const bool rigid = t.resonance_hz <= 0.0;
  const double w_res = 2.0 * std::numbers::pi * t.resonance_hz;
  const double k = rigid ? 0.0 : w_res * w_res * (Jm * Jl / t.J);
  const double d = rigid ? 0.0 : 2.0 * 0.05 * std::sqrt(k * Jm * Jl / t.J);
  const int sub = t.substeps;
  const double h = 1.0 / (t.rate * sub);
  const std::size_t n = static_cast<std::size_t>(t.duration * t.rate);
  SyntheticLog log;
  // State: motor angle, motor speed, load angle, load speed, and the current of a voltage drive.
  double y[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
  double play = 0.0;  // reading behind the backlash
  auto f = [&](const double* s, double drive, double* ds) {
    double i = drive;
    ds[4] = 0.0;
    if (t.voltage_drive) {
      i = s[4];
      ds[4] = (drive - t.R * s[4] - t.keN * s[1]) / t.L;
    }
    const double friction = t.b * s[1] + t.c * std::tanh(s[1] / 1e-3) + t.offset;
    if (rigid) {
      ds[0] = s[1];
      ds[1] = (t.K * i - friction) / t.J;
      ds[2] = s[1];
      ds[3] = ds[1];
      return;
    }
    const double spring = k * (s[0] - s[2]) + d * (s[1] - s[3]);
    ds[0] = s[1];
    ds[1] = (t.K * i - friction - spring) / Jm;
    ds[2] = s[3];
    ds[3] = spring / Jl;
  };
  for (std::size_t j = 0; j < n; ++j) {
    const double time = static_cast<double>(j) / t.rate;
    double i = command(time);  // the current, or the voltage of a voltage drive
    // The reading: backlash (play operator), noise, then quantisation.
    const double load = y[2];
    if (load > play + 0.5 * t.backlash) play = load - 0.5 * t.backlash;
    if (load < play - 0.5 * t.backlash) play = load + 0.5 * t.backlash;
    const double read = play + (t.reading_noise > 0.0 ? t.reading_noise * noise(rng) : 0.0);
    const double reading = t.quantum > 0.0 ? t.quantum * std::round(read / t.quantum) : read;
    if (t.closed_loop) {  // the device's PID on the reading it gets; the duty drives the winding
      // The reference fades in over its first second (a device starts from rest).
      const double fade = std::min(1.0, time);
      const double ref = t.reference_amplitude * fade * multisine(time);
      const double duty = runtime::pid_update(gains, 1.0 / t.rate, pid, ref - reading);
      log.duty.push_back(duty);
      log.reference.push_back(ref);
      i = duty * t.supply_V;
    }
    log.time.push_back(time);
    if (t.voltage_drive) log.voltage.push_back(i);
    log.current.push_back((t.voltage_drive ? y[4] : i) + t.current_noise * noise(rng));
    log.theta.push_back(reading);
    for (int s = 0; s < sub; ++s) {  // RK4, the current held over the sample
      double k1[5], k2[5], k3[5], k4[5], tmp[5];
      f(y, i, k1);
      for (int q = 0; q < 5; ++q) tmp[q] = y[q] + 0.5 * h * k1[q];
      f(tmp, i, k2);
      for (int q = 0; q < 5; ++q) tmp[q] = y[q] + 0.5 * h * k2[q];
      f(tmp, i, k3);
      for (int q = 0; q < 5; ++q) tmp[q] = y[q] + h * k3[q];
      f(tmp, i, k4);
      for (int q = 0; q < 5; ++q) y[q] += h / 6.0 * (k1[q] + 2.0 * k2[q] + 2.0 * k3[q] + k4[q]);
    }
  }
  return log;
}

}  // namespace fivebar::testing
