#pragma once
// Small helpers shared by the scalar and batch kinematics (private).

#include <algorithm>
#include <cmath>

#include "fivebar/kinematics.hpp"
#include "fivebar/tolerances.hpp"

namespace fivebar::detail {

inline double cross(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }
inline double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

/// Tolerance on h^2 = (r1 - a)(r1 + a): its rounding error is a few eps * r1 * max(r1, |a|).
inline double reach_tolerance(double r1, double a) {
  return tol::kReachRel * r1 * std::max(r1, std::fabs(a));
}

/// Circle pair (c1, r1), (c2, r2) prepared for the intersection: the foot of the intersection
/// chord is measured from the centre of the SMALLER circle, so that h^2 = (r - a)(r + a) keeps
/// the digits of the small radius when the other is much larger (link ratios up to 1e4).
struct CirclePair {
  double rs;   ///< smaller radius
  double hdd;  ///< (rs - rb)(rs + rb) / 2 <= 0
  double w0;   ///< 0 when the small circle is c1, else 1
  double sgn;  ///< +1 when the small circle is c1, else -1
  static CirclePair make(double r1, double r2) {
    return r1 <= r2 ? CirclePair{r1, 0.5 * ((r1 - r2) * (r1 + r2)), 0.0, 1.0}
                    : CirclePair{r2, 0.5 * ((r2 - r1) * (r2 + r1)), 1.0, -1.0};
  }
};

/// Foot distance `a` from c1 along u = (c2 - c1)/d, and h^2; `reach` false when the circles miss
/// each other by more than rounding. Shared verbatim by the scalar and batch paths. Takes 1/d^2
/// rather than 1/d: as = d (1/2 + hdd/d^2) then waits for the square root d by one multiplication
/// only (the division runs beside the square root), which shortens the dependency chain of a
/// scalar FK or IK by about a tenth.
inline bool chord(const CirclePair& c, double d, double inv_d2, double& a, double& h2) {
  const double as = d * (0.5 + c.hdd * inv_d2);  // from the small circle's centre
  h2 = (c.rs - as) * (c.rs + as);
  a = c.w0 * d + c.sgn * as;
  return h2 >= -reach_tolerance(c.rs, as);
}

/// 1/cond of [[m00, m01], [m10, m11]] from the Frobenius norm and determinant:
/// sigma_max^2 = (f + sqrt((f - 2g)(f + 2g)))/2, sigma_min = g / sigma_max, g = |det|.
inline double lci2(double m00, double m01, double m10, double m11) {
  const double f = m00 * m00 + m01 * m01 + m10 * m10 + m11 * m11;
  const double g = std::fabs(m00 * m11 - m01 * m10);
  const double disc = std::max(0.0, (f - 2.0 * g) * (f + 2.0 * g));
  const double denom = f + std::sqrt(disc);
  return denom > 0.0 ? std::min(1.0, 2.0 * g / denom) : 0.0;
}

/// Worst status first: unreachable > singular_type1 > singular_type2 > ok. Written as selects on
/// integers (no short-circuit) so that loops calling it stay vectorisable.
inline Status classify(bool reachable, bool type1, bool type2) {
  const int t2 = type2 ? int(Status::singular_type2) : int(Status::ok);
  const int t1 = type1 ? int(Status::singular_type1) : t2;
  return static_cast<Status>(reachable ? t1 : int(Status::unreachable));
}

/// Same, from the |sin| of the worst elbow angle and of the tactor angle.
inline Status classify(bool reachable, double type1_sin_min, double type2_sin) {
  return classify(reachable, type1_sin_min < tol::kSingularSin, type2_sin < tol::kSingularSin);
}

}  // namespace fivebar::detail
