// The only translation unit that includes CGAL's 2-D Boolean set operations (docs/architecture.md "Dependencies and where each is walled": CGAL in
// few TUs). Regions are General_polygon_set_2 over Gps_circle_segment_traits_2<Epeck>: arcs of
// circles with rational centres and squared radii, endpoints with one-root coordinates.
//
// Joint-limit corners must lie exactly on two circles each. A limit angle theta is therefore
// represented by the rational unit vector e = ((1 - t^2), 2t) / (1 + t^2), t = tan(theta/2)
// rounded to double (|angle error| <= 1 ulp): then O + L e, O + (L1 + L3) e and O + (L1 - L3) e are
// rational and lie exactly on their circles.
#include "cgal/exact_region.hpp"

#include <CGAL/Boolean_set_operations_2.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/General_polygon_set_2.h>
#include <CGAL/Gps_circle_segment_traits_2.h>

#include <cmath>
#include <list>
#include <numbers>

namespace fivebar::detail {

namespace {

using K = CGAL::Exact_predicates_exact_constructions_kernel;
using FT = K::FT;
using KPoint = K::Point_2;
using Circle = K::Circle_2;
using Traits = CGAL::Gps_circle_segment_traits_2<K>;
using PolygonSet = CGAL::General_polygon_set_2<Traits>;
using Polygon = Traits::General_polygon_2;
using PolygonWithHoles = Traits::General_polygon_with_holes_2;
using Curve = Traits::Curve_2;
using XCurve = Traits::X_monotone_curve_2;
using Point = Traits::Point_2;
using CoordNT = Traits::CoordNT;

/// One long-lived traits object: a copied polygon set keeps a pointer to its source's traits
/// (CGAL issue 9638), so every set is built on this one.
const Traits& traits() {
  static const Traits t;
  return t;
}

Point one_root(const FT& x, const FT& y) { return Point(CoordNT(x), CoordNT(y)); }

void append(Polygon& pgn, const Curve& curve) {
  std::vector<boost::variant<Point, XCurve>> parts;
  traits().make_x_monotone_2_object()(curve, std::back_inserter(parts));
  for (const auto& part : parts) {
    if (const XCurve* xc = boost::get<XCurve>(&part)) pgn.push_back(*xc);
  }
}

Polygon disk(const KPoint& c, const FT& r) {
  Polygon pgn;
  append(pgn, Curve(Circle(c, r * r, CGAL::COUNTERCLOCKWISE)));
  return pgn;
}

/// Rational unit vector for angle theta (see file comment).
std::pair<FT, FT> rational_direction(double theta) {
  double a = std::remainder(theta, 2.0 * std::numbers::pi);  // (-pi, pi]
  const bool flip = std::fabs(a) > std::numbers::pi / 2;
  if (flip) a = a > 0 ? a - std::numbers::pi : a + std::numbers::pi;
  const FT t(std::tan(0.5 * a));
  const FT den = FT(1) + t * t;
  FT x = (FT(1) - t * t) / den, y = FT(2) * t / den;
  if (flip) {
    x = -x;
    y = -y;
  }
  return {x, y};
}

}  // namespace

struct ExactRegion {
  PolygonSet set{traits()};
};

std::shared_ptr<const ExactRegion> exact_empty() { return std::make_shared<ExactRegion>(); }

std::shared_ptr<const ExactRegion> exact_leg_region(const Vec2& O, double l_prox, double l_dist, int sigma,
                                                    const JointRange* limits) {
  auto out = std::make_shared<ExactRegion>();
  const KPoint o(FT(O.x()), FT(O.y()));
  const FT lp(l_prox), ld(l_dist);
  const FT r_out = lp + ld;
  const FT r_in = lp > ld ? lp - ld : ld - lp;
  if (limits == nullptr || limits->span() >= 2.0 * std::numbers::pi) {
    out->set.insert(disk(o, r_out));
    if (r_in > 0) out->set.difference(disk(o, r_in));
    return out;
  }
  // Curvilinear rectangle: image of theta in [lo, hi], psi in sigma*[0, pi] (workspace.hpp).
  const auto [clo, slo] = rational_direction(limits->lo);
  const auto [chi, shi] = rational_direction(limits->lo + limits->span());
  auto at = [&](const FT& r, const FT& c, const FT& s) { return KPoint(o.x() + r * c, o.y() + r * s); };
  const KPoint a_lo = at(lp, clo, slo), a_hi = at(lp, chi, shi);
  const KPoint s_lo = at(r_out, clo, slo), s_hi = at(r_out, chi, shi);
  const FT r_f = lp - ld;  // signed: the folded tactor is at O + (L_i - L_{i+2}) e(theta)
  const KPoint f_lo = at(r_f, clo, slo), f_hi = at(r_f, chi, shi);
  const auto P = [](const KPoint& p) { return one_root(p.x(), p.y()); };
  const CGAL::Orientation psi_up = sigma > 0 ? CGAL::COUNTERCLOCKWISE : CGAL::CLOCKWISE;
  const CGAL::Orientation psi_down = sigma > 0 ? CGAL::CLOCKWISE : CGAL::COUNTERCLOCKWISE;
  Polygon pgn;
  append(pgn, Curve(Circle(o, r_out * r_out, CGAL::COUNTERCLOCKWISE), P(s_lo), P(s_hi)));  // stretched
  append(pgn, Curve(Circle(a_hi, ld * ld, psi_up), P(s_hi), P(f_hi)));                      // theta = hi
  if (r_in > 0) append(pgn, Curve(Circle(o, r_in * r_in, CGAL::CLOCKWISE), P(f_hi), P(f_lo)));  // folded
  append(pgn, Curve(Circle(a_lo, ld * ld, psi_down), P(f_lo), P(s_lo)));                    // theta = lo
  if (pgn.orientation() == CGAL::CLOCKWISE) pgn.reverse_orientation();
  out->set.insert(pgn);
  return out;
}

std::shared_ptr<const ExactRegion> exact_intersection(const ExactRegion& a, const ExactRegion& b) {
  auto out = std::make_shared<ExactRegion>();
  out->set = a.set;
  out->set.intersection(b.set);
  return out;
}

namespace {

CurvePiece to_piece(const XCurve& xc) {
  CurvePiece p;
  p.source = {CGAL::to_double(xc.source().x()), CGAL::to_double(xc.source().y())};
  p.target = {CGAL::to_double(xc.target().x()), CGAL::to_double(xc.target().y())};
  if (xc.is_circular()) {
    const Circle& c = xc.supporting_circle();
    p.is_arc = true;
    p.center = {CGAL::to_double(c.center().x()), CGAL::to_double(c.center().y())};
    p.radius = std::sqrt(CGAL::to_double(c.squared_radius()));
    p.ccw = xc.orientation() == CGAL::COUNTERCLOCKWISE;
  }
  return p;
}

BoundaryLoop to_loop(const Polygon& pgn, bool hole) {
  BoundaryLoop loop;
  loop.hole = hole;
  for (auto it = pgn.curves_begin(); it != pgn.curves_end(); ++it) loop.pieces.push_back(to_piece(*it));
  return loop;
}

ExtractedBoundary extract(const PolygonSet& set) {
  ExtractedBoundary out;
  std::list<PolygonWithHoles> pwhs;
  set.polygons_with_holes(std::back_inserter(pwhs));
  for (const PolygonWithHoles& pwh : pwhs) {
    if (pwh.is_unbounded()) continue;
    ++out.components;
    out.loops.push_back(to_loop(pwh.outer_boundary(), false));
    for (auto h = pwh.holes_begin(); h != pwh.holes_end(); ++h) {
      ++out.holes;
      out.loops.push_back(to_loop(*h, true));
    }
  }
  return out;
}

Polygon polygon_of(const std::vector<Vec2>& pts) {
  Polygon pgn;
  const std::size_t n = pts.size();
  for (std::size_t k = 0; k < n; ++k) {
    const Vec2& a = pts[k];
    const Vec2& b = pts[(k + 1) % n];
    append(pgn, Curve(KPoint(FT(a.x()), FT(a.y())), KPoint(FT(b.x()), FT(b.y()))));
  }
  if (pgn.orientation() == CGAL::CLOCKWISE) pgn.reverse_orientation();
  return pgn;
}

}  // namespace

ExtractedBoundary extract_boundary(const ExactRegion& r) { return extract(r.set); }

bool exact_contains_polygon(const ExactRegion& r, const std::vector<Vec2>& polygon) {
  PolygonSet outside(traits());
  outside.insert(polygon_of(polygon));
  outside.difference(r.set);
  return outside.is_empty();
}

bool exact_disjoint_polygon(const ExactRegion& r, const std::vector<Vec2>& polygon) {
  PolygonSet inside(traits());
  inside.insert(polygon_of(polygon));
  inside.intersection(r.set);
  return inside.is_empty();
}

ExtractedBoundary exact_polygon_overlap(const ExactRegion& r, const std::vector<Vec2>& polygon) {
  PolygonSet inside(traits());
  inside.insert(polygon_of(polygon));
  inside.intersection(r.set);
  return extract(inside);
}

}  // namespace fivebar::detail
