// Quad-precision reference kinematics (see report/quad.hpp for the formulas and their accuracy).
#include "report/quad.hpp"

#include <algorithm>
#include <vector>

namespace fivebar::quadref {

namespace {

const quad kPi = kQuadPi;

quad qmax(quad a, quad b) { return a < b ? b : a; }
quad qmin(quad a, quad b) { return a < b ? a : b; }

/// (2 d r1 sin(angle at c1))^2 by Heron's factors; negative when the circles miss each other.
quad heron(quad d, quad r1, quad r2) { return (d + r1 + r2) * (-d + r1 + r2) * (d - r1 + r2) * (d + r1 - r2); }

/// Heron products within a few rounding errors of zero are tangencies, not misses: K is a
/// product of four factors each carrying ~eps_q * scale of absolute error.
bool heron_reachable(quad& K, quad d, quad r1, quad r2) {
  const quad s = qmax(d, qmax(r1, r2));
  const quad tol = 64 * kQuadEps * s * s * s * s;
  if (K < 0 && K >= -tol) K = 0;
  return K >= 0;
}

QVec unit(quad angle) {
  quad s, c;
  sincosq(angle, &s, &c);
  return {c, s};
}

/// 1 / cond of a 2x2 matrix, from its Frobenius norm and determinant (closed-form SVD).
quad lci_of(quad m00, quad m01, quad m10, quad m11) {
  const quad f = m00 * m00 + m01 * m01 + m10 * m10 + m11 * m11;
  const quad g = qabs(m00 * m11 - m01 * m10);
  const quad disc = qmax(0, (f - 2 * g) * (f + 2 * g));
  const quad den = f + sqrtq(disc);
  return den > 0 ? qmin(1, 2 * g / den) : 0;
}

}  // namespace

QMechanism::QMechanism(const Mechanism& m)
    : O1(q(m.O1)), O2(q(m.O2)), L{m.L[0], m.L[1], m.L[2], m.L[3]}, w1(m.working_mode.sign1),
      w2(m.working_mode.sign2) {}

quad circle_gap(quad dist, quad r1, quad r2) { return qmax(dist - (r1 + r2), qabs(r1 - r2) - dist); }

void analyse(const QMechanism& m, QPose& p) {
  const QVec e1 = p.A1 - m.O1, e2 = p.A2 - m.O2, f1 = p.P - p.A1, f2 = p.P - p.A2;
  const quad c1 = cross(e1, f1), c2 = cross(e2, f2), cb = cross(f1, f2);
  p.type1_sin = {qmin(1, qabs(c1) / (m.L[0] * m.L[2])), qmin(1, qabs(c2) / (m.L[1] * m.L[3]))};
  p.type2_sin = qmin(1, qabs(cb) / (m.L[2] * m.L[3]));
  // Differentiating |P - A_i|^2 = L_{i+2}^2: (P - A_i) . dP = cross(A_i - O_i, P - A_i) dtheta_i.
  const quad m00 = f2.y * c1, m01 = -f1.y * c2, m10 = -f2.x * c1, m11 = f1.x * c2;
  p.lci = lci_of(m00, m01, m10, m11);
  p.jacobian_valid = cb != 0;
  if (p.jacobian_valid) {
    p.J = {{{m00 / cb, m01 / cb}, {m10 / cb, m11 / cb}}};
    const quad lb = lci_of(f1.x, f1.y, f2.x, f2.y);
    p.cond_B = lb > 0 ? 1 / lb : 0;
  } else {
    p.J = {};
    p.cond_B = 0;
  }
}

quad fk_gap(const QMechanism& m, quad theta1, quad theta2) {
  const QVec A1 = m.O1 + m.L[0] * unit(theta1), A2 = m.O2 + m.L[1] * unit(theta2);
  return circle_gap(norm(A2 - A1), m.L[2], m.L[3]);
}

quad ik_gap(const QMechanism& m, QVec P) {
  return qmax(circle_gap(norm(P - m.O1), m.L[0], m.L[2]), circle_gap(norm(P - m.O2), m.L[1], m.L[3]));
}

QPose fk(const QMechanism& m, quad theta1, quad theta2, int side) {
  QPose p;
  p.theta1 = theta1;
  p.theta2 = theta2;
  p.A1 = m.O1 + m.L[0] * unit(theta1);
  p.A2 = m.O2 + m.L[1] * unit(theta2);
  const QVec v = p.A2 - p.A1;
  const quad dist = norm(v);
  const quad L3 = m.L[2], L4 = m.L[3];
  if (dist == 0) {
    if (L3 != L4) return p;  // concentric circles of different radii never meet
    p.reachable = true;
    p.continuum = true;
    p.P = p.A1 + L3 * QVec{0, quad(side >= 0 ? 1 : -1)};
    analyse(m, p);
    return p;
  }
  quad K = heron(dist, L3, L4);
  if (!heron_reachable(K, dist, L3, L4)) return p;
  // Law of cosines at A1: cos = (d^2 + L3^2 - L4^2) / (2 d L3), sin = sqrt(K) / (2 d L3).
  const quad alpha = atan2q(sqrtq(K), dist * dist + L3 * L3 - L4 * L4);
  const quad phi = atan2q(v.y, v.x);
  p.P = p.A1 + L3 * unit(phi + (side >= 0 ? alpha : -alpha));
  p.reachable = true;
  analyse(m, p);
  return p;
}

QPose ik(const QMechanism& m, QVec P, int sign1, int sign2) {
  QPose p;
  p.P = P;
  for (int i = 0; i < 2; ++i) {
    const QVec O = i == 0 ? m.O1 : m.O2;
    const quad Lp = m.L[i], Ld = m.L[i + 2];
    const int sigma = i == 0 ? sign1 : sign2;
    const QVec v = P - O;
    const quad D = norm(v);
    quad theta = 0;
    if (D == 0) {
      if (Lp != Ld) return p;
      p.continuum = true;  // P on the base joint with L_i = L_{i+2}: any theta closes the leg
    } else {
      quad K = heron(D, Lp, Ld);
      if (!heron_reachable(K, D, Lp, Ld)) return p;
      // Angle at O between O->P and O->A; A = O + L e(phi - sigma beta) has
      // cross(A - O, P - A) = L D sin(sigma beta), of sign sigma.
      const quad beta = atan2q(sqrtq(K), D * D + Lp * Lp - Ld * Ld);
      theta = atan2q(v.y, v.x) - sigma * beta;
    }
    (i == 0 ? p.theta1 : p.theta2) = theta;
    (i == 0 ? p.A1 : p.A2) = O + Lp * unit(theta);
  }
  p.reachable = true;
  analyse(m, p);
  return p;
}

quad lens_area(quad a, quad b, quad dist) {
  if (a <= 0 || b <= 0 || dist >= a + b) return 0;
  if (dist <= qabs(a - b)) return kPi * qmin(a, b) * qmin(a, b);
  quad K = heron(dist, a, b);
  if (K < 0) K = 0;
  const quad k = sqrtq(K);
  // Half-angles of the lens at each centre from atan2 (no acos near +-1).
  const quad alpha = atan2q(k, dist * dist + a * a - b * b);
  const quad beta = atan2q(k, dist * dist + b * b - a * a);
  return a * a * alpha + b * b * beta - k / 2;
}

quad annuli_area(const QMechanism& m) {
  const quad dist = norm(m.O2 - m.O1);
  const quad R1 = m.L[0] + m.L[2], r1 = qabs(m.L[0] - m.L[2]);
  const quad R2 = m.L[1] + m.L[3], r2 = qabs(m.L[1] - m.L[3]);
  return lens_area(R1, R2, dist) - lens_area(R1, r2, dist) - lens_area(r1, R2, dist) + lens_area(r1, r2, dist);
}

QExtremes ellipse_extremes(const Ellipse& e, QVec p) {
  const quad a = quad(e.axes.x()) / 2, b = quad(e.axes.y()) / 2;
  quad sr, cr;
  sincosq(quad(e.angle), &sr, &cr);
  const QVec dp = p - q(e.center);
  const quad x = cr * dp.x + sr * dp.y, y = -sr * dp.x + cr * dp.y;
  auto f = [&](quad t) {
    const QVec u = unit(t);
    const quad dx = a * u.x - x, dy = b * u.y - y;
    return dx * dx + dy * dy;
  };
  // g = f'/2 and g'; every extremum of f is a root of g of odd multiplicity.
  auto g = [&](quad t) {
    const QVec u = unit(t);
    return (b * b - a * a) * u.y * u.x + a * x * u.y - b * y * u.x;
  };
  auto dg = [&](quad t) {
    const QVec u = unit(t), u2 = unit(2 * t);
    return (b * b - a * a) * u2.x + a * x * u.x + b * y * u.y;
  };
  constexpr int N = 512;
  std::vector<quad> ts(N + 1), gs(N + 1);
  QExtremes out;
  out.min_distance = quad(1e300);
  out.max_distance = 0;
  auto consider = [&](quad t) {
    const quad v = f(t);
    out.min_distance = qmin(out.min_distance, v);
    out.max_distance = qmax(out.max_distance, v);
  };
  for (int k = 0; k <= N; ++k) {
    ts[k] = 2 * kPi * k / N;
    gs[k] = g(ts[k]);
    if (k < N) consider(ts[k]);
  }
  for (int k = 0; k < N; ++k) {
    if (gs[k] == 0) continue;
    if ((gs[k] > 0) == (gs[k + 1] > 0) && gs[k + 1] != 0) continue;
    // Safeguarded Newton in the bracket [lo, hi] with g(lo) of sign glo.
    quad lo = ts[k], hi = ts[k + 1], t = (lo + hi) / 2;
    const bool glo_pos = gs[k] > 0;
    for (int it = 0; it < 300 && hi - lo > quad(1e-32); ++it) {
      const quad gt = g(t);
      if (gt == 0) break;
      if ((gt > 0) == glo_pos) {
        lo = t;
      } else {
        hi = t;
      }
      const quad dgt = dg(t);
      quad tn = dgt != 0 ? t - gt / dgt : (lo + hi) / 2;
      if (!(tn > lo && tn < hi)) tn = (lo + hi) / 2;
      if (qabs(tn - t) < quad(1e-33)) {
        t = tn;
        break;
      }
      t = tn;
    }
    consider(t);
  }
  out.min_distance = sqrtq(out.min_distance);
  out.max_distance = sqrtq(out.max_distance);
  out.inside = (x / a) * (x / a) + (y / b) * (y / b) <= 1;
  return out;
}

quad annuli_margin(const QMechanism& m, const Ellipse& e) {
  quad margin = quad(1e300);
  for (int i = 0; i < 2; ++i) {
    const QVec O = i == 0 ? m.O1 : m.O2;
    const quad outer = m.L[i] + m.L[i + 2], inner = qabs(m.L[i] - m.L[i + 2]);
    const QExtremes ex = ellipse_extremes(e, O);
    margin = qmin(margin, outer - ex.max_distance);
    if (inner > 0) margin = qmin(margin, (ex.inside ? quad(0) : ex.min_distance) - inner);
  }
  return margin;
}

}  // namespace fivebar::quadref
