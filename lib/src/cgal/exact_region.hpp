#pragma once
// Private bridge between fivebar::Region and its CGAL representation (region_cgal.cpp).
// Only region_cgal.cpp includes CGAL; everything else sees this opaque interface.

#include <memory>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/workspace/region.hpp"

namespace fivebar::detail {

struct ExactRegion;  // defined in region_cgal.cpp

/// Boundary of an exact region in doubles, with its topology.
struct ExtractedBoundary {
  std::vector<BoundaryLoop> loops;
  int components = 0;
  int holes = 0;
};

std::shared_ptr<const ExactRegion> exact_leg_region(const Vec2& O, double l_prox, double l_dist, int sigma,
                                                    const JointRange* limits);
std::shared_ptr<const ExactRegion> exact_intersection(const ExactRegion& a, const ExactRegion& b);
std::shared_ptr<const ExactRegion> exact_empty();
ExtractedBoundary extract_boundary(const ExactRegion& r);
bool exact_contains_polygon(const ExactRegion& r, const std::vector<Vec2>& polygon);
/// Does the closed polygon share no point with the region (exact)?
bool exact_disjoint_polygon(const ExactRegion& r, const std::vector<Vec2>& polygon);
/// Boundary of (polygon ∩ r), for its area.
ExtractedBoundary exact_polygon_overlap(const ExactRegion& r, const std::vector<Vec2>& polygon);

}  // namespace fivebar::detail
