#pragma once
/// Manufacturing tolerance and sensing error of a five-bar (issue 17, first slice): how far the
/// printed device's tactor can be from where the controller believes it is.
///
/// The controller computes the joint angles by the nominal IK and drives the motors there; the
/// printed device, whose lengths, base positions and joint angle offsets differ from the design,
/// then puts the tactor at FK_printed(theta_nominal). Ten parameters q are perturbed, in the order
/// of ToleranceParameter: L1, L2, L3, L4 (mm), O1x, O1y, O2x, O2y (mm), theta1, theta2 (rad, the
/// offset of the true joint angle from the one the controller believes).
///
/// First order, closed form. Each leg closes the loop
///   P = A_i + L_{i+2} u_i,   A_i = O_i + L_i e(theta_i),   u_i = e(phi_i) = (P - A_i) / L_{i+2},
/// with e(a) = (cos a, sin a) and e'(a) = (-sin a, cos a). Differentiating,
///   dP = dO_i + dL_i e(theta_i) + L_i e'(theta_i) dtheta_i + dL_{i+2} u_i + L_{i+2} e'(phi_i) dphi_i.
/// The distal angle phi_i is unknown; u_i . e'(phi_i) = 0 eliminates it: dotting with u_i,
///   u_i . dP = u_i . dO_i + (u_i . e(theta_i)) dL_i + L_i cross(e(theta_i), u_i) dtheta_i + dL_{i+2},
/// (cross(a, b) = a_x b_y - a_y b_x), one row per leg: the 2x2 system M dP = R dq with
/// M = [u_1^T; u_2^T]. det M = cross(u_1, u_2) is the sine of the tactor angle, so M is singular
/// exactly on the type II singularity (distal links collinear); there the first-order model breaks
/// down and a Status says so. Sensitivity S = dP/dq = M^{-1} R (2x10), checked against central
/// finite differences of fk() in test/test_tolerance.cpp.
///
/// With independent parameter errors of standard deviations sigma_j, the tactor covariance is
/// C = S diag(sigma^2) S^T; the 3-sigma ellipse has semi-axes 3 sqrt(eig(C)); the worst case puts
/// every parameter at the edge of its +-3 sigma band with the worst sign,
/// sum_j |S_j| 3 sigma_j, which bounds the 3-sigma ellipse's major semi-axis (triangle inequality).
/// The resolution is the tactor step of one ADC count on one joint: max_i |J_i| dtheta_count.

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>

#include "fivebar/design.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/sections/tolerance.hpp"

namespace fivebar {

/// The perturbed parameters, in the column order of the sensitivity matrix.
enum class ToleranceParameter : std::uint8_t { L1, L2, L3, L4, O1x, O1y, O2x, O2y, theta1, theta2 };
inline constexpr std::size_t kToleranceParameters = 10;
/// Standard deviation of each parameter (mm for lengths and positions, rad for angles), >= 0.
using ParameterSigmas = std::array<double, kToleranceParameters>;
using SensitivityMatrix = Eigen::Matrix<double, 2, static_cast<int>(kToleranceParameters)>;

/// Names of the parameters ("L1", ..., "theta2"), in ToleranceParameter order.
const std::array<const char*, kToleranceParameters>& tolerance_parameter_names();

/// dP/dq at a tactor point in the mechanism's working mode.
struct Sensitivity {
  Status status = Status::unreachable;  ///< ik()'s status; S and pose fields zero unless ok
  Pose pose;                            ///< the nominal configuration (from ik())
  SensitivityMatrix S = SensitivityMatrix::Zero();  ///< mm per mm, mm per rad
};

/// First-order tolerance figures at one tactor point.
struct ToleranceEstimate {
  Status status = Status::unreachable;  ///< not ok: every other field is zero
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();  ///< mm^2
  Vec2 ellipse_semi_axes{0.0, 0.0};  ///< 3-sigma semi-axes, major first, mm
  double ellipse_angle = 0.0;        ///< direction of the major axis, rad, in (-pi/2, pi/2]
  double worst_case_mm = 0.0;        ///< sum_j |S_j| * 3 sigma_j, mm
  double resolution_um = 0.0;        ///< tactor step of one count on the worse joint, micrometres
};

/// Closed-form sensitivity of the tactor to the ten parameters at P (derivation above).
/// Status is ik()'s: not ok (unreachable or within tol::kSingularSin of a singularity) gives zeros.
Sensitivity tolerance_sensitivity(const Mechanism& m, const Vec2& P);

/// Standard deviations of the ten parameters from a `tolerance:` section: a link's pin-centre
/// distance moves with its length error and with the along-link component of each of its two
/// holes' position errors, sqrt(link^2 + 2 pin^2); base positions by base_sigma_mm per axis; the
/// joint angle offsets by angle_sigma_deg (converted to rad).
ParameterSigmas parameter_sigmas(const ToleranceSettings& settings);

/// Joint angle of one ADC count (rad) when `bits` resolve one full turn: 2 pi / 2^bits.
/// Precondition: 1 <= bits <= 32.
double angle_per_count(int bits);

/// First-order covariance, 3-sigma ellipse, worst case and resolution at P for the given sigmas
/// and joint angle per ADC count (rad). Status as tolerance_sensitivity().
ToleranceEstimate tolerance_first_order(const Mechanism& m, const Vec2& P, const ParameterSigmas& sigma,
                                        double rad_per_count);

/// Monte Carlo reference: `samples` printed devices, each parameter drawn independently from
/// N(0, sigma_j) by std::mt19937_64 seeded with `seed` (deterministic for a seed on one standard
/// library); each device's tactor is its FK at the nominal IK angles on the nominal assembly branch.
struct MonteCarloTolerance {
  Status status = Status::unreachable;  ///< nominal ik()'s status; zeros unless ok
  std::size_t used = 0;     ///< samples whose perturbed FK was reachable and regular
  std::size_t failed = 0;   ///< samples whose perturbed device cannot reach (or is singular)
  Vec2 mean_error{0.0, 0.0};                             ///< mean of P_printed - P, mm
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();  ///< sample covariance (n - 1), mm^2
};
MonteCarloTolerance tolerance_monte_carlo(const Mechanism& m, const Vec2& P, const ParameterSigmas& sigma,
                                          std::size_t samples, std::uint64_t seed);

}  // namespace fivebar
