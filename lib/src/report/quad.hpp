#pragma once
// High-precision reference for `fivebar report` (private): five-bar FK, IK, Jacobian, LCI, the
// closed-form annuli area and the ellipse-annuli margin in IEEE binary128 (__float128, GCC's
// libquadmath; 113-bit significand, eps_q = 2^-112 ~ 1.9e-34).
//
// Written independently of lib/src/kinematics*.cpp: the circle intersections use the law of
// cosines with the angle taken as atan2(sqrt(K), d^2 + r1^2 - r2^2), K the Heron product
// (d+r1+r2)(-d+r1+r2)(d-r1+r2)(d+r1-r2) = (2 d r1 sin)^2, instead of the library's chord foot
// a and height h. Factored this way K keeps its digits at tangency (no 1 - cos^2 cancellation),
// so the quad result is good to ~eps_q * L / sin, and to ~sqrt(eps_q) * L ~ 1.4e-17 L at exact
// tangency: far below every double-precision bound the report compares against.
//
// Inputs are doubles (the exact values a double computation sees), converted exactly.

#include <quadmath.h>

#include <array>
#include <cmath>

#include "fivebar/design.hpp"

namespace fivebar::quadref {

using quad = __float128;

struct QVec {
  quad x = 0, y = 0;
};
inline QVec operator+(QVec a, QVec b) { return {a.x + b.x, a.y + b.y}; }
inline QVec operator-(QVec a, QVec b) { return {a.x - b.x, a.y - b.y}; }
inline QVec operator*(quad s, QVec a) { return {s * a.x, s * a.y}; }
inline quad cross(QVec a, QVec b) { return a.x * b.y - a.y * b.x; }
inline quad dot(QVec a, QVec b) { return a.x * b.x + a.y * b.y; }
inline quad norm(QVec a) { return hypotq(a.x, a.y); }
inline quad qabs(quad v) { return v < 0 ? -v : v; }
/// pi in quad (acos(-1): correctly rounded by libquadmath; avoids the non-standard Q suffix).
inline const quad kQuadPi = acosq(-1);
/// Unit roundoff of binary128, 2^-112.
inline const quad kQuadEps = quad(0x1p-112);
inline QVec q(const Vec2& v) { return {quad(v.x()), quad(v.y())}; }
inline double d(quad v) { return double(v); }
inline Vec2 d(QVec v) { return {double(v.x), double(v.y)}; }

/// A mechanism with exact (double -> quad) data.
struct QMechanism {
  QVec O1, O2;
  std::array<quad, 4> L{};
  int w1 = -1, w2 = 1;  ///< working-mode signs
  explicit QMechanism(const Mechanism& m);
  QMechanism() = default;
};

/// A configuration and its local properties, in quad.
struct QPose {
  bool reachable = false;
  /// True when the equations have a continuum of solutions (concentric circles of equal radii:
  /// coincident elbows with L3 = L4, or P on a base joint with L_i = L_{i+2}); the fields then
  /// describe one member of it.
  bool continuum = false;
  quad theta1 = 0, theta2 = 0;
  QVec A1, A2, P;
  std::array<quad, 2> type1_sin{0, 0};  ///< |sin| at the elbows
  quad type2_sin = 0;                   ///< |sin| at the tactor
  /// dP/dtheta = B^-1 C (B rows (P - A_i)^T, C = diag(cross(A_i - O_i, P - A_i))); valid unless
  /// type2_sin == 0.
  std::array<std::array<quad, 2>, 2> J{};
  bool jacobian_valid = false;
  quad lci = 0;     ///< 1/cond(J), from adj(B) C (finite at every singularity)
  quad cond_B = 0;  ///< 2-norm condition number of B (infinite -> 0 stored when singular)
};

/// Signed gap of a circle pair from meeting: > 0 when they miss each other by that much (mm).
quad circle_gap(quad d, quad r1, quad r2);

/// FK on branch `side` (+1: cross(A2 - A1, P - A1) >= 0).
QPose fk(const QMechanism& m, quad theta1, quad theta2, int side);
/// IK in working mode (sign1, sign2).
QPose ik(const QMechanism& m, QVec P, int sign1, int sign2);
/// Fills the sines, Jacobian and LCI from the positions O_i, A_i, P.
void analyse(const QMechanism& m, QPose& pose);

/// Gap of FK's distal circles (A1, L3), (A2, L4) at the angles (> 0 unreachable).
quad fk_gap(const QMechanism& m, quad theta1, quad theta2);
/// Largest gap of IK's two legs at P (> 0 unreachable).
quad ik_gap(const QMechanism& m, QVec P);

/// Area of the intersection of two disks (radii a, b; centre distance dist).
quad lens_area(quad a, quad b, quad dist);
/// Area of the intersection of the two legs' annuli (no joint limits).
quad annuli_area(const QMechanism& m);

/// Extremes of |E(t) - p| over the ellipse boundary, and whether p is in the filled ellipse.
struct QExtremes {
  quad min_distance = 0, max_distance = 0;
  bool inside = false;
};
QExtremes ellipse_extremes(const Ellipse& e, QVec p);
/// Signed margin of the filled ellipse inside the annuli intersection (no joint limits): the
/// distance from the ellipse to the region's complement, negative when it sticks out.
quad annuli_margin(const QMechanism& m, const Ellipse& e);

}  // namespace fivebar::quadref
