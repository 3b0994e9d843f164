#pragma once
/// The calibration model of one station (docs/calibrate.md "Model"): the parameters of its
/// mechanisms and of the measuring instrument, the predicted measurement of a pose and its
/// closed-form Jacobian.
///
/// Per mechanism twelve parameters, in this order: L1, L2, L3, L4 (mm); O1 x, y (mm, station
/// frame); O2 - O1 x, y (mm); per joint j the potentiometer's volts_at_zero V0_j (V) and
/// rad_per_volt k_j (rad/V), theta_j = k_j (V_j - V0_j) (fivebar/sections/controller.hpp). Per
/// station three instrument parameters (the planar pose of the instrument's frame in the station
/// frame): rotation phi (rad) and translation t (mm); the instrument reads
///   y = R(phi) P(theta) + t,
/// P the tactor by FK in the mechanism's assembly mode (fivebar/kinematics.hpp fk()).
///
/// Jacobian. With u_i = (P - A_i)/L_{i+2} and M = [u_1^T; u_2^T], the loop closure gives
/// M dP = R dq (fivebar/tolerance.hpp, the derivation of tolerance_sensitivity()), one row per leg:
/// u_i . dO_i + (u_i . e(theta_i)) dL_i + L_i cross(e(theta_i), u_i) dtheta_i + dL_{i+2}.
/// O2 = O1 + d, so dP/dO1 = I and dP/dd = M^{-1} [0; u_2^T]; dtheta_j/dV0_j = -k_j and
/// dtheta_j/dk_j = V_j - V0_j. Then dy/dq = R(phi) dP/dq, dy/dphi = R'(phi) P, dy/dt = I.

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/kinematics.hpp"

namespace fivebar::calibrate {

inline constexpr int kMechanismParameters = 12;
inline constexpr int kFrameParameters = 3;
using MechanismVector = Eigen::Matrix<double, kMechanismParameters, 1>;
using FrameVector = Eigen::Vector3d;  ///< phi (rad), t x, t y (mm)

/// Short names of the twelve mechanism parameters ("L1", ..., "O1x", "O1y", "O2x", "O2y",
/// "theta1.volts_at_zero", "theta1.rad_per_volt", "theta2.volts_at_zero", "theta2.rad_per_volt").
/// O2x, O2y are O2 - O1.
const std::array<std::string, kMechanismParameters>& mechanism_parameter_names();
/// "frame.rotation", "frame.x", "frame.y".
const std::array<std::string, kFrameParameters>& frame_parameter_names();

/// A mechanism's parameter vector from the design (links, bases) and two potentiometers.
MechanismVector mechanism_vector(const Mechanism& m, double volts_at_zero1, double rad_per_volt1,
                                 double volts_at_zero2, double rad_per_volt2);
/// The mechanism with the geometry of `q` (names, modes and limits of `m`).
Mechanism with_geometry(const Mechanism& m, const MechanismVector& q);
/// Joint angles (rad) of the readings under `q`.
std::array<double, 2> joint_angles(const MechanismVector& q, double volts1, double volts2);

/// The predicted instrument reading of one pose and its Jacobian.
struct Prediction {
  Status status = Status::unreachable;  ///< fk()'s; y and the Jacobians are zero unless ok
  Vec2 y{0.0, 0.0};                     ///< mm, instrument frame
  Eigen::Matrix<double, 2, kMechanismParameters> dq = Eigen::Matrix<double, 2, kMechanismParameters>::Zero();
  Eigen::Matrix<double, 2, kFrameParameters> dframe = Eigen::Matrix<double, 2, kFrameParameters>::Zero();
};

/// The model above at readings (volts1, volts2) of mechanism `m` (its modes) with parameters q
/// and instrument pose `frame`. A type II singular pose gives status singular_type2 (no Jacobian).
Prediction predict(const Mechanism& m, const MechanismVector& q, const FrameVector& frame, double volts1, double volts2);

}  // namespace fivebar::calibrate
