#pragma once
/// Controller validation: the sampled-data loop of one mechanism linearised at a pose,
/// discretised exactly, closed by the exported PID with one period of delay, and its spectral
/// radius over the target ellipse (the stability map), with margins on the gains.
///
/// Units inside: SI (m, kg, s, rad, N, V, A), as fivebar/dynamics.hpp; results carry mm at the edges.
///
/// Linearised plant (continuous time)
/// ----------------------------------
/// The model of fivebar/dynamics.hpp ("Model") at an equilibrium: joint angles theta*, w = 0,
/// i = 0, duty 0, the skin anchored at the tactor (a = P(theta*), contact in stick). State
/// x = (dtheta1, dtheta2, w1, w2, i1, i2) (deviations), input u = (duty1, duty2):
///   dtheta/dt = w
///   M dw/dt   = -K_s dtheta - (C_s + B_v + B_emf) w + K_t i      (B_emf enters through di/dt below)
///   L_j di_j/dt = V_s,j u_j - R_j i_j - k_e,j N_j w_j
/// with K_s = k J^T J and C_s = c J^T J the skin's stiffness and damping mapped through the
/// Jacobian J = dP/dtheta (F = -k (P - a) - c dP/dt, tau = J^T F: its derivative at P = a, where
/// F = 0 so that dJ/dtheta does not enter), B_v = diag(b_j) the viscous friction, K_t =
/// diag(eta_j N_j k_t,j). At w = 0 the Coriolis term h(theta, w) is quadratic in w and drops out,
/// and with zero torque dM/dtheta does not enter either: these are the exact first derivatives of
/// the right-hand side (checked against its central finite differences in test/test_control.cpp).
/// Coulomb friction is left out: its smoothed sign tanh(w / w_s) has a slope tau_c / w_s at
/// w = 0 that is a regularisation of a relay, not a damper; dropping it is the conservative choice
/// for a linear stability verdict (it only dissipates while a joint moves). The driver's voltage
/// and current limits and the ADC quantisation are nonlinear and are not in the linear model
/// either (a small-signal verdict; `simulate()` has them).
///
/// Exact discretisation under zero-order hold (e.g. Franklin, Powell & Workman, "Digital Control
/// of Dynamic Systems", 3rd ed., 1998, the ZOH equivalent): with T = 1 / loop_rate_hz,
///   exp([A B; 0 0] T) = [Ad Bd; 0 I],   Ad = e^{AT},  Bd = int_0^T e^{As} ds B,
/// by Eigen's matrix exponential (unsupported/MatrixFunctions: scaling and squaring with Pade).
///
/// Closed loop, as the device samples (fivebar/dynamics.hpp "Controller", DiscretePid): at t_k the
/// error e_k = -dtheta_k (regulation about the pose), the integral s_k = s_{k-1} + T e_k, the
/// backward difference d_k = (e_k - e_{k-1}) / T and duty_k = kp e_k + ki s_k + kd d_k per joint;
/// duty_k is applied over [t_{k+1}, t_{k+2}) (one period of computation delay). The loop state
/// z = (x, u, s, e_prev) (6 + 2 + 2 + 2 = 12) then evolves as
///   x_{k+1} = Ad x_k + Bd u_k,   u_{k+1} = duty_k,   s_{k+1} = s_k + T e_k,   e_prev_{k+1} = e_k,
/// so z_{k+1} = Phi z_k, and the loop is asymptotically stable iff the spectral radius
/// rho(Phi) = max |eig(Phi)| < 1. (The integral clamp and the duty clamp are inactive for small
/// signals.) The dominant pole z* (largest modulus) maps to s* = ln(z*) / T, its damping ratio
/// zeta = -Re(s*) / |s*| and frequency |Im(s*)| / (2 pi); the least damped
/// complex pole is reported beside it (with an integral term the dominant pole is often the slow
/// real pole of the integrator, ~exp(-(ki / kp) T)).

#include <Eigen/Core>

#include <array>
#include <complex>
#include <functional>
#include <map>
#include <string_view>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/json.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/rendered_plot.hpp"
#include "fivebar/sections/contact.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/workspace/region.hpp"

namespace fivebar {

/// Poses per axis of the grid over each target on which `fivebar export` checks the loop's
/// stability, and on which the tuner constrains it (the same poses, so that a tuned loop passes).
inline constexpr int kControlGateGrid = 21;

inline constexpr int kPlantStates = 6;   ///< dtheta1, dtheta2, w1, w2, i1, i2
inline constexpr int kLoopStates = 12;   ///< plant, held duty (2), integral (2), previous error (2)
using PlantMatrix = Eigen::Matrix<double, kPlantStates, kPlantStates>;
using PlantInput = Eigen::Matrix<double, kPlantStates, 2>;
using LoopMatrix = Eigen::Matrix<double, kLoopStates, kLoopStates>;

/// The continuous linear model at one pose (above).
struct LinearPlant {
  Status status = Status::unreachable;  ///< dynamics_terms()' status; matrices zero unless ok
  PlantMatrix A = PlantMatrix::Zero();
  PlantInput B = PlantInput::Zero();     ///< per unit duty
  Eigen::Matrix2d M = Eigen::Matrix2d::Zero();  ///< kg m^2
  Eigen::Matrix2d J = Eigen::Matrix2d::Zero();  ///< dP/dtheta, m/rad
  Eigen::Vector2d theta = Eigen::Vector2d::Zero();
  Vec2 P_mm{0.0, 0.0};
};

/// The linear model of `model` at joint angles `theta` (rad); `contact` null: no skin (free tactor).
LinearPlant linear_plant(const MechanismModel& model, const Eigen::Vector2d& theta, const ContactSettings* contact);

/// ZOH equivalent of dx/dt = A x + B u at period T (any sizes): {Ad, Bd}.
std::array<Eigen::MatrixXd, 2> zoh(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, double period_s);

/// The ZOH equivalent of a plant.
struct DiscretePlant {
  PlantMatrix Ad = PlantMatrix::Identity();
  PlantInput Bd = PlantInput::Zero();
  double period_s = 0.0;
};
DiscretePlant discretise(const LinearPlant& plant, double period_s);

/// Phi of the closed loop (state order above). `delay` false: the duty is applied at the sample it
/// is computed at (the u rows then only record it).
LoopMatrix closed_loop(const DiscretePlant& plant, const std::array<PidGains, 2>& gains, bool delay = true);

/// The pole of largest modulus and what it means.
struct LoopPoles {
  double rho = 0.0;                     ///< spectral radius
  std::complex<double> dominant{0.0, 0.0};
  double damping = 1.0;                 ///< zeta of the dominant pole (1 for rho = 0; negative when rho > 1)
  double frequency_hz = 0.0;            ///< |Im ln(z*)| / (2 pi T)
  /// The least damped of the complex poles (an oscillation; the dominant pole is often the
  /// integrator's slow real one): its zeta and frequency; 1 and 0 when every pole is real.
  double oscillatory_damping = 1.0;
  double oscillatory_frequency_hz = 0.0;
};
LoopPoles loop_poles(const LoopMatrix& phi, double period_s);

// --- One mechanism's loop from a design -----------------------------------------------------------

/// What the loop of one mechanism needs.
struct LoopModel {
  std::string station;
  MechanismModel model;
  std::array<PidGains, 2> gains;  ///< joint 1, joint 2
  double period_s = 0.01;
  bool contact = true;            ///< skin in stick at the tactor
  ContactSettings skin;
  bool delay = true;
};

/// The loop models of every mechanism of `station` (lower first): `motor:` and `controller:` of the
/// design with their overrides, `contact:` (or its defaults), masses from `inertia` by mechanism
/// name. InputError naming a missing section (as simulation_inputs()).
std::vector<LoopModel> loop_models(const Design& design, const Station& station,
                                   const std::map<std::string, MechanismInertia>& inertia);

/// rho and the poles at one pose, for a plant discretised once (gains vary, the plant does not).
struct PoseLoop {
  Vec2 P_mm{0.0, 0.0};
  Status status = Status::unreachable;  ///< ik()/dynamics status: not ok has no poles
  DiscretePlant plant;
  LoopPoles poles;
};

/// The discretised plant and poles at tactor point P (mm) in the working mode.
PoseLoop pose_loop(const LoopModel& loop, const Vec2& P_mm);

/// Points of an n x n lattice over the filled ellipse's bounding box (its own frame) that lie inside
/// it; n odd includes the centre. (ellipse_grid(), fivebar/collision.hpp, takes a spacing in mm.)
std::vector<Vec2> ellipse_lattice(const Ellipse& e, int n);

}  // namespace fivebar
