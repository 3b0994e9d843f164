#pragma once
// Small helpers shared by the scalar and batch kinematics (private).

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "fivebar/kinematics.hpp"
#include "fivebar/numerics.hpp"

namespace fivebar::detail {

inline double cross(double ax, double ay, double bx, double by) { return ax * by - ay * bx; }
inline double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

/// Exact power-of-two scaling for a squared length x > 0: s = 2^-2m and u = 2^(m-1), where
/// 2^2m <= x < 2^(2m+2). Scaling by a power of 4 commutes exactly with the square root, so
/// sqrt(y s) u == sqrt(y) / 2 bit for bit whenever neither y nor y s leaves the normal range, and
/// y s stays within a few orders of x when y ~ x^2, even where y itself would overflow or
/// underflow. Integer operations only, no division.
struct Pow4Scale {
  double s, u;
  static Pow4Scale of(double x) {
    const auto bits = std::bit_cast<std::uint64_t>(x);
    const int e = std::clamp(int((bits >> 52) & 0x7ff), 1, 2046) - 1023;  // unbiased exponent
    const int m = e >> 1;                                                  // floor(e / 2)
    return {std::bit_cast<double>(std::uint64_t(1023 - 2 * m) << 52),
            std::bit_cast<double>(std::uint64_t(1022 + m) << 52)};
  }
};

/// Circle pair (c1, r1), (c2, r2) prepared for the intersection, in terms of the squared centre
/// distance d^2 only: the circles meet iff (r1 - r2)^2 <= d^2 <= (r1 + r2)^2.
struct CirclePair {
  double k;        ///< (r1 - r2)(r1 + r2) / 2: the chord foot is a = d/2 + k/d from c1
  double dm;       ///< (r1 - r2)^2: inner tangency
  double dp;       ///< (r1 + r2)^2: outer tangency
  double dm_lo;    ///< dm (1 - kReachRel): below it the circles miss each other (one inside the other)
  double dp_hi;    ///< dp (1 + kReachRel): above it they miss each other (apart)
  Pow4Scale norm;  ///< of dp: keeps the fourth power under the root in range
  static CirclePair make(double r1, double r2) {
    const double dm = (r1 - r2) * (r1 - r2), dp = (r1 + r2) * (r1 + r2);
    return {0.5 * ((r1 - r2) * (r1 + r2)), dm, dp, dm * (1.0 - tol::kReachRel), dp * (1.0 + tol::kReachRel),
            Pow4Scale::of(dp)};
  }
  /// The same pair, with chord() returning side hd instead of hd (side = +-1, folded into the
  /// exact power-of-two factor: bit for bit side times the unsigned result, one multiply fewer).
  CirclePair on_side(double side) const {
    CirclePair c = *this;
    c.norm.u *= side;
    return c;
  }
};

/// chord()'s precondition: d^2 >= kMinD2. Centres closer than sqrt(kMinD2) ~ 1.5e-154 (times the
/// length unit) count as coincident: below the smallest normal d^2, 1/d^2 overflows and
/// t = 1/2 + k/d^2 would be inf or NaN even where the circles meet (equal radii). From kMinD2 up,
/// 1/d^2 is finite, and where the circles meet |k| <= |r1 - r2| (r1 + r2) / 2 <= d (r1 + r2) / 2
/// keeps t d finite.
inline constexpr double kMinD2 = std::numeric_limits<double>::min();

/// Intersection of a circle pair whose centres are (dx, dy) = c2 - c1 apart, d^2 = dx^2 + dy^2,
/// as two ratios to d:  point - c1 = t (dx, dy) + side hd (-dy, dx),  t = a/d, hd = h/d.
///   t  = 1/2 + k/d^2,
///   hd = sqrt((d^2 - (r1 - r2)^2) ((r1 + r2)^2 - d^2)) / (2 d^2)   (Heron: 2 d h = that root),
/// so no square root of d^2 is ever taken: one division (1/d^2, passed in) and one square root,
/// and the root does not wait for the division (the two run side by side).
/// Each factor under the root is a difference of squared lengths that vanishes at one tangency
/// and carries an absolute error of a few eps d^2 there (the same as the foot form
/// h^2 = (r - a)(r + a), whose a carries eps d); so h keeps its digits near both tangencies and at
/// any link ratio. Within kReachRel (relative, in d^2) of a tangency the factor is clamped to 0.
/// The product under the root is scaled by an exact power of 4 (Pow4Scale), so it neither
/// overflows nor underflows for any centre distance from sqrt(kMinD2) up. Shared verbatim by the
/// scalar and batch paths; returns reachability.
inline bool chord(const CirclePair& c, double d2, double inv_d2, double& t, double& hd) {
  t = 0.5 + c.k * inv_d2;
  const double g_in = std::max(0.0, d2 - c.dm);   // 0 at inner tangency
  const double g_out = std::max(0.0, c.dp - d2);  // 0 at outer tangency
  hd = std::sqrt(g_in * (g_out * c.norm.s)) * (c.norm.u * inv_d2);
  return (d2 >= c.dm_lo) & (d2 <= c.dp_hi);
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
template <class T>
inline T classify_as(bool reachable, bool type1, bool type2) {
  const T t2 = type2 ? T(Status::singular_type2) : T(Status::ok);
  const T t1 = type1 ? T(Status::singular_type1) : t2;
  return reachable ? t1 : T(Status::unreachable);
}
inline Status classify(bool reachable, bool type1, bool type2) {
  return static_cast<Status>(classify_as<int>(reachable, type1, type2));
}

/// Same, from the |sin| of the worst elbow angle and of the tactor angle.
inline Status classify(bool reachable, double type1_sin_min, double type2_sin) {
  return classify(reachable, type1_sin_min < tol::kSingularSin, type2_sin < tol::kSingularSin);
}

}  // namespace fivebar::detail
