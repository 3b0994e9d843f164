// Coverage of the target ellipse: certified containment and signed margin, covered fraction,
// conditioning (LCI, force capability) and assembly side over the filled ellipse.
#include "fivebar/coverage.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "fivebar/kinematics.hpp"
#include "fivebar/tolerances.hpp"

namespace fivebar {

namespace {

constexpr double kPi = std::numbers::pi;

/// Margins closer to zero than this (times the length scale) are re-decided exactly.
constexpr double kMarginRel = 1e-9;
/// Boundary samples for the general (joint-limited) path.
constexpr int kBoundarySamples = 256;
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

double polygon_area(const std::vector<Vec2>& p) {
  double a = 0.0;
  for (std::size_t k = 0; k < p.size(); ++k) {
    const Vec2& u = p[k] - p[0];
    const Vec2& v = p[(k + 1) % p.size()] - p[0];
    a += u.x() * v.y() - u.y() * v.x();
  }
  return 0.5 * std::fabs(a);
}

bool inside_filled(const Ellipse& e, const Vec2& p) {
  const Frame f(e);
  const Vec2 q = f.to_local(p);
  return (q.x() / f.a) * (q.x() / f.a) + (q.y() / f.b) * (q.y() / f.b) <= 1.0;
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
  auto g = [&](double t) {
    return (b * b - a * a) * std::sin(t) * std::cos(t) + a * x * std::sin(t) - b * y * std::cos(t);
  };
  auto dg = [&](double t) { return (b * b - a * a) * std::cos(2 * t) + a * x * std::cos(t) + b * y * std::sin(t); };
  constexpr int N = 48;
  double fs[N];
  for (int k = 0; k < N; ++k) fs[k] = f(2 * kPi * k / N);
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
        const double gt = g(t), d = dg(t);
        double tn = d != 0.0 ? t - gt / d : 0.5 * (lo + hi);
        if ((gt > 0.0) == (glo > 0.0)) {
          lo = t;
          glo = gt;
        } else {
          hi = t;
        }
        if (!(tn > lo && tn < hi)) tn = 0.5 * (lo + hi);
        if (std::fabs(tn - t) <= 4 * tol::kEps * (1.0 + std::fabs(t))) {
          t = tn;
          break;
        }
        t = tn;
      }
    }
    const double ft = std::min(f(t), fc);
    const double tt = f(t) <= fc ? t : 2 * kPi * k / N;
    const double fx = std::max(f(t), fc);
    const double tx = f(t) >= fc ? t : 2 * kPi * k / N;
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

/// General path: distance from the ellipse boundary to the region boundary, minimised over the
/// ellipse parameter (samples, then golden-section refinement of every local minimum).
double boundary_gap(const Region& region, const Ellipse& e, Vec2* where, bool* crosses) {
  const Frame fr(e);
  std::vector<double> d(kBoundarySamples);
  *crosses = false;
  for (int k = 0; k < kBoundarySamples; ++k) {
    const Vec2 q = fr.at(1.0, 2 * kPi * k / kBoundarySamples);
    d[k] = region.boundary_distance(q);
    if (!region.contains(q)) *crosses = true;
  }
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < kBoundarySamples; ++k) {
    const double dp = d[(k + kBoundarySamples - 1) % kBoundarySamples], dn = d[(k + 1) % kBoundarySamples];
    if (!(d[k] <= dp && d[k] <= dn)) continue;
    double lo = 2 * kPi * (k - 1) / kBoundarySamples, hi = 2 * kPi * (k + 1) / kBoundarySamples;
    const double r = 0.5 * (std::sqrt(5.0) - 1.0);
    double x1 = hi - r * (hi - lo), x2 = lo + r * (hi - lo);
    double f1 = region.boundary_distance(fr.at(1.0, x1)), f2 = region.boundary_distance(fr.at(1.0, x2));
    for (int it = 0; it < 60 && hi - lo > 1e-13; ++it) {
      if (f1 < f2) {
        hi = x2;
        x2 = x1;
        f2 = f1;
        x1 = hi - r * (hi - lo);
        f1 = region.boundary_distance(fr.at(1.0, x1));
      } else {
        lo = x1;
        x1 = x2;
        f1 = f2;
        x2 = lo + r * (hi - lo);
        f2 = region.boundary_distance(fr.at(1.0, x2));
      }
    }
    const double t = f1 < f2 ? x1 : x2;
    const double v = std::min({f1, f2, d[k]});
    if (v < best) {
      best = v;
      *where = v == d[k] ? fr.at(1.0, 2 * kPi * k / kBoundarySamples) : fr.at(1.0, t);
    }
  }
  return best;
}

/// Deepest point of the filled ellipse outside the region (for negative margins).
double deepest_outside(const Region& region, const Ellipse& e, Vec2* where) {
  const Frame fr(e);
  double worst = 0.0;
  for (int ring = 0; ring <= 16; ++ring) {
    const double r = ring / 16.0;
    const int n = ring == 0 ? 1 : 128;
    for (int k = 0; k < n; ++k) {
      const Vec2 q = fr.at(r, 2 * kPi * k / n);
      if (region.contains(q)) continue;
      const double dist = region.boundary_distance(q);
      if (dist > worst) {
        worst = dist;
        *where = q;
      }
    }
  }
  return worst;
}

void conditioning_over(const Mechanism& m, const Ellipse& e, const CoverageOptions& options, CoverageResult& out) {
  const Frame fr(e);
  std::vector<double> px, py;
  px.push_back(e.center.x());
  py.push_back(e.center.y());
  for (int ring = 1; ring <= options.rings; ++ring) {
    for (int k = 0; k < options.angles; ++k) {
      const Vec2 q = fr.at(double(ring) / options.rings, 2 * kPi * k / options.angles);
      px.push_back(q.x());
      py.push_back(q.y());
    }
  }
  const std::size_t n = px.size();
  std::vector<double> lci(n), force(n);
  std::vector<std::int8_t> assembly(n);
  std::vector<Status> status(n);
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
  // Refine the minimum LCI by a compass search inside the ellipse (the field is smooth there).
  if (out.min_lci > 0.0) {
    Vec2 p = out.min_lci_point;
    double step = std::max(fr.a, fr.b) / std::max(2, options.rings);
    for (int it = 0; it < 40 && step > 1e-9 * std::max(fr.a, fr.b); ++it) {
      bool moved = false;
      for (const Vec2& dir : {Vec2(1, 0), Vec2(-1, 0), Vec2(0, 1), Vec2(0, -1)}) {
        const Vec2 cand = p + step * dir;
        if (!inside_filled(e, cand)) continue;
        const Pose pose = ik(m, cand);
        if (pose.status == Status::ok && pose.lci < out.min_lci) {
          out.min_lci = pose.lci;
          p = cand;
          moved = true;
        }
      }
      if (!moved) step *= 0.5;
    }
    out.min_lci_point = p;
  }
  out.lci_ok = out.min_lci >= m.min_lci;
}

}  // namespace

CoverageResult coverage(const Mechanism& m, const Region& region, const Ellipse& target,
                        const CoverageOptions& options) {
  CoverageResult out;
  const double tol = kMarginRel * m.length_scale();
  bool crosses = false;
  if (!m.joint_limits) {
    out.margin_mm = annuli_margin(m, target, &out.worst_point);
    out.inside = out.margin_mm > 0.0;
    out.method = "closed form: ellipse against both annuli (robust point-ellipse extremes)";
  } else {
    Vec2 where = target.center;
    const double gap = boundary_gap(region, target, &where, &crosses);
    bool loop_inside = false;
    for (const BoundaryLoop& loop : region.loops())
      if (!loop.pieces.empty() && inside_filled(target, loop.pieces[0].source)) loop_inside = true;
    out.inside = !crosses && !loop_inside && region.contains(target.center) && gap > 0.0;
    if (out.inside) {
      out.margin_mm = gap;
      out.worst_point = where;
    } else {
      out.margin_mm = -deepest_outside(region, target, &out.worst_point);
      if (out.margin_mm == 0.0) out.worst_point = where;
    }
    out.method = "distance from the ellipse to every boundary arc (sampled + golden-section refined)";
  }
  if (std::fabs(out.margin_mm) <= tol) {
    // Within rounding of tangency: decide exactly with a polygon provably around the ellipse.
    const double scale = (1.0 + 1e-12) / std::cos(kPi / kExactPolygon);
    out.inside = region.contains_polygon_exact(ellipse_polygon(target, kExactPolygon, scale));
    std::ostringstream s;
    s << "; |margin| <= " << tol << " mm: exact CGAL test of a circumscribed " << kExactPolygon
      << "-gon (conservative by <= " << 0.5 * std::max(target.axes.x(), target.axes.y()) * (scale - 1.0) << " mm)";
    out.method += s.str();
  }
  if (out.inside) {
    out.covered_fraction = 1.0;
  } else {
    const auto poly = ellipse_polygon(target, kFractionPolygon, 1.0);
    out.covered_fraction = std::clamp(region.polygon_overlap_area(poly) / polygon_area(poly), 0.0, 1.0);
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

CoverageResult coverage(const Mechanism& m, const Ellipse& target, const CoverageOptions& options) {
  if (!m.joint_limits) {
    // The closed form needs no region but for the covered fraction and the exact fallback.
    const Region region = reachable_region(m);
    return coverage(m, region, target, options);
  }
  return coverage(m, reachable_region(m), target, options);
}

CoverageResult coverage_shared(const Mechanism& lower, const Mechanism& upper, const Ellipse& target,
                               const CoverageOptions& options) {
  const Region rl = reachable_region(lower), ru = reachable_region(upper);
  const CoverageResult cl = coverage(lower, rl, target, options);
  const CoverageResult cu = coverage(upper, ru, target, options);
  CoverageResult out;
  // Distance to the complement of an intersection is the smaller of the two distances.
  const bool lower_worse = cl.margin_mm <= cu.margin_mm;
  out.margin_mm = lower_worse ? cl.margin_mm : cu.margin_mm;
  out.worst_point = lower_worse ? cl.worst_point : cu.worst_point;
  out.inside = cl.inside && cu.inside;
  const Region shared = rl.intersection(ru);
  if (out.inside) {
    out.covered_fraction = 1.0;
  } else {
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
  out.method = "smaller of the two mechanisms' margins; fraction on the exact intersection";
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
