// Scalar five-bar kinematics. Derivations: FK/IK are circle-circle intersections (paper eqs.
// (1)-(4)) in the stable form of docs/conventions.md "Numerics" (no acos); the Jacobian follows from differentiating the loop
// constraints |P - A_i|^2 = L_{i+2}^2:  (P - A_i) . dP = cross(A_i - O_i, P - A_i) dtheta_i,
// i.e. B dP = C dtheta with B = [(P-A1)^T; (P-A2)^T], C = diag(c1, c2), so J = B^-1 C
// (det B = cross(P-A1, P-A2): type II; c_i = 0: type I; Gosselin & Angeles 1990).
#include "fivebar/kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "kinematics/kinematics_common.hpp"

namespace fivebar {

using detail::cross;

std::string_view to_string(Status status) {
  switch (status) {
    case Status::ok: return "ok";
    case Status::unreachable: return "unreachable";
    case Status::singular_type1: return "singular_type1";
    case Status::singular_type2: return "singular_type2";
  }
  return "unknown";
}

CircleIntersection intersect_circles(const Vec2& c1, double r1, const Vec2& c2, double r2,
                                     int side) {
  CircleIntersection out;
  const Vec2 dv = c2 - c1;
  const double d2 = dv.squaredNorm();
  const double d = std::sqrt(d2);
  out.d = d;
  const double scale = std::max({r1, r2, d});
  // Coincident relative to the circles, or too close for 1/d^2 (detail::kMinD2).
  if (d <= tol::kCoincidentRel * scale || !(d2 >= detail::kMinD2)) {
    // Concentric: no intersection, or (equal radii) every point of the circle. Report one point
    // (straight "up" from c1) and let the caller's singularity analysis classify it.
    if (std::fabs(r1 - r2) <= tol::kReachRel * scale) {
      out.status = Status::ok;
      out.offset = Vec2(0.0, side >= 0 ? r1 : -r1);
      out.point = c1 + out.offset;
      out.h = r1;
    }
    return out;
  }
  // Same expressions, in the same order, as the batch kernels (kinematics_batch.cpp).
  const double inv_d2 = 1.0 / d2;
  double t, hd;
  if (!detail::chord(detail::CirclePair::make(r1, r2), d2, inv_d2, t, hd)) return out;
  const double s = side >= 0 ? 1.0 : -1.0;
  out.status = Status::ok;
  out.h = hd * d;
  const double hs = s * hd;  // exact: s is +-1
  out.offset = Vec2(t * dv.x() - hs * dv.y(), t * dv.y() + hs * dv.x());
  out.point = c1 + out.offset;
  return out;
}

double lci(const Eigen::Matrix2d& J) { return detail::lci2(J(0, 0), J(0, 1), J(1, 0), J(1, 1)); }

namespace {

std::int8_t sign_if(double v, bool defined) {
  return !defined ? std::int8_t{0} : v > 0.0 ? std::int8_t{1} : v < 0.0 ? std::int8_t{-1} : std::int8_t{0};
}

/// Fills everything that follows from the positions O_i, A_i, P.
void analyse(const Mechanism& m, Pose& pose) {
  const auto& L = m.L;
  const Vec2 e1 = pose.A1 - m.O1, f1 = pose.P - pose.A1;
  const Vec2 e2 = pose.A2 - m.O2, f2 = pose.P - pose.A2;
  const double c1 = cross(e1, f1), c2 = cross(e2, f2), cb = cross(f1, f2);
  pose.type1_sin = {std::min(1.0, std::fabs(c1) / (L[0] * L[2])),
                    std::min(1.0, std::fabs(c2) / (L[1] * L[3]))};
  pose.type2_sin = std::min(1.0, std::fabs(cb) / (L[2] * L[3]));
  pose.transmission = {std::atan2(std::fabs(c1), -e1.dot(f1)), std::atan2(std::fabs(c2), -e2.dot(f2)),
                       std::atan2(std::fabs(cb), f1.dot(f2))};
  pose.mode = {sign_if(c1, pose.type1_sin[0] >= tol::kSingularSin),
               sign_if(c2, pose.type1_sin[1] >= tol::kSingularSin)};
  pose.assembly = sign_if(cb, pose.type2_sin >= tol::kSingularSin);

  // M = adj(B) C = det(B) J stays finite at every singularity; cond(M) = cond(J).
  const double m00 = f2.y() * c1, m01 = -f1.y() * c2, m10 = -f2.x() * c1, m11 = f1.x() * c2;
  pose.lci = detail::lci2(m00, m01, m10, m11);
  const double fro2 = m00 * m00 + m01 * m01 + m10 * m10 + m11 * m11;
  const double g = std::fabs(m00 * m11 - m01 * m10);
  const double smax = std::sqrt(0.5 * (fro2 + std::sqrt(std::max(0.0, (fro2 - 2 * g) * (fro2 + 2 * g)))));
  pose.force_capability = smax > 0.0 ? std::fabs(cb) / smax : 0.0;

  double dist = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 2; ++i) {
    const Vec2& O = i == 0 ? m.O1 : m.O2;
    const double d = (pose.P - O).norm();
    const double outer = L[i] + L[i + 2], inner = std::fabs(L[i] - L[i + 2]);
    dist = std::min({dist, std::fabs(d - outer), std::fabs(d - inner)});
  }
  pose.type1_distance_mm = dist;

  pose.status = detail::classify(true, std::min(pose.type1_sin[0], pose.type1_sin[1]), pose.type2_sin);
  pose.jacobian_valid = pose.type2_sin >= tol::kSingularSin;
  if (pose.jacobian_valid) {
    pose.J << m00 / cb, m01 / cb, m10 / cb, m11 / cb;
  } else {
    pose.J.setZero();
    pose.force_capability = 0.0;
  }
  if (m.joint_limits) {
    const double slack = tol::kClosureRel;  // angles are exact to a few ulp; don't flip on rounding
    pose.within_joint_limits = (*m.joint_limits)[0].contains(pose.theta1, slack) &&
                               (*m.joint_limits)[1].contains(pose.theta2, slack);
  }
}

double closure_error(const Mechanism& m, const Pose& pose) {
  const Vec2 A1 = m.O1 + m.L[0] * Vec2(std::cos(pose.theta1), std::sin(pose.theta1));
  const Vec2 A2 = m.O2 + m.L[1] * Vec2(std::cos(pose.theta2), std::sin(pose.theta2));
  return std::max(std::fabs((pose.P - A1).norm() - m.L[2]), std::fabs((pose.P - A2).norm() - m.L[3]));
}

Pose fk_branch(const Mechanism& m, double theta1, double theta2, int side) {
  Pose pose;
  pose.theta1 = theta1;
  pose.theta2 = theta2;
  pose.A1 = m.O1 + m.L[0] * Vec2(std::cos(theta1), std::sin(theta1));
  pose.A2 = m.O2 + m.L[1] * Vec2(std::cos(theta2), std::sin(theta2));
  const CircleIntersection x = intersect_circles(pose.A1, m.L[2], pose.A2, m.L[3], side);
  if (x.status == Status::unreachable) {
    Pose none;
    none.theta1 = theta1;
    none.theta2 = theta2;
    none.A1 = pose.A1;
    none.A2 = pose.A2;
    return none;
  }
  pose.P = x.point;
  analyse(m, pose);
  pose.closure_error_mm =
      std::max(std::fabs((pose.P - pose.A1).norm() - m.L[2]), std::fabs((pose.P - pose.A2).norm() - m.L[3]));
  return pose;
}

}  // namespace

Pose fk(const Mechanism& m, double theta1, double theta2, AssemblyMode branch) {
  if (branch == AssemblyMode::Plus) return fk_branch(m, theta1, theta2, +1);
  if (branch == AssemblyMode::Minus) return fk_branch(m, theta1, theta2, -1);
  Pose plus = fk_branch(m, theta1, theta2, +1);
  if (plus.status == Status::unreachable || plus.mode == m.working_mode) return plus;
  Pose minus = fk_branch(m, theta1, theta2, -1);
  return minus.mode == m.working_mode ? minus : plus;
}

Pose fk(const Mechanism& m, double theta1, double theta2) {
  return fk(m, theta1, theta2, m.assembly_mode);
}

std::array<Pose, 2> fk_all(const Mechanism& m, double theta1, double theta2) {
  return {fk_branch(m, theta1, theta2, +1), fk_branch(m, theta1, theta2, -1)};
}

Pose ik(const Mechanism& m, const Vec2& P, WorkingMode mode) {
  Pose pose;
  pose.P = P;
  // Leg i: elbow A_i on circles (O_i, L_i) and (P, L_{i+2}). With A = O + a u + s h n,
  // cross(A - O, P - A) = -s h d, so working-mode sign sigma takes side s = -sigma.
  const CircleIntersection x1 = intersect_circles(m.O1, m.L[0], P, m.L[2], -mode.sign1);
  const CircleIntersection x2 = intersect_circles(m.O2, m.L[1], P, m.L[3], -mode.sign2);
  if (x1.status == Status::unreachable || x2.status == Status::unreachable) {
    Pose none;
    none.P = P;
    return none;
  }
  pose.A1 = x1.point;
  pose.A2 = x2.point;
  pose.theta1 = std::atan2(x1.offset.y(), x1.offset.x());
  pose.theta2 = std::atan2(x2.offset.y(), x2.offset.x());
  analyse(m, pose);
  // Verify the branch by running it forward (ruckig Profile::check): the elbow positions that
  // FK computes from the returned angles must close the loop at P.
  pose.closure_error_mm = closure_error(m, pose);
  if (!(pose.closure_error_mm <= tol::kClosureRel * m.length_scale())) {
    // Only possible when the intersection is numerically degenerate; never return it as ok.
    if (pose.status == Status::ok) pose.status = Status::singular_type1;
  }
  return pose;
}

Pose ik(const Mechanism& m, const Vec2& P) { return ik(m, P, m.working_mode); }

std::array<Pose, 4> ik_all(const Mechanism& m, const Vec2& P) {
  const auto modes = all_working_modes();
  return {ik(m, P, modes[0]), ik(m, P, modes[1]), ik(m, P, modes[2]), ik(m, P, modes[3])};
}

}  // namespace fivebar
