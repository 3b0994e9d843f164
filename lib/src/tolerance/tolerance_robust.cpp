// Certified first-order robust margin along the target's boundary, the order-statistic bound of
// a Monte Carlo quantile, and the nonlinear corners of the +-3 sigma box (fivebar/tolerance.hpp).
//
// Robust margin. A leg's set is the annulus r_in <= |X - O| <= r_out, cut by the joint range into
// the curvilinear rectangle of fivebar/workspace/region.hpp: four circular arcs (stretched and folded
// about O; theta = lo and theta = hi about the elbow A = O + L_prox e(theta_limit), radius
// L_dist), joined tangentially. For a point b inside the set the distance to the set's boundary is
// the smallest distance |R - |b - c|| to an arc whose radial projection of b lies on it (the
// nearest boundary point is a foot of a normal; the joins are tangent, so both arcs' normals
// agree there). With the parameters q of ToleranceParameter, dR/dq and dc/dq are constants of the
// arc (dR/dL_prox = 1 for the stretched arc, dc/dO = I, dc/dL_prox = e(theta_limit) for a limit
// arc, ...), so the gradient of the distance is g = sign(R - |b - c|) (dR/dq - u . dc/dq), u the
// unit vector from c to b, and sigma_k(b) = |diag(sigma) g|. Along the ellipse boundary b(t)
// (|b'| <= a, its semi-major axis) d_k - z sigma_k is Lipschitz in t with constant
// a (1 + z |diag(sigma) dc/dq| / |b - c|) (u turns at |b'| / |b - c|), which gives the branch and
// bound's lower bound on an interval; an arc enters an interval's bound when its projection can
// reach the arc within the interval (the direction of b - c turns by at most a h / |b - c|).
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "fivebar/tolerance.hpp"
#include "fivebar/workspace/region.hpp"

namespace fivebar {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::array<Vec2, kToleranceParameters> zeros() {
  std::array<Vec2, kToleranceParameters> z;
  z.fill(Vec2::Zero());
  return z;
}

/// One boundary arc of a leg's set with the derivatives of its radius and centre.
struct Arc {
  Vec2 c{0.0, 0.0};
  double R = 0.0;
  bool full = true;  ///< the whole circle (no joint limits)
  Vec2 from{1.0, 0.0}, to{1.0, 0.0};
  bool ccw = true;
  std::array<double, kToleranceParameters> dR{};
  std::array<Vec2, kToleranceParameters> dc = zeros();  // Eigen's default constructor leaves them unset
  double centre_sigma = 0.0;  ///< |diag(sigma) dc/dq| (Frobenius), the Lipschitz factor of sigma_k in u
};

std::vector<Arc> leg_arcs(const Mechanism& m, int leg, const ParameterSpread& sigma) {
  const Vec2& O = leg == 0 ? m.O1 : m.O2;
  const double lp = m.L[static_cast<std::size_t>(leg)], ld = m.L[static_cast<std::size_t>(leg + 2)];
  const std::size_t prox = static_cast<std::size_t>(leg), dist = static_cast<std::size_t>(leg + 2);
  const std::size_t ox = 4 + 2 * static_cast<std::size_t>(leg), oy = ox + 1;
  const int sign = leg == 0 ? m.working_mode.sign1 : m.working_mode.sign2;
  const JointRange* limits = m.joint_limits ? &(*m.joint_limits)[static_cast<std::size_t>(leg)] : nullptr;
  if (limits != nullptr && limits->span() >= 2.0 * std::numbers::pi) limits = nullptr;
  const auto about_O = [&](double R, double dprox, double ddist) {
    Arc a;
    a.c = O;
    a.R = R;
    a.dR[prox] = dprox;
    a.dR[dist] = ddist;
    a.dc[ox] = Vec2(1.0, 0.0);
    a.dc[oy] = Vec2(0.0, 1.0);
    return a;
  };
  std::vector<Arc> arcs;
  const double r_in = std::fabs(lp - ld);
  const double s_in = lp >= ld ? 1.0 : -1.0;
  Arc outer = about_O(lp + ld, 1.0, 1.0);
  Arc inner = about_O(r_in, s_in, -s_in);
  if (limits == nullptr) {
    arcs.push_back(outer);
    if (r_in > 0.0) arcs.push_back(inner);
  } else {
    const double lo = limits->lo, hi = limits->lo + limits->span();
    const Vec2 e_lo(std::cos(lo), std::sin(lo)), e_hi(std::cos(hi), std::sin(hi));
    outer.full = false;
    outer.from = e_lo;
    outer.to = e_hi;
    outer.ccw = true;
    arcs.push_back(outer);
    const auto limit_arc = [&](const Vec2& e, const Vec2& from, const Vec2& to, bool ccw) {
      Arc a;
      a.c = O + lp * e;
      a.R = ld;
      a.full = false;
      a.from = from;
      a.to = to;
      a.ccw = ccw;
      a.dR[dist] = 1.0;
      a.dc[prox] = e;
      a.dc[ox] = Vec2(1.0, 0.0);
      a.dc[oy] = Vec2(0.0, 1.0);
      return a;
    };
    arcs.push_back(limit_arc(e_hi, e_hi, -e_hi, sign > 0));  // theta = hi: stretched end to folded end
    if (r_in > 0.0) {
      inner.full = false;
      inner.from = (lp - ld) * e_hi;
      inner.to = (lp - ld) * e_lo;
      inner.ccw = false;
      arcs.push_back(inner);
    }
    arcs.push_back(limit_arc(e_lo, -e_lo, e_lo, sign < 0));  // theta = lo: folded end to stretched end
  }
  for (Arc& a : arcs) {
    double v = 0.0;
    if (sigma.correlated()) {  // |dc/dq F| (Frobenius) = sqrt(trace(dc C dc^T))
      std::array<double, kToleranceParameters> gx{}, gy{};
      for (std::size_t j = 0; j < kToleranceParameters; ++j) {
        gx[j] = a.dc[j].x();
        gy[j] = a.dc[j].y();
      }
      v = sigma.variance(gx) + sigma.variance(gy);
    } else {
      for (std::size_t j = 0; j < kToleranceParameters; ++j) v += sigma.sigma()[j] * sigma.sigma()[j] * a.dc[j].squaredNorm();
    }
    a.centre_sigma = std::sqrt(v);
  }
  return arcs;
}

struct ArcValue {
  double d = 0.0, s = 0.0, rho = 0.0;
  std::array<double, kToleranceParameters> g{};
};

ArcValue arc_value(const Arc& a, const ParameterSpread& sigma, const Vec2& b) {
  ArcValue v;
  const Vec2 r = b - a.c;
  v.rho = r.norm();
  const Vec2 u = v.rho > 0.0 ? Vec2(r / v.rho) : Vec2(1.0, 0.0);
  const double side = a.R - v.rho >= 0.0 ? 1.0 : -1.0;
  v.d = std::fabs(a.R - v.rho);
  for (std::size_t j = 0; j < kToleranceParameters; ++j) v.g[j] = side * (a.dR[j] - u.dot(a.dc[j]));
  v.s = std::sqrt(sigma.variance(v.g));
  return v;
}

bool on_arc(const Arc& a, const Vec2& b) { return a.full || direction_within_arc(a.from, a.to, a.ccw, b - a.c); }

/// Angle between the directions of two vectors (rad, in [0, pi]).
double angle_between(const Vec2& x, const Vec2& y) {
  return std::atan2(std::fabs(x.x() * y.y() - x.y() * y.x()), x.dot(y));
}

/// Does the point lie in both legs' sets? (The annuli and, with limits, the joint ranges of the
/// working mode's elbow: fivebar/workspace/region.hpp.)
bool in_legs(const Mechanism& m, const Vec2& b) {
  for (int leg = 0; leg < 2; ++leg) {
    const Vec2& O = leg == 0 ? m.O1 : m.O2;
    const double lp = m.L[static_cast<std::size_t>(leg)], ld = m.L[static_cast<std::size_t>(leg + 2)];
    const double d = (b - O).norm();
    if (d > lp + ld || d < std::fabs(lp - ld)) return false;
    if (!m.joint_limits) continue;
    const JointRange& l = (*m.joint_limits)[static_cast<std::size_t>(leg)];
    if (l.span() >= 2.0 * std::numbers::pi) continue;
    const int sign = leg == 0 ? m.working_mode.sign1 : m.working_mode.sign2;
    const CircleIntersection x = intersect_circles(O, lp, b, ld, -sign);
    if (x.status == Status::unreachable) return false;
    const double hi = l.lo + l.span();
    if (!direction_within_arc(Vec2(std::cos(l.lo), std::sin(l.lo)), Vec2(std::cos(hi), std::sin(hi)), true, x.offset))
      return false;
  }
  return true;
}

RobustPoint evaluate(const std::vector<Arc>& arcs, const ParameterSpread& sigma, double z, const Vec2& b,
                     double* fraction) {
  RobustPoint out;
  out.inside = true;
  out.distance_mm = kInf;
  out.robust_mm = kInf;
  for (const Arc& a : arcs) {
    if (!on_arc(a, b)) continue;
    const ArcValue v = arc_value(a, sigma, b);
    out.distance_mm = std::min(out.distance_mm, v.d);
    const double r = v.d - z * v.s;
    if (r < out.robust_mm) {
      out.robust_mm = r;
      out.sigma_mm = v.s;
      out.gradient = v.g;
    }
    if (fraction != nullptr) {
      const double f = v.s > 0.0 ? 0.5 * std::erfc(-v.d / (v.s * std::numbers::sqrt2)) : 1.0;
      *fraction = std::min(*fraction, f);
    }
  }
  return out;
}

std::vector<Arc> mechanism_arcs(const Mechanism& m, const ParameterSpread& sigma) {
  std::vector<Arc> arcs = leg_arcs(m, 0, sigma);
  const std::vector<Arc> second = leg_arcs(m, 1, sigma);
  arcs.insert(arcs.end(), second.begin(), second.end());
  return arcs;
}

}  // namespace

RobustPoint robust_margin_at(const Mechanism& m, const ParameterSpread& sigma, double z, const Vec2& b) {
  if (!in_legs(m, b)) return RobustPoint{};
  return evaluate(mechanism_arcs(m, sigma), sigma, z, b, nullptr);
}

RobustMarginBound robust_margin_min(const Mechanism& m, const Ellipse& target, const ParameterSpread& sigma, double z,
                                    double tol_mm) {
  RobustMarginBound out;
  const std::vector<Arc> arcs = mechanism_arcs(m, sigma);
  const double speed = 0.5 * std::max(target.axes.x(), target.axes.y()) * (1.0 + 1e-12);
  double fraction = 1.0;
  out.value_mm = kInf;
  const auto f = [&](double t) {
    const Vec2 b = target.boundary_point(t);
    ++out.evaluations;
    const RobustPoint r = evaluate(arcs, sigma, z, b, &fraction);
    if (r.robust_mm < out.value_mm) {
      out.value_mm = r.robust_mm;
      out.point = b;
      out.at = r;
    }
    return b;
  };
  // Lower bound of min_k (d_k - z sigma_k) over [t - h, t + h] from the arcs at b = b(t).
  const auto bound = [&](const Vec2& b, double h) {
    double lb = kInf;
    for (const Arc& a : arcs) {
      const ArcValue v = arc_value(a, sigma, b);
      const double rho_min = v.rho - speed * h;
      if (!(rho_min > 0.0)) return -kInf;
      const double turn = speed * h / rho_min;
      const bool reach = on_arc(a, b) || angle_between(b - a.c, a.from) <= turn || angle_between(b - a.c, a.to) <= turn;
      if (!reach) continue;
      const double lipschitz = speed * (1.0 + z * a.centre_sigma / rho_min);
      lb = std::min(lb, v.d - z * v.s - lipschitz * h);
    }
    return lb;
  };
  struct Interval {
    double t, h, lb;
    bool operator>(const Interval& o) const { return lb > o.lb; }
  };
  constexpr int kInitial = 256;
  constexpr std::size_t kMaxEvaluations = 1u << 18;
  std::vector<Interval> heap;
  const double h0 = std::numbers::pi / kInitial;
  for (int k = 0; k < kInitial; ++k) {
    const double t = (2 * k + 1) * h0;
    heap.push_back({t, h0, bound(f(t), h0)});
  }
  std::make_heap(heap.begin(), heap.end(), std::greater<>());
  while (!heap.empty()) {
    const Interval top = heap.front();
    if (top.lb >= out.value_mm - tol_mm) break;
    if (out.evaluations >= kMaxEvaluations || top.h < 1e-14) {
      out.capped = true;
      break;
    }
    std::pop_heap(heap.begin(), heap.end(), std::greater<>());
    heap.pop_back();
    const double h = 0.5 * top.h;
    for (const double t : {top.t - h, top.t + h}) {
      heap.push_back({t, h, bound(f(t), h)});
      std::push_heap(heap.begin(), heap.end(), std::greater<>());
    }
  }
  out.lower_mm = heap.empty() ? out.value_mm : std::min(out.value_mm, heap.front().lb);
  out.fraction_first_order = fraction;
  out.certified = !out.capped && std::isfinite(out.lower_mm);
  return out;
}

QuantileBound quantile_lower_bound_rank(std::size_t n, double p, double confidence) {
  QuantileBound out;
  if (n == 0 || !(p > 0.0 && p < 1.0)) return out;
  // P(Bin(n, p) >= r) >= confidence  <=>  P(Bin <= r - 1) <= 1 - confidence: accumulate the pmf
  // (in logs: (1 - p)^n underflows for large n) until the cdf passes 1 - confidence.
  const double nn = static_cast<double>(n);
  const double log_n1 = std::lgamma(nn + 1.0), lp = std::log(p), lq = std::log1p(-p);
  double cdf = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const double kk = static_cast<double>(k);
    const double pmf = std::exp(log_n1 - std::lgamma(kk + 1.0) - std::lgamma(nn - kk + 1.0) + kk * lp + (nn - kk) * lq);
    if (cdf + pmf > 1.0 - confidence) break;
    cdf += pmf;
    out.rank = k + 1;
    out.coverage = 1.0 - cdf;
  }
  return out;
}

CornerEnumeration tolerance_corners(const Mechanism& m, const Vec2& P, const ParameterSpread& sigma, double k_sigma) {
  CornerEnumeration out;
  const Pose nominal = ik(m, P);
  out.status = nominal.status;
  if (nominal.status != Status::ok) return out;
  Mechanism printed = m;
  printed.joint_limits.reset();
  printed.assembly_mode = nominal.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
  // Independent: the parameters with sigma > 0; correlated: the principal components (F's columns).
  const ParameterSpread spread = sigma.at(nominal.theta1, nominal.theta2);
  std::vector<std::size_t> free;
  for (std::size_t j = 0; j < kToleranceParameters; ++j) {
    const auto g = spread.generator(j);
    if (std::any_of(g.begin(), g.end(), [](double x) { return x != 0.0; })) free.push_back(j);
  }
  out.corners = std::size_t{1} << free.size();
  for (std::size_t mask = 0; mask < out.corners; ++mask) {
    std::array<double, kToleranceParameters> z{};
    std::array<std::int8_t, kToleranceParameters> signs{};
    for (std::size_t b = 0; b < free.size(); ++b) {
      signs[free[b]] = (mask >> b) & 1U ? 1 : -1;
      z[free[b]] = signs[free[b]] * k_sigma;
    }
    const std::array<double, kToleranceParameters> dq = spread.draw(z);
    for (std::size_t i = 0; i < 4; ++i) printed.L[i] = m.L[i] + dq[i];
    printed.O1 = m.O1 + Vec2(dq[4], dq[5]);
    printed.O2 = m.O2 + Vec2(dq[6], dq[7]);
    const bool lengths_ok = std::all_of(printed.L.begin(), printed.L.end(), [](double l) { return l > 0.0; });
    const PointResult r = lengths_ok ? fk_point(printed, nominal.theta1 + dq[8], nominal.theta2 + dq[9]) : PointResult{};
    if (r.status != Status::ok) {
      ++out.failed;
      continue;
    }
    const double d = (r.P - P).norm();
    if (d > out.worst_mm) {
      out.worst_mm = d;
      out.worst_corner = signs;
    }
  }
  return out;
}

}  // namespace fivebar
