#pragma once
/// Polylines of workspace curves: exact boundary pieces (segments and circular arcs) and the target
/// ellipse as point lists, and marching-squares segments joined into chains. Geometry only: the VTK
/// documents (fivebar/workspace/io.hpp) and the pictures (lib/src/plot/) both draw from here.

#include <numbers>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/workspace/region.hpp"

namespace fivebar {

/// Largest angle an arc advances between two polyline points (1 degree).
inline constexpr double kArcStepRad = std::numbers::pi / 180.0;

/// Points along a piece from source to target, both included: a segment as its two ends, an arc
/// in equal steps of at most `max_step_rad` (> 0) around its centre, each point on the circle.
std::vector<Vec2> discretise(const CurvePiece& piece, double max_step_rad = kArcStepRad);
/// A loop as a closed polyline: its pieces in order, shared ends once, the first point not repeated.
std::vector<Vec2> discretise(const BoundaryLoop& loop, double max_step_rad = kArcStepRad);
/// Joins polylines whose ends meet within `tol_mm` (marching squares gives one segment per cell)
/// into the longest chains; a chain that returns to its start is closed (first point not repeated).
struct Polyline {
  std::vector<Vec2> points;
  bool closed = false;
};
std::vector<Polyline> chain_segments(const std::vector<std::vector<Vec2>>& pieces, double tol_mm);

/// Polylines of the target ellipse: `segments` equal parameter steps, closed.
std::vector<Vec2> ellipse_polyline(const Ellipse& e, int segments = 360);

}  // namespace fivebar
