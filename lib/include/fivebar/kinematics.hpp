#pragma once
/// Exact five-bar kinematics: FK (paper eqs. (1)-(2)) and IK (eqs. (3)-(4)) by the numerically
/// stable circle-circle intersection (no acos), the closed-form Jacobian dP/dtheta, its LCI,
/// transmission angles and distances to the type I / type II singularities.
/// Every result carries a Status; no NaN or infinity ever leaves these functions for finite input.

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <span>
#include <string_view>

#include "fivebar/design.hpp"

namespace fivebar {

/// Outcome of a kinematic evaluation, ordered by precedence (worst first wins).
enum class Status : std::uint8_t {
  ok = 0,
  unreachable = 1,     ///< the circles do not meet: no configuration exists
  singular_type1 = 2,  ///< a leg stretched or folded: |cross(A_i-O_i, P-A_i)| ~ 0
  singular_type2 = 3,  ///< distal links collinear: |cross(P-A1, P-A2)| ~ 0
};
std::string_view to_string(Status status);

/// A full configuration of a mechanism and its local properties.
/// Angles in radians, lengths in mm. Fields other than `status` are finite always; when
/// `status == unreachable` the geometric fields are zero.
struct Pose {
  Status status = Status::unreachable;
  double theta1 = 0.0;
  double theta2 = 0.0;
  Vec2 A1{0.0, 0.0};
  Vec2 A2{0.0, 0.0};
  Vec2 P{0.0, 0.0};
  WorkingMode mode{0, 0};   ///< realised signs of cross(A_i - O_i, P - A_i) (0 on type I)
  std::int8_t assembly = 0; ///< realised sign of cross(A2 - A1, P - A1) (0 on type II)
  /// dP/dtheta (mm/rad); valid only when jacobian_valid (false on a type II singularity).
  Eigen::Matrix2d J = Eigen::Matrix2d::Zero();
  bool jacobian_valid = false;
  double lci = 0.0;               ///< 1/cond(J) in [0, 1]; 0 at any singularity
  double force_capability = 0.0;  ///< 1/sigma_max(J): smallest tactor force per unit torque, N per N*mm
  /// Angles (rad, in [0, pi]) at elbow 1 (between O1-A1 and P-A1), elbow 2 and at the tactor
  /// (between A1-P and A2-P); pi/2 is ideal transmission, 0 or pi singular.
  std::array<double, 3> transmission{0.0, 0.0, 0.0};
  std::array<double, 2> type1_sin{0.0, 0.0};  ///< |sin| of the elbow angles
  double type2_sin = 0.0;                     ///< |sin| of the tactor angle
  double type1_distance_mm = 0.0;  ///< distance from P to the nearest type I circle |P-O_i| = L_i +- L_{i+2}
  double closure_error_mm = 0.0;   ///< loop closure residual of FK(theta) against P
  bool within_joint_limits = true; ///< false when the mechanism has limits and theta is outside them
};

/// Forward kinematics in the mechanism's assembly mode. With AssemblyMode::Any the branch whose
/// working mode equals the design's is chosen (the one the device runs in), else "+".
Pose fk(const Mechanism& m, double theta1, double theta2);
/// Forward kinematics on a given branch (Plus / Minus; Any as above).
Pose fk(const Mechanism& m, double theta1, double theta2, AssemblyMode branch);
/// Both FK branches, "+" then "-".
std::array<Pose, 2> fk_all(const Mechanism& m, double theta1, double theta2);

/// Inverse kinematics in the mechanism's working mode; every branch is verified by FK.
Pose ik(const Mechanism& m, const Vec2& P);
/// Inverse kinematics on a given working mode.
Pose ik(const Mechanism& m, const Vec2& P, WorkingMode mode);
/// All four IK branches in the order of all_working_modes(): "++", "+-", "-+", "--".
std::array<Pose, 4> ik_all(const Mechanism& m, const Vec2& P);

/// 1 / condition number of a 2x2 matrix, in [0, 1], computed without inverting it.
double lci(const Eigen::Matrix2d& J);

/// Stable circle-circle intersection (no acos, docs/conventions.md "Numerics"): circles (c1, r1) and (c2, r2); `side` = +1
/// picks the point left of c1->c2 (cross(c2 - c1, p - c1) >= 0), -1 the other. Computed from the
/// squared centre distance d^2 alone: foot a/d = 1/2 + (r1^2 - r2^2)/(2 d^2) and height from
/// Heron's factors (d^2 - (r1 - r2)^2)((r1 + r2)^2 - d^2) = (2 d h)^2, each vanishing at one
/// tangency, so h keeps its digits there; one division and one square root. Within rounding of a
/// tangency (tol::kReachRel) the height is clamped to 0.
struct CircleIntersection {
  Status status = Status::unreachable;  ///< ok, unreachable, or singular_type1 for tangency
  Vec2 point{0.0, 0.0};
  Vec2 offset{0.0, 0.0};  ///< point - c1, computed without the cancellation of that subtraction
  double h = 0.0;  ///< distance of the point from the centre line
  double d = 0.0;  ///< centre distance
};
CircleIntersection intersect_circles(const Vec2& c1, double r1, const Vec2& c2, double r2, int side);

// --- Lean scalar forms -------------------------------------------------------------------------
// The point or the angles and a status, nothing else: for control loops and per-sample checks.

struct PointResult {
  Status status = Status::unreachable;
  Vec2 P{0.0, 0.0};  ///< mm; zero when unreachable
};
struct AnglesResult {
  Status status = Status::unreachable;
  double theta1 = 0.0;  ///< rad; zero when unreachable
  double theta2 = 0.0;
  double closure_error_mm = 0.0;
};
/// FK to the tactor point in the mechanism's assembly mode (as fk()).
PointResult fk_point(const Mechanism& m, double theta1, double theta2);
/// IK to the joint angles in the mechanism's working mode (as ik()); verifies the loop closure of
/// the elbow configuration, without ik()'s forward sin/cos pass.
AnglesResult ik_angles(const Mechanism& m, const Vec2& P);

// --- Batch (structure of arrays) --------------------------------------------------------------
// All spans of one call have the same length n. Written branch-free over fast vectorisable
// sin/cos/atan2 (fivebar/detail/fastmath.hpp, < 3 ulp); statuses as in the scalar functions,
// without the Jacobian-based quantities.

/// FK of n joint-angle pairs in the mechanism's assembly mode.
void fk_batch(const Mechanism& m, std::span<const double> theta1, std::span<const double> theta2,
              std::span<double> px, std::span<double> py, std::span<Status> status);
/// IK of n tactor points in the mechanism's working mode.
void ik_batch(const Mechanism& m, std::span<const double> px, std::span<const double> py,
              std::span<double> theta1, std::span<double> theta2, std::span<Status> status);
/// LCI at n tactor points in the working mode (0 where unreachable or singular). Uses only the
/// elbow positions: square roots, no trigonometry.
void lci_batch(const Mechanism& m, std::span<const double> px, std::span<const double> py,
               std::span<double> lci, std::span<Status> status);

/// LCI, force capability (1/sigma_max(J)) and the realised assembly sign (sign of
/// cross(P - A1, P - A2), 0 on type II) at n tactor points in the working mode; zeros where not ok.
/// Elbow positions only: square roots, no trigonometry.
void conditioning_batch(const Mechanism& m, std::span<const double> px, std::span<const double> py,
                        std::span<double> lci, std::span<double> force, std::span<std::int8_t> assembly,
                        std::span<Status> status);

}  // namespace fivebar
