#pragma once
/// Branch-free sin/cos and atan2 that GCC vectorises inside loops (glibc's are opaque calls).
/// Argument reduction and kernels follow fdlibm (Sun Microsystems, 1993): Cody-Waite reduction by
/// pi/2 in three parts, minimax polynomials on [-pi/4, pi/4] (sin, cos) and |t| <= tan(pi/8)
/// (atan). Accuracy: < 3 ulp against the exact value for |x| <= kFastTrigMax (measured worst
/// 2.3 ulp; test_kinematics checks it against long double); glibc's are < 1 ulp. Callers handle |x| > kFastTrigMax themselves.
/// Internal: not part of the stable API.

#include <cmath>

/// FIVEBAR_SIMD_CLONES on a function with a vectorisable loop: GCC compiles it three times, for
/// baseline x86-64 (SSE2, two doubles per vector), AVX2 (four) and x86-64-v4 (AVX-512: eight, 32
/// vector registers, mask registers), and picks the clone at load time (ifunc). Translation units
/// that use it are compiled with -ffp-contract=off (lib/ and test/bench/ CMakeLists): AVX2 and
/// AVX-512 machines have FMA, and contracting a*b+c into one rounding would change results. So
/// every clone runs the same IEEE operations in the same order and gives bit-identical results
/// (test `no_fused_multiply_add` checks the objects). Elsewhere (other compilers or targets) it
/// expands to nothing.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define FIVEBAR_SIMD_CLONES __attribute__((target_clones("arch=x86-64-v4", "avx2", "default")))
#else
#define FIVEBAR_SIMD_CLONES
#endif

namespace fivebar::detail {

/// Largest |x| (rad) for which fast_sincos is accurate: the reduction multiplies the quadrant
/// number by 33-bit parts of pi/2 exactly while it stays below 2^20.
inline constexpr double kFastTrigMax = 1.0e6;

inline void fast_sincos(double x, double& s_out, double& c_out) {
  constexpr double kInvPio2 = 6.36619772367581382433e-01;
  constexpr double kPio2_1 = 1.57079632673412561417e+00;   // first 33 bits of pi/2
  constexpr double kPio2_2 = 6.07710050630396597660e-11;   // next 33 bits
  constexpr double kPio2_2t = 2.02226624879595063154e-21;  // pi/2 - kPio2_1 - kPio2_2
  constexpr double kRound = 0x1.8p52;                      // adding it rounds to an integer
  const double fn = (x * kInvPio2 + kRound) - kRound;  // nearest integer to x / (pi/2)
  const double r = ((x - fn * kPio2_1) - fn * kPio2_2) - fn * kPio2_2t;
  // Quadrant fn mod 4 as q in {-2, -1, 0, 1, 2} (q = -2 and 2 are the same quadrant), kept in
  // doubles: 64-bit integer compares do not vectorise on baseline x86-64.
  const double q = fn - 4.0 * ((fn * 0.25 + kRound) - kRound);

  const double z = r * r;
  constexpr double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                   S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                   S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
  constexpr double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                   C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                   C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
  const double ps = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
  const double sin_r = r + (z * r) * (S1 + z * ps);
  const double pc = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
  const double hz = 0.5 * z;
  const double w = 1.0 - hz;
  const double cos_r = w + (((1.0 - w) - hz) + z * pc);

  const bool swap = std::fabs(q) == 1.0;
  const double s = swap ? cos_r : sin_r;
  const double c = swap ? sin_r : cos_r;
  // sin is negated in quadrants 2 and 3 (q = +-2, -1), cos in quadrants 1 and 2 (q = 1, +-2).
  s_out = (q == -1.0 || std::fabs(q) == 2.0) ? -s : s;
  c_out = (q == 1.0 || std::fabs(q) == 2.0) ? -c : c;
}

/// fdlibm's atan kernel: t (s1 + s2) with atan(t) = t - that, for |t| <= 7/16.
inline double atan_tail(double t) {
  constexpr double aT0 = 3.33333333333329318027e-01, aT1 = -1.99999999998764832476e-01,
                   aT2 = 1.42857142725034663711e-01, aT3 = -1.11111104054623557880e-01,
                   aT4 = 9.09088713343650656196e-02, aT5 = -7.69187620504482999495e-02,
                   aT6 = 6.66107313738753120669e-02, aT7 = -5.83357013379057348645e-02,
                   aT8 = 4.97687799461593236017e-02, aT9 = -3.65315727442169155270e-02,
                   aT10 = 1.62858201153657823623e-02;
  const double z = t * t;
  const double w = z * z;
  const double s1 = z * (aT0 + w * (aT2 + w * (aT4 + w * (aT6 + w * (aT8 + w * aT10)))));
  const double s2 = w * (aT1 + w * (aT3 + w * (aT5 + w * (aT7 + w * aT9))));
  return t * (s1 + s2);
}

/// From a0 = atan2(min(|x|, |y|), max(|x|, |y|)) in [0, pi/4] to atan2(y, x) in [-pi, pi], with pi/2
/// and pi in two parts so that the subtractions keep a0's digits.
inline double atan_unfold(double a0, double x, double y) {
  constexpr double kPio2Hi = 1.57079632679489655800e+00, kPio2Lo = 6.12323399573676603587e-17;
  constexpr double kPiHi = 3.14159265358979311600e+00, kPiLo = 1.22464679914735317720e-16;
  const double a1 = std::fabs(y) > std::fabs(x) ? (kPio2Hi - a0) + kPio2Lo : a0;
  const double a2 = x < 0.0 ? (kPiHi - a1) + kPiLo : a1;
  return std::copysign(a2, y);
}

/// atan2(y, x) in [-pi, pi]; atan2(0, 0) = 0. Finite inputs only.
inline double fast_atan2(double y, double x) {
  constexpr double kTanPi8 = 0.41421356237309504880;
  constexpr double kPio4Hi = 7.85398163397448278999e-01, kPio4Lo = 3.06161699786838301793e-17;
  const double ax = std::fabs(x);
  const double ay = std::fabs(y);
  const double hi = ax > ay ? ax : ay;
  const double lo = ax > ay ? ay : ax;
  const double q = lo / (hi > 0.0 ? hi : 1.0);  // in [0, 1]
  const bool reduce = q > kTanPi8;
  const double t = reduce ? (q - 1.0) / (q + 1.0) : q;
  const double tail = atan_tail(t);
  return atan_unfold(reduce ? kPio4Hi - ((tail - kPio4Lo) - t) : t - tail, x, y);
}

/// The angle of (x, y) when its length r > 0 is known: atan2(y, x) in [-pi, pi] with one division
/// instead of fast_atan2's two and no reduction step. Folded into the first octant
/// (lo = min(|x|, |y|), hi = max), phi = atan2(lo, hi) <= pi/4 is twice the angle whose tangent is
/// tan(phi/2) = lo / (r + hi) <= tan(pi/8): the range of the atan kernel as it stands. Both terms
/// of r + hi are positive, so the sum and the quotient are correctly rounded; a relative error
/// delta in r against sqrt(x^2 + y^2) moves the result by at most 0.42 delta (rad). For an elbow
/// offset of an IK, whose length is the proximal link's to within the reach slack (16 eps).
inline double fast_angle(double y, double x, double r) {
  const double ax = std::fabs(x);
  const double ay = std::fabs(y);
  const double hi = ax > ay ? ax : ay;
  const double lo = ax > ay ? ay : ax;
  const double t = lo / (r + hi);                           // tan(phi / 2) in [0, tan(pi/8)]
  return atan_unfold(2.0 * (t - atan_tail(t)), x, y);  // exact doubling
}

}  // namespace fivebar::detail
