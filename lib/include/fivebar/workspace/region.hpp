#pragma once
/// Reachable workspace of a mechanism: the exact region (circular arcs, built with CGAL behind
/// this header), its area, perimeter and topology; point queries; and sampled fields over a grid
/// (reachability, LCI, singularity distances, transmission angles, force capability).
///
/// Region of one leg i in working-mode sign sigma with joint range [lo, hi]: the image of
/// (theta, psi) -> O_i + L_i e(theta) + L_{i+2} e(theta + psi), theta in [lo, hi], psi in
/// sigma*(0, pi): a curvilinear rectangle bounded by the stretched circle |P - O_i| = L_i + L_{i+2},
/// the folded circle |P - O_i| = |L_i - L_{i+2}| and two half circles of radius L_{i+2} around the
/// extreme elbow positions. Without limits it is the annulus. The mechanism's region is the
/// intersection of its two legs' regions (Gosselin & Angeles 1990 for the annuli).

#include <Eigen/Core>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/kinematics.hpp"

namespace fivebar {

/// One piece of a region boundary: a segment or a circular arc from `source` to `target`,
/// oriented so that the region lies on its left.
struct CurvePiece {
  Vec2 source{0.0, 0.0};
  Vec2 target{0.0, 0.0};
  bool is_arc = false;
  Vec2 center{0.0, 0.0};  ///< arcs only
  double radius = 0.0;    ///< arcs only
  bool ccw = true;        ///< arcs only: traversed counter-clockwise around center
  /// Signed angle swept from source to target (rad; > 0 ccw); 0 for segments.
  double sweep() const;
  double length() const;
  /// Closest point of the piece to p.
  Vec2 closest_point(const Vec2& p) const;
};

/// Is the direction of v (from an arc's centre) within the arc that runs from direction `from` to
/// direction `to` (counter-clockwise when ccw)? Cross products only: no angles.
bool direction_within_arc(const Vec2& from, const Vec2& to, bool ccw, const Vec2& v);

/// A closed boundary curve: counter-clockwise for an outer boundary, clockwise for a hole.
struct BoundaryLoop {
  std::vector<CurvePiece> pieces;
  bool hole = false;
};

namespace detail {
struct ExactRegion;  // CGAL polygon set (lib/src/cgal/)
}

/// A region bounded by circular arcs and segments, with an exact (CGAL) representation for set
/// operations and a double-precision boundary for queries and drawing.
class Region {
 public:
  Region();
  /// Boundary loops: each component's outer loop followed by its holes.
  const std::vector<BoundaryLoop>& loops() const { return loops_; }
  bool empty() const { return loops_.empty(); }
  double area_mm2() const { return area_mm2_; }
  double perimeter_mm() const { return perimeter_mm_; }
  int components() const { return components_; }
  int holes() const { return holes_; }
  /// Axis-aligned bounds {xmin, ymin, xmax, ymax}; all zero when empty.
  std::array<double, 4> bounds() const;
  /// Distance from p to the nearest boundary point (mm), and the point.
  double boundary_distance(const Vec2& p, Vec2* nearest = nullptr) const;
  /// Point membership by the winding of the boundary (double precision).
  bool contains(const Vec2& p) const;
  /// Signed distance (mm): positive inside, negative outside.
  double signed_distance(const Vec2& p) const;
  /// Exact set operations (CGAL).
  Region intersection(const Region& other) const;
  /// Exact test: does the closed polygon (vertices in order) lie inside the closed region?
  bool contains_polygon_exact(const std::vector<Vec2>& polygon) const;
  /// Exact test: does the closed polygon share no point with the closed region?
  bool disjoint_polygon_exact(const std::vector<Vec2>& polygon) const;
  /// Exact area of the polygon's part inside the region (mm^2), from the arrangement.
  double polygon_overlap_area(const std::vector<Vec2>& polygon) const;

  /// Builds from the exact representation (library internal).
  explicit Region(std::shared_ptr<const detail::ExactRegion> exact);

 private:
  std::shared_ptr<const detail::ExactRegion> exact_;
  std::vector<BoundaryLoop> loops_;
  double area_mm2_ = 0.0;
  double perimeter_mm_ = 0.0;
  int components_ = 0;
  int holes_ = 0;
};

/// Exact region of tactor points reachable in the mechanism's working mode within its joint
/// limits (assembly mode and min_lci not applied: they are not circle-bounded; see
/// restricted_area()).
Region reachable_region(const Mechanism& m);

/// Closed-form area of the intersection of the two legs' annuli (no joint limits): sums of lens
/// areas. The reference that tests hold the CGAL area to.
double annuli_intersection_area(const Mechanism& m);

/// Grid of samples over a rectangle: x = x0 + i*spacing, i < nx; y = y0 + j*spacing, j < ny.
struct Grid {
  double x0 = 0.0, y0 = 0.0, spacing = 0.1;
  int nx = 0, ny = 0;
  Vec2 point(int i, int j) const { return {x0 + i * spacing, y0 + j * spacing}; }
  std::size_t size() const { return std::size_t(nx) * std::size_t(ny); }
  /// Grid covering `bounds` {xmin, ymin, xmax, ymax} plus `pad` on every side.
  static Grid covering(const std::array<double, 4>& bounds, double spacing, double pad = 0.0);
};

/// Per-sample fields of one mechanism, row-major (index j * nx + i). Values where the point is
/// not reachable are 0 (reach = 0).
struct WorkspaceField {
  Grid grid;
  std::vector<std::uint8_t> reach;        ///< 1: reachable in the working mode within joint limits
  std::vector<std::uint8_t> status;       ///< Status of the IK (as std::uint8_t)
  std::vector<std::uint8_t> assembly_ok;  ///< 1: tactor on the design's side of the distal links
  std::vector<double> lci;
  std::vector<double> type1_distance_mm;  ///< distance to the nearest type I circle
  std::vector<double> type1_sin;          ///< min over legs of |sin| of the elbow angle
  std::vector<double> type2_sin;          ///< |sin| of the angle between the distal links
  std::vector<double> transmission_deg;   ///< tactor transmission angle (90 ideal)
  std::vector<double> force_capability;   ///< 1/sigma_max(J), N per N*mm of motor torque
};

/// Samples every field of `m` over `grid` (batch kernels; no trigonometry but for the angles).
WorkspaceField sample_field(const Mechanism& m, const Grid& grid);

/// Area of a region defined by a signed margin function sampled on a grid (> 0 inside): every
/// grid cell is refined as a quadtree where its corners disagree or where it could hide a sign
/// change (the smallest |margin| at its corners below the local slope times its half diagonal),
/// so thin regions and small components between grid nodes are found; the leaves are measured
/// by marching squares with every crossing bisected on the margin function (docs/coverage.md).
struct SampledArea {
  double area_mm2 = 0.0;
  /// Estimate: the change from undoing the deepest split, plus the change where a deepest cell
  /// showed the other sign between its corners and was measured on its half cells.
  double error_mm2 = 0.0;
  std::size_t cells = 0;  ///< cells visited (grid cells and their refinements)
  std::vector<std::vector<Vec2>> contours;  ///< segments of the refined boundary
};

/// Which restricted region restricted_area() measures.
enum class Restriction {
  reach,     ///< the exact region (for checking the sampled method against CGAL)
  assembly,  ///< reachable and tactor on the design's assembly side (no type II crossing)
  lci,       ///< reachable, on the assembly side, and LCI >= min_lci
};
/// Signed margin of `restriction` at p (> 0 inside; continuous; length units where possible).
double restriction_margin(const Mechanism& m, Restriction restriction, const Vec2& p);
/// Area of the restricted region on `grid`, each cell refined down to spacing / 2^max_depth.
SampledArea restricted_area(const Mechanism& m, Restriction restriction, const Grid& grid, int max_depth = 3);

}  // namespace fivebar
