#pragma once
/// The right-hand side of the simulated station (fivebar/dynamics.hpp "Model"), free of SUNDIALS:
/// lib/src/simulate/cvode.cpp integrates it. Private to the library.
///
/// State per mechanism k, at offset kStateSize k: theta1, theta2 (rad), w1, w2 (rad/s),
/// i1, i2 (A), anchor x, y (m).

#include <array>
#include <cstddef>
#include <vector>

#include "fivebar/dynamics.hpp"

namespace fivebar::dynamics_detail {

inline constexpr std::size_t kStateSize = 8;

struct System {
  const SimulationInput* input = nullptr;
  const SimulationOptions* options = nullptr;
  std::vector<std::array<double, 2>> duty;  ///< held over the current period, per mechanism
  std::vector<char> slipping;               ///< contact mode per mechanism
  /// Switched PWM (SimulationOptions::pwm): per mechanism and joint, the bridge on (sign(duty)
  /// V_supply) or off (0 V) over the current segment between two switching instants.
  std::vector<std::array<bool, 2>> on;
  /// Switched PWM: the driver's current limiter holding |i| at I_max in this on-phase (entered at
  /// a root of sign(duty) i - I_max, left at the phase's end).
  std::vector<std::array<bool, 2>> limiting;
  bool contact_roots = false;  ///< one stick/slip root function per mechanism
  bool limit_roots = false;    ///< switched PWM: one limiter root function per joint
  double k = 0.0;      ///< N/m
  double c = 0.0;      ///< N s/m
  double limit = 0.0;  ///< mu N, N
  bool last_failure_singular = false;  ///< the last failed evaluation was a singular pose
  std::size_t evaluations = 0;  ///< right-hand sides evaluated by the integrator
  std::size_t mechanisms() const { return input->mechanisms.size(); }
};

/// One mechanism evaluated at a state.
struct Evaluation {
  bool ok = false;
  DynamicsTerms terms;
  std::array<double, 2> voltage{0.0, 0.0};
  std::array<bool, 2> saturated{false, false};  ///< |duty| >= 1 or the current limit acting
  Vec2 force{0.0, 0.0};                         ///< skin force on the tactor, N
  std::array<double, kStateSize> dy{};
};

System make_system(const SimulationInput& input, const SimulationOptions& options);
/// Mechanism `k` of the state vector `y` (all mechanisms).
Evaluation evaluate(System& s, std::size_t k, const double* y);
/// dy/dt of the whole state; false when a pose is singular or unreachable (CVODE retries).
bool rhs(System& s, const double* y, double* dy);
/// Number of root functions: per mechanism the stick/slip switch (contact on), then (switched PWM)
/// one per joint for the current limiter's onset.
int root_count(const System& s);
/// Root function `r` belongs to mechanism k and, for a limiter root, joint j (-1: the contact's).
struct RootOwner {
  std::size_t k = 0;
  int joint = -1;
};
RootOwner root_owner(const System& s, std::size_t r);
/// The switching functions in the order above.
void roots(System& s, const double* y, double* g);
/// Root directions for the current modes: contact +1 (sticking: the spring force reaches mu N),
/// -1 (sliding: the tactor turns back); limiter +1 (|i| reaching I_max).
std::vector<int> root_directions(const System& s);
/// Switched PWM: at the start of a segment, a joint whose bridge is on and whose current is
/// already at or beyond the limit starts limited; every other joint not.
void reset_limiters(System& s, const double* y);

}  // namespace fivebar::dynamics_detail
