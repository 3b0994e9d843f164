// Coverage of the target ellipse: certified containment and signed margin, covered fraction,
// conditioning (LCI, force capability) and assembly side over the filled ellipse.
#include "fivebar/coverage/coverage.hpp"

#include <algorithm>
#include <deque>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>

#include "fivebar/kinematics.hpp"
#include "fivebar/numerics.hpp"

namespace fivebar {

namespace {

constexpr double kPi = std::numbers::pi;

/// Boundary samples for the general (joint-limited) path.
/// Polygon sizes of the exact fallback and of the covered-fraction measure.
constexpr int kFractionPolygon = 512;

struct Frame {
  double a, b, c, s;
  Vec2 center;
  explicit Frame(const Ellipse& e)
      : a(0.5 * e.axes.x()), b(0.5 * e.axes.y()), c(std::cos(e.angle)), s(std::sin(e.angle)), center(e.center) {}
  Vec2 to_local(const Vec2& p) const {
    const Vec2 d = p - center;
    return {c * d.x() + s * d.y(), -s * d.x() + c * d.y()};
  }
  Vec2 to_world(const Vec2& q) const { return center + Vec2(c * q.x() - s * q.y(), s * q.x() + c * q.y()); }
  /// Point at fraction r in [0, 1] of the way from the centre to the boundary point at t.
  Vec2 at(double r, double t) const { return to_world({r * a * std::cos(t), r * b * std::sin(t)}); }
};

/// Ellipse polygon: vertices at N equal parameter steps, scaled by `scale` (1 / cos(pi/N) gives
/// a polygon circumscribing the ellipse: the affine image of the regular N-gon around the circle).
std::vector<Vec2> ellipse_polygon(const Ellipse& e, int n, double scale) {
  const Frame f(e);
  std::vector<Vec2> out(n);
  for (int k = 0; k < n; ++k) out[k] = f.at(scale, 2 * kPi * k / n);
  return out;
}

/// Unit-circle samples (cos, sin) of k * 2 pi / n by rotation (error ~ k eps, ample for sampling).
void unit_circle(int n, std::vector<double>& c, std::vector<double>& s) {
  c.resize(n);
  s.resize(n);
  const double cd = std::cos(2 * kPi / n), sd = std::sin(2 * kPi / n);
  double x = 1.0, y = 0.0;
  for (int k = 0; k < n; ++k) {
    c[k] = x;
    s[k] = y;
    const double xn = x * cd - y * sd;
    y = x * sd + y * cd;
    x = xn;
  }
}

double polygon_area(const std::vector<Vec2>& p) {
  double a = 0.0;
  for (std::size_t k = 0; k < p.size(); ++k) {
    const Vec2& u = p[k] - p[0];
    const Vec2& v = p[(k + 1) % p.size()] - p[0];
    a += u.x() * v.y() - u.y() * v.x();
  }
  return 0.5 * std::fabs(a);
}


}  // namespace

EllipseExtremes ellipse_distance_extremes(const Ellipse& e, const Vec2& p) {
  const Frame fr(e);
  const Vec2 q = fr.to_local(p);
  const double a = fr.a, b = fr.b, x = q.x(), y = q.y();
  // f(t) = |(a cos t, b sin t) - (x, y)|^2, a trigonometric polynomial of degree 2: at most four
  // critical points. g = f'/2 and its derivative in closed form.
  auto f = [&](double t) {
    const double dx = a * std::cos(t) - x, dy = b * std::sin(t) - y;
    return dx * dx + dy * dy;
  };
  // g and g' from one sincos (cos 2t = c^2 - s^2).
  auto g = [&](double t) {
    double st, ct;
    ::sincos(t, &st, &ct);
    return (b * b - a * a) * st * ct + a * x * st - b * y * ct;
  };
  auto g_and_dg = [&](double t, double& gv, double& dv) {
    double st, ct;
    ::sincos(t, &st, &ct);
    gv = (b * b - a * a) * st * ct + a * x * st - b * y * ct;
    dv = (b * b - a * a) * (ct * ct - st * st) + a * x * ct + b * y * st;
  };
  constexpr int N = 48;
  struct Table {
    std::vector<double> c, s;
    Table() { unit_circle(N, c, s); }
  };
  static const Table table;  // built once; a static, not thread_local: no TLS wrapper per access
  const double* uc = table.c.data();
  const double* us = table.s.data();
  double fs[N];
  for (int k = 0; k < N; ++k) {
    const double dx = a * uc[k] - x, dy = b * us[k] - y;
    fs[k] = dx * dx + dy * dy;
  }
  double best_min = std::numeric_limits<double>::infinity(), best_max = -1.0, t_min = 0.0, t_max = 0.0;
  for (int k = 0; k < N; ++k) {
    const double fp = fs[(k + N - 1) % N], fc = fs[k], fn = fs[(k + 1) % N];
    const bool is_min = fc <= fp && fc <= fn, is_max = fc >= fp && fc >= fn;
    if (!is_min && !is_max) continue;
    // Safeguarded Newton on g in the bracket around the sample.
    double lo = 2 * kPi * (k - 1) / N, hi = 2 * kPi * (k + 1) / N, t = 2 * kPi * k / N;
    double glo = g(lo), ghi = g(hi);
    if ((glo > 0.0) != (ghi > 0.0)) {
      for (int it = 0; it < 60; ++it) {
        double gt, d;
        g_and_dg(t, gt, d);
        if (gt == 0.0) break;
        double tn = d != 0.0 ? t - gt / d : 0.5 * (lo + hi);
        // Newton converges quadratically: stop once its step is at rounding level.
        if (std::fabs(tn - t) <= 1e-14 * (1.0 + std::fabs(t))) {
          t = tn;
          break;
        }
        if ((gt > 0.0) == (glo > 0.0)) {
          lo = t;
          glo = gt;
        } else {
          hi = t;
        }
        if (!(tn >= lo && tn <= hi)) tn = 0.5 * (lo + hi);  // safeguard: stay in the bracket
        t = tn;
      }
    }
    const double fr_t = f(t);
    const double ft = std::min(fr_t, fc);
    const double tt = fr_t <= fc ? t : 2 * kPi * k / N;
    const double fx = std::max(fr_t, fc);
    const double tx = fr_t >= fc ? t : 2 * kPi * k / N;
    if (is_min && ft < best_min) {
      best_min = ft;
      t_min = tt;
    }
    if (is_max && fx > best_max) {
      best_max = fx;
      t_max = tx;
    }
  }
  EllipseExtremes out;
  out.min_distance = std::sqrt(best_min);
  out.max_distance = std::sqrt(best_max);
  out.nearest = fr.at(1.0, t_min);
  out.farthest = fr.at(1.0, t_max);
  out.p_inside = (x / a) * (x / a) + (y / b) * (y / b) <= 1.0;
  return out;
}

double annuli_margin(const Mechanism& m, const Ellipse& target, Vec2* worst_point) {
  double margin = std::numeric_limits<double>::infinity();
  Vec2 worst = target.center;
  for (int i = 0; i < 2; ++i) {
    const Vec2& O = i == 0 ? m.O1 : m.O2;
    const double outer = m.L[i] + m.L[i + 2], inner = std::fabs(m.L[i] - m.L[i + 2]);
    const EllipseExtremes ex = ellipse_distance_extremes(target, O);
    // Distance from the filled ellipse to the complement of the disk |P - O| <= outer ...
    if (outer - ex.max_distance < margin) {
      margin = outer - ex.max_distance;
      worst = ex.farthest;
    }
    // ... and to the hole |P - O| < inner (the filled ellipse's nearest point is O if it holds O).
    if (inner > 0.0) {
      const double near = ex.p_inside ? 0.0 : ex.min_distance;
      if (near - inner < margin) {
        margin = near - inner;
        worst = ex.p_inside ? O : ex.nearest;
      }
    }
  }
  if (worst_point) *worst_point = worst;
  return margin;
}

namespace {

/// Rounding bound of a closed-form or refined distance (relative to the mechanism's length
/// scale): the measured agreement with a quad-precision reference is about 1e-15 relative
/// (docs/coverage.md); the bound keeps two orders of magnitude above it.
constexpr double kRoundRel = 1e-13;

/// Certified minimum of a function of the ellipse parameter t over [0, 2 pi) that is Lipschitz
/// with constant `lipschitz` (the signed distance to a set, along a curve of speed <= lipschitz):
/// `value` is attained at t (an upper bound of the minimum), `lower` is a certified lower bound
/// (Piyavskii's bound (f(a) + f(b) - L (b - a)) / 2 over every interval not yet split).
struct CertifiedMin {
  double value = std::numeric_limits<double>::infinity();
  double lower = -std::numeric_limits<double>::infinity();
  double t = 0.0;
  bool capped = false;  ///< the evaluation budget ran out before the tolerance was met
};

/// Branch and bound until the lower bound is within max(abs_tol, rel_tol |value|) of the value
/// (or the budget runs out), then a golden-section polish of the attained minimum.
template <class F>
CertifiedMin lipschitz_min(F&& f, double lipschitz, double abs_tol, double rel_tol, std::size_t max_evals) {
  struct Interval {
    double a, b, fa, fb, lb;
    bool operator>(const Interval& o) const { return lb > o.lb; }
  };
  constexpr int kInitial = 64;
  CertifiedMin out;
  std::vector<Interval> heap;
  heap.reserve(4 * kInitial);
  const double step = 2 * kPi / kInitial;
  double f0 = 0.0, prev = 0.0;
  for (int k = 0; k <= kInitial; ++k) {
    const double t = k * step;
    const double v = k == kInitial ? f0 : f(t);
    if (k == 0) f0 = v;
    if (v < out.value) {
      out.value = v;
      out.t = t;
    }
    if (k > 0) heap.push_back({t - step, t, prev, v, 0.5 * (prev + v - lipschitz * step)});
    prev = v;
  }
  std::make_heap(heap.begin(), heap.end(), std::greater<>());
  std::size_t evals = kInitial;
  while (!heap.empty()) {
    const Interval top = heap.front();
    const double tol = std::max(abs_tol, rel_tol * std::fabs(out.value));
    if (top.lb >= out.value - tol) break;
    if (evals >= max_evals || top.b - top.a < 1e-15) {
      out.capped = true;
      break;
    }
    std::pop_heap(heap.begin(), heap.end(), std::greater<>());
    heap.pop_back();
    const double m = 0.5 * (top.a + top.b), fm = f(m);
    ++evals;
    if (fm < out.value) {
      out.value = fm;
      out.t = m;
    }
    const double h = 0.5 * (top.b - top.a);
    heap.push_back({top.a, m, top.fa, fm, 0.5 * (top.fa + fm - lipschitz * h)});
    std::push_heap(heap.begin(), heap.end(), std::greater<>());
    heap.push_back({m, top.b, fm, top.fb, 0.5 * (fm + top.fb - lipschitz * h)});
    std::push_heap(heap.begin(), heap.end(), std::greater<>());
  }
  out.lower = heap.empty() ? out.value : std::min(out.value, heap.front().lb);
  // Polish the attained minimum (the lower bound is unchanged: it is already certified).
  double width = step;
  for (const Interval& i : heap)
    if (i.a <= out.t && out.t <= i.b) width = std::min(width, i.b - i.a);
  double lo = out.t - width, hi = out.t + width;
  const double r = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = hi - r * (hi - lo), x2 = lo + r * (hi - lo);
  double g1 = f(x1), g2 = f(x2);
  for (int it = 0; it < 60 && hi - lo > 1e-15 * (1.0 + std::fabs(out.t)); ++it) {
    if (g1 < g2) {
      hi = x2, x2 = x1, g2 = g1, x1 = hi - r * (hi - lo), g1 = f(x1);
    } else {
      lo = x1, x1 = x2, g1 = g2, x2 = lo + r * (hi - lo), g2 = f(x2);
    }
  }
  if (std::min(g1, g2) < out.value) {
    out.value = std::min(g1, g2);
    out.t = g1 < g2 ? x1 : x2;
  }
  return out;
}

/// One leg's reachable set in double precision, analytic (no CGAL): the annulus, or the
/// curvilinear rectangle of its joint range (workspace.hpp). The mechanism's region is the
/// intersection of its legs' sets, and the distance from the ellipse to the complement of an
/// intersection is the smaller of the distances to the complements: legs are fitted one by one.
struct LegSet {
  Vec2 O;
  double lp = 0, ld = 0, r_out = 0, r_in = 0;
  int sigma = 1;
  const JointRange* limits = nullptr;
  Vec2 e_lo{1.0, 0.0}, e_hi{1.0, 0.0};  // directions of the joint limits
  std::vector<CurvePiece> pieces;  // the boundary (limited legs only)

  bool contains(const Vec2& p) const {
    const double d = (p - O).norm();
    if (d > r_out || d < r_in) return false;
    if (!limits) return true;
    const CircleIntersection x = intersect_circles(O, lp, p, ld, -sigma);
    if (x.status == Status::unreachable) return false;
    return direction_within_arc(e_lo, e_hi, true, x.offset);  // theta in [lo, hi] without atan2
  }
  double boundary_distance(const Vec2& p) const {
    double best = std::numeric_limits<double>::infinity();
    for (const CurvePiece& c : pieces) best = std::min(best, (c.closest_point(p) - p).norm());
    return best;
  }
  /// Signed distance to the leg's set (> 0 inside): 1-Lipschitz in p.
  double signed_distance(const Vec2& p) const {
    if (!limits) {
      const double d = (p - O).norm();
      return r_in > 0.0 ? std::min(r_out - d, d - r_in) : r_out - d;
    }
    const double d = boundary_distance(p);
    return contains(p) ? d : -d;
  }
};

CurvePiece arc(const Vec2& center, double radius, const Vec2& from, const Vec2& to, bool ccw) {
  CurvePiece c;
  c.is_arc = true;
  c.center = center;
  c.radius = radius;
  c.source = from;
  c.target = to;
  c.ccw = ccw;
  return c;
}

LegSet make_leg(const Vec2& O, double lp, double ld, int sigma, const JointRange* limits) {
  LegSet leg;
  leg.O = O;
  leg.lp = lp;
  leg.ld = ld;
  leg.sigma = sigma;
  leg.r_out = lp + ld;
  leg.r_in = std::fabs(lp - ld);
  if (limits == nullptr || limits->span() >= 2 * kPi) return leg;
  leg.limits = limits;
  const double lo = limits->lo, hi = limits->lo + limits->span();
  const Vec2 e_lo(std::cos(lo), std::sin(lo)), e_hi(std::cos(hi), std::sin(hi));
  leg.e_lo = e_lo;
  leg.e_hi = e_hi;
  const Vec2 a_lo = O + lp * e_lo, a_hi = O + lp * e_hi;
  const Vec2 s_lo = O + leg.r_out * e_lo, s_hi = O + leg.r_out * e_hi;
  const Vec2 f_lo = O + (lp - ld) * e_lo, f_hi = O + (lp - ld) * e_hi;
  leg.pieces.push_back(arc(O, leg.r_out, s_lo, s_hi, true));       // stretched
  leg.pieces.push_back(arc(a_hi, ld, s_hi, f_hi, sigma > 0));      // theta = hi
  if (leg.r_in > 0) leg.pieces.push_back(arc(O, leg.r_in, f_hi, f_lo, false));  // folded
  leg.pieces.push_back(arc(a_lo, ld, f_lo, s_lo, sigma < 0));      // theta = lo
  return leg;
}

/// A signed margin with certified bounds: the true margin lies in [lower, upper].
struct LegFit {
  double margin = 0.0;
  double lower = 0.0, upper = 0.0;
  Vec2 worst{0.0, 0.0};
};

/// Closed form against an annulus: distance from the filled ellipse to the complement of the
/// disk |P - O| <= r_out and to the hole |P - O| < r_in.
LegFit fit_annulus(const LegSet& leg, const Ellipse& e, double round) {
  LegFit f;
  const EllipseExtremes ex = ellipse_distance_extremes(e, leg.O);
  f.margin = leg.r_out - ex.max_distance;
  f.worst = ex.farthest;
  if (leg.r_in > 0.0) {
    const double near = ex.p_inside ? 0.0 : ex.min_distance;
    if (near - leg.r_in < f.margin) {
      f.margin = near - leg.r_in;
      f.worst = ex.p_inside ? leg.O : ex.nearest;
    }
  }
  f.lower = f.margin - round;
  f.upper = f.margin + round;
  return f;
}

/// Joint-limited leg: the set is simply connected (span < 2 pi), so the filled ellipse is inside
/// it exactly when its boundary is, and the margin is the minimum over the ellipse boundary of
/// the signed distance to the set, certified by branch and bound (lipschitz_min).
LegFit fit_limited(const LegSet& leg, const Ellipse& e, double round) {
  const Frame fr(e);
  const double speed = std::max(fr.a, fr.b) * (1.0 + 1e-12);
  const CertifiedMin m = lipschitz_min([&](double t) { return leg.signed_distance(fr.at(1.0, t)); }, speed,
                                       1e-7 * std::max(fr.a, fr.b) + round, 1e-3, 1u << 16);
  LegFit f;
  f.margin = m.value;
  f.worst = fr.at(1.0, m.t);
  f.lower = m.lower - round;
  f.upper = m.value + round;
  return f;
}

/// Signed margin of the ellipse in the mechanism's region (legs one by one), with bounds.
LegFit fit_mechanism(const Mechanism& m, const Ellipse& e, const char** method) {
  const JointRange* l1 = m.joint_limits ? &(*m.joint_limits)[0] : nullptr;
  const JointRange* l2 = m.joint_limits ? &(*m.joint_limits)[1] : nullptr;
  const LegSet legs[2] = {make_leg(m.O1, m.L[0], m.L[2], m.working_mode.sign1, l1),
                          make_leg(m.O2, m.L[1], m.L[3], m.working_mode.sign2, l2)};
  const double round = kRoundRel * m.length_scale();
  LegFit out;
  out.margin = out.lower = out.upper = std::numeric_limits<double>::infinity();
  bool limited = false;
  for (const LegSet& leg : legs) {
    limited = limited || leg.limits != nullptr;
    const LegFit f = leg.limits ? fit_limited(leg, e, round) : fit_annulus(leg, e, round);
    if (f.margin < out.margin) {
      out.margin = f.margin;
      out.worst = f.worst;
    }
    // The margin of an intersection is the smallest of the legs': so are its bounds.
    out.lower = std::min(out.lower, f.lower);
    out.upper = std::min(out.upper, f.upper);
  }
  *method = limited ? "signed distance from the ellipse boundary to each leg's set (closed form for annuli; "
                      "certified branch and bound over the joint-limit arcs)"
                    : "closed form: ellipse against both annuli (robust point-ellipse extremes)";  // no allocation
  return out;
}

/// Signed distance to the mechanism's region, leg by leg (the signed distance to an
/// intersection where it is positive; an upper bound of it where it is negative).
double mechanism_signed_distance(const LegSet (&legs)[2], const Vec2& p) {
  return std::min(legs[0].signed_distance(p), legs[1].signed_distance(p));
}

/// Slack added to every exact test for the rounding of the ellipse's points in double.
double ellipse_slack(const Ellipse& e) {
  const double a = 0.5 * std::max(e.axes.x(), e.axes.y());
  return 1e-12 * a + 16.0 * tol::kEps * (std::max(std::fabs(e.center.x()), std::fabs(e.center.y())) + a);
}

/// A polygon around the ellipse whose excess is at most half the local margin: tangent points
/// close together where the ellipse nears the boundary, far apart elsewhere (the excess of a
/// tangent polygon over a step dt is about A dt^2 / 8). Empty when it would need more than
/// kMaxVertices (an ellipse that follows the boundary within rounding over a long stretch).
std::vector<Vec2> adaptive_circumscribed_polygon(const Mechanism& m, const Ellipse& e, double* excess) {
  const JointRange* l1 = m.joint_limits ? &(*m.joint_limits)[0] : nullptr;
  const JointRange* l2 = m.joint_limits ? &(*m.joint_limits)[1] : nullptr;
  const LegSet legs[2] = {make_leg(m.O1, m.L[0], m.L[2], m.working_mode.sign1, l1),
                          make_leg(m.O2, m.L[1], m.L[3], m.working_mode.sign2, l2)};
  const Frame fr(e);
  const double A = std::max(fr.a, fr.b), slack = ellipse_slack(e) / std::min(fr.a, fr.b);
  auto s = [&](double t) { return mechanism_signed_distance(legs, fr.at(1.0, t)); };
  constexpr double kMaxStep = 2 * kPi / 256, kMinStep = 1e-9;
  std::vector<double> tangents;
  double t = 0.0;
  *excess = 0.0;
  constexpr std::size_t kMaxVertices = 20000;  // beyond: the exact test would cost seconds
  while (t < 2 * kPi) {
    if (tangents.size() >= kMaxVertices) return {};
    tangents.push_back(t);
    double dt = kMaxStep;
    for (;;) {
      const double local = std::min({s(t), s(t + 0.5 * dt), s(t + dt)});
      if (dt <= kMinStep || A * dt * dt / 8.0 <= 0.5 * local) break;
      dt *= 0.5;
    }
    t += dt;
  }
  const std::size_t n = tangents.size();
  std::vector<Vec2> poly(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t0 = tangents[k], t1 = k + 1 < n ? tangents[k + 1] : 2 * kPi;
    const double half = 0.5 * (t1 - t0), mid = 0.5 * (t0 + t1);
    const double r = (1.0 + slack) / std::cos(half);
    *excess = std::max(*excess, A * (r - 1.0));
    poly[k] = fr.to_world({r * fr.a * std::cos(mid), r * fr.b * std::sin(mid)});
  }
  return poly;
}

/// Exact verdict in the band where the double-precision bounds straddle zero: inside when a
/// polygon around the ellipse is inside the exact region; not inside when a point of the filled
/// ellipse near the worst point is outside it; otherwise undecided.
struct ExactVerdict {
  bool inside = false;
  bool decided = false;
  std::string method;
};
ExactVerdict exact_verdict(const Mechanism& m, const Region& region, const Ellipse& e, const Vec2& worst) {
  ExactVerdict v;
  double excess = 0.0;
  const std::vector<Vec2> poly = adaptive_circumscribed_polygon(m, e, &excess);
  std::ostringstream how;
  if (!poly.empty() && region.contains_polygon_exact(poly)) {
    v.inside = v.decided = true;
    how << "; exact CGAL test: a circumscribed " << poly.size() << "-gon (excess <= " << excess
        << " mm) lies inside the region";
    v.method = how.str();
    return v;
  }
  const Frame fr(e);
  const double slack = ellipse_slack(e);
  const double pull = 2.0 * slack / std::min(fr.a, fr.b);
  const Vec2 w = e.center + (1.0 - pull) * (worst - e.center);
  const double h = 0.25 * slack;
  const std::vector<Vec2> tri = {w + Vec2(h, 0.0), w + Vec2(-0.5 * h, 0.866 * h), w + Vec2(-0.5 * h, -0.866 * h)};
  if (region.disjoint_polygon_exact(tri)) {
    v.decided = true;
    how << "; exact CGAL test: the ellipse point (" << w.x() << ", " << w.y() << ") lies outside the region";
    v.method = how.str();
    return v;
  }
  if (poly.empty()) {
    how << "; undecided: the ellipse follows the boundary within rounding over a long stretch (a polygon "
           "around it would need more than 20000 vertices) and the worst point is not outside the region";
  } else {
    how << "; undecided within " << excess << " mm: a circumscribed " << poly.size()
        << "-gon is not inside the exact region and the worst point is not outside it";
  }
  v.method = how.str();
  return v;
}

/// Whether the ellipse is inside, from the bounds; the exact test in the band where they
/// straddle zero. `region` builds the exact region on demand.
template <class RegionFn>
void decide(const Mechanism& m, const Ellipse& e, const LegFit& fit, RegionFn&& region, bool& inside, bool& decided,
            std::string& method) {
  decided = true;
  if (fit.lower > 0.0) {
    inside = true;
  } else if (fit.upper < 0.0) {
    inside = false;
  } else {
    const ExactVerdict v = exact_verdict(m, region(), e, fit.worst);
    inside = v.inside;
    decided = v.decided;
    method += v.method;
  }
}

/// Type II (assembly side) over the filled ellipse, certified: h(P) = cross(P - A1, P - A2) /
/// (l3 l4) is the sine of the angle between the distal links, so |h(P) - h(Q)| is at most the
/// sum of the changes of the distal link directions phi_i; differentiating P = O_i + l_p
/// e(theta_i) + l_d e(phi_i) and dotting with e(theta_i) gives |dphi_i| <= |dP| / (l_d
/// |sin(theta_i - phi_i)|), integrated over a cell below. Polar cells (r, t) of the ellipse are
/// split until h keeps the design's sign with |h(centre)| above that range (no crossing), or a
/// cell centre is on the wrong side (a crossing, with its point), or the cells shrink to
/// rounding (undecided).
struct AssemblyCheck {
  bool ok = true;
  bool decided = true;
  Vec2 crossing{0.0, 0.0};
  std::size_t cells = 0;
};
AssemblyCheck certified_assembly(const Mechanism& m, const Ellipse& e) {
  AssemblyCheck out;
  if (m.assembly_mode == AssemblyMode::Any) return out;
  const int want = int(m.assembly_mode);
  const Frame fr(e);
  const double A = std::max(fr.a, fr.b);
  const double rho_min = 1e-12 * m.length_scale();
  const double lp[2] = {m.L[0], m.L[1]}, ld[2] = {m.L[2], m.L[3]};
  const Vec2 O[2] = {m.O1, m.O2};
  const int sigma[2] = {m.working_mode.sign1, m.working_mode.sign2};
  struct Cell {
    double r0, r1, t0, t1;
  };
  // Breadth first (largest cells first): a wrong-side centre is found at the coarsest level that
  // has one, before any cell along the curve is split down to rounding.
  std::deque<Cell> stack;
  constexpr int kRings = 2, kAngles = 8;
  for (int i = 0; i < kRings; ++i)
    for (int k = 0; k < kAngles; ++k)
      stack.push_back({double(i) / kRings, double(i + 1) / kRings, 2 * kPi * k / kAngles, 2 * kPi * (k + 1) / kAngles});
  constexpr std::size_t kMaxCells = 2000000;
  while (!stack.empty()) {
    const Cell c = stack.front();
    stack.pop_front();
    ++out.cells;
    const double rc = 0.5 * (c.r0 + c.r1), tc = 0.5 * (c.t0 + c.t1);
    const Vec2 P = fr.at(rc, tc);
    const double rho = A * (0.5 * (c.r1 - c.r0) + c.r1 * 0.5 * (c.t1 - c.t0));
    Vec2 elbow[2];
    bool reachable = true;
    double bound = 0.0;
    for (int i = 0; i < 2; ++i) {
      const CircleIntersection x = intersect_circles(O[i], lp[i], P, ld[i], -sigma[i]);
      if (x.status == Status::unreachable) {
        reachable = false;
        break;
      }
      elbow[i] = x.point;
      // Range of phi over the cell: phi = alpha + f(r) in polar coordinates (r, alpha) about O
      // (the triangle O, elbow, tactor depends on r alone). alpha moves by at most
      // rho / (d - rho); |df| <= |dP| / (l_d |sin psi|) with cos psi = kappa(r) = (r^2 - l_p^2 -
      // l_d^2) / (2 l_p l_d), and dr = l_p l_d dkappa / r turns it into |df| <= l_p / r |dpsi|:
      // bounded by the change of psi = acos(kappa) over [d - rho, d + rho], finite even at a
      // type I singularity.
      const double d = (P - O[i]).norm();
      if (d <= rho) {
        bound = std::numeric_limits<double>::infinity();
        continue;
      }
      auto psi = [&](double r) {
        return std::acos(std::clamp((r * r - lp[i] * lp[i] - ld[i] * ld[i]) / (2 * lp[i] * ld[i]), -1.0, 1.0));
      };
      bound += rho / (d - rho) + lp[i] / (d - rho) * std::fabs(psi(d + rho) - psi(d - rho));
    }
    if (!reachable) {
      // Only asked over an ellipse inside the region: a centre outside it is a rounding case.
      out.decided = false;
      out.ok = false;
      out.crossing = P;
      return out;
    }
    const double h = ((P - elbow[0]).x() * (P - elbow[1]).y() - (P - elbow[0]).y() * (P - elbow[1]).x()) / (ld[0] * ld[1]);
    if (h * want < 0.0 && std::fabs(h) > 64 * tol::kEps) {
      out.ok = false;
      out.crossing = P;
      return out;
    }
    // |h(P) - h(centre)| <= sum of the ranges of phi_i (|dh / dphi_i| <= 1), plus rounding.
    if (h * want > 0.0 && std::fabs(h) > bound * (1.0 + 1e-12) + 64 * tol::kEps) continue;
    if (rho < rho_min || out.cells >= kMaxCells) {
      out.ok = false;
      out.decided = false;
      out.crossing = P;
      return out;
    }
    const double rm = 0.5 * (c.r0 + c.r1), tm = 0.5 * (c.t0 + c.t1);
    stack.push_back({c.r0, rm, c.t0, tm});
    stack.push_back({c.r0, rm, tm, c.t1});
    stack.push_back({rm, c.r1, c.t0, tm});
    stack.push_back({rm, c.r1, tm, c.t1});
  }
  return out;
}

void conditioning_over(const Mechanism& m, const Ellipse& e, const CoverageOptions& options, CoverageResult& out) {
  const Frame fr(e);
  thread_local std::vector<double> uc, us, px, py, lci, force;
  thread_local std::vector<std::int8_t> assembly;
  thread_local std::vector<Status> status;
  if (int(uc.size()) != options.angles) unit_circle(options.angles, uc, us);
  px.assign(1, e.center.x());
  py.assign(1, e.center.y());
  for (int ring = 1; ring <= options.rings; ++ring) {
    const double r = double(ring) / options.rings;
    for (int k = 0; k < options.angles; ++k) {
      const Vec2 q = fr.to_world({r * fr.a * uc[k], r * fr.b * us[k]});
      px.push_back(q.x());
      py.push_back(q.y());
    }
  }
  const std::size_t n = px.size();
  lci.resize(n);
  force.resize(n);
  assembly.resize(n);
  status.resize(n);
  conditioning_batch(m, px, py, lci, force, assembly, status);
  out.min_lci = std::numeric_limits<double>::infinity();
  out.min_force_capability = std::numeric_limits<double>::infinity();
  out.assembly_ok = true;
  std::size_t best = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (lci[k] < out.min_lci) {
      out.min_lci = lci[k];
      best = k;
    }
    out.min_force_capability = std::min(out.min_force_capability, force[k]);
    if (m.assembly_mode != AssemblyMode::Any && assembly[k] != std::int8_t(m.assembly_mode)) out.assembly_ok = false;
  }
  out.min_lci_point = {px[best], py[best]};
  if (!(out.min_lci > 0.0)) {
    out.lci_ok = out.min_lci >= m.min_lci;
    return;
  }
  // Refinement. The minimum of a smooth field over the filled ellipse lies on the boundary or is
  // an interior local minimum: refine the best boundary sample along the boundary (golden
  // section in the parameter t), the best interior sample by compass search, keep the smaller.
  auto lci_at = [&](const Vec2& q) {
    double x = q.x(), y = q.y(), l, f;
    std::int8_t a;
    Status st;
    conditioning_batch(m, {&x, 1}, {&y, 1}, {&l, 1}, {&f, 1}, {&a, 1}, {&st, 1});
    return st == Status::ok ? l : 0.0;
  };
  const std::size_t outer = 1 + std::size_t(options.rings - 1) * std::size_t(options.angles);
  std::size_t best_b = outer, best_i = 0;
  for (std::size_t k = outer; k < n; ++k) best_b = lci[k] < lci[best_b] ? k : best_b;
  for (std::size_t k = 0; k < outer; ++k) best_i = lci[k] < lci[best_i] ? k : best_i;
  const double tol = options.lci_refine * std::max(fr.a, fr.b);
  {
    const double dt = 2 * kPi / options.angles;
    double lo = double(best_b - outer) * dt - dt, hi = lo + 2 * dt;
    const double r = 0.5 * (std::sqrt(5.0) - 1.0);
    double x1 = hi - r * (hi - lo), x2 = lo + r * (hi - lo);
    double f1 = lci_at(fr.at(1.0, x1)), f2 = lci_at(fr.at(1.0, x2));
    while ((hi - lo) * std::max(fr.a, fr.b) > tol) {
      if (f1 < f2) {
        hi = x2, x2 = x1, f2 = f1, x1 = hi - r * (hi - lo), f1 = lci_at(fr.at(1.0, x1));
      } else {
        lo = x1, x1 = x2, f1 = f2, x2 = lo + r * (hi - lo), f2 = lci_at(fr.at(1.0, x2));
      }
    }
    const double f = std::min(f1, f2);
    if (f < out.min_lci) {
      out.min_lci = f;
      out.min_lci_point = fr.at(1.0, f1 < f2 ? x1 : x2);
    }
  }
  if (lci[best_i] <= out.min_lci) {
    // Compass search from the best interior sample, four candidates a step evaluated together.
    Vec2 p(px[best_i], py[best_i]);
    double value = lci[best_i];
    double step = std::max(fr.a, fr.b) / std::max(2, options.rings);
    const Vec2 dirs[4] = {Vec2(1, 0), Vec2(-1, 0), Vec2(0, 1), Vec2(0, -1)};
    double cx[4], cy[4], cl[4], cf[4];
    std::int8_t ca[4];
    Status cs[4];
    for (int it = 0; it < 80 && step > tol; ++it) {
      for (int k = 0; k < 4; ++k) {
        cx[k] = p.x() + step * dirs[k].x();
        cy[k] = p.y() + step * dirs[k].y();
      }
      conditioning_batch(m, cx, cy, cl, cf, ca, cs);
      int pick = -1;
      for (int k = 0; k < 4; ++k) {
        const Vec2 q = fr.to_local({cx[k], cy[k]});
        const bool in = (q.x() / fr.a) * (q.x() / fr.a) + (q.y() / fr.b) * (q.y() / fr.b) <= 1.0;
        if (cs[k] == Status::ok && cl[k] < value && in) {
          value = cl[k];
          pick = k;
        }
      }
      if (pick >= 0) {
        p = {cx[pick], cy[pick]};
      } else {
        step *= 0.5;
      }
    }
    if (value < out.min_lci) {
      out.min_lci = value;
      out.min_lci_point = p;
    }
  }
  out.lci_ok = out.min_lci >= m.min_lci;
}

CoverageResult coverage_impl(const Mechanism& m, const Region* given, const Ellipse& target,
                             const CoverageOptions& options) {
  CoverageResult out;
  std::optional<Region> built;
  auto region = [&]() -> const Region& {
    if (given) return *given;
    if (!built) built = reachable_region(m);
    return *built;
  };
  const char* method = "";
  const LegFit fit = fit_mechanism(m, target, &method);
  out.method = method;
  out.margin_mm = fit.margin;
  out.margin_error_mm = std::max(fit.upper - fit.margin, fit.margin - fit.lower);
  out.worst_point = fit.worst;
  decide(m, target, fit, region, out.inside, out.decided, out.method);
  if (out.decided) out.margin_mm = out.inside ? std::max(out.margin_mm, 0.0) : std::min(out.margin_mm, 0.0);
  if (out.inside) {
    out.covered_fraction = 1.0;
  } else {
    const auto poly = ellipse_polygon(target, kFractionPolygon, 1.0);
    out.covered_fraction = std::clamp(region().polygon_overlap_area(poly) / polygon_area(poly), 0.0, 1.0);
    if (out.decided && fit.upper < 0.0) {
      // Outside: the depth against the whole region (the legs' margins only bound it).
      const Frame fr(target);
      const Region& r = region();
      const CertifiedMin d = lipschitz_min([&](double t) { return r.signed_distance(fr.at(1.0, t)); },
                                           std::max(fr.a, fr.b) * (1.0 + 1e-12),
                                           1e-9 * m.length_scale(), 1e-4, 1u << 16);
      if (d.value < out.margin_mm) {
        out.margin_mm = d.value;
        out.worst_point = fr.at(1.0, d.t);
        out.margin_error_mm = std::max(d.value - d.lower, kRoundRel * m.length_scale());
      }
    }
  }
  conditioning_over(m, target, options, out);
  if (out.inside && m.assembly_mode != AssemblyMode::Any) {
    const AssemblyCheck a = certified_assembly(m, target);
    out.assembly_ok = a.ok;
    if (!a.decided) out.decided = false;
    if (!a.ok) out.assembly_crossing = a.crossing;
    out.method += !a.decided ? "; assembly side undecided near the type II curve"
                  : a.ok     ? "; assembly side certified over the filled ellipse (" + std::to_string(a.cells) + " cells)"
                             : "; wrong assembly side found after " + std::to_string(a.cells) + " cells";
    if (!a.ok && a.decided && out.min_lci > 0.0) {
      // The wrong side is reached through a type II singularity: LCI vanishes on the way.
      out.min_lci = 0.0;
      out.min_lci_point = a.crossing;
      out.lci_ok = out.min_lci >= m.min_lci;
    }
  }
  out.covered = out.inside && out.lci_ok && out.assembly_ok && out.decided;
  std::ostringstream why;
  if (!out.decided) {
    why << "undecided: the ellipse is within rounding of the region boundary or of the type II curve";
  } else if (!out.inside) {
    why << "ellipse not inside the reachable region (margin " << out.margin_mm << " mm)";
  }
  if (!out.assembly_ok && out.decided) {
    why << (why.tellp() > 0 ? "; " : "") << "tactor crosses to the wrong assembly side";
    if (out.assembly_crossing)
      why << " (at " << out.assembly_crossing->x() << ", " << out.assembly_crossing->y() << ")";
  }
  if (!out.lci_ok)
    why << (why.tellp() > 0 ? "; " : "") << "min LCI " << out.min_lci << " below the design's " << m.min_lci;
  out.reason = why.str();
  return out;
}

}  // namespace

CoverageResult coverage(const Mechanism& m, const Region& region, const Ellipse& target,
                        const CoverageOptions& options) {
  return coverage_impl(m, &region, target, options);
}

Containment containment(const Mechanism& m, const Ellipse& target) {
  const char* method = "";
  const LegFit fit = fit_mechanism(m, target, &method);
  Containment c;
  c.margin_mm = fit.margin;
  c.margin_error_mm = std::max(fit.upper - fit.margin, fit.margin - fit.lower);
  c.worst_point = fit.worst;
  std::string how;
  std::optional<Region> region;
  decide(m, target, fit, [&]() -> const Region& {
    if (!region) region = reachable_region(m);
    return *region;
  }, c.inside, c.decided, how);
  c.exact_fallback = !how.empty();
  if (c.decided) c.margin_mm = c.inside ? std::max(c.margin_mm, 0.0) : std::min(c.margin_mm, 0.0);
  return c;
}

void conditioning(const Mechanism& m, const Ellipse& target, const CoverageOptions& options, CoverageResult& out) {
  conditioning_over(m, target, options, out);
  if (m.assembly_mode == AssemblyMode::Any) return;
  const AssemblyCheck a = certified_assembly(m, target);
  out.assembly_ok = a.ok;
  out.decided = a.decided;
  if (!a.ok) out.assembly_crossing = a.crossing;
  if (!a.ok && a.decided) {
    out.min_lci = 0.0;
    out.min_lci_point = a.crossing;
    out.lci_ok = out.min_lci >= m.min_lci;
  }
}

CoverageResult coverage(const Mechanism& m, const Ellipse& target, const CoverageOptions& options) {
  // The exact region is built only when needed: the covered fraction of an ellipse that is not
  // inside, or the exact test near tangency.
  return coverage_impl(m, nullptr, target, options);
}

namespace {

/// The shared record from the two mechanisms' own (coverage() of each on `target`); the exact
/// shared region is asked for only when the fraction needs it.
template <class SharedRegion>
CoverageResult combine_shared(const CoverageResult& cl, const CoverageResult& cu, SharedRegion&& shared_region,
                              const Ellipse& target) {
  CoverageResult out;
  // Distance to the complement of an intersection is the smaller of the two distances.
  const bool lower_worse = cl.margin_mm <= cu.margin_mm;
  out.margin_mm = lower_worse ? cl.margin_mm : cu.margin_mm;
  out.margin_error_mm = lower_worse ? cl.margin_error_mm : cu.margin_error_mm;
  out.worst_point = lower_worse ? cl.worst_point : cu.worst_point;
  out.inside = cl.inside && cu.inside;
  // Undecided only when no decided mechanism already rules the shared region out.
  out.decided = (cl.decided && cu.decided) || (cl.decided && !cl.inside) || (cu.decided && !cu.inside);
  out.assembly_crossing = cl.assembly_crossing ? cl.assembly_crossing : cu.assembly_crossing;
  if (out.inside) {
    out.covered_fraction = 1.0;
  } else {
    const Region& shared = shared_region();
    const auto poly = ellipse_polygon(target, kFractionPolygon, 1.0);
    out.covered_fraction = std::clamp(shared.polygon_overlap_area(poly) / polygon_area(poly), 0.0, 1.0);
  }
  const bool lower_lci = cl.min_lci <= cu.min_lci;
  out.min_lci = lower_lci ? cl.min_lci : cu.min_lci;
  out.min_lci_point = lower_lci ? cl.min_lci_point : cu.min_lci_point;
  out.min_force_capability = std::min(cl.min_force_capability, cu.min_force_capability);
  out.lci_ok = cl.lci_ok && cu.lci_ok;
  out.assembly_ok = cl.assembly_ok && cu.assembly_ok;
  out.covered = cl.covered && cu.covered;
  out.method = "smaller of the two mechanisms' margins (exact for an intersection); fraction on the exact "
               "intersection";
  if (!out.covered) {
    out.reason = cl.covered ? "upper: " + cu.reason : cu.covered ? "lower: " + cl.reason
                                                                  : "lower: " + cl.reason + "; upper: " + cu.reason;
  }
  return out;
}

}  // namespace

CoverageResult coverage_shared(const Mechanism& lower, const Mechanism& upper, const Ellipse& target,
                               const CoverageOptions& options) {
  std::optional<Region> shared;
  return combine_shared(coverage_impl(lower, nullptr, target, options), coverage_impl(upper, nullptr, target, options),
                        [&]() -> const Region& {
                          if (!shared) shared = reachable_region(lower).intersection(reachable_region(upper));
                          return *shared;
                        },
                        target);
}

CoverageResult coverage_shared(const CoverageResult& lower, const CoverageResult& upper, const Region& shared,
                               const Ellipse& target) {
  return combine_shared(lower, upper, [&]() -> const Region& { return shared; }, target);
}

bool StationCoverage::covered() const {
  for (const auto* c : {&lower, &upper, &shared})
    if (c->has_value() && !(*c)->covered) return false;
  return true;
}

StationCoverage station_coverage(const Station& station, const std::optional<Ellipse>& override_target,
                                 const CoverageOptions& options) {
  StationCoverage out;
  out.station = station.name;
  const Ellipse& e = override_target ? *override_target : station.target;
  if (station.lower) out.lower = coverage(*station.lower, e, options);
  if (station.upper) out.upper = coverage(*station.upper, e, options);
  if (station.lower && station.upper) out.shared = coverage_shared(*station.lower, *station.upper, e, options);
  return out;
}

}  // namespace fivebar
