#pragma once
/// `fivebar identify --plan`: an excitation for the motor rig (docs/identify.md "Planning"): a
/// multisine position reference with Schroeder phases (low crest factor), scaled into the joint's
/// range, speed limit and current limit under the prior model, with the standard deviations the
/// inverse-model fit is expected to give (from the information matrix W^T W / s^2 at a stated drive
/// noise).

#include <Eigen/Dense>

#include <string>
#include <vector>

#include "fivebar/identify/model.hpp"

namespace fivebar::identify {

struct PlanOptions {
  double duration_s = 10.0;
  double sample_rate_hz = 1000.0;
  double f_min_hz = 0.2;        ///< lowest harmonic (the period is 1 / f_min)
  double f_max_hz = 5.0;        ///< highest harmonic
  double range_lo = -1.0, range_hi = 1.0;  ///< joint range, rad
  double max_speed = 6.283185307179586;    ///< rad/s
  double current_limit = 1.0;   ///< A (the motor's driver)
  double drive_noise = 0.01;    ///< sigma of the logged drive torque, N m (an assumption the caller states)
  /// The reading's quantum, rad (the potentiometer through the ADC: rad_per_volt x range / 2^bits);
  /// its uniform rounding error, variance q^2 / 12, enters the fit through the filtered derivatives.
  double angle_quantum = 0.0;
  /// Fade-in and fade-out, s: the multisine rises from rest (position at the centre, speed and
  /// acceleration zero) and returns to it, each over this time (at most a quarter of the duration).
  double fade_s = 1.0;
  int decimation = 10;
  bool per_direction = false;
};

struct ExcitationPlan {
  std::vector<double> time, position, velocity, acceleration, current, duty;
  double scale = 0.0;            ///< amplitude factor applied to the unit multisine
  std::string limited_by;        ///< "range", "speed" or "current"
  std::vector<std::string> names;   ///< mechanical_names()
  Eigen::VectorXd truth;         ///< the priors the sigmas are computed at
  Eigen::VectorXd expected_sigma;
  double expected_residual = 0.0;  ///< s of the fit: the drive noise and the quantisation after the filters, N m
  double quantisation_share = 0.0; ///< of s^2, the quantisation's
  double fade_s = 0.0;           ///< the fade applied
  int edge_samples = 0;          ///< left out of the predicted fit at each end, as identify does
  double crest_factor = 0.0;
};

/// InputError on a bad option (naming the flag).
ExcitationPlan plan_excitation(const JointPrior& prior, const PlanOptions& options);

}  // namespace fivebar::identify
