// The identify study (fivebar/identify.hpp): filters against their closed forms, the log reader's
// refusals, the least-squares core on exact data, calibrated uncertainties on synthetic logs with
// unmodelled effects over 100 seeds, non-excited parameters named, and the EMPS benchmark's real
// measurements (Janot, Gautier, Brunot 2019) against its published IDIM-LS parameters.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <string>

#include "fivebar/error.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/identify.hpp"
#include "fivebar/provenance.hpp"
#include "fivebar/sections/provenance.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/resources/estimates.hpp"
#include "fivebar/runtime/config.hpp"
#include "identify_synthetic.hpp"

namespace fivebar {
namespace {

namespace id = identify;
using testing::synthetic_log;
using testing::SyntheticTruth;

// --- Filters ------------------------------------------------------------------------------------

TEST(IdentifyFilter, ButterworthMatchesTheBilinearClosedForm) {
  // |H(f)|^2 = 1 / (1 + (tan(pi f / fs) / tan(pi fc / fs))^(2n)) for the bilinear Butterworth.
  for (int order : {1, 2, 4, 5, 8}) {
    const double fs = 1000.0, fc = 100.0;
    const auto sos = id::butterworth_lowpass(order, fc, fs);
    for (double f : {0.0, 10.0, 50.0, 100.0, 200.0, 400.0}) {
      const double r = std::tan(std::numbers::pi * f / fs) / std::tan(std::numbers::pi * fc / fs);
      const double expected = 1.0 / std::sqrt(1.0 + std::pow(r, 2 * order));
      EXPECT_NEAR(id::gain(sos, f, fs), expected, 1e-9) << "order " << order << " at " << f << " Hz";
    }
  }
}

TEST(IdentifyFilter, FiltfiltHasZeroPhaseAndSquaredGain) {
  const double fs = 1000.0, fc = 50.0, f = 20.0;
  const auto sos = id::butterworth_lowpass(4, fc, fs);
  std::vector<double> x(4000);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = std::sin(2.0 * std::numbers::pi * f * static_cast<double>(i) / fs);
  const auto y = id::filtfilt(sos, x);
  const double g = id::gain(sos, f, fs);
  // Away from the ends the output is the input scaled by |H|^2, without delay.
  for (std::size_t i = 1000; i < 3000; ++i) EXPECT_NEAR(y[i], g * g * x[i], 1e-6);
  // A constant passes unchanged, ends included (steady-state initial conditions).
  const auto c = id::filtfilt(sos, std::vector<double>(100, 3.0));
  for (double v : c) EXPECT_NEAR(v, 3.0, 1e-9);
}

TEST(IdentifyFilter, DerivativeAndDecimation) {
  std::vector<double> x(101);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = 2.0 * static_cast<double>(i) * 0.01 + 1.0;
  for (double d : id::derivative(x, 0.01)) EXPECT_NEAR(d, 2.0, 1e-9);
  // Decimating a slow sine keeps it (every 10th sample, 1 Hz at 1 kHz) and removes a tone above the
  // new Nyquist frequency.
  std::vector<double> s(5000), n(5000);
  for (std::size_t i = 0; i < s.size(); ++i) {
    const double t = static_cast<double>(i) / 1000.0;
    s[i] = std::sin(2.0 * std::numbers::pi * t);
    n[i] = s[i] + std::sin(2.0 * std::numbers::pi * 120.0 * t);
  }
  const auto d = id::decimate(n, 10);
  ASSERT_EQ(d.size(), 500u);
  for (std::size_t k = 50; k < 450; ++k) EXPECT_NEAR(d[k], s[10 * k], 2e-3);
}

// --- Log reader -----------------------------------------------------------------------------------

std::string error_of(const std::string& text) {
  std::istringstream in(text);
  try {
    id::read_identify_log(in, "bench.csv");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::string rows(const std::string& header, int n, const std::string& row_tail) {
  std::string s = header + "\n";
  for (int i = 0; i < n; ++i) s += std::to_string(0.001 * i) + row_tail + "\n";
  return s;
}

TEST(IdentifyLog, ReadsJointsDrivesAndReadings) {
  std::string text = "time_s,index_lower_theta1_duty,index_lower_theta1_volts,index_lower_theta1_current_A,torque_Nm,theta_rad\n";
  for (int i = 0; i < 20; ++i) text += std::to_string(0.01 * i) + ",0.5,2.5,0.1,0.01," + std::to_string(i) + "\n";
  std::istringstream in(text);
  const id::IdentifyLog log = id::read_identify_log(in, "bench.csv");
  ASSERT_EQ(log.joints.size(), 2u);
  EXPECT_EQ(log.joints[0].prefix, "index_lower_theta1");
  EXPECT_EQ(log.joints[0].station, "index");
  EXPECT_EQ(log.joints[0].mechanism, "lower");
  EXPECT_EQ(log.joints[0].joint, 1);
  EXPECT_EQ(log.joints[0].drive, id::DriveKind::duty);
  EXPECT_EQ(log.joints[0].reading, id::ReadingKind::volts);
  EXPECT_EQ(log.joints[0].current.size(), 20u);
  EXPECT_EQ(log.joints[1].prefix, "");
  EXPECT_EQ(log.joints[1].drive, id::DriveKind::torque);
  EXPECT_NEAR(log.sample_time(), 0.01, 1e-12);
}

TEST(IdentifyLog, RefusesBadInputNamingFileLineAndColumn) {
  {
    const std::string e = error_of(rows("time_s,torque_Nm", 20, ",1"));
    EXPECT_NE(e.find("bench.csv:1"), std::string::npos) << e;
    EXPECT_NE(e.find("missing reading column"), std::string::npos) << e;
  }
  {
    const std::string e = error_of(rows("time_s,torque_Nm,theta_rad,speed", 20, ",1,2,3"));
    EXPECT_NE(e.find("bench.csv:1: column 4 'speed': unknown column"), std::string::npos) << e;
  }
  {
    const std::string e = error_of(rows("torque_Nm,theta_rad", 20, ""));
    EXPECT_NE(e.find("missing column 'time_s'"), std::string::npos) << e;
  }
  {
    std::string t = rows("time_s,torque_Nm,theta_rad", 20, ",1,2");
    t.replace(t.find("0.005000,1,2"), 12, "0.005000,nan,2");
    const std::string e = error_of(t);
    EXPECT_NE(e.find("bench.csv:7: column 'torque_Nm' = 'nan': not a finite decimal number"), std::string::npos) << e;
  }
  {
    std::string t = rows("time_s,torque_Nm,theta_rad", 20, ",1,2");
    t.replace(t.find("0.005000,1,2"), 12, "0.003000,1,2");
    const std::string e = error_of(t);
    EXPECT_NE(e.find("bench.csv:7: column 'time_s'"), std::string::npos) << e;
    EXPECT_NE(e.find("does not increase"), std::string::npos) << e;
  }
  {
    std::string t = rows("time_s,torque_Nm,theta_rad", 20, ",1,2");
    t.replace(t.find("0.005000,1,2"), 12, "0.005000,1e300,2");
    const std::string e = error_of(t);
    EXPECT_NE(e.find("bench.csv:7: column 'torque_Nm' = '1e300': outside +-"), std::string::npos) << e;
  }
  {
    const std::string e = error_of(rows("time_s,force_N,theta_rad", 20, ",1,2"));
    EXPECT_NE(e.find("units do not match"), std::string::npos) << e;
  }
  {
    const std::string e = error_of(rows("time_s,torque_Nm,theta_rad,theta_rad", 20, ",1,2,3"));
    EXPECT_NE(e.find("duplicate"), std::string::npos) << e;
  }
  {
    const std::string e = error_of(rows("time_s,torque_Nm,theta_rad", 5, ",1,2"));
    EXPECT_NE(e.find("at least 16"), std::string::npos) << e;
  }
  {
    const std::string e = error_of("time_s,torque_Nm,theta_rad\n" + std::string(5000, '1') + "\n");
    EXPECT_NE(e.find("bench.csv:2: line longer"), std::string::npos) << e;
  }
  {
    std::string t = rows("time_s,torque_Nm,theta_rad", 20, ",1,2");
    t.replace(t.find("0.005000,1,2"), 12, "0.005000,1");
    EXPECT_NE(error_of(t).find("bench.csv:7: 2 cells"), std::string::npos) << error_of(t);
  }
}

TEST(IdentifyLog, VoltsAndCountsBecomeAnglesThroughThePotentiometerAndTheAdc) {
  id::JointPrior prior;  // potentiometer 2.5 V at 0, 60 deg per volt; 16-bit ADC over -10 ... 10 V
  id::JointLog j;
  j.reading = id::ReadingKind::volts;
  j.reading_values = {2.5, 3.5, 1.0};
  auto q = id::joint_angle(j, prior);
  EXPECT_NEAR(q[0], 0.0, 1e-15);
  EXPECT_NEAR(q[1], std::numbers::pi / 3.0, 1e-12);
  EXPECT_NEAR(q[2], -std::numbers::pi / 2.0, 1e-12);
  j.reading = id::ReadingKind::counts;
  j.reading_values = {40960.0, 65536.0 * 13.5 / 20.0};  // 2.5 V and 3.5 V
  q = id::joint_angle(j, prior);
  EXPECT_NEAR(q[0], 0.0, 1e-12);
  EXPECT_NEAR(q[1], std::numbers::pi / 3.0, 1e-12);
}

// --- Least squares --------------------------------------------------------------------------------

TEST(IdentifyLeastSquares, RecoversExactParametersAndNamesDependentColumns) {
  Eigen::MatrixXd W(50, 3);
  Eigen::VectorXd Y(50);
  for (int i = 0; i < 50; ++i) {
    W(i, 0) = std::sin(0.3 * i);
    W(i, 1) = std::cos(0.17 * i);
    W(i, 2) = 1.0;
    Y[i] = 2.0 * W(i, 0) - 3.0 * W(i, 1) + 0.5;
  }
  const id::Estimate e = id::least_squares(W, Y, {"a", "b", "c"}, Eigen::Vector3d::Zero(), 1e-4);
  EXPECT_NEAR(e.value[0], 2.0, 1e-12);
  EXPECT_NEAR(e.value[1], -3.0, 1e-12);
  EXPECT_NEAR(e.value[2], 0.5, 1e-12);
  // A fourth column equal to 2 a - c is not separable: held at its prior and named.
  Eigen::MatrixXd W4(50, 4);
  W4 << W, 2.0 * W.col(0) - W.col(2);
  const id::Estimate d = id::least_squares(W4, Y, {"a", "b", "c", "d"}, Eigen::Vector4d(0, 0, 0, 7.0), 1e-4);
  EXPECT_FALSE(d.identified[3]);
  EXPECT_EQ(d.value[3], 7.0);
  EXPECT_NE(d.notes[3].find("2.0000 x a"), std::string::npos) << d.notes[3];
  EXPECT_NE(d.notes[3].find("-1.0000 x c"), std::string::npos) << d.notes[3];
}

// --- Synthetic logs: calibrated uncertainties -------------------------------------------------------

id::JointLog joint_of(const testing::SyntheticLog& s) {
  id::JointLog j;
  j.drive = id::DriveKind::current;
  j.drive_column = "current_A";
  j.drive_values = s.current;
  j.reading = id::ReadingKind::angle;
  j.reading_column = "theta_rad";
  j.reading_values = s.theta;
  return j;
}

id::JointPrior prior_for(const SyntheticTruth& t) {
  id::JointPrior p;
  // The design's default motor gives eta N k_t = 0.7 N m / A, the truth's K.
  EXPECT_NEAR(p.motor.gearbox_efficiency * p.motor.gear_ratio * p.motor.torque_constant(), t.K, 1e-12);
  return p;
}

TEST(IdentifySynthetic, EstimatesFallWithinTheirThreeSigmaOnAtLeast97PercentOf100Seeds) {
  const SyntheticTruth truth;
  const id::JointPrior prior = prior_for(truth);
  id::IdentifyOptions o;
  o.output_error = false;
  const double want[4] = {truth.J, truth.b, truth.c, truth.offset};
  int inside = 0, total = 0;
  double worst = 0.0;
  for (unsigned seed = 1; seed <= 100; ++seed) {
    const auto log = synthetic_log(truth, seed);
    const auto r = id::identify_joint(joint_of(log), log.time, prior, nullptr, nullptr, o);
    for (int k = 0; k < 4; ++k) {
      ASSERT_TRUE(r.idim.identified[static_cast<std::size_t>(k)]) << r.idim.names[static_cast<std::size_t>(k)];
      const double z = std::abs(r.idim.value[k] - want[k]) / r.idim.sigma[k];
      worst = std::max(worst, z);
      inside += z <= 3.0;
      ++total;
    }
  }
  const double fraction = static_cast<double>(inside) / total;
  std::cout << "3-sigma coverage " << fraction * 100.0 << " % of " << total << " estimates, worst " << worst << " sigma\n";
  EXPECT_GE(fraction, 0.97);
}

TEST(IdentifySynthetic, OutputErrorRefinementRecoversTheTruthOnARigidMotor) {
  SyntheticTruth truth;
  truth.resonance_hz = 0.0;
  truth.backlash = 0.0;
  const id::JointPrior prior = prior_for(truth);
  id::IdentifyOptions o;
  const auto log = synthetic_log(truth, 7);
  const auto r = id::identify_joint(joint_of(log), log.time, prior, nullptr, nullptr, o);
  ASSERT_TRUE(r.output_error.has_value()) << r.output_error_status;
  const double want[4] = {truth.J, truth.b, truth.c, truth.offset};
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(r.output_error->value[k], want[k], 0.05 * std::abs(want[k]) + 1e-4) << k;
  EXPECT_GT(r.estimation_oe.position_fit_percent, 95.0);
  EXPECT_GE(r.estimation_oe.position_fit_percent, r.estimation_idim.position_fit_percent - 1e-9);
}

TEST(IdentifySynthetic, ConstantDirectionCannotSeparateCoulombFromOffset) {
  SyntheticTruth truth;
  truth.bias_current = 0.2;   // always forward: sgn(w) = 1 like the offset's column
  truth.amplitude = 0.02;
  const auto log = synthetic_log(truth, 3);
  // Keep the part after the start-up, when the speed has settled well above zero.
  testing::SyntheticLog cut;
  for (std::size_t i = 2000; i < log.time.size(); ++i) {
    cut.time.push_back(log.time[i]);
    cut.current.push_back(log.current[i]);
    cut.theta.push_back(log.theta[i]);
  }
  id::IdentifyOptions o;
  o.output_error = false;
  const auto r = id::identify_joint(joint_of(cut), cut.time, prior_for(truth), nullptr, nullptr, o);
  ASSERT_EQ(r.unidentifiable.size(), 1u);
  EXPECT_EQ(r.unidentifiable[0], "offset_Nm");
  EXPECT_NE(r.idim.notes[3].find("coulomb_Nm"), std::string::npos) << r.idim.notes[3];
}

TEST(IdentifySynthetic, VoltageDriveWithCurrentGivesResistanceAndBackEmf) {
  // A voltage-driven motor with its current logged: the electrical equation alone, V = R i + k_e N w,
  // generated in closed form from a motion and a current (L = 0 so that di/dt does not enter).
  MotorParams m;
  const double R = 4.2, keN = 0.9;  // ohm, V s / rad at the output
  const std::size_t n = 5000;
  id::JointLog j;
  j.drive = id::DriveKind::voltage;
  j.drive_column = "voltage_V";
  j.reading_column = "theta_rad";
  std::vector<double> time(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * 1e-3;
    time[k] = t;
    const double q = 0.5 * std::sin(2.0 * std::numbers::pi * 0.5 * t) + 0.2 * std::sin(2.0 * std::numbers::pi * 1.3 * t);
    const double w = 0.5 * std::numbers::pi * std::cos(std::numbers::pi * t) + 0.52 * std::numbers::pi * std::cos(2.6 * std::numbers::pi * t);
    const double i = 0.3 * std::sin(2.0 * std::numbers::pi * 0.7 * t + 0.4);
    j.reading_values.push_back(q);
    j.current.push_back(i);
    j.drive_values.push_back(R * i + keN * w);
  }
  id::JointPrior p;
  p.motor = m;
  id::IdentifyOptions o;
  o.output_error = false;
  o.zero_order_hold = false;  // the closed form above relates instantaneous values (--instant-drive)
  const auto r = id::identify_joint(j, time, p, nullptr, nullptr, o);
  ASSERT_TRUE(r.electrical.has_value());
  EXPECT_NEAR(r.electrical->value[0], R, 2e-3 * R);
  EXPECT_NEAR(r.electrical->value[2], keN, 2e-3 * keN);
  bool found = false;
  for (const id::Parameter& q : r.parameters) {
    if (q.key == "motor.terminal_resistance_ohm") {
      found = true;
      EXPECT_TRUE(q.identified);
      EXPECT_NEAR(q.value, R, 2e-3 * R);
    }
  }
  EXPECT_TRUE(found);
}

// A lab's log of a voltage-driven motor (synthetic_log with voltage_drive): the voltage command held
// over each 1 ms sample, the current sampled at the sample instants (1 kHz, 2 mA noise), the
// winding's L/R = 0.1 ms below the sample period, and the reading's compliance, backlash and 16-bit
// quantisation. Logged as a voltage or as a duty, with or without the current column.
struct VoltageCase {
  bool duty, with_current;
  const char* name;
};

id::JointLog voltage_joint(const testing::SyntheticLog& s, const VoltageCase& c, double supply) {
  id::JointLog j;
  j.drive = c.duty ? id::DriveKind::duty : id::DriveKind::voltage;
  j.drive_column = c.duty ? "duty" : "voltage_V";
  for (double v : s.voltage) j.drive_values.push_back(c.duty ? v / supply : v);
  j.reading = id::ReadingKind::angle;
  j.reading_column = "theta_rad";
  j.reading_values = s.theta;
  if (c.with_current) j.current = s.current;
  return j;
}

TEST(IdentifyFilter, TheReversalWindowIsHalfOfEachLowPasssMainLobe) {
  // 1 kHz, the position's low-pass at 100 Hz (5 samples), decimation by 10 (its filter at 40 Hz:
  // 12.5 samples), the two samples of the one-sided differences.
  EXPECT_EQ(id::reversal_samples(100.0, 1000.0, 10), 5 + 13 + 2);
  EXPECT_EQ(id::reversal_samples(100.0, 1000.0, 1), 5 + 2);
  EXPECT_EQ(id::reversal_samples(50.0, 500.0, 5), 5 + 7 + 2);  // 0.5 fs / (0.8 fs / 10) = 6.25
}

TEST(IdentifySynthetic, VoltageAndDutyDrivesAreUnbiasedWithAndWithoutTheCurrent) {
  SyntheticTruth truth;
  truth.voltage_drive = true;
  truth.substeps = 40;  // 25 us steps: a quarter of the winding's time constant
  // Rigid: with the 300 Hz compliance the reading lags the motor, whose speed the back-EMF sees, by
  // 2 zeta / omega = 0.05 ms, and the back-EMF's damping (0.14 N m s / rad, 70 times the inertia per
  // second) turns that into an inertia 0.5 % (5 sigma) low: a model error, not the method's.
  truth.resonance_hz = 0.0;
  const id::JointPrior prior;  // the design's default motor: the truth's R, L, k_e N and eta
  const MotorParams& m = prior.motor;
  ASSERT_NEAR(m.resistance(), truth.R, 1e-12);
  ASSERT_NEAR(m.inductance(), truth.L, 1e-12);
  ASSERT_NEAR(m.back_emf_constant() * m.gear_ratio, truth.keN, 1e-12);
  ASSERT_NEAR(m.gearbox_efficiency * truth.keN, truth.K, 1e-12);
  id::IdentifyOptions o;
  o.output_error = false;
  const double want[4] = {truth.J, truth.b, truth.c, truth.offset};
  const int seeds = 20;
  for (const VoltageCase& c : {VoltageCase{false, true, "voltage and current"}, VoltageCase{false, false, "voltage alone"},
                               VoltageCase{true, true, "duty and current"}}) {
    SCOPED_TRACE(c.name);
    int inside = 0, total = 0;
    double worst = 0.0;
    for (unsigned seed = 1; seed <= static_cast<unsigned>(seeds); ++seed) {
      const auto log = synthetic_log(truth, seed);
      const auto r = id::identify_joint(voltage_joint(log, c, m.supply_voltage_V), log.time, prior, nullptr, nullptr, o);
      for (int k = 0; k < 4; ++k) {
        ASSERT_TRUE(r.idim.identified[static_cast<std::size_t>(k)]) << r.idim.names[static_cast<std::size_t>(k)];
        const double z = std::abs(r.idim.value[k] - want[k]) / r.idim.sigma[k];
        worst = std::max(worst, z);
        inside += z <= 3.0;
        ++total;
      }
      EXPECT_NEAR(r.idim.value[0], truth.J, 0.01 * truth.J) << "seed " << seed;
      EXPECT_GT(r.idim.value[2], 0.0) << "seed " << seed;
      ASSERT_EQ(r.electrical.has_value(), c.with_current);
      if (!c.with_current) continue;
      const id::Estimate& el = *r.electrical;
      for (int k : {0, 2}) {
        ASSERT_TRUE(el.identified[static_cast<std::size_t>(k)]);
        const double z = std::abs(el.value[k] - (k == 0 ? truth.R : truth.keN)) / el.sigma[k];
        worst = std::max(worst, z);
        inside += z <= 3.0;
        ++total;
      }
      // L/R = 0.1 ms against a 1 ms sample: the log cannot resolve L; held and named.
      EXPECT_FALSE(el.identified[1]);
      EXPECT_NE(el.notes[1].find("below the sample period"), std::string::npos) << el.notes[1];
    }
    std::cout << c.name << ": " << inside << " of " << total << " estimates within 3 sigma, worst " << worst << " sigma\n";
    // The goal is 95 %. Measured (seeds 1 ... 20): 119 of 120 with the current, 80 of 80 without,
    // worst 3.0 sigma. With the rows near reversals kept (skip_reversals false), 113 of 120 and 70 of
    // 80: the reading stalled in the 2e-5 rad of backlash while the motor turned left the viscous
    // friction 1.5 to 2 sigma high and the Coulomb friction 2.4 to 2.6 low (the backlash alone
    // does it; the quantisation or the current's noise alone do not). Before the sampled current's
    // model, the same logs gave R +2 ... +18 %, L 4 ... 14 times its value, the inertia -7.6 %.
    EXPECT_GE(inside, static_cast<int>(std::ceil(0.95 * total))) << "worst " << worst;
    EXPECT_LT(worst, 4.0);
  }
}

// A log taken while the device's PID runs (synthetic_log with closed_loop): the PID computes the
// duty from the noisy, quantised reading, so the drive carries the reading's noise back into the
// regression; IDIM-LS is biased by it, IDIM-IV (instruments from the loop simulated without noise)
// is not.
struct ClosedLoopRun {
  int inside_ls = 0, inside_iv = 0, total = 0;
  double worst_ls = 0.0, worst_iv = 0.0, mean_z_ls[4] = {0, 0, 0, 0}, mean_z_iv[4] = {0, 0, 0, 0};
  int converged = 0, runs = 0;
};

ClosedLoopRun closed_loop_coverage(const SyntheticTruth& truth, bool with_current, int seeds) {
  id::JointPrior prior;
  id::IdentifyOptions o;
  o.output_error = false;
  const double want[4] = {truth.J, truth.b, truth.c, truth.offset};
  ClosedLoopRun run;
  for (unsigned seed = 1; seed <= static_cast<unsigned>(seeds); ++seed) {
    const auto log = synthetic_log(truth, seed);
    std::istringstream in(log.csv(with_current));
    const id::IdentifyLog parsed = id::read_identify_log(in, "closed.csv");
    const id::JointLog& j = parsed.joints.front();
    EXPECT_EQ(j.reference_column, "theta_ref_rad");
    auto pid = id::device_pid(j.reference, runtime::Gains{truth.kp, truth.ki, truth.kd, truth.i_clamp}, 1.0 / truth.rate, 1.0);
    const auto r = id::identify_joint({{&j, &parsed.time, pid.get()}}, prior, {}, o);
    ++run.runs;
    run.converged += r.iv_converged;
    if (!r.iv) continue;
    for (int k = 0; k < 4; ++k) {
      const double zl = (r.idim.value[k] - want[k]) / r.idim.sigma[k];
      const double zi = (r.iv->value[k] - want[k]) / r.iv->sigma[k];
      run.mean_z_ls[k] += zl / seeds;
      run.mean_z_iv[k] += zi / seeds;
      run.worst_ls = std::max(run.worst_ls, std::abs(zl));
      run.worst_iv = std::max(run.worst_iv, std::abs(zi));
      run.inside_ls += std::abs(zl) <= 3.0;
      run.inside_iv += std::abs(zi) <= 3.0;
      ++run.total;
    }
  }
  return run;
}

TEST(IdentifyClosedLoop, InstrumentalVariablesAreUnbiasedUnderTheDevicesPid) {
  SyntheticTruth truth;
  truth.voltage_drive = true;
  truth.closed_loop = true;
  truth.resonance_hz = 0.0;
  truth.substeps = 40;
  truth.reading_noise = 2e-3;
  truth.quantum = 20.0 / 65536.0 / 0.9549296585513721;  // the showcase's 16-bit +-10 V ADC through its potentiometer
  truth.kp = 6.376473352297236;  // the showcase's tuned index lower gains
  truth.ki = 62.44954783058385;
  truth.kd = 0.11315351641304752;
  // A bench that logs at 1 kHz with the PID running at that rate (the winding's L/R = 0.1 ms and
  // the mechanical time constant J / (k_t k_e N^2 / R) = 14 ms, both well above one sample).
  truth.rate = 1000.0;
  truth.duration = 10.0;
  for (bool current : {true, false}) {
    SCOPED_TRACE(current ? "duty and current" : "duty alone");
    const int seeds = 20;
    const ClosedLoopRun run = closed_loop_coverage(truth, current, seeds);
    std::cout << (current ? "with" : "without") << " current: IV converged " << run.converged << "/" << run.runs << ", within 3 sigma: IDIM-LS "
              << run.inside_ls << "/" << run.total << " (worst " << run.worst_ls << "), IDIM-IV " << run.inside_iv << "/" << run.total
              << " (worst " << run.worst_iv << "); mean z of the inertia LS " << run.mean_z_ls[0] << ", IV " << run.mean_z_iv[0] << "\n";
    EXPECT_EQ(run.converged, seeds);
    // Measured: IDIM-IV 80/80 in both cases (worst 1.4 sigma), mean z of every parameter within 0.2.
    EXPECT_GE(run.inside_iv, static_cast<int>(std::ceil(0.95 * run.total)));
    for (double z : run.mean_z_iv) EXPECT_LT(std::abs(z), 0.5);
    // The same logs bias IDIM-LS: the inertia 3.6 to 4 of its sigmas low on average (measured),
    // 60/80 within 3 sigma. This checks that the logs are closed loop enough to matter.
    EXPECT_LT(run.mean_z_ls[0], -2.0);
  }
}

// Several logs in one fit: their rows stacked. A second formulation: each log fitted alone and
// the two estimates combined by inverse-variance weighting, which the stacked fit equals up to the
// pooled residual and the rows the filters trim at each log's ends.
TEST(IdentifySynthetic, SeveralLogsFitTogetherAsTheirInverseVarianceMean) {
  SyntheticTruth truth;
  truth.duration = 6.0;
  const auto a = synthetic_log(truth, 11), b = synthetic_log(truth, 12);
  std::istringstream ia(a.csv()), ib(b.csv());
  const id::IdentifyLog la = id::read_identify_log(ia, "a.csv"), lb = id::read_identify_log(ib, "b.csv");
  id::IdentifyOptions o;
  o.output_error = false;
  const id::JointPrior prior;
  const auto ra = id::identify_joint(la.joints[0], la.time, prior, nullptr, nullptr, o);
  const auto rb = id::identify_joint(lb.joints[0], lb.time, prior, nullptr, nullptr, o);
  const auto rab = id::identify_joint({{&la.joints[0], &la.time, nullptr}, {&lb.joints[0], &lb.time, nullptr}}, prior, {}, o);
  EXPECT_EQ(rab.logs, 2);
  const double truth_values[4] = {truth.J, truth.b, truth.c, truth.offset};
  for (int k = 0; k < 4; ++k) {
    const double wa = 1.0 / (ra.idim.sigma[k] * ra.idim.sigma[k]), wb = 1.0 / (rb.idim.sigma[k] * rb.idim.sigma[k]);
    const double mean = (wa * ra.idim.value[k] + wb * rb.idim.value[k]) / (wa + wb);
    const double sigma = 1.0 / std::sqrt(wa + wb);
    SCOPED_TRACE(rab.idim.names[static_cast<std::size_t>(k)]);
    EXPECT_NEAR(rab.idim.value[k], mean, 0.5 * sigma);
    EXPECT_NEAR(rab.idim.sigma[k], sigma, 0.15 * sigma);
    EXPECT_NEAR(rab.idim.value[k], truth_values[k], 4.0 * rab.idim.sigma[k]);
  }
  // With the output-error refinement: one simulation per log, the parameters shared.
  o.output_error = true;
  const auto roe = id::identify_joint({{&la.joints[0], &la.time, nullptr}, {&lb.joints[0], &lb.time, nullptr}}, prior, {}, o);
  ASSERT_TRUE(roe.output_error.has_value()) << roe.output_error_status;
  EXPECT_NEAR(roe.output_error->value[0], truth.J, 0.05 * truth.J);
  // Logs of one fit record the same columns, and are all open or all closed loop.
  id::JointLog other = lb.joints[0];
  other.drive = id::DriveKind::torque;
  other.drive_column = "torque_Nm";
  EXPECT_THROW(id::identify_joint({{&la.joints[0], &la.time, nullptr}, {&other, &lb.time, nullptr}}, prior, {}, o), InputError);
  std::vector<double> ref(la.time.size(), 0.0);
  auto pid = id::device_pid(ref, runtime::Gains{1.0, 0.0, 0.0, 0.0}, 1e-3, 1.0);
  EXPECT_THROW(id::identify_joint({{&la.joints[0], &la.time, pid.get()}, {&lb.joints[0], &lb.time, nullptr}}, prior, {}, o), InputError);
}

TEST(IdentifySynthetic, InductanceIsIdentifiedWhenTheWindingLagsOverASample) {
  // L/R = 2 ms against a 1 ms sample: the current carries over from one sample to the next and the
  // sampled-current regression resolves L.
  SyntheticTruth truth;
  truth.voltage_drive = true;
  truth.L = 10e-3;
  id::JointPrior prior;
  prior.motor.inductance_mH = 10.0;
  id::IdentifyOptions o;
  o.output_error = false;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const auto log = synthetic_log(truth, seed);
    const auto r = id::identify_joint(voltage_joint(log, VoltageCase{false, true, ""}, 6.0), log.time, prior, nullptr, nullptr, o);
    ASSERT_TRUE(r.electrical.has_value());
    ASSERT_TRUE(r.electrical->identified[1]) << r.electrical->notes[1];
    // Measured: L 14 ... 21 % high on these logs and k_e N 0.2 % high, both far outside their
    // sigmas (a bias not found yet, docs/identify.md "Not done yet"): bounds, not coverage.
    EXPECT_NEAR(r.electrical->value[1], truth.L, 0.25 * truth.L);
    EXPECT_NEAR(r.electrical->value[0], truth.R, 5e-3 * truth.R);
    EXPECT_NEAR(r.electrical->value[2], truth.keN, 5e-3 * truth.keN);
  }
}

// --- Planning ---------------------------------------------------------------------------------------

TEST(IdentifyPlan, StaysWithinItsLimitsWithALowCrestFactor) {
  id::JointPrior prior;
  id::PlanOptions po;
  po.range_lo = -1.0;
  po.range_hi = 1.0;
  po.max_speed = 3.0;
  po.current_limit = 0.5;
  const id::ExcitationPlan plan = id::plan_excitation(prior, po);
  double qmax = 0.0, wmax = 0.0, imax = 0.0;
  for (std::size_t i = 0; i < plan.time.size(); ++i) {
    qmax = std::max(qmax, std::abs(plan.position[i]));
    wmax = std::max(wmax, std::abs(plan.velocity[i]));
    imax = std::max(imax, std::abs(plan.current[i]));
  }
  EXPECT_LE(qmax, 0.9 + 1e-9);
  EXPECT_LE(wmax, 0.9 * 3.0 + 1e-9);
  EXPECT_LE(imax, 0.9 * 0.5 + 1e-9);
  EXPECT_LT(plan.crest_factor, 2.5);  // Schroeder phases: a low crest factor
  ASSERT_EQ(plan.expected_sigma.size(), 4);
  for (int k = 0; k < 4; ++k) EXPECT_GT(plan.expected_sigma[k], 0.0);
}

TEST(IdentifyPlan, StartsAndEndsAtRest) {
  id::JointPrior prior;
  id::PlanOptions po;
  const id::ExcitationPlan plan = id::plan_excitation(prior, po);
  const double centre = 0.5 * (po.range_lo + po.range_hi);
  ASSERT_EQ(plan.fade_s, 1.0);
  double peak_w = 0.0, peak_a = 0.0;
  for (std::size_t i = 0; i < plan.time.size(); ++i) {
    peak_w = std::max(peak_w, std::abs(plan.velocity[i]));
    peak_a = std::max(peak_a, std::abs(plan.acceleration[i]));
  }
  for (std::size_t i : {std::size_t{0}, plan.time.size() - 1}) {
    EXPECT_NEAR(plan.position[i], centre, 1e-12);
    EXPECT_NEAR(plan.velocity[i], 0.0, 1e-12);
    EXPECT_NEAR(plan.acceleration[i], 0.0, 1e-9 * peak_a);
  }
  // The first 10 ms (ten samples) stay below 1 % of the peak speed: no step at the start.
  for (std::size_t i = 0; i < 10; ++i) EXPECT_LT(std::abs(plan.velocity[i]), 0.01 * peak_w) << i;
  // The plan's motion is its own derivative: the speed against a central difference of the position.
  const double dt = plan.time[1] - plan.time[0];
  for (std::size_t i = 1; i + 1 < plan.time.size(); i += 97) {
    EXPECT_NEAR((plan.position[i + 1] - plan.position[i - 1]) / (2.0 * dt), plan.velocity[i], 1e-3 * peak_w) << i;
  }
}

TEST(IdentifyPlan, ExpectedSigmasMatchTheSpreadOfFitsToLogsOfThePlan) {
  // Logs of the plan played perfectly by the prior model, with white noise of the stated sigma on
  // the logged drive torque and the reading rounded to the quantum of the default potentiometer and
  // ADC (its offset random per log, as a run's start is): the spread of the IDIM-LS estimates over
  // 40 seeds, and the sigmas each fit reports, are what the plan predicts.
  id::JointPrior prior;
  id::PlanOptions po;
  po.range_lo = -1.0;
  po.range_hi = 1.0;
  po.drive_noise = 2e-3;
  po.angle_quantum = prior.rad_per_volt * (prior.adc_hi_v - prior.adc_lo_v) / std::ldexp(1.0, prior.adc_bits);
  const id::ExcitationPlan plan = id::plan_excitation(prior, po);
  // The quantum matters here: a large share of the predicted residual.
  EXPECT_GT(plan.quantisation_share, 0.3);
  std::cout << "plan: residual " << plan.expected_residual << " N m, quantisation share " << plan.quantisation_share << "\n";
  const MotorParams& m = prior.motor;
  const double K = m.gearbox_efficiency * m.gear_ratio * m.torque_constant();
  id::IdentifyOptions o;
  o.output_error = false;
  o.zero_order_hold = false;  // the logged drive is the instantaneous torque
  const int seeds = 40;
  std::vector<Eigen::VectorXd> estimates;
  Eigen::VectorXd reported = Eigen::VectorXd::Zero(4);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_real_distribution<double> offset(0.0, po.angle_quantum);
  for (int s = 0; s < seeds; ++s) {
    id::JointLog j;
    j.drive = id::DriveKind::current;
    j.drive_column = "current_A";
    j.reading_column = "theta_rad";
    // Each run tracks the plan with its own small error (a random-phase 1 ... 5 Hz motion of a few
    // quanta), so that the rounding differs from run to run as it does on a bench.
    const double off = offset(rng);
    std::array<double, 5> ph{};
    for (double& x : ph) x = 2.0 * std::numbers::pi * offset(rng) / po.angle_quantum;
    for (std::size_t i = 0; i < plan.time.size(); ++i) {
      double e = 0.0, de = 0.0, dde = 0.0;
      for (int h = 1; h <= 5; ++h) {
        const double wh = 2.0 * std::numbers::pi * h, amp = 3.0 * po.angle_quantum / h;
        e += amp * std::sin(wh * plan.time[i] + ph[static_cast<std::size_t>(h - 1)]);
        de += amp * wh * std::cos(wh * plan.time[i] + ph[static_cast<std::size_t>(h - 1)]);
        dde -= amp * wh * wh * std::sin(wh * plan.time[i] + ph[static_cast<std::size_t>(h - 1)]);
      }
      const double q = plan.position[i] + e;
      j.reading_values.push_back(po.angle_quantum * std::round((q + off) / po.angle_quantum) - off);
      const double w = plan.velocity[i] + de;
      const double tau = plan.truth[0] * (plan.acceleration[i] + dde) + plan.truth[1] * w + plan.truth[2] * (w > 0 ? 1.0 : w < 0 ? -1.0 : 0.0);
      j.drive_values.push_back((tau + po.drive_noise * noise(rng)) / K);
    }
    const auto r = id::identify_joint(j, plan.time, prior, nullptr, nullptr, o);
    estimates.push_back(r.idim.value);
    reported += r.idim.sigma / seeds;
  }
  for (int k = 0; k < 4; ++k) {
    double mean = 0.0, var = 0.0;
    for (const auto& e : estimates) mean += e[k] / seeds;
    for (const auto& e : estimates) var += (e[k] - mean) * (e[k] - mean) / (seeds - 1);
    const double ratio = std::sqrt(var) / plan.expected_sigma[k];
    const double reported_ratio = reported[k] / plan.expected_sigma[k];
    // The sigmas each fit reports are what the plan predicts, within a factor 1.5 either way. The
    // spread is not above them (40 samples give a standard deviation to about +-11 %): the
    // quantisation's error, through two differences, lies mostly above the excitation's band, so
    // s^2 (W^T W)^-1, which takes it as white, over-states the inertia's and the offset's spread
    // (measured 0.28 and 0.33 of it; the frictions' 0.7 ... 0.8): conservative.
    EXPECT_LT(ratio, 1.5) << plan.names[static_cast<std::size_t>(k)];
    EXPECT_GT(reported_ratio, 1.0 / 1.5) << plan.names[static_cast<std::size_t>(k)];
    EXPECT_LT(reported_ratio, 1.5) << plan.names[static_cast<std::size_t>(k)];
    std::cout << plan.names[static_cast<std::size_t>(k)] << ": spread / expected sigma " << ratio << ", reported / expected "
              << reported_ratio << "\n";
  }
}

// --- EMPS: real measurements --------------------------------------------------------------------------

// The EMPS benchmark: A. Janot, M. Gautier, M. Brunot, "Data Set and Reference Models of EMPS",
// Workshop on Nonlinear System Identification Benchmarks, 2019 (nonlinearbenchmark.org), in the
// identify log format (time_s, torque_Nm = the force in N, theta_rad = the position in m). Its
// published IDIM-LS estimates (PDF section 3.4): M = 95.1089 kg (sigma 0.1085), Fv = 203.5034 N s/m
// (1.1460), Fc = 20.3935 N (0.1012), offset = -3.1648 N (0.0444); relative force error 4.08 % on
// estimation, 5.98 % cross-test.
std::filesystem::path emps_dir() { return std::filesystem::path(fivebar_test_paths::shared_data_dir()) / "sysid" / "emps"; }

TEST(IdentifyEmps, MatchesThePublishedIdimLsParameters) {
  const auto dir = emps_dir();
  if (!std::filesystem::exists(dir / "est.csv")) GTEST_SKIP() << "EMPS data not found under " << dir;
  const id::IdentifyLog est = id::read_identify_log(dir / "est.csv");
  const id::IdentifyLog val = id::read_identify_log(dir / "val.csv");
  // The published settings: 4th-order Butterworth at 100 Hz, decimation 10, the force taken as the
  // instantaneous value at each sample (the reference scripts do not shift it by half a sample).
  id::IdentifyOptions o;
  o.output_error = false;
  o.zero_order_hold = false;
  ASSERT_EQ(est.joints.size(), 1u);
  const auto r = id::identify_joint(est.joints[0], est.time, id::JointPrior{}, &val.joints[0], &val.time, o);
  EXPECT_EQ(r.cutoff_hz, 100.0);
  EXPECT_EQ(r.decimation, 10);
  const double published[4] = {95.1089, 203.5034, 20.3935, -3.1648};
  const double sigma[4] = {0.1085, 1.1460, 0.1012, 0.0444};
  // The published run and this one differ only in the implementation of the filters (MATLAB's
  // butter/filtfilt/decimate against the ones here, whose padding and decimation phase differ); the
  // rows within the filters' settling of either end are left out (IdentifyOptions, edge_samples),
  // so what is left of that difference is a fraction of the estimate's own noise: within 1.5
  // published sigmas (measured: M -0.2, Fv +0.3, Fc -0.5, offset -1.0).
  EXPECT_GT(r.edge_samples, 0);
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(r.idim.value[k], published[k], 1.5 * sigma[k]) << r.idim.names[static_cast<std::size_t>(k)];
    // The same statistic from the same data and residual: within 5 % (measured within 2 %).
    EXPECT_NEAR(r.idim.sigma[k], sigma[k], 0.05 * sigma[k]) << r.idim.names[static_cast<std::size_t>(k)];
  }
  // The relative force errors: 4.08 % estimation, 5.98 % cross-test (measured 4.01 %, 5.93 %; with
  // the edge rows kept they were 4.65 % and 6.31 %).
  EXPECT_NEAR(r.estimation_idim.drive_relative_error_percent, 4.08, 0.15);
  ASSERT_TRUE(r.validation_idim.has_value());
  EXPECT_NEAR(r.validation_idim->drive_relative_error_percent, 5.98, 0.15);
  // The open-loop simulation with the identified model reproduces the position at about the fit of
  // the reference model's own simulation (91.8 % estimation, 88.8 % validation).
  EXPECT_GT(r.estimation_idim.position_fit_percent, 85.0);
  EXPECT_GT(r.validation_idim->position_fit_percent, 80.0);
  // Read as what it is, a linear axis (force_N, position_m): the same numbers under the axis' names,
  // and no design key of a rotary motor.
  id::JointLog linear = est.joints[0];
  linear.linear = true;
  const auto l = id::identify_joint(linear, est.time, id::JointPrior{}, nullptr, nullptr, o);
  ASSERT_EQ(l.parameters.size(), 4u);
  EXPECT_EQ(l.parameters[0].key, "mass_kg");
  EXPECT_EQ(l.parameters[1].key, "viscous_N_s_per_m");
  EXPECT_EQ(l.parameters[2].key, "coulomb_N");
  EXPECT_EQ(l.parameters[3].key, "offset_N");
  for (int k = 0; k < 4; ++k) EXPECT_NEAR(l.parameters[static_cast<std::size_t>(k)].value, r.idim.value[k], 1e-9 * std::abs(r.idim.value[k]));
  std::cout << "EMPS IDIM-LS: M " << r.idim.value[0] << " +- " << r.idim.sigma[0] << ", Fv " << r.idim.value[1] << " +- "
            << r.idim.sigma[1] << ", Fc " << r.idim.value[2] << " +- " << r.idim.sigma[2] << ", offset " << r.idim.value[3]
            << " +- " << r.idim.sigma[3] << "; force error " << r.estimation_idim.drive_relative_error_percent << " % / "
            << r.validation_idim->drive_relative_error_percent << " %; position fit " << r.estimation_idim.position_fit_percent
            << " % / " << r.validation_idim->position_fit_percent << " %\n";
}

/// EMPS's controller (its data set's description): a P position loop around a velocity loop,
/// vir = sat_10V(kv (kp (qg - q) - dq_f)), dq_f = (q_k - q_k-2) / (2 Ts), force = gtau vir. The
/// description's one-sample delay is left out: applied to the measured position, the law without it
/// gives the logged vir to 0.68 % (relative), with it 3.7 %. Written here from the description, not
/// from the library's PID.
class EmpsLoop final : public id::LoopController {
 public:
  explicit EmpsLoop(std::vector<double> qg) : qg_(std::move(qg)) {}
  void reset() override { first_ = true; }
  double drive(std::size_t k, double q) override {
    if (first_) {
      q1_ = q2_ = q;
      first_ = false;
    }
    const double dq = (q - q2_) / (2.0 * kTs);
    const double out = std::clamp(kKv * (kKp * (qg_[k] - q) - dq), -10.0, 10.0);
    q2_ = q1_;
    q1_ = q;
    return kGtau * out;
  }
  static constexpr double kTs = 1e-3, kKp = 160.18, kKv = 243.45, kGtau = 35.15065188;

 private:
  std::vector<double> qg_;
  bool first_ = true;
  double q1_ = 0.0, q2_ = 0.0;
};

/// A column of EMPS's full CSV (t_s,vir_V,force_N,qm_m,qg_m).
std::vector<double> emps_column(const std::filesystem::path& file, const std::string& name) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> head;
  std::stringstream hs(line);
  for (std::string c; std::getline(hs, c, ',');) head.push_back(c);
  const auto at = static_cast<std::size_t>(std::find(head.begin(), head.end(), name) - head.begin());
  std::vector<double> out;
  while (std::getline(in, line)) {
    std::stringstream ls(line);
    std::string cell;
    for (std::size_t c = 0; c <= at; ++c) std::getline(ls, cell, ',');
    out.push_back(std::stod(cell));
  }
  return out;
}

TEST(IdentifyEmps, ClosedLoopSimulationAndInstrumentalVariables) {
  const auto dir = emps_dir();
  if (!std::filesystem::exists(dir / "emps_estimation.csv")) GTEST_SKIP() << "EMPS data not found under " << dir;
  const id::IdentifyLog est = id::read_identify_log(dir / "est.csv");
  const std::vector<double> qg = emps_column(dir / "emps_estimation.csv", "qg_m");
  ASSERT_EQ(qg.size(), est.time.size());
  EmpsLoop loop(qg);
  // 1. The loop simulated with the published IDIM-LS model, driven by the reference, against the
  // measured force: the description reports 5.848 % relative error for its Simulink model.
  Eigen::Vector4d published(95.1089, 203.5034, 20.3935, -3.1648);
  std::vector<double> force;
  id::simulate_closed_loop(est.time, loop, 1.0, 0.0, published, false, est.joints[0].reading_values[0], 0.0, 1e-3, &force);
  double num = 0.0, den = 0.0;
  for (std::size_t k = 0; k < force.size(); ++k) {
    num += (force[k] - est.joints[0].drive_values[k]) * (force[k] - est.joints[0].drive_values[k]);
    den += est.joints[0].drive_values[k] * est.joints[0].drive_values[k];
  }
  const double force_error = 100.0 * std::sqrt(num / den);
  std::cout << "EMPS closed-loop simulation with the published model: force relative error " << force_error << " % (published 5.848 %)\n";
  // Measured 5.03 %: the published Simulink model's 5.848 % includes the description's one-sample
  // delay (with it, 6.5 % here). No worse than the published figure, and not better than the
  // inverse model's own residual (4.08 %): the loop simulation adds its drift to it.
  EXPECT_LT(force_error, 5.848 + 0.5);
  EXPECT_GT(force_error, 4.0);
  // 2. IDIM-IV on the same log: instruments from this loop simulated with each estimate.
  id::IdentifyOptions o;
  o.output_error = false;
  o.zero_order_hold = false;
  const auto r = id::identify_joint({{&est.joints[0], &est.time, &loop}}, id::JointPrior{}, {}, o);
  ASSERT_TRUE(r.iv.has_value()) << r.iv_status;
  EXPECT_TRUE(r.iv_converged) << r.iv_status;
  EXPECT_EQ(r.method, "IDIM-IV");
  std::cout << "EMPS IDIM-IV (" << r.iv_status << "): M " << r.iv->value[0] << " +- " << r.iv->sigma[0] << ", Fv " << r.iv->value[1]
            << " +- " << r.iv->sigma[1] << ", Fc " << r.iv->value[2] << " +- " << r.iv->sigma[2] << ", offset " << r.iv->value[3]
            << " +- " << r.iv->sigma[3] << "; force error " << r.estimation_idim.drive_relative_error_percent << " %\n";
  // EMPS's encoder noise is small and its filters remove it, so IDIM-LS is not noticeably biased
  // here and IDIM-IV lands on the published IDIM-LS values too: within 1.5 published sigmas
  // (measured within 0.5), with the same sigmas within 5 %.
  const double ls[4] = {95.1089, 203.5034, 20.3935, -3.1648};
  const double sigma[4] = {0.1085, 1.1460, 0.1012, 0.0444};
  for (int k = 0; k < 4; ++k) {
    EXPECT_NEAR(r.iv->value[k], ls[k], 1.5 * sigma[k]) << r.iv->names[static_cast<std::size_t>(k)];
    EXPECT_NEAR(r.iv->sigma[k], sigma[k], 0.05 * sigma[k]) << r.iv->names[static_cast<std::size_t>(k)];
  }
}

}  // namespace
}  // namespace fivebar

// --rig mechanism: a log of both motors of the assembled lower index mechanism, simulated here with
// the closed chain's own M(theta) and h (fivebar/dynamics.hpp) and each joint's rotor and friction as
// the truth, the torques from a PD about the target centre plus a random multisine. The gear ratio
// is set to 5 so that the links' inertia is not negligible against the rotors': identifying each
// joint alone (without the chain) then misses the truth, with the chain it does not.
namespace fivebar {
namespace {

namespace mech_rig {

struct JointTruth {
  double J, b, c, off;
};

}  // namespace mech_rig

TEST(IdentifyMechanismRig, EachJointsRotorAndFrictionThroughTheClosedChain) {
  using mech_rig::JointTruth;
  Design d = load_design(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  d.get<MotorSettings>()->defaults.gear_ratio = 5.0;
  const Station& st = d.require_station("index");
  const Mechanism& m = *st.mechanism("lower");
  MechanismModel model;
  model.mechanism = m;
  model.inertia = station_inertia(d, st, nullptr, {}).at("lower");
  model.motors = {d.get<MotorSettings>()->joint("index", "lower", 1), d.get<MotorSettings>()->joint("index", "lower", 2)};
  for (auto& mp : model.motors) mp.rotor_inertia_g_cm2 = 0.0;  // the links alone; the rotors are the truth below
  const Pose centre = ik(m, st.target.center);
  ASSERT_EQ(centre.status, Status::ok);
  model.branch = centre.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
  const double links = dynamics_terms(model, Eigen::Vector2d(centre.theta1, centre.theta2), Eigen::Vector2d::Zero()).M(0, 0);
  // Torques in units of the drive's scale (below): friction a few per cent of it.
  const double scale = 10.0 * links;  // N m: about 10 rad/s^2 of the links alone
  const std::array<JointTruth, 2> truth{JointTruth{1.5 * links, 0.02 * scale, 0.05 * scale, 0.02 * scale},
                                        JointTruth{1.2 * links, 0.03 * scale, 0.04 * scale, -0.015 * scale}};

  const char* seed_env = std::getenv("FIVEBAR_TEST_SEED");
  std::mt19937_64 rng(seed_env != nullptr ? std::strtoull(seed_env, nullptr, 10) : 11);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::array<std::array<double, 12>, 2> ph{};
  for (auto& p : ph)
    for (double& x : p) x = phase(rng);
  const double rate = 1000.0, duration = 6.0;
  const int sub = 5;
  const double h = 1.0 / (rate * sub);
  Eigen::Vector2d q(centre.theta1, centre.theta2), w = Eigen::Vector2d::Zero();
  // A gentle PD about the centre (about 1 Hz, damped): the motion stays in the band the filters keep.
  const double kp = 100.0 * links, kd = 22.0 * links;
  id::IdentifyLog log;
  log.path = "mechanism.csv";
  std::array<id::JointLog, 2> jl;
  for (int j = 0; j < 2; ++j) {
    jl[static_cast<std::size_t>(j)].prefix = "index_lower_theta" + std::to_string(j + 1);
    jl[static_cast<std::size_t>(j)].station = "index";
    jl[static_cast<std::size_t>(j)].mechanism = "lower";
    jl[static_cast<std::size_t>(j)].joint = j + 1;
    jl[static_cast<std::size_t>(j)].drive = id::DriveKind::torque;
    jl[static_cast<std::size_t>(j)].drive_column = jl[static_cast<std::size_t>(j)].prefix + "_torque_Nm";
    jl[static_cast<std::size_t>(j)].reading = id::ReadingKind::angle;
    jl[static_cast<std::size_t>(j)].reading_column = jl[static_cast<std::size_t>(j)].prefix + "_theta_rad";
  }
  const auto accel = [&](const Eigen::Vector2d& qq, const Eigen::Vector2d& ww, const Eigen::Vector2d& tau) {
    const DynamicsTerms t = dynamics_terms(model, qq, ww);
    EXPECT_EQ(t.status, Status::ok);
    Eigen::Matrix2d M = t.M;
    Eigen::Vector2d rhs = tau - t.h;
    for (int j = 0; j < 2; ++j) {
      const JointTruth& tr = truth[static_cast<std::size_t>(j)];
      M(j, j) += tr.J;
      rhs[j] -= tr.b * ww[j] + tr.c * std::tanh(ww[j] / 1e-3) + tr.off;
    }
    return Eigen::Vector2d(M.ldlt().solve(rhs));
  };
  const double count = 2.0 * std::numbers::pi / 65536.0;
  for (int n = 0; n < static_cast<int>(duration * rate); ++n) {
    const double t = n / rate;
    Eigen::Vector2d tau;
    for (int j = 0; j < 2; ++j) {
      double s = 0.0;
      for (int k = 1; k <= 12; ++k) s += std::sin(2.0 * std::numbers::pi * 0.5 * k * t + ph[static_cast<std::size_t>(j)][static_cast<std::size_t>(k - 1)]);
      const double ref = j == 0 ? centre.theta1 : centre.theta2;
      tau[j] = kp * (ref - q[j]) - kd * w[j] + scale * s / std::sqrt(6.0);
    }
    log.time.push_back(t);
    for (int j = 0; j < 2; ++j) {
      jl[static_cast<std::size_t>(j)].drive_values.push_back(tau[j] + 0.002 * scale * noise(rng));
      jl[static_cast<std::size_t>(j)].reading_values.push_back(std::round(q[j] / count) * count);
    }
    for (int k = 0; k < sub; ++k) {  // RK4, the torque held over the sample
      const Eigen::Vector2d a1 = accel(q, w, tau);
      const Eigen::Vector2d a2 = accel(q + 0.5 * h * w, w + 0.5 * h * a1, tau);
      const Eigen::Vector2d a3 = accel(q + 0.5 * h * (w + 0.5 * h * a1), w + 0.5 * h * a2, tau);
      const Eigen::Vector2d a4 = accel(q + h * (w + 0.5 * h * a2), w + h * a3, tau);
      q += h / 6.0 * (w + 2.0 * (w + 0.5 * h * a1) + 2.0 * (w + 0.5 * h * a2) + (w + h * a3));
      w += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
    }
  }
  log.joints = {jl[0], jl[1]};
  id::IdentifyOptions o;
  const auto results = id::identify_mechanism(d, log, "index", "lower", o);
  ASSERT_EQ(results.size(), 2u);
  for (int j = 0; j < 2; ++j) {
    SCOPED_TRACE("theta" + std::to_string(j + 1));
    const auto& r = results[static_cast<std::size_t>(j)];
    const JointTruth& tr = truth[static_cast<std::size_t>(j)];
    const std::array<double, 4> want{tr.J, tr.b, tr.c, tr.off};
    for (int k = 0; k < 4; ++k) {
      ASSERT_TRUE(r.idim.identified[static_cast<std::size_t>(k)]) << r.idim.names[static_cast<std::size_t>(k)];
      EXPECT_LE(std::abs(r.idim.value[k] - want[static_cast<std::size_t>(k)]), 3.0 * r.idim.sigma[k])
          << r.idim.names[static_cast<std::size_t>(k)] << " = " << r.idim.value[k] << " +- " << r.idim.sigma[k] << ", truth " << want[static_cast<std::size_t>(k)];
    }
    EXPECT_GT(r.estimation_idim.drive_fit_percent, 90.0);
    // Alone (no closed chain), the joint's inertia takes the links' share and misses the truth.
    id::JointPrior alone = id::joint_prior(d, "index", "lower", j + 1, 0.0, false);
    o.output_error = false;
    const auto single = id::identify_joint(log.joints[static_cast<std::size_t>(j)], log.time, alone, nullptr, nullptr, o);
    EXPECT_GT(std::abs(single.idim.value[0] - tr.J), 3.0 * single.idim.sigma[0]) << single.idim.value[0];
  }
}

// docs/reliability.md's rule for the identification: 20 million rows of one joint (inside the
// log's row bound) are estimated past 2 GB and refused with the estimate unless confirmed; a
// bench-sized log is not. The rate is the measured one (estimates.hpp): 2e7 x 170 B = 3.4 GB.
TEST(IdentifyBudget, TheLogSizeLimitIsNotAMemoryBoundTheEstimateIs) {
  const ResourceEstimate big = identify_estimate(20'000'000, 1);
  EXPECT_NEAR(big.memory_bytes, 20e6 * kIdentifyBytesPerRowJoint, 1.0);
  EXPECT_GT(big.memory_bytes, kConfirmMemoryBytes);
  try {
    check_budget(big, false, "confirm with fivebar identify --yes");
    ADD_FAILURE() << "20 million rows were not refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("the identification (20000000 log rows of 1 joint) is large"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("3.4 GB of memory"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--yes"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(check_budget(big, true, ""));
  EXPECT_NO_THROW(check_budget(identify_estimate(100'000, 4), false, ""));
}

}  // namespace
}  // namespace fivebar

// --- The quality gate between a fit and the design (fivebar/identify/patch.hpp) -------------------

namespace fivebar {
namespace {

/// A hand-made identification of the bench motor: each key's value and sigma as given, every drive
/// fit `fit_percent`.
id::JointIdentification hand_fit(double fit_percent, const std::vector<std::array<double, 2>>& rotor_viscous_coulomb) {
  id::JointIdentification r;
  r.joint = "motor";
  r.estimation_idim.drive_fit_percent = fit_percent;
  const char* keys[] = {"motor.rotor_inertia_g_cm2", "motor.viscous_friction_mNm_s_per_rad", "motor.coulomb_friction_mNm"};
  for (std::size_t i = 0; i < rotor_viscous_coulomb.size(); ++i) {
    r.parameters.push_back({keys[i], rotor_viscous_coulomb[i][0], rotor_viscous_coulomb[i][1], true, ""});
  }
  r.parameters.push_back({"motor.terminal_resistance_ohm", 5.0, 0.0, false, "held at its prior"});
  return r;
}

MeasurementSource hand_source() { return {"bench.csv", std::string(64, 'a'), "2026-11-29", "fivebar identify (test)"}; }

TEST(IdentifyGate, AKeyTheLogDoesNotDetermineStaysAnAssumptionAndTheOthersAreTrusted) {
  const Design d = load_design(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  // Viscous friction 0.19 +- 0.16 (84 %): above the 50 % bound. The others within it.
  const id::Patch p = id::patch_design(d, {hand_fit(89.6, {{{0.59, 0.004}}, {{0.19, 0.16}}, {{0.83, 0.10}}})}, hand_source(), false);
  EXPECT_TRUE(p.gate.reasons.empty());
  EXPECT_EQ(p.patched, (std::vector<std::string>{"motor.rotor_inertia_g_cm2", "motor.coulomb_friction_mNm"}));
  ASSERT_EQ(p.not_patched.size(), 1u);
  EXPECT_NE(p.not_patched[0].find("motor.viscous_friction_mNm_s_per_rad"), std::string::npos) << p.not_patched[0];
  EXPECT_NE(p.not_patched[0].find("84 % of the value (bound 50 %)"), std::string::npos) << p.not_patched[0];
  ASSERT_TRUE(p.design.has_value());
  const MotorParams m = p.design->get<MotorSettings>()->defaults;
  EXPECT_EQ(m.rotor_inertia_g_cm2, 0.59);
  EXPECT_EQ(m.coulomb_friction_mNm, 0.83);
  EXPECT_EQ(m.viscous_friction_mNm_s_per_rad, d.get<MotorSettings>()->defaults.viscous_friction_mNm_s_per_rad);
  // What export's require_measured reads: the written keys carry a passed gate, the skipped one none.
  EXPECT_TRUE(is_measured(*p.design, "motor.coulomb_friction_mNm"));
  EXPECT_FALSE(is_measured(*p.design, "motor.viscous_friction_mNm_s_per_rad"));
  std::vector<std::string> untrusted;
  for (const UntrustedValue& u : untrusted_values(*p.design, "motor", {})) untrusted.push_back(u.key);
  EXPECT_EQ(std::count(untrusted.begin(), untrusted.end(), "motor.coulomb_friction_mNm"), 0);
  EXPECT_EQ(std::count(untrusted.begin(), untrusted.end(), "motor.rotor_inertia_g_cm2"), 0);
  const auto& e = p.design->get<ProvenanceSettings>()->entries.at("motor.coulomb_friction_mNm");
  ASSERT_TRUE(e.gate.has_value());
  EXPECT_TRUE(e.gate->passed);
  EXPECT_NE(e.gate->tests.find("drive fit 89.6 %"), std::string::npos) << e.gate->tests;
}

TEST(IdentifyGate, ADriveFitBelowTheFloorWritesNothing) {
  const Design d = load_design(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  // Two joints, one below the floor: the fit is refused as a whole.
  id::JointIdentification good = hand_fit(95.0, {{{0.59, 0.004}}});
  id::JointIdentification bad = hand_fit(79.9, {{{0.61, 0.004}}});
  bad.joint = "other";
  const id::Patch p = id::patch_design(d, {good, bad}, hand_source(), false);
  EXPECT_FALSE(p.gate.passed);
  ASSERT_EQ(p.gate.reasons.size(), 1u);
  EXPECT_NE(p.gate.reasons[0].find("joint other: drive fit 79.9 %"), std::string::npos) << p.gate.reasons[0];
  EXPECT_FALSE(p.design.has_value());
  EXPECT_TRUE(p.patched.empty());
  EXPECT_EQ(p.not_patched.size(), 2u);
  // With a validation log the gate reads its fit, not the estimation log's.
  bad.validation_idim = id::Fit{};
  bad.validation_idim->drive_fit_percent = 90.0;
  EXPECT_TRUE(id::patch_design(d, {good, bad}, hand_source(), false).gate.reasons.empty());
  bad.estimation_idim.drive_fit_percent = 99.0;
  bad.validation_idim->drive_fit_percent = 50.0;
  EXPECT_FALSE(id::patch_design(d, {good, bad}, hand_source(), false).gate.reasons.empty());
}

TEST(IdentifyGate, TheOutputErrorValuesNeedTheirSolverToHaveConverged) {
  const Design d = load_design(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  id::JointIdentification r = hand_fit(95.0, {{{0.59, 0.004}}});
  r.estimation_oe.drive_fit_percent = 95.0;
  r.output_error_status = "NO_CONVERGENCE: maximum number of iterations reached";
  const id::Patch p = id::patch_design(d, {r}, hand_source(), true);
  EXPECT_FALSE(p.gate.solver.converged);
  EXPECT_FALSE(p.design.has_value());
  // IDIM-LS's values do not rest on that solver.
  EXPECT_TRUE(id::patch_design(d, {r}, hand_source(), false).design.has_value());
  r.output_error_status = "converged";
  EXPECT_TRUE(id::patch_design(d, {r}, hand_source(), true).design.has_value());
}

}  // namespace
}  // namespace fivebar
