// Reachable workspace: region queries in double precision over the exact (CGAL) boundary, the
// closed-form annuli area, sampled fields and marching-squares areas of the restricted regions.
#include "fivebar/workspace/region.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "cgal/exact_region.hpp"
#include "fivebar/numerics.hpp"
#include "kinematics/kinematics_common.hpp"

namespace fivebar {

namespace {

constexpr double kPi = std::numbers::pi;

double cross2(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }


}  // namespace

// --- CurvePiece ----------------------------------------------------------------------------------

bool direction_within_arc(const Vec2& from, const Vec2& to, bool ccw, const Vec2& v) {
  // A clockwise arc from a to b is the counter-clockwise arc from b to a.
  const Vec2& a = ccw ? from : to;
  const Vec2& b = ccw ? to : from;
  const double w = cross2(a, b);
  const bool minor = w > 0.0 || (w == 0.0 && a.dot(b) < 0.0);  // ccw span in (0, pi]
  if (minor) return cross2(a, v) >= 0.0 && cross2(v, b) >= 0.0;
  return !(cross2(b, v) > 0.0 && cross2(v, a) > 0.0);  // outside only in the complementary minor arc
}

double CurvePiece::sweep() const {
  if (!is_arc) return 0.0;
  const Vec2 a = source - center, b = target - center;
  double phi = std::atan2(cross2(a, b), a.dot(b));  // (-pi, pi]
  // x-monotone arcs sweep at most pi, but accept any arc: go the arc's own way round.
  if (ccw && phi < 0.0) phi += 2.0 * kPi;
  if (!ccw && phi > 0.0) phi -= 2.0 * kPi;
  return phi;
}

double CurvePiece::length() const { return is_arc ? radius * std::fabs(sweep()) : (target - source).norm(); }

Vec2 CurvePiece::closest_point(const Vec2& p) const {
  if (!is_arc) {
    const Vec2 d = target - source;
    const double len2 = d.squaredNorm();
    const double s = len2 > 0.0 ? std::clamp((p - source).dot(d) / len2, 0.0, 1.0) : 0.0;
    return source + s * d;
  }
  const Vec2 v = p - center;
  const double r = v.norm();
  if (r > 0.0 && direction_within_arc(source - center, target - center, ccw, v)) {
    return center + (radius / r) * v;
  }
  return (p - source).squaredNorm() <= (p - target).squaredNorm() ? source : target;
}

// --- Region ----------------------------------------------------------------------------------

namespace {
/// Area enclosed by boundary loops (Green's theorem about a local origin; see Region()).
double loops_area(const std::vector<BoundaryLoop>& loops) {
  if (loops.empty() || loops[0].pieces.empty()) return 0.0;
  const Vec2 origin = loops[0].pieces[0].source;
  long double area = 0.0L;
  for (const BoundaryLoop& loop : loops) {
    for (const CurvePiece& p : loop.pieces) {
      const Vec2 s = p.source - origin, t = p.target - origin;
      if (p.is_arc) {
        area += 0.5L * ((long double)cross2(p.center - origin, t - s) + (long double)p.radius * p.radius * p.sweep());
      } else {
        area += 0.5L * (long double)cross2(s, t);
      }
    }
  }
  return double(area);
}
}  // namespace

Region::Region() : exact_(detail::exact_empty()) {}

Region::Region(std::shared_ptr<const detail::ExactRegion> exact) : exact_(std::move(exact)) {
  detail::ExtractedBoundary b = detail::extract_boundary(*exact_);
  loops_ = std::move(b.loops);
  components_ = b.components;
  holes_ = b.holes;
  // Green's theorem about a local origin (limits cancellation): a segment adds cross(s, t)/2, an
  // arc around c of signed sweep phi adds (cross(c, t - s) + r^2 phi)/2.
  long double perimeter = 0.0L;
  for (const BoundaryLoop& loop : loops_)
    for (const CurvePiece& p : loop.pieces) perimeter += p.length();
  const double area = loops_area(loops_);
  area_mm2_ = area;
  perimeter_mm_ = double(perimeter);
}

std::array<double, 4> Region::bounds() const {
  if (loops_.empty()) return {0.0, 0.0, 0.0, 0.0};
  std::array<double, 4> b{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                          -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  auto add = [&](const Vec2& q) {
    b[0] = std::min(b[0], q.x());
    b[1] = std::min(b[1], q.y());
    b[2] = std::max(b[2], q.x());
    b[3] = std::max(b[3], q.y());
  };
  for (const BoundaryLoop& loop : loops_) {
    for (const CurvePiece& p : loop.pieces) {
      add(p.source);
      add(p.target);
      if (p.is_arc) {  // axis extremes of the circle that the arc passes
        for (int k = 0; k < 4; ++k) {
          const Vec2 q = p.center + p.radius * Vec2(k == 0 ? 1 : k == 2 ? -1 : 0, k == 1 ? 1 : k == 3 ? -1 : 0);
          if ((p.closest_point(q) - q).norm() <= 1e-12 * p.radius) add(q);
        }
      }
    }
  }
  return b;
}

double Region::boundary_distance(const Vec2& p, Vec2* nearest) const {
  double best = std::numeric_limits<double>::infinity();
  for (const BoundaryLoop& loop : loops_) {
    for (const CurvePiece& piece : loop.pieces) {
      const Vec2 q = piece.closest_point(p);
      const double d = (q - p).norm();
      if (d < best) {
        best = d;
        if (nearest) *nearest = q;
      }
    }
  }
  return best;
}

bool Region::contains(const Vec2& p) const {
  // Even-odd rule with a ray towards +x: count crossings with every piece.
  int crossings = 0;
  for (const BoundaryLoop& loop : loops_) {
    for (const CurvePiece& piece : loop.pieces) {
      if (!piece.is_arc) {
        const Vec2 &a = piece.source, &b = piece.target;
        if ((a.y() > p.y()) != (b.y() > p.y())) {
          const double x = a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y());
          if (x > p.x()) ++crossings;
        }
        continue;
      }
      const double dy = p.y() - piece.center.y();
      const double h2 = piece.radius * piece.radius - dy * dy;
      if (h2 <= 0.0) continue;
      const double h = std::sqrt(h2);
      for (double sx : {-h, h}) {
        const Vec2 q(piece.center.x() + sx, p.y());
        if (q.x() <= p.x()) continue;
        // On the arc (half-open at the end with the larger y, so shared vertices count once)?
        if ((piece.closest_point(q) - q).norm() > 1e-12 * piece.radius) continue;
        const Vec2 &a = piece.source, &b = piece.target;
        const bool at_a = (q - a).norm() <= 1e-12 * piece.radius, at_b = (q - b).norm() <= 1e-12 * piece.radius;
        if (at_a || at_b) {
          const Vec2& v = at_a ? a : b;
          const Vec2& o = at_a ? b : a;
          if (!(o.y() > v.y())) continue;  // count a vertex only from the piece leaving upwards
        }
        ++crossings;
      }
    }
  }
  return (crossings & 1) != 0;
}

double Region::signed_distance(const Vec2& p) const {
  const double d = boundary_distance(p);
  if (!std::isfinite(d)) return -std::numeric_limits<double>::max();
  return contains(p) ? d : -d;
}

Region Region::intersection(const Region& other) const {
  return Region(detail::exact_intersection(*exact_, *other.exact_));
}

bool Region::contains_polygon_exact(const std::vector<Vec2>& polygon) const {
  return detail::exact_contains_polygon(*exact_, polygon);
}

bool Region::disjoint_polygon_exact(const std::vector<Vec2>& polygon) const {
  return detail::exact_disjoint_polygon(*exact_, polygon);
}


double Region::polygon_overlap_area(const std::vector<Vec2>& polygon) const {
  return loops_area(detail::exact_polygon_overlap(*exact_, polygon).loops);
}

Region reachable_region(const Mechanism& m) {
  const JointRange* l1 = m.joint_limits ? &(*m.joint_limits)[0] : nullptr;
  const JointRange* l2 = m.joint_limits ? &(*m.joint_limits)[1] : nullptr;
  const auto leg1 = detail::exact_leg_region(m.O1, m.L[0], m.L[2], m.working_mode.sign1, l1);
  const auto leg2 = detail::exact_leg_region(m.O2, m.L[1], m.L[3], m.working_mode.sign2, l2);
  return Region(detail::exact_intersection(*leg1, *leg2));
}

// --- closed-form annuli area ---------------------------------------------------------------------

namespace {

/// r^2 (alpha - sin(alpha) cos(alpha)): the circular segment of half-angle alpha, without the
/// cancellation of x - sin x for small x = 2 alpha (series there).
double segment_area(double r, double alpha) {
  const double x = 2.0 * alpha;
  double x_minus_sin;
  if (x < 0.5) {
    const double x2 = x * x;
    x_minus_sin = x * x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0 * (1.0 - x2 / 110.0))));
  } else {
    x_minus_sin = x - std::sin(x);
  }
  return 0.5 * r * r * x_minus_sin;
}

/// Area of the intersection of two disks (radii a, b; centre distance d). Half-angles by atan2 of
/// Heron's product and d^2 +- (a - b)(a + b), which keep their digits for nearly equal radii and
/// close centres (link ratios of 1e2 and more), then one circular segment per disk.
double lens_area(double a, double b, double d) {
  if (a <= 0.0 || b <= 0.0 || d >= a + b) return 0.0;
  if (d <= std::fabs(a - b)) return kPi * std::min(a, b) * std::min(a, b);
  const double k = std::sqrt(std::max(0.0, (-d + a + b) * (d + a - b) * (d - a + b) * (d + a + b)));
  const double diff = (a - b) * (a + b);
  const double alpha = std::atan2(k, d * d + diff);  // half-angle at the centre of disk a
  const double beta = std::atan2(k, d * d - diff);
  return segment_area(a, alpha) + segment_area(b, beta);
}

}  // namespace

double annuli_intersection_area(const Mechanism& m) {
  const double d = (m.O2 - m.O1).norm();
  const double R1 = m.L[0] + m.L[2], r1 = std::fabs(m.L[0] - m.L[2]);
  const double R2 = m.L[1] + m.L[3], r2 = std::fabs(m.L[1] - m.L[3]);
  // A_i = D(R_i) \ D(r_i) with D(r_i) inside D(R_i): inclusion-exclusion over the four disks.
  return lens_area(R1, R2, d) - lens_area(R1, r2, d) - lens_area(r1, R2, d) + lens_area(r1, r2, d);
}

// --- grid and fields -----------------------------------------------------------------------------

Grid Grid::covering(const std::array<double, 4>& b, double spacing, double pad) {
  Grid g;
  g.spacing = spacing;
  g.x0 = b[0] - pad;
  g.y0 = b[1] - pad;
  g.nx = std::max(2, int(std::ceil((b[2] + pad - g.x0) / spacing)) + 1);
  g.ny = std::max(2, int(std::ceil((b[3] + pad - g.y0) / spacing)) + 1);
  return g;
}

WorkspaceField sample_field(const Mechanism& m, const Grid& grid) {
  WorkspaceField f;
  f.grid = grid;
  const std::size_t n = grid.size();
  f.reach.assign(n, 0);
  f.status.assign(n, std::uint8_t(Status::unreachable));
  f.assembly_ok.assign(n, 0);
  f.lci.assign(n, 0.0);
  f.type1_distance_mm.assign(n, 0.0);
  f.type1_sin.assign(n, 0.0);
  f.type2_sin.assign(n, 0.0);
  f.transmission_deg.assign(n, 0.0);
  f.force_capability.assign(n, 0.0);
  const int want = int(m.assembly_mode);
  for (int j = 0; j < grid.ny; ++j) {
    for (int i = 0; i < grid.nx; ++i) {
      const std::size_t k = std::size_t(j) * grid.nx + i;
      const Pose p = ik(m, grid.point(i, j));
      f.status[k] = std::uint8_t(p.status);
      if (p.status == Status::unreachable || !p.within_joint_limits) continue;
      f.reach[k] = 1;
      f.assembly_ok[k] = want == 0 || p.assembly == want;
      f.lci[k] = p.lci;
      f.type1_distance_mm[k] = p.type1_distance_mm;
      f.type1_sin[k] = std::min(p.type1_sin[0], p.type1_sin[1]);
      f.type2_sin[k] = p.type2_sin;
      f.transmission_deg[k] = p.transmission[2] * 180.0 / kPi;
      f.force_capability[k] = p.force_capability;
    }
  }
  return f;
}

// --- restricted regions by marching squares ------------------------------------------------------

double restriction_margin(const Mechanism& m, Restriction restriction, const Vec2& p) {
  // Reach: annuli constraints and joint-angle constraints, each in mm; zero exactly on the
  // boundary of the exact region.
  double margin = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 2; ++i) {
    const Vec2& O = i == 0 ? m.O1 : m.O2;
    const double d = (p - O).norm();
    const double outer = m.L[i] + m.L[i + 2], inner = std::fabs(m.L[i] - m.L[i + 2]);
    margin = std::min(margin, outer - d);
    if (inner > 0.0) margin = std::min(margin, d - inner);
  }
  if (margin < 0.0) return margin;
  if (!m.joint_limits) {
    // Only the elbows are needed: the two circle intersections ik() starts from, and for the LCI
    // the matrix analyse() forms from them (kinematics.cpp): the same numbers in the same order,
    // without the angles, transmission angles and closure check that the margin does not use
    // (ik() is unreachable exactly when one intersection is).
    const CircleIntersection x1 = intersect_circles(m.O1, m.L[0], p, m.L[2], -m.working_mode.sign1);
    const CircleIntersection x2 = intersect_circles(m.O2, m.L[1], p, m.L[3], -m.working_mode.sign2);
    if (x1.status == Status::unreachable || x2.status == Status::unreachable) return std::min(margin, 0.0);
    if (restriction == Restriction::reach) return margin;
    const Vec2 f1 = p - x1.point, f2 = p - x2.point;
    const double cb = detail::cross(f1, f2);
    if (m.assembly_mode != AssemblyMode::Any) margin = std::min(margin, double(int(m.assembly_mode)) * cb / (m.L[2] + m.L[3]));
    if (restriction == Restriction::assembly) return margin;
    const double c1 = detail::cross(x1.point - m.O1, f1), c2 = detail::cross(x2.point - m.O2, f2);
    const double lci = detail::lci2(f2.y() * c1, -f1.y() * c2, -f2.x() * c1, f1.x() * c2);
    return std::min(margin, (lci - m.min_lci) * m.length_scale());
  }
  const Pose pose = ik(m, p);
  if (pose.status == Status::unreachable) return std::min(margin, 0.0);
  if (m.joint_limits) {
    for (int i = 0; i < 2; ++i) {
      const JointRange& r = (*m.joint_limits)[i];
      const double theta = i == 0 ? pose.theta1 : pose.theta2;
      // Angular distance inside the arc (negative outside), scaled to mm by the proximal link.
      const double from_lo = std::remainder(theta - r.lo, 2 * kPi);
      const double off = from_lo < 0 ? from_lo + 2 * kPi : from_lo;  // [0, 2 pi)
      const double span = r.span();
      const double inside = off <= span ? std::min(off, span - off) : -std::min(off - span, 2 * kPi - off);
      margin = std::min(margin, inside * m.L[i]);
    }
  }
  if (restriction == Restriction::reach) return margin;
  if (m.assembly_mode != AssemblyMode::Any) {
    const double cb = detail::cross(pose.P - pose.A1, pose.P - pose.A2);
    margin = std::min(margin, double(int(m.assembly_mode)) * cb / (m.L[2] + m.L[3]));
  }
  if (restriction == Restriction::assembly) return margin;
  return std::min(margin, (pose.lci - m.min_lci) * m.length_scale());
}


namespace {

/// Area of the part of a square cell where f > 0, by marching squares with every crossing
/// bisected on f: corners c0 = (x, y), c1 = (x + h, y), c2 = (x + h, y + h), c3 = (x, y + h).
/// Segments of the boundary are appended to `segments` when given.
template <class Margin>
double cell_area(const Vec2& base, double h, const double (&f)[4], const Margin& margin,
                 std::vector<std::array<Vec2, 2>>* segments) {
  const Vec2 p[4] = {Vec2(0, 0), Vec2(h, 0), Vec2(h, h), Vec2(0, h)};
  int inside = 0;
  for (int c = 0; c < 4; ++c) inside += f[c] > 0.0;
  if (inside == 0) return 0.0;
  if (inside == 4) return h * h;
  auto crossing = [&](Vec2 a, double fa, Vec2 b) -> Vec2 {
    for (int it = 0; it < 30; ++it) {  // 2^-30 of the cell: far below the discretisation error
      const Vec2 mid = 0.5 * (a + b);
      const double fm = margin(base + mid);
      if ((fm > 0.0) == (fa > 0.0)) {
        a = mid;
        fa = fm;
      } else {
        b = mid;
      }
    }
    return 0.5 * (a + b);
  };
  auto cross_pt = [&](int c) { return crossing(p[c], f[c], p[(c + 1) % 4]); };
  auto poly_area = [](const std::vector<Vec2>& poly) {
    double a = 0.0;
    for (std::size_t k = 0; k < poly.size(); ++k) a += cross2(poly[k], poly[(k + 1) % poly.size()]);
    return 0.5 * std::fabs(a);
  };
  const bool saddle = inside == 2 && (f[0] > 0.0) == (f[2] > 0.0);
  double area = 0.0;
  if (saddle && !(margin(base + Vec2(0.5 * h, 0.5 * h)) > 0.0)) {
    for (int c = 0; c < 4; ++c) {
      if (!(f[c] > 0.0)) continue;
      const Vec2 a = cross_pt(c), b = cross_pt((c + 3) % 4);
      area += poly_area({p[c], a, b});
      if (segments) segments->push_back({a + base, b + base});
    }
    return area;
  }
  std::vector<Vec2> poly, xs;
  for (int c = 0; c < 4; ++c) {
    if (f[c] > 0.0) poly.push_back(p[c]);
    if ((f[c] > 0.0) != (f[(c + 1) % 4] > 0.0)) {
      const Vec2 x = cross_pt(c);
      poly.push_back(x);
      xs.push_back(x);
    }
  }
  if (segments)
    for (std::size_t k = 0; k + 1 < xs.size(); k += 2) segments->push_back({xs[k] + base, xs[k + 1] + base});
  return poly_area(poly);
}

/// Adaptive refinement of one cell (quadtree). A cell is split when its corners disagree in sign
/// or when it could hide a sign change: min |f| at its corners below the local slope times its
/// half diagonal (the slope estimated from the differences along its edges and those of its
/// parent, times kSlopeSafety). `fine` accumulates the area at the leaves, `coarse` the same
/// with every deepest split undone (the Richardson-like difference of the two is the
/// discretisation error), `hidden` the change where a deepest cell near zero showed the other sign
/// at an edge midpoint or its centre (a piece between its corners, measured on its half cells).
constexpr double kSlopeSafety = 2.0;
struct Adaptive {
  double fine = 0.0, coarse = 0.0, hidden = 0.0;
  std::size_t cells = 0;
  std::vector<std::array<Vec2, 2>> segments;
};
template <class Margin>
void refine_cell(const Vec2& base, double h, const double (&f)[4], double parent_slope, int depth, int max_depth,
                 const Margin& margin, Adaptive& out) {
  ++out.cells;
  double slope = parent_slope;
  for (int c = 0; c < 4; ++c) slope = std::max(slope, std::fabs(f[c] - f[(c + 1) % 4]) / h);
  slope *= kSlopeSafety;
  const bool mixed = !((f[0] > 0.0) == (f[1] > 0.0) && (f[1] > 0.0) == (f[2] > 0.0) && (f[2] > 0.0) == (f[3] > 0.0));
  const double fmin = std::min({std::fabs(f[0]), std::fabs(f[1]), std::fabs(f[2]), std::fabs(f[3])});
  const bool could_hide = fmin <= slope * h * std::numbers::sqrt2 / 2.0;
  if (!mixed && !could_hide) {
    const double a = f[0] > 0.0 ? h * h : 0.0;
    out.fine += a;
    out.coarse += a;
    return;
  }
  if (depth == max_depth) {
    const double a = cell_area(base, h, f, margin, &out.segments);
    out.fine += a;
    out.coarse += a;
    if (!mixed) {
      // Same sign at the corners of a deepest cell that is close to zero: look at its edge
      // midpoints and centre for the other sign (a piece between the corners).
      const double g = 0.5 * h;
      const double v[5] = {margin(base + Vec2(g, 0)), margin(base + Vec2(h, g)), margin(base + Vec2(g, h)),
                           margin(base + Vec2(0, g)), margin(base + Vec2(g, g))};
      bool other = false;
      for (int k = 0; k < 5; ++k) other = other || (v[k] > 0.0) != (f[0] > 0.0);
      if (other) {
        // A piece seen between the corners: measured on the four half cells, the change
        // counted as error (as one more level of refinement would).
        const double q[4][4] = {{f[0], v[0], v[4], v[3]}, {v[0], f[1], v[1], v[4]}, {v[4], v[1], f[2], v[2]},
                                {v[3], v[4], v[2], f[3]}};
        const Vec2 b[4] = {base, base + Vec2(g, 0), base + Vec2(g, g), base + Vec2(0, g)};
        double sub = 0.0;
        for (int k = 0; k < 4; ++k) sub += cell_area(b[k], g, q[k], margin, &out.segments);
        out.fine += sub - a;
        out.coarse += sub - a;
        out.hidden += std::fabs(sub - a);
      }
    }
    return;
  }
  const double g = 0.5 * h;
  const double e0 = margin(base + Vec2(g, 0)), e1 = margin(base + Vec2(h, g)), e2 = margin(base + Vec2(g, h)),
               e3 = margin(base + Vec2(0, g)), c = margin(base + Vec2(g, g));
  const double q[4][4] = {{f[0], e0, c, e3}, {e0, f[1], e1, c}, {c, e1, f[2], e2}, {e3, c, e2, f[3]}};
  const Vec2 b[4] = {base, base + Vec2(g, 0), base + Vec2(g, g), base + Vec2(0, g)};
  if (depth + 1 == max_depth) {
    // The deepest split: its undone version (this cell as a leaf) gives the coarse estimate.
    Adaptive child;
    for (int k = 0; k < 4; ++k) refine_cell(b[k], g, q[k], slope / kSlopeSafety, depth + 1, max_depth, margin, child);
    out.fine += child.fine;
    out.coarse += cell_area(base, h, f, margin, nullptr);
    out.hidden += child.hidden;
    out.cells += child.cells;
    out.segments.insert(out.segments.end(), child.segments.begin(), child.segments.end());
    return;
  }
  for (int k = 0; k < 4; ++k) refine_cell(b[k], g, q[k], slope / kSlopeSafety, depth + 1, max_depth, margin, out);
}

}  // namespace

SampledArea restricted_area(const Mechanism& m, Restriction restriction, const Grid& grid, int max_depth) {
  auto margin = [&](const Vec2& p) { return restriction_margin(m, restriction, p); };
  std::vector<double> values(grid.size());
  for (int j = 0; j < grid.ny; ++j)
    for (int i = 0; i < grid.nx; ++i) values[std::size_t(j) * grid.nx + i] = margin(grid.point(i, j));
  auto value = [&](int i, int j) { return values[std::size_t(j) * grid.nx + i]; };
  Adaptive a;
  const double h = grid.spacing;
  // The slope of a cell's neighbourhood: the largest difference quotient along the grid lines
  // from the nodes (x, y), x in [i - 1, i + 2], y in [j - 1, j + 2] (to x + 1 and to y + 1 where
  // those exist). The node's own largest quotient first, then the window's maximum in two passes
  // (rows, then columns): maxima of the same numbers, so the same slope as the 4 x 4 loop over
  // every cell. A NaN quotient never wins a std::max(slope, q).
  const int nxs = grid.nx - 1;  // nodes with a right neighbour
  std::vector<double> node_slope, row_max;
  if (nxs > 0 && grid.ny > 0) {
    node_slope.assign(std::size_t(nxs) * std::size_t(grid.ny), 0.0);
    row_max.assign(node_slope.size(), 0.0);
    for (int y = 0; y < grid.ny; ++y) {
      for (int x = 0; x < nxs; ++x) {
        double q = std::max(0.0, std::fabs(value(x + 1, y) - value(x, y)) / h);
        if (y + 1 < grid.ny) q = std::max(q, std::fabs(value(x, y + 1) - value(x, y)) / h);
        node_slope[std::size_t(y) * nxs + x] = q;
      }
    }
    for (int y = 0; y < grid.ny; ++y) {
      for (int i = 0; i < nxs; ++i) {
        double widest = 0.0;
        for (int x = std::max(0, i - 1); x <= std::min(nxs - 1, i + 2); ++x) {
          widest = std::max(widest, node_slope[std::size_t(y) * nxs + x]);
        }
        row_max[std::size_t(y) * nxs + i] = widest;
      }
    }
  }
  for (int j = 0; j + 1 < grid.ny; ++j) {
    for (int i = 0; i + 1 < grid.nx; ++i) {
      const double f[4] = {value(i, j), value(i + 1, j), value(i + 1, j + 1), value(i, j + 1)};
      double slope = 0.0;
      for (int y = std::max(0, j - 1); y <= std::min(grid.ny - 1, j + 2); ++y) slope = std::max(slope, row_max[std::size_t(y) * nxs + i]);
      refine_cell(grid.point(i, j), h, f, slope, 0, max_depth, margin, a);
    }
  }
  SampledArea out;
  out.area_mm2 = a.fine;
  // Discretisation (the last level against the one before, where the boundary was refined) plus
  // every deepest cell that could still hide a piece of the region.
  out.error_mm2 = std::fabs(a.fine - a.coarse) + a.hidden;
  out.cells = a.cells;
  for (const auto& seg : a.segments) out.contours.push_back({seg[0], seg[1]});
  return out;
}

}  // namespace fivebar
