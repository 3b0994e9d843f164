// Lean kinematics: FK to the tactor point and IK to the joint angles with a status, nothing else.
// One per-element kernel serves two entry points:
//   - the batch (structure-of-arrays) loops, over fastmath.hpp's vectorisable sin/cos and angle:
//     the bodies are branch-free (selects only), so GCC vectorises them at -O3 without
//     -ffast-math (-fno-math-errno and -fno-trapping-math suffice);
//   - fk_point / ik_angles, the scalar forms, over glibc's sin/cos/atan2 (< 1 ulp).
// The arithmetic is the full scalar path's (kinematics.cpp), expression for expression, through
// the shared detail::chord(); test_kinematics checks they agree. Each circle intersection costs
// one division and one square root: chord() works from the squared centre distance alone, so an
// FK takes one square root and an IK two.
//
// ik_angles verifies the loop closure of the elbow configuration. The batch IK is not re-verified
// per point: the elbows are the exact circle intersection and the angles are those of the elbow
// offsets, so closure holds by construction up to the angle's error (< 3 ulp); test_kinematics
// verifies batch IK by FK on every regime. The batch angle is fast_angle, which knows the offset's
// length (the proximal link) and so needs one division where a general atan2 needs two.
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>

#include "fivebar/detail/fastmath.hpp"
#include "fivebar/kinematics.hpp"
#include "kinematics/kinematics_common.hpp"

namespace fivebar {

namespace {

using detail::cross;

struct FastTrig {
  static void sincos(double x, double& s, double& c) { detail::fast_sincos(x, s, c); }
  /// The angle of an elbow offset (y, x) of known length r: one division (detail::fast_angle).
  static double angle(double y, double x, double r) { return detail::fast_angle(y, x, r); }
};
struct LibmTrig {
  static void sincos(double x, double& s, double& c) { ::sincos(x, &s, &c); }  // glibc, one reduction
  static double angle(double y, double x, double /*r*/) { return std::atan2(y, x); }  // < 1 ulp
};

/// Loop-invariant constants of one mechanism.
struct FkConst {
  double o1x, o1y, o2x, o2y, L1, L2, L3, L4;
  detail::CirclePair distal;
  double thr13, thr24, thr34, fixed_side, w1, w2;  // thrIJ = kSingularSin * L_I * L_J
  explicit FkConst(const Mechanism& m)
      : o1x(m.O1.x()), o1y(m.O1.y()), o2x(m.O2.x()), o2y(m.O2.y()), L1(m.L[0]), L2(m.L[1]),
        L3(m.L[2]), L4(m.L[3]), distal(detail::CirclePair::make(L3, L4)),
        thr13(tol::kSingularSin * L1 * L3), thr24(tol::kSingularSin * L2 * L4),
        thr34(tol::kSingularSin * L3 * L4),
        fixed_side(m.assembly_mode == AssemblyMode::Minus ? -1.0 : 1.0), w1(m.working_mode.sign1),
        w2(m.working_mode.sign2) {}
};

/// FK of one angle pair. kAny selects the branch per point by the working mode (as fk() does);
/// a template parameter rather than a loop-invariant select, which defeats GCC's vectoriser.
template <class Trig, bool kAny, class S>
inline void fk_one(const FkConst& g, double theta1, double theta2, double& px, double& py, S& status) {
  double s1, c1, s2, c2;
  Trig::sincos(theta1, s1, c1);
  Trig::sincos(theta2, s2, c2);
  const double e1x = g.L1 * c1, e1y = g.L1 * s1, e2x = g.L2 * c2, e2y = g.L2 * s2;
  const double a1x = g.o1x + e1x, a1y = g.o1y + e1y, a2x = g.o2x + e2x, a2y = g.o2y + e2y;
  const double dx = a2x - a1x, dy = a2y - a1y;
  const double d2 = dx * dx + dy * dy;
  const bool coincident = !(d2 >= detail::kMinD2);
  const double inv_d2 = 1.0 / (coincident ? 1.0 : d2);
  double t, hd;  // P - A1 = t (dx, dy) + side hd (-dy, dx)
  const bool reach = !coincident & detail::chord(g.distal, d2, inv_d2, t, hd);
  const double tx = t * dx, ty = t * dy;
  double side = g.fixed_side;
  if constexpr (kAny) {
    const double hx = hd * dx, hy = hd * dy;
    const double f1x_p = tx - hy, f1y_p = ty + hx;  // P - A1 on "+"
    const double f1x_m = tx + hy, f1y_m = ty - hx;  // P - A1 on "-"
    const double p1 = cross(e1x, e1y, f1x_p, f1y_p) * g.w1;
    const double p2 = cross(e2x, e2y, f1x_p - dx, f1y_p - dy) * g.w2;
    const double m1 = cross(e1x, e1y, f1x_m, f1y_m) * g.w1;
    const double m2 = cross(e2x, e2y, f1x_m - dx, f1y_m - dy) * g.w2;
    // As fk(): "+" if it is in the working mode, else "-" if that is, else "+".
    side = (std::min(p1, p2) > 0.0) | !(std::min(m1, m2) > 0.0) ? 1.0 : -1.0;
  }
  const double hs = side * hd;  // exact: side is +-1
  const double ox = tx - hs * dy, oy = ty + hs * dx;  // P - A1
  const double pxk = a1x + ox, pyk = a1y + oy;
  // |cross(P - A2, ...)| with P - A2 = (P - A1) - (A2 - A1); |cross(P - A1, P - A2)| = d h = d^2 hd.
  const bool sing1 = (std::fabs(cross(e1x, e1y, ox, oy)) < g.thr13) |
                     (std::fabs(cross(e2x, e2y, ox - dx, oy - dy)) < g.thr24);
  const bool sing2 = d2 * hd < g.thr34;
  px = reach ? pxk : 0.0;
  py = reach ? pyk : 0.0;
  status = detail::classify_as<S>(reach, sing1, sing2);
}

struct LegConst {
  double ox, oy;
  double r;                    // proximal link length |A - O|
  detail::CirclePair circles;  // (O, L_i) and (P, L_{i+2}), on the chord side -sigma of the working mode
};

struct IkConst {
  LegConst g1, g2;
  double thr13, thr24, thr34;  // kSingularSin * L_I * L_J
  explicit IkConst(const Mechanism& m)
      : g1{m.O1.x(), m.O1.y(), m.L[0], detail::CirclePair::make(m.L[0], m.L[2]).on_side(-m.working_mode.sign1)},
        g2{m.O2.x(), m.O2.y(), m.L[1], detail::CirclePair::make(m.L[1], m.L[3]).on_side(-m.working_mode.sign2)},
        thr13(tol::kSingularSin * m.L[0] * m.L[2]), thr24(tol::kSingularSin * m.L[1] * m.L[3]),
        thr34(tol::kSingularSin * m.L[2] * m.L[3]) {}
};

/// Elbow offset A - O for a leg at tactor (px, py); returns reachability.
inline bool elbow_offset(const LegConst& g, double px, double py, double& ex, double& ey) {
  const double dx = px - g.ox, dy = py - g.oy;
  const double d2 = dx * dx + dy * dy;
  const bool coincident = !(d2 >= detail::kMinD2);
  const double inv_d2 = 1.0 / (coincident ? 1.0 : d2);
  double t, hs;  // A - O = t (dx, dy) + hs (-dy, dx), hs = s hd signed by the chord side s
  const bool reach = !coincident & detail::chord(g.circles, d2, inv_d2, t, hs);
  // Finite when the circles meet (see detail::kMinD2); otherwise they may not be, and every caller selects
  // its outputs on the reach flag, so the offsets themselves are not selected.
  ex = t * dx - hs * dy;
  ey = t * dy + hs * dx;
  return reach;
}

/// Elbows and their singularity measures at one tactor point.
struct Elbows {
  double e1x, e1y, e2x, e2y, f1x, f1y, f2x, f2y;
  bool reach;
};
inline Elbows elbows(const IkConst& g, double px, double py) {
  Elbows e;
  const bool r1 = elbow_offset(g.g1, px, py, e.e1x, e.e1y);
  const bool r2 = elbow_offset(g.g2, px, py, e.e2x, e.e2y);
  e.f1x = px - (g.g1.ox + e.e1x);
  e.f1y = py - (g.g1.oy + e.e1y);
  e.f2x = px - (g.g2.ox + e.e2x);
  e.f2y = py - (g.g2.oy + e.e2y);
  e.reach = r1 & r2;
  return e;
}

template <class Trig, class S>
inline void ik_from_elbows(const IkConst& g, const Elbows& e, double& theta1, double& theta2, S& status) {
  const bool sing1 = (std::fabs(cross(e.e1x, e.e1y, e.f1x, e.f1y)) < g.thr13) |
                     (std::fabs(cross(e.e2x, e.e2y, e.f2x, e.f2y)) < g.thr24);
  const bool sing2 = std::fabs(cross(e.f1x, e.f1y, e.f2x, e.f2y)) < g.thr34;
  theta1 = e.reach ? Trig::angle(e.e1y, e.e1x, g.g1.r) : 0.0;
  theta2 = e.reach ? Trig::angle(e.e2y, e.e2x, g.g2.r) : 0.0;
  status = detail::classify_as<S>(e.reach, sing1, sing2);
}

// Inside the vectorised loops statuses are 16-bit codes in a block on the stack, narrowed to
// Status after each block. A byte-sized element in the loop makes GCC run 32 points per AVX2
// iteration (eight registers per double, heavy spilling); 16 measured fastest (more independent
// chains than 4 or 8 to hide the division and root latencies, fewer spills than 32).
using Code = std::int16_t;
constexpr std::size_t kBlock = 256;
constexpr Code kOutsideBit = 4;  // fk_batch: an angle beyond the fast reduction's range

/// The blocking of the batch loops: `body(b, len, code)` fills code[0, len) for the points
/// [b, b + len), and each block's codes are then narrowed into `status`, with the `flags` bits
/// masked off; returns the OR of those bits over all points. Inlined into each SIMD clone, and so
/// must the body be (its lambda carries always_inline): a body left out of line is compiled once,
/// for baseline x86-64, and the FK batch ran 3x slower so. ctest batch_kernels_inlined checks it.
template <class Body>
[[gnu::always_inline]] inline Code for_blocks(std::span<Status> status, Code flags, Body&& body) {
  alignas(64) Code code[kBlock];
  Code seen = 0;
  for (std::size_t b = 0; b < status.size(); b += kBlock) {
    const std::size_t len = std::min(kBlock, status.size() - b);
    body(b, len, code);
    Status* __restrict st = status.data() + b;
    Code block_seen = 0;
    for (std::size_t k = 0; k < len; ++k) {
      st[k] = Status(code[k] & ~flags);
      block_seen |= code[k] & flags;
    }
    seen |= block_seen;
  }
  return seen;
}

}  // namespace

// --- scalar lean forms ---------------------------------------------------------------------------

PointResult fk_point(const Mechanism& m, double theta1, double theta2) {
  PointResult r;
  if (!(std::isfinite(theta1) && std::isfinite(theta2))) return r;
  const FkConst g(m);
  double px, py;
  if (m.assembly_mode == AssemblyMode::Any) {
    fk_one<LibmTrig, true>(g, theta1, theta2, px, py, r.status);
  } else {
    fk_one<LibmTrig, false>(g, theta1, theta2, px, py, r.status);
  }
  r.P = {px, py};
  return r;
}

AnglesResult ik_angles(const Mechanism& m, const Vec2& P) {
  AnglesResult r;
  const IkConst g(m);
  const Elbows e = elbows(g, P.x(), P.y());
  if (!e.reach) return r;  // unreachable, angles 0
  // Loop closure of the configuration the angles describe: |A_i - O_i| = L_i, |P - A_i| = L_{i+2}
  // (first-order length residuals, no square roots), taken before the atan2 calls while the
  // elbows are still in registers. ik() additionally runs the angles forward through sin/cos;
  // here that would cost as much as the IK itself, and atan2 of the elbow offset is exact to
  // < 1 ulp.
  const auto residual = [](double x, double y, double l) { return std::fabs((x * x + y * y) - l * l) / (2.0 * l); };
  const double closure = std::max({residual(e.e1x, e.e1y, m.L[0]), residual(e.e2x, e.e2y, m.L[1]),
                                   residual(e.f1x, e.f1y, m.L[2]), residual(e.f2x, e.f2y, m.L[3])});
  ik_from_elbows<LibmTrig>(g, e, r.theta1, r.theta2, r.status);
  r.closure_error_mm = closure;
  // kClosureRel * length_scale(); the links alone settle it unless the bases are further apart
  // than the longest link, and only then is |O2 - O1| (a square root) needed.
  const double longest_link = std::max({m.L[0], m.L[1], m.L[2], m.L[3]});
  const bool closed = closure <= tol::kClosureRel * longest_link || closure <= tol::kClosureRel * m.length_scale();
  if (!closed && r.status == Status::ok) r.status = Status::singular_type1;  // only a numerically degenerate chord can get here
  return r;
}

// --- batch ---------------------------------------------------------------------------------------

FIVEBAR_SIMD_CLONES void fk_batch(const Mechanism& m, std::span<const double> theta1, std::span<const double> theta2,
              std::span<double> px, std::span<double> py, std::span<Status> status) {
  const std::size_t n = theta1.size();
  assert(theta2.size() == n && px.size() == n && py.size() == n && status.size() == n);
  const FkConst g(m);
  // Arguments beyond the fast reduction's range (|theta| > 1e6 rad, or not finite) are rare: the
  // loop only marks them (kOutsideBit in the code), and only if there was one does a second pass
  // redo them exactly.
  const auto mark = [](double t1, double t2, Code c) {
    return (std::fabs(t1) <= detail::kFastTrigMax) & (std::fabs(t2) <= detail::kFastTrigMax) ? c : Code(c | kOutsideBit);
  };
  const bool any = m.assembly_mode == AssemblyMode::Any;
  const Code outside = for_blocks(status, kOutsideBit, [&](std::size_t b, std::size_t len, Code* __restrict code) __attribute__((always_inline)) {
    const double* __restrict t1 = theta1.data() + b;
    const double* __restrict t2 = theta2.data() + b;
    double* __restrict x = px.data() + b;
    double* __restrict y = py.data() + b;
    if (any) {
      for (std::size_t k = 0; k < len; ++k) {
        Code c;
        fk_one<FastTrig, true>(g, t1[k], t2[k], x[k], y[k], c);
        code[k] = mark(t1[k], t2[k], c);
      }
    } else {
      for (std::size_t k = 0; k < len; ++k) {
        Code c;
        fk_one<FastTrig, false>(g, t1[k], t2[k], x[k], y[k], c);
        code[k] = mark(t1[k], t2[k], c);
      }
    }
  });
  if (!outside) return;
  for (std::size_t k = 0; k < n; ++k) {
    if (!(std::fabs(theta1[k]) <= detail::kFastTrigMax && std::fabs(theta2[k]) <= detail::kFastTrigMax)) {
      const PointResult p = fk_point(m, theta1[k], theta2[k]);
      px[k] = p.P.x();
      py[k] = p.P.y();
      status[k] = p.status;
    }
  }
}

FIVEBAR_SIMD_CLONES void ik_batch(const Mechanism& m, std::span<const double> px, std::span<const double> py,
              std::span<double> theta1, std::span<double> theta2, std::span<Status> status) {
  assert(py.size() == px.size() && theta1.size() == px.size() && theta2.size() == px.size() &&
         status.size() == px.size());
  const IkConst g(m);
  for_blocks(status, 0, [&](std::size_t b, std::size_t len, Code* __restrict code) __attribute__((always_inline)) {
    const double* __restrict x = px.data() + b;
    const double* __restrict y = py.data() + b;
    double* __restrict t1 = theta1.data() + b;
    double* __restrict t2 = theta2.data() + b;
    for (std::size_t k = 0; k < len; ++k) ik_from_elbows<FastTrig>(g, elbows(g, x[k], y[k]), t1[k], t2[k], code[k]);
  });
}

FIVEBAR_SIMD_CLONES void lci_batch(const Mechanism& m, std::span<const double> px, std::span<const double> py,
               std::span<double> lci, std::span<Status> status) {
  assert(py.size() == px.size() && lci.size() == px.size() && status.size() == px.size());
  const IkConst g(m);
  for_blocks(status, 0, [&](std::size_t b, std::size_t len, Code* __restrict code) __attribute__((always_inline)) {
    const double* __restrict x = px.data() + b;
    const double* __restrict y = py.data() + b;
    double* __restrict out = lci.data() + b;
    for (std::size_t k = 0; k < len; ++k) {
      const Elbows e = elbows(g, x[k], y[k]);
      const double c1 = cross(e.e1x, e.e1y, e.f1x, e.f1y), c2 = cross(e.e2x, e.e2y, e.f2x, e.f2y);
      const double cb = cross(e.f1x, e.f1y, e.f2x, e.f2y);
      const Code c = detail::classify_as<Code>(e.reach, (std::fabs(c1) < g.thr13) | (std::fabs(c2) < g.thr24),
                                               std::fabs(cb) < g.thr34);
      // M = adj(B) C, cond(M) = cond(J) (see kinematics.cpp).
      const double v = detail::lci2(e.f2y * c1, -e.f1y * c2, -e.f2x * c1, e.f1x * c2);
      out[k] = c == Code(Status::ok) ? v : 0.0;
      code[k] = c;
    }
  });
}

FIVEBAR_SIMD_CLONES void conditioning_batch(const Mechanism& m, std::span<const double> px, std::span<const double> py,
                        std::span<double> lci, std::span<double> force, std::span<std::int8_t> assembly,
                        std::span<Status> status) {
  const std::size_t n = px.size();
  assert(py.size() == n && lci.size() == n && force.size() == n && assembly.size() == n && status.size() == n);
  const IkConst g(m);
  for (std::size_t k = 0; k < n; ++k) {
    const Elbows e = elbows(g, px[k], py[k]);
    const double c1 = cross(e.e1x, e.e1y, e.f1x, e.f1y), c2 = cross(e.e2x, e.e2y, e.f2x, e.f2y);
    const double cb = cross(e.f1x, e.f1y, e.f2x, e.f2y);
    const bool sing2 = std::fabs(cb) < g.thr34;
    const Status st = detail::classify(e.reach, (std::fabs(c1) < g.thr13) | (std::fabs(c2) < g.thr24), sing2);
    const double m00 = e.f2y * c1, m01 = -e.f1y * c2, m10 = -e.f2x * c1, m11 = e.f1x * c2;
    const double fro2 = m00 * m00 + m01 * m01 + m10 * m10 + m11 * m11;
    const double det = std::fabs(m00 * m11 - m01 * m10);
    const double root = fro2 + std::sqrt(std::max(0.0, (fro2 - 2.0 * det) * (fro2 + 2.0 * det)));
    const bool ok = st == Status::ok;
    lci[k] = ok & (root > 0.0) ? std::min(1.0, 2.0 * det / root) : 0.0;
    const double smax = std::sqrt(0.5 * root);
    force[k] = ok & (smax > 0.0) ? std::fabs(cb) / smax : 0.0;
    assembly[k] = std::int8_t(e.reach & !sing2 ? (cb > 0.0 ? 1 : -1) : 0);
    status[k] = st;
  }
}

}  // namespace fivebar
