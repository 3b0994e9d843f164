// Coverage of the target ellipse: certified containment and signed margin, covered fraction,
// conditioning (LCI, force capability) and assembly side over the filled ellipse.
#include "fivebar/coverage.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>

#include "fivebar/kinematics.hpp"
#include "fivebar/tolerances.hpp"

namespace fivebar {

namespace {

constexpr double kPi = std::numbers::pi;

/// Margins closer to zero than this (times the length scale) are re-decided exactly.
constexpr double kMarginRel = 1e-9;
/// Boundary samples for the general (joint-limited) path.
/// Polygon sizes of the exact fallback and of the covered-fraction measure.
constexpr int kExactPolygon = 1024;
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

struct LegFit {
  bool inside = false;
  double margin = 0.0;
  Vec2 worst{0.0, 0.0};
};

/// Closed form against an annulus: distance from the filled ellipse to the complement of the
/// disk |P - O| <= r_out and to the hole |P - O| < r_in.
LegFit fit_annulus(const LegSet& leg, const Ellipse& e) {
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
  f.inside = f.margin > 0.0;
  return f;
}

/// Joint-limited leg: samples of the ellipse boundary, membership of each, distance to the four
/// boundary arcs; every local minimum of that distance refined by golden section.
LegFit fit_limited(const LegSet& leg, const Ellipse& e) {
  constexpr int N = 128;
  const Frame fr(e);
  thread_local std::vector<double> uc, us;
  if (uc.size() != N) unit_circle(N, uc, us);
  auto point = [&](double c, double s) { return fr.to_world({fr.a * c, fr.b * s}); };
  double d[N];
  bool all_in = leg.contains(e.center);
  double deepest = 0.0;
  Vec2 deepest_at = e.center;
  for (int k = 0; k < N; ++k) {
    const Vec2 q = point(uc[k], us[k]);
    d[k] = leg.boundary_distance(q);
    if (!leg.contains(q)) {
      all_in = false;
      if (d[k] > deepest) {
        deepest = d[k];
        deepest_at = q;
      }
    }
  }
  LegFit f;
  if (!all_in) {
    f.margin = -deepest;
    f.worst = deepest_at;
    return f;
  }
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < N; ++k) {
    if (!(d[k] <= d[(k + N - 1) % N] && d[k] <= d[(k + 1) % N])) continue;
    auto dist = [&](double t) { return leg.boundary_distance(fr.at(1.0, t)); };
    double lo = 2 * kPi * (k - 1) / N, hi = 2 * kPi * (k + 1) / N;
    const double r = 0.5 * (std::sqrt(5.0) - 1.0);
    double x1 = hi - r * (hi - lo), x2 = lo + r * (hi - lo);
    double f1 = dist(x1), f2 = dist(x2);
    for (int it = 0; it < 48; ++it) {
      if (f1 < f2) {
        hi = x2, x2 = x1, f2 = f1, x1 = hi - r * (hi - lo), f1 = dist(x1);
      } else {
        lo = x1, x1 = x2, f1 = f2, x2 = lo + r * (hi - lo), f2 = dist(x2);
      }
    }
    const double v = std::min({f1, f2, d[k]});
    if (v < best) {
      best = v;
      f.worst = v == d[k] ? point(uc[k], us[k]) : fr.at(1.0, f1 < f2 ? x1 : x2);
    }
  }
  f.margin = best;
  f.inside = best > 0.0;
  return f;
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

/// Containment and margin of the ellipse in the mechanism's region (legs one by one).
LegFit fit_mechanism(const Mechanism& m, const Ellipse& e, const char** method) {
  const JointRange* l1 = m.joint_limits ? &(*m.joint_limits)[0] : nullptr;
  const JointRange* l2 = m.joint_limits ? &(*m.joint_limits)[1] : nullptr;
  const LegSet legs[2] = {make_leg(m.O1, m.L[0], m.L[2], m.working_mode.sign1, l1),
                          make_leg(m.O2, m.L[1], m.L[3], m.working_mode.sign2, l2)};
  LegFit out;
  out.margin = std::numeric_limits<double>::infinity();
  out.inside = true;
  bool limited = false;
  for (const LegSet& leg : legs) {
    limited = limited || leg.limits != nullptr;
    const LegFit f = leg.limits ? fit_limited(leg, e) : fit_annulus(leg, e);
    out.inside = out.inside && f.inside;
    if (f.margin < out.margin) {
      out.margin = f.margin;
      out.worst = f.worst;
    }
  }
  *method = limited ? "distance from the ellipse to each leg's boundary arcs (closed form for annuli; sampled + "
                      "golden-section refined for joint-limit arcs)"
                    : "closed form: ellipse against both annuli (robust point-ellipse extremes)";  // no allocation
  return out;
}

/// Within rounding of tangency: decide exactly with a polygon provably around the ellipse.
bool exact_inside(const Region& region, const Ellipse& target) {
  const double scale = (1.0 + 1e-12) / std::cos(kPi / kExactPolygon);
  return region.contains_polygon_exact(ellipse_polygon(target, kExactPolygon, scale));
}

std::string exact_method(const Mechanism& m, const Ellipse& target) {
  const double scale = (1.0 + 1e-12) / std::cos(kPi / kExactPolygon);
  std::ostringstream s;
  s << "; |margin| <= " << kMarginRel * m.length_scale() << " mm: exact CGAL test of a circumscribed "
    << kExactPolygon << "-gon (conservative by <= " << 0.5 * std::max(target.axes.x(), target.axes.y()) * (scale - 1.0)
    << " mm)";
  return s.str();
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
  out.worst_point = fit.worst;
  out.inside = fit.inside;
  if (std::fabs(out.margin_mm) <= kMarginRel * m.length_scale()) {
    out.inside = exact_inside(region(), target);
    out.method += exact_method(m, target);
  }
  if (out.inside) {
    out.covered_fraction = 1.0;
  } else {
    const auto poly = ellipse_polygon(target, kFractionPolygon, 1.0);
    out.covered_fraction = std::clamp(region().polygon_overlap_area(poly) / polygon_area(poly), 0.0, 1.0);
  }
  conditioning_over(m, target, options, out);
  out.covered = out.inside && out.lci_ok && out.assembly_ok;
  std::ostringstream why;
  if (!out.inside) why << "ellipse not inside the reachable region (margin " << out.margin_mm << " mm)";
  if (!out.assembly_ok) why << (why.tellp() > 0 ? "; " : "") << "tactor crosses to the wrong assembly side";
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
  c.inside = fit.inside;
  c.margin_mm = fit.margin;
  c.worst_point = fit.worst;
  if (std::fabs(c.margin_mm) <= kMarginRel * m.length_scale()) {
    c.inside = exact_inside(reachable_region(m), target);
    c.exact_fallback = true;
  }
  return c;
}

void conditioning(const Mechanism& m, const Ellipse& target, const CoverageOptions& options, CoverageResult& out) {
  conditioning_over(m, target, options, out);
}

CoverageResult coverage(const Mechanism& m, const Ellipse& target, const CoverageOptions& options) {
  // The exact region is built only when needed: the covered fraction of an ellipse that is not
  // inside, or the exact test near tangency.
  return coverage_impl(m, nullptr, target, options);
}

CoverageResult coverage_shared(const Mechanism& lower, const Mechanism& upper, const Ellipse& target,
                               const CoverageOptions& options) {
  const CoverageResult cl = coverage_impl(lower, nullptr, target, options);
  const CoverageResult cu = coverage_impl(upper, nullptr, target, options);
  CoverageResult out;
  // Distance to the complement of an intersection is the smaller of the two distances.
  const bool lower_worse = cl.margin_mm <= cu.margin_mm;
  out.margin_mm = lower_worse ? cl.margin_mm : cu.margin_mm;
  out.worst_point = lower_worse ? cl.worst_point : cu.worst_point;
  out.inside = cl.inside && cu.inside;
  if (out.inside) {
    out.covered_fraction = 1.0;
  } else {
    const Region shared = reachable_region(lower).intersection(reachable_region(upper));
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
