#pragma once
/// Does a mechanism (or both mechanisms of a station) reach every point of the target ellipse,
/// with margin, in its working mode, within joint limits, away from singularities?
///
/// Containment and margin are exact in the sense of a certified decision: a double-precision
/// fast path (closed-form annuli constraints with robust point-ellipse extrema; or distances from
/// the ellipse to every boundary arc when there are joint limits) decides whenever |margin| is
/// clear of rounding, and an exact CGAL test on polygons provably outside / inside the ellipse
/// decides the rest. `method` says which one decided.

#include <optional>
#include <string>

#include "fivebar/design.hpp"
#include "fivebar/workspace.hpp"

namespace fivebar {

struct CoverageOptions {
  /// Samples over the filled ellipse for min LCI / force / assembly side (rings x angles).
  int rings = 6;
  int angles = 48;
  /// The min-LCI point is refined by compass search down to this fraction of the ellipse size
  /// (LCI is smooth: its minimum is then known to about the square of it).
  double lci_refine = 1e-5;
};

struct CoverageResult {
  bool covered = false;          ///< filled ellipse inside the region and thresholds met
  bool inside = false;           ///< filled ellipse inside the (circle-bounded) region
  double margin_mm = 0.0;        ///< signed distance from the ellipse to the region boundary
  double covered_fraction = 0.0; ///< of the ellipse area inside the region
  Vec2 worst_point{0.0, 0.0};    ///< ellipse point realising the margin
  double min_lci = 0.0;          ///< over the filled ellipse (0 if any point unreachable)
  Vec2 min_lci_point{0.0, 0.0};
  double min_force_capability = 0.0;  ///< N per N*mm, over the filled ellipse
  bool lci_ok = true;            ///< min_lci >= the mechanism's min_lci
  bool assembly_ok = true;       ///< the design's assembly side holds over the whole ellipse
  std::string method;            ///< how containment was decided
  std::string reason;            ///< why not covered (empty when covered)
};

/// Coverage of `target` by one mechanism.
CoverageResult coverage(const Mechanism& m, const Ellipse& target, const CoverageOptions& options = {});
/// Same with a precomputed exact region of m (for repeated queries).
CoverageResult coverage(const Mechanism& m, const Region& region, const Ellipse& target,
                        const CoverageOptions& options = {});

/// Coverage of the shared region (both tactors reach every point): margins are the smaller of
/// the two, the fraction is measured on the exact intersection.
CoverageResult coverage_shared(const Mechanism& lower, const Mechanism& upper, const Ellipse& target,
                               const CoverageOptions& options = {});

/// Results of a station: per mechanism present and shared when both are.
struct StationCoverage {
  std::string station;
  std::optional<CoverageResult> lower, upper, shared;
  bool covered() const;
};
StationCoverage station_coverage(const Station& station, const std::optional<Ellipse>& override_target = {},
                                 const CoverageOptions& options = {});

/// Containment and signed margin only (no covered fraction, no conditioning), decided as in
/// coverage(): analytic per-leg fit, exact CGAL fallback within rounding of tangency.
struct Containment {
  bool inside = false;
  double margin_mm = 0.0;
  Vec2 worst_point{0.0, 0.0};
  bool exact_fallback = false;  ///< the exact test decided
};
Containment containment(const Mechanism& m, const Ellipse& target);
/// Fills min_lci (+ point), min_force_capability, lci_ok and assembly_ok of `out` over the
/// filled ellipse, as coverage() does.
void conditioning(const Mechanism& m, const Ellipse& target, const CoverageOptions& options, CoverageResult& out);

/// Fast verdict without joint limits: closed-form margin of the ellipse against both annuli.
/// Returns the signed margin (mm) and the worst ellipse point.
double annuli_margin(const Mechanism& m, const Ellipse& target, Vec2* worst_point = nullptr);

/// Extremes of |q - p| over the boundary of the ellipse (robust: sampling of the degree-2
/// trigonometric polynomial |q(t) - p|^2 and safeguarded Newton on its derivative).
struct EllipseExtremes {
  double min_distance = 0.0, max_distance = 0.0;
  Vec2 nearest{0.0, 0.0}, farthest{0.0, 0.0};
  bool p_inside = false;  ///< p inside the filled ellipse
};
EllipseExtremes ellipse_distance_extremes(const Ellipse& e, const Vec2& p);

}  // namespace fivebar
