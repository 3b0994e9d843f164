#pragma once
// Private to lib/src/identify/: the output-error refinement (Ceres stays inside ceres_output_error.cpp).

#include <string>
#include <vector>

#include "fivebar/identify/identify.hpp"

namespace fivebar::identify_detail {

/// One open-loop log for the refinement: its time, drive torque input, logged position and start.
struct Series {
  const std::vector<double>* time;
  const std::vector<double>* u;
  const std::vector<double>* q;
  double q0, w0;
};

/// Minimises sum (q_k - qhat_k)^2 over every log and the identified mechanical parameters, qhat from
/// identify::simulate_position; held parameters stay at `start`. Returns the estimate (sigma from
/// the Jacobian at the optimum, s^2 (J^T J)^-1) and sets `status`.
identify::Estimate output_error(const std::vector<Series>& logs, double g, const identify::Estimate& start, bool per_direction,
                                double coulomb_smoothing, std::string& status);

}  // namespace fivebar::identify_detail

namespace fivebar::identify_detail {

/// The winding's first-order lag tau = L / R seen over one sample dt of a zero-order-held voltage
/// (lib/src/identify/electrical.cpp): with s_k the current the sample's voltage tends to,
/// i_k+1 = a i_k + (1 - a) s_k and the current's mean over the sample is s_k + (i_k - s_k) phi.
struct ElectricalLag {
  double a = 0.0;       ///< exp(-dt / tau)
  double phi = 0.0;     ///< (tau / dt)(1 - a)
  double lambda = 1.0;  ///< where in the sample (0 start, 1 end) the speed the current at its end sees lies
};
ElectricalLag electrical_lag(double tau, double dt);
/// The mean over each sample of the lagged response (unit DC gain) to `x` held over the sample, from
/// steady state: applied to the voltage and to the speed, the mean current a voltage drive gives.
std::vector<double> lagged_mean(const std::vector<double>& x, const ElectricalLag& lag);
/// The mean current over each sample from the sampled current (the last sample: its own value).
std::vector<double> sampled_current_mean(const std::vector<double>& i, const ElectricalLag& lag);
/// The winding (R, L, k_e N) from the sampled-current regression i_k+1 = a i_k + b V_k - c w_k
/// (`arx` over a, b, c), by the delta method; `a_free` false: a was held at `a_held` and L is held
/// with `held_note`.
identify::Estimate winding_estimate(const identify::Estimate& arx, double dt, bool a_free, double a_held,
                                    const std::string& held_note);

}  // namespace fivebar::identify_detail
