#pragma once
// Private to lib/src/identify/: the output-error refinement (Ceres stays inside ceres_output_error.cpp).

#include <string>
#include <vector>

#include "fivebar/identify/identify.hpp"

namespace fivebar::identify_detail {

/// Minimises sum (q_k - qhat_k)^2 over the identified mechanical parameters, qhat from
/// identify::simulate_position; held parameters stay at `start`. Returns the estimate (sigma from
/// the Jacobian at the optimum, s^2 (J^T J)^-1) and sets `status`.
identify::Estimate output_error(const std::vector<double>& time, const std::vector<double>& u, double g,
                                const std::vector<double>& q, const identify::Estimate& start, bool per_direction,
                                double q0, double w0, double coulomb_smoothing, std::string& status);

}  // namespace fivebar::identify_detail
