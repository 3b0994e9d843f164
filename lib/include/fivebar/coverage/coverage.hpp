#pragma once
/// Does a mechanism (or both mechanisms of a station) reach every point of the target ellipse,
/// with margin, in its working mode, within joint limits, away from singularities?
///
/// Containment and margin are certified (docs/coverage.md): the margin comes with bounds (closed
/// form against annuli, within rounding; a Lipschitz branch and bound of the signed distance to
/// each leg's set along the ellipse when there are joint limits); the verdict follows the sign
/// whenever the bounds exclude zero. In the band where they straddle zero an exact CGAL test
/// decides (a polygon around the ellipse, refined where the ellipse nears the boundary, inside
/// the region; or a point of the ellipse outside it); when neither holds the verdict is
/// undecided (`decided` false) and never contradicts the margin. The assembly side is certified
/// over the filled ellipse by a branch and bound on the sine of the angle between the distal
/// links. `method` says what decided.

#include <optional>
#include <string>

#include "fivebar/design.hpp"
#include "fivebar/workspace/region.hpp"

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
  double margin_error_mm = 0.0;  ///< certified bound of |margin_mm - true margin|
  bool decided = true;           ///< false: within rounding of a boundary, verdict undecided
  double covered_fraction = 0.0; ///< of the ellipse area inside the region
  Vec2 worst_point{0.0, 0.0};    ///< ellipse point realising the margin
  double min_lci = 0.0;          ///< over the filled ellipse (0 if any point unreachable)
  Vec2 min_lci_point{0.0, 0.0};
  double min_force_capability = 0.0;  ///< N per N*mm, over the filled ellipse
  bool lci_ok = true;            ///< min_lci >= the mechanism's min_lci
  bool assembly_ok = true;       ///< the design's assembly side holds over the whole ellipse
  std::optional<Vec2> assembly_crossing;  ///< a point of the ellipse on the wrong side (when found)
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
/// The same record from what a caller already has: `lower` and `upper` are coverage() of each
/// mechanism on `target` (default options), `shared` the intersection of their exact regions
/// (read only for the covered fraction when the ellipse is not inside both).
CoverageResult coverage_shared(const CoverageResult& lower, const CoverageResult& upper, const Region& shared,
                               const Ellipse& target);

/// Results of a station: per mechanism present and shared when both are.
struct StationCoverage {
  std::string station;
  std::optional<CoverageResult> lower, upper, shared;
  bool covered() const;
};
StationCoverage station_coverage(const Station& station, const std::optional<Ellipse>& override_target = {},
                                 const CoverageOptions& options = {});

/// Containment and signed margin only (no covered fraction, no conditioning), decided as in
/// coverage(): certified per-leg bounds, exact CGAL test where they straddle zero.
struct Containment {
  bool inside = false;
  double margin_mm = 0.0;
  double margin_error_mm = 0.0;  ///< certified bound of |margin_mm - true margin|
  Vec2 worst_point{0.0, 0.0};
  bool decided = true;           ///< false: within rounding of the boundary (inside is then false)
  bool exact_fallback = false;   ///< the exact test was asked
};
Containment containment(const Mechanism& m, const Ellipse& target);
/// Fills min_lci (+ point), min_force_capability, lci_ok, assembly_ok (certified, with
/// assembly_crossing and decided) of `out` over the filled ellipse, as coverage() does; the
/// ellipse must be inside the region (containment() first).
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
