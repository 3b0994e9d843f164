// Batch (structure-of-arrays) kinematics. The loop bodies are branch-free (selects only) and call
// only inline arithmetic, sqrt and the fdlibm-style kernels of fastmath.hpp, so GCC vectorises
// them at -O2/-O3 without -ffast-math (-fno-math-errno suffices for sqrt). The arithmetic is the
// scalar path's, expression for expression; test_kinematics checks the two agree.
//
// IK here is not re-verified by a forward pass: the elbows are the exact circle intersection and
// the angles are atan2 of the elbow offsets, so loop closure holds by construction up to the
// atan2 error (< 3 ulp); test_kinematics verifies batch IK by FK on every regime.
#include <algorithm>
#include <cassert>
#include <cmath>

#include "fivebar/detail/fastmath.hpp"
#include "fivebar/kinematics.hpp"
#include "kinematics_common.hpp"

namespace fivebar {

namespace {

using detail::cross;

struct LegConst {
  double ox, oy;
  detail::CirclePair circles;  // (O, L_i) and (P, L_{i+2})
};

LegConst leg(const Vec2& O, double l_prox, double l_dist) {
  return {O.x(), O.y(), detail::CirclePair::make(l_prox, l_dist)};
}

/// Elbow offset A - O for a leg at tactor (px, py), side s = -sigma; returns reachability.
inline bool elbow_offset(const LegConst& g, double px, double py, double s, double& ex, double& ey) {
  const double dx = px - g.ox, dy = py - g.oy;
  const double d2 = dx * dx + dy * dy;
  const bool coincident = !(d2 > 0.0);
  const double d = std::sqrt(coincident ? 1.0 : d2);
  const double inv_d = 1.0 / d;
  double a, h2;
  const bool reach = !coincident & detail::chord(g.circles, d, inv_d, a, h2);
  const double h = std::sqrt(std::max(0.0, h2));
  const double ux = dx * inv_d, uy = dy * inv_d;
  ex = reach ? a * ux - s * h * uy : 0.0;
  ey = reach ? a * uy + s * h * ux : 0.0;
  return reach;
}

/// FK kernel; kAny selects the branch per point by the working mode, else `fixed_side` is used.
/// Templated so that the branch choice is not a loop-invariant select (which defeats GCC's
/// vectoriser).
template <bool kAny>
void fk_kernel(const Mechanism& m, std::span<const double> theta1, std::span<const double> theta2,
               std::span<double> px, std::span<double> py, std::span<Status> status) {
  const std::size_t n = theta1.size();
  const double o1x = m.O1.x(), o1y = m.O1.y(), o2x = m.O2.x(), o2y = m.O2.y();
  const double L1 = m.L[0], L2 = m.L[1], L3 = m.L[2], L4 = m.L[3];
  const detail::CirclePair distal = detail::CirclePair::make(L3, L4);
  const double inv13 = 1.0 / (L1 * L3), inv24 = 1.0 / (L2 * L4), inv34 = 1.0 / (L3 * L4);
  const double fixed_side = m.assembly_mode == AssemblyMode::Minus ? -1.0 : 1.0;
  const double w1 = m.working_mode.sign1, w2 = m.working_mode.sign2;
  for (std::size_t k = 0; k < n; ++k) {
    double s1, c1, s2, c2;
    detail::fast_sincos(theta1[k], s1, c1);
    detail::fast_sincos(theta2[k], s2, c2);
    const double e1x = L1 * c1, e1y = L1 * s1, e2x = L2 * c2, e2y = L2 * s2;
    const double a1x = o1x + e1x, a1y = o1y + e1y, a2x = o2x + e2x, a2y = o2y + e2y;
    const double dx = a2x - a1x, dy = a2y - a1y;
    const double d2 = dx * dx + dy * dy;
    const bool coincident = !(d2 > 0.0);
    const double d = std::sqrt(coincident ? 1.0 : d2);
    const double inv_d = 1.0 / d;
    double a, h2;
    const bool reach = !coincident & detail::chord(distal, d, inv_d, a, h2);
    const double h = std::sqrt(std::max(0.0, h2));
    const double ux = dx * inv_d, uy = dy * inv_d;
    double side = fixed_side;
    if constexpr (kAny) {
      // "+" candidate: P - A1 and P - A2, and whether its working mode is the design's.
      const double f1x_p = a * ux - h * uy, f1y_p = a * uy + h * ux;
      const double f1x_m = a * ux + h * uy, f1y_m = a * uy - h * ux;  // "-" candidate
      const double p1 = cross(e1x, e1y, f1x_p, f1y_p) * w1;
      const double p2 = cross(e2x, e2y, f1x_p - dx, f1y_p - dy) * w2;
      const double m1 = cross(e1x, e1y, f1x_m, f1y_m) * w1;
      const double m2 = cross(e2x, e2y, f1x_m - dx, f1y_m - dy) * w2;
      // As the scalar fk(): "+" if it is in the working mode, else "-" if that is, else "+".
      side = (std::min(p1, p2) > 0.0) | !(std::min(m1, m2) > 0.0) ? 1.0 : -1.0;
    }
    const double ox = a * ux - side * h * uy, oy = a * uy + side * h * ux;  // P - A1
    const double pxk = a1x + ox, pyk = a1y + oy;
    const double f1x = pxk - a1x, f1y = pyk - a1y, f2x = pxk - a2x, f2y = pyk - a2y;
    const double t1 = std::fabs(cross(e1x, e1y, f1x, f1y)) * inv13;
    const double t2 = std::fabs(cross(e2x, e2y, f2x, f2y)) * inv24;
    const double tb = d * h * inv34;
    px[k] = reach ? pxk : 0.0;
    py[k] = reach ? pyk : 0.0;
    status[k] = detail::classify(reach, std::min(t1, t2), tb);
  }
}

}  // namespace

void fk_batch(const Mechanism& m, std::span<const double> theta1, std::span<const double> theta2,
              std::span<double> px, std::span<double> py, std::span<Status> status) {
  const std::size_t n = theta1.size();
  assert(theta2.size() == n && px.size() == n && py.size() == n && status.size() == n);
  if (m.assembly_mode == AssemblyMode::Any) {
    fk_kernel<true>(m, theta1, theta2, px, py, status);
  } else {
    fk_kernel<false>(m, theta1, theta2, px, py, status);
  }
  // Arguments beyond the fast reduction's range (|theta| > 1e6 rad) are rare: redo them exactly.
  for (std::size_t k = 0; k < n; ++k) {
    if (!(std::fabs(theta1[k]) <= detail::kFastTrigMax && std::fabs(theta2[k]) <= detail::kFastTrigMax)) {
      const bool finite = std::isfinite(theta1[k]) && std::isfinite(theta2[k]);
      const Pose p = finite ? fk(m, theta1[k], theta2[k]) : Pose{};
      px[k] = p.P.x();
      py[k] = p.P.y();
      status[k] = p.status;
    }
  }
}

void ik_batch(const Mechanism& m, std::span<const double> px, std::span<const double> py,
              std::span<double> theta1, std::span<double> theta2, std::span<Status> status) {
  const std::size_t n = px.size();
  assert(py.size() == n && theta1.size() == n && theta2.size() == n && status.size() == n);
  const LegConst g1 = leg(m.O1, m.L[0], m.L[2]);
  const LegConst g2 = leg(m.O2, m.L[1], m.L[3]);
  const double s1 = -m.working_mode.sign1, s2 = -m.working_mode.sign2;
  const double inv13 = 1.0 / (m.L[0] * m.L[2]), inv24 = 1.0 / (m.L[1] * m.L[3]),
               inv34 = 1.0 / (m.L[2] * m.L[3]);
  for (std::size_t k = 0; k < n; ++k) {
    double e1x, e1y, e2x, e2y;
    const bool r1 = elbow_offset(g1, px[k], py[k], s1, e1x, e1y);
    const bool r2 = elbow_offset(g2, px[k], py[k], s2, e2x, e2y);
    const double f1x = px[k] - (g1.ox + e1x), f1y = py[k] - (g1.oy + e1y);
    const double f2x = px[k] - (g2.ox + e2x), f2y = py[k] - (g2.oy + e2y);
    const double t1 = std::fabs(cross(e1x, e1y, f1x, f1y)) * inv13;
    const double t2 = std::fabs(cross(e2x, e2y, f2x, f2y)) * inv24;
    const double tb = std::fabs(cross(f1x, f1y, f2x, f2y)) * inv34;
    const bool reach = r1 & r2;
    theta1[k] = reach ? detail::fast_atan2(e1y, e1x) : 0.0;
    theta2[k] = reach ? detail::fast_atan2(e2y, e2x) : 0.0;
    status[k] = detail::classify(reach, std::min(t1, t2), tb);
  }
}

void lci_batch(const Mechanism& m, std::span<const double> px, std::span<const double> py,
               std::span<double> lci, std::span<Status> status) {
  const std::size_t n = px.size();
  assert(py.size() == n && lci.size() == n && status.size() == n);
  const LegConst g1 = leg(m.O1, m.L[0], m.L[2]);
  const LegConst g2 = leg(m.O2, m.L[1], m.L[3]);
  const double s1 = -m.working_mode.sign1, s2 = -m.working_mode.sign2;
  const double inv13 = 1.0 / (m.L[0] * m.L[2]), inv24 = 1.0 / (m.L[1] * m.L[3]),
               inv34 = 1.0 / (m.L[2] * m.L[3]);
  for (std::size_t k = 0; k < n; ++k) {
    double e1x, e1y, e2x, e2y;
    const bool r1 = elbow_offset(g1, px[k], py[k], s1, e1x, e1y);
    const bool r2 = elbow_offset(g2, px[k], py[k], s2, e2x, e2y);
    const double f1x = px[k] - (g1.ox + e1x), f1y = py[k] - (g1.oy + e1y);
    const double f2x = px[k] - (g2.ox + e2x), f2y = py[k] - (g2.oy + e2y);
    const double c1 = cross(e1x, e1y, f1x, f1y), c2 = cross(e2x, e2y, f2x, f2y);
    const double cb = cross(f1x, f1y, f2x, f2y);
    const bool reach = r1 & r2;
    const Status st = detail::classify(reach, std::min(std::fabs(c1) * inv13, std::fabs(c2) * inv24),
                                       std::fabs(cb) * inv34);
    // M = adj(B) C, cond(M) = cond(J) (see kinematics.cpp).
    const double v = detail::lci2(f2y * c1, -f1y * c2, -f2x * c1, f1x * c2);
    lci[k] = st == Status::ok ? v : 0.0;
    status[k] = st;
  }
}

}  // namespace fivebar
