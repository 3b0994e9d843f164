#pragma once
/// One SUNDIALS integrator behind a small interface, so that simulate()'s sample loop
/// (lib/src/simulate/cvode.cpp) drives CVODE BDF or ARKODE ERK alike. Private to the library; the
/// implementations are the only files that include SUNDIALS: lib/src/simulate/cvode.cpp (BDF) and
/// lib/src/simulate/arkode.cpp (explicit Runge-Kutta).

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "simulate/system.hpp"

namespace fivebar::dynamics_detail {

enum class StepOutcome {
  ok,           ///< one internal step taken (or the stop time reached)
  root,         ///< a stick/slip root found: root_info() says which
  rhs_failure,  ///< the right-hand side failed repeatedly (a singular pose)
  failure,      ///< error test or convergence failures at the minimum step
};

class Stepper {
 public:
  virtual ~Stepper() = default;
  /// The state (n values), read and written by the caller between steps.
  virtual double* y() = 0;
  /// Restart from y() at t, integrating no further than t_stop, with these root directions
  /// (empty when root finding is off).
  virtual void restart(double t, double t_stop, const std::vector<int>& root_directions) = 0;
  /// One internal step towards t_stop; `t` receives the time reached.
  virtual StepOutcome step(double t_stop, double& t) = 0;
  /// Which root functions vanished at the last root return (n_roots values, +-1 or 0).
  virtual void root_info(std::vector<int>& found) = 0;
  /// The integrator's dense output at time t within the last step, into out (n values); false
  /// when t lies outside it.
  virtual bool interpolate(double t, double* out) = 0;
  /// The solver's last error message.
  virtual const std::string& message() const = 0;
};

/// CVODE BDF (orders 1-5), Newton iterations, dense direct solver (difference-quotient Jacobian).
std::unique_ptr<Stepper> make_bdf(System& system, std::size_t n, double rtol, const std::vector<double>& atol,
                                  int n_roots);
/// ARKODE ERKStep with the Dormand-Prince 5(4) table (7 stages, FSAL), embedded error estimate.
std::unique_ptr<Stepper> make_erk(System& system, std::size_t n, double rtol, const std::vector<double>& atol,
                                  int n_roots);

}  // namespace fivebar::dynamics_detail
