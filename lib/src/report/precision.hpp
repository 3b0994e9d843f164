#pragma once
// FK and IK in a chosen floating-point type (float, double, long double) for the work-precision
// study of `fivebar report accuracy` (private). The formulas are the library's stable ones
// (lib/src/kinematics/kinematics_common.hpp, detail::chord): the intersection as ratios to the centre
// distance d, computed from d^2 alone, t = a/d = 1/2 + (r1 - r2)(r1 + r2)/(2 d^2) and
// h/d = sqrt((d^2 - (r1 - r2)^2)((r1 + r2)^2 - d^2)/(r1 + r2)^2) (r1 + r2) / (2 d^2), each factor clamped at
// rounding-level tangency; angles from atan2. Only the arithmetic type changes, so the series
// show what precision alone buys.

#include <algorithm>
#include <cmath>
#include <limits>

#include "fivebar/design.hpp"

namespace fivebar::precision {

template <class T>
struct MechanismT {
  T o1x, o1y, o2x, o2y;
  T L[4];
  int w1, w2;
  explicit MechanismT(const Mechanism& m)
      : o1x(T(m.O1.x())), o1y(T(m.O1.y())), o2x(T(m.O2.x())), o2y(T(m.O2.y())),
        L{T(m.L[0]), T(m.L[1]), T(m.L[2]), T(m.L[3])}, w1(m.working_mode.sign1), w2(m.working_mode.sign2) {}
};

/// Intersection of circles (c1, r1), (c2, r2): offset of the point from c1 on side `side`
/// (+1: left of c1->c2). False when they miss each other by more than rounding.
template <class T>
inline bool chord_offset(T c1x, T c1y, T r1, T c2x, T c2y, T r2, T side, T& ox, T& oy) {
  const T dx = c2x - c1x, dy = c2y - c1y;
  const T d2 = dx * dx + dy * dy;
  if (!(d2 > T(0))) return false;
  const T dm = (r1 - r2) * (r1 - r2), dp = (r1 + r2) * (r1 + r2);
  const T rel = T(16) * std::numeric_limits<T>::epsilon();
  if (d2 < dm * (T(1) - rel) || d2 > dp * (T(1) + rel)) return false;
  const T inv_d2 = T(1) / d2;
  const T t = T(0.5) + T(0.5) * ((r1 - r2) * (r1 + r2)) * inv_d2;  // a / d
  const T hd = std::sqrt(std::max(T(0), d2 - dm) * (std::max(T(0), dp - d2) / dp)) * (T(0.5) * (r1 + r2) * inv_d2);  // h / d
  ox = t * dx - side * (hd * dy);
  oy = t * dy + side * (hd * dx);
  return true;
}

/// FK on branch `side` (+1: cross(A2 - A1, P - A1) >= 0); false when unreachable.
template <class T>
inline bool fk(const MechanismT<T>& m, T theta1, T theta2, int side, T& px, T& py) {
  const T a1x = m.o1x + m.L[0] * std::cos(theta1), a1y = m.o1y + m.L[0] * std::sin(theta1);
  const T a2x = m.o2x + m.L[1] * std::cos(theta2), a2y = m.o2y + m.L[1] * std::sin(theta2);
  T ox, oy;
  if (!chord_offset(a1x, a1y, m.L[2], a2x, a2y, m.L[3], T(side), ox, oy)) return false;
  px = a1x + ox;
  py = a1y + oy;
  return true;
}

/// IK in the mechanism's working mode; false when unreachable.
template <class T>
inline bool ik(const MechanismT<T>& m, T px, T py, T& theta1, T& theta2) {
  T e1x, e1y, e2x, e2y;
  // cross(A - O, P - A) = -s h d for the side s: working-mode sign sigma takes s = -sigma.
  if (!chord_offset(m.o1x, m.o1y, m.L[0], px, py, m.L[2], T(-m.w1), e1x, e1y)) return false;
  if (!chord_offset(m.o2x, m.o2y, m.L[1], px, py, m.L[3], T(-m.w2), e2x, e2y)) return false;
  theta1 = std::atan2(e1y, e1x);
  theta2 = std::atan2(e2y, e2x);
  return true;
}

}  // namespace fivebar::precision
