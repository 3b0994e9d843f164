#pragma once
/// Non-dimensional performance atlases of the symmetric five-bar (docs/atlas.md), in the manner of
/// X.-J. Liu, J. Wang, G. Pritschow, "Kinematics, singularity and workspace of planar 5R symmetrical
/// parallel mechanisms", Mech. Mach. Theory 41 (2006) 145-169 (a non-dimensional design space and
/// the atlas of the maximal inscribed circle over it), and X.-J. Liu, J. Li, Y. Zhou, "Kinematic
/// optimal design of a 2-degree-of-freedom 3-parallelogram planar parallel manipulator", Mech. Mach.
/// Theory 87 (2015) 1-17 (performance atlases of workspace and transmissibility): a figure of merit
/// over the whole family of designs, so that a station is seen among its neighbours.
///
/// Design space
/// ------------
/// A symmetric five-bar has L1 = L2, L3 = L4 and base spacing b = |O2 - O1|. With the mean length
///   D = (L1 + L3 + b) / 3,   r1 = L1 / D,   r2 = L3 / D,   r3 = b / D,   so   r1 + r2 + r3 = 3,
/// every design is a point of the triangle r_i > 0 (the "physical model of the solution space"),
/// and designs that differ only by a scale are the same point: every length figure below is in
/// units of D. The triangle is drawn as an equilateral chart
///   x = (r2 - r1) / sqrt(3),   y = r3        (r1 = 3 at (-sqrt 3, 0), r2 = 3 at (sqrt 3, 0), r3 = 3 at (0, 3)),
/// and back: r3 = y, r1 = (3 - y) / 2 - (sqrt 3 / 2) x, r2 = (3 - y) / 2 + (sqrt 3 / 2) x.
/// The atlas mechanism of a point has O1 = (-r3/2, 0), O2 = (r3/2, 0), D = 1. Without joint limits
/// its legs reach the annuli |r2 - r1| <= |P - O_i| <= r1 + r2; they overlap only when
/// r3 <= 2 (r1 + r2), i.e. r3 <= 2: above that line nothing is reachable.
///
/// Figures of merit of a point (for a target shape: aspect beta = minor / major <= 1 and the angle of
/// its major axis from the base line O1 -> O2)
/// ----------------------------------------------------------------------------------------------
/// (a) Inscribed target s*: the largest semi-major axis s of an ellipse of that shape, centred on
///     the symmetry axis at c = M + y n (M the bases' midpoint, n the unit normal left of O1 -> O2),
///     that the mechanism covers: inside the reachable region (containment(), certified) and on the
///     design's assembly side over the whole filled ellipse (conditioning(), certified), maximised
///     over the height y. For a circle (beta = 1) s* is the radius of the largest inscribed circle
///     centred on the axis, the counterpart of the 2006 paper's maximal inscribed circle.
///     - For a fixed centre the scaled ellipses are nested, so both verdicts are monotone in s.
///       The signed margin m(s) (containment().margin_mm) is non-increasing and 1-Lipschitz in s
///       (a boundary point c + s u(t) has |u| <= 1), so with s0 tiny and m0 = m(s0), s0 + m0 is
///       inside up to rounding and (s0 + m0) / beta is outside (the ellipse holds the disk of
///       radius beta s). s_c, the root of m, is bracketed there and found by regula falsi
///       (Illinois) with a bisection step whenever the bracket does not halve, each side of the
///       bracket fixed by the certified verdict, to a width of rel_tol s. Each probe is a quarter
///       of that width beside the falsi estimate, so that no probe lands within rounding of the
///       boundary (where containment() would fall back to its exact CGAL test).
///     - The assembly side: a bisection on s over the sign of cross(P - A1, P - A2) at rings x
///       angles samples of the filled ellipse (conditioning_batch()) gives the sampled limit, an
///       upper bound of the true one (a sample on the wrong side is a real crossing; a thin
///       wrong-side sliver between samples can be missed). The certified check (conditioning())
///       then accepts it, or reports a crossing q, which bounds s from above (the scale of the
///       ellipse through q), and the sampled bisection runs again below it.
///     - The height: side = +1 (assembly "+"), -1 ("-"), both (any). On the axis both bases are at
///       d(y) = sqrt(y^2 + (b/2)^2) and the centre is in both annuli for r_in <= d <= r_out
///       (r_in = max |L1 - L3|, |L2 - L4|; r_out = min L1 + L3, L2 + L4): an interval of |y|,
///       scanned at `heights` points with the sampled limits. Those bound the certified limits
///       from above, so the heights are certified in decreasing order of their sampled limit until
///       no remaining one can beat the best certified (branch and bound). A golden-section search
///       (sampled limits) over the two scan intervals around that height refines it, and the
///       refined height is kept when its certified limit is at least the scan's best. s*(y) is a
///       minimum of piecewise smooth functions: the scan finds the basin, the search its top.
/// (b) Conditioning: min LCI over the concentric ellipse of semi-major fraction * s*. Over the
///     inscribed target itself it is 0 by construction: its boundary touches a leg circle (a type I
///     singularity) or the assembly boundary (type II). Measured by conditioning() (sampled and
///     refined, as coverage's min LCI).
/// (c) Transmission: min over the same ellipse of |sin| of the angle between the distal links at
///     the tactor (Pose::type2_sin of ik(), what `fivebar fk` prints as "type II |sin|"; 1 is ideal
///     transmission, 0 a type II singularity), at the rings x angles samples of the filled ellipse.
///
/// Cells carry a status: `outside` (not a design: off the triangle), `no_workspace` (no ellipse
/// of any size fits on the design's side: the annuli do not overlap there, or no centre on the
/// axis is reachable on that side); figures are then NaN in the `.vti` (with the status beside
/// them), empty in the CSV and null in JSON.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fivebar/coverage/coverage.hpp"
#include "fivebar/design.hpp"
#include "fivebar/json.hpp"
#include "fivebar/rendered_plot.hpp"

namespace fivebar {

/// A point of the normalised design space: r1 = L1 / D, r2 = L3 / D, r3 = b / D, r1 + r2 + r3 = 3.
struct DesignPoint {
  double r1 = 1.0, r2 = 1.0, r3 = 1.0;
  double D_mm = 1.0;  ///< the mean length of the mechanism it was taken from (1 for a chart point)
};
/// Chart coordinates of a point: x = (r2 - r1) / sqrt(3), y = r3.
Vec2 chart_of(const DesignPoint& p);
/// The point at chart (x, y) (D = 1); not checked against the triangle.
DesignPoint point_at_chart(double x, double y);
/// True when every r_i > 0 (inside the triangle).
bool in_design_space(const DesignPoint& p);

/// The point of a symmetric mechanism; nullopt with `why` set when it is not symmetric (L1 != L2
/// or L3 != L4 beyond rounding) or has coincident bases of zero spacing and zero lengths.
std::optional<DesignPoint> design_point(const Mechanism& m, std::string* why = nullptr);
/// The atlas mechanism of a point at scale D_mm: O1 = (-r3 D / 2, 0), O2 = (r3 D / 2, 0), links
/// (r1 D, r1 D, r2 D, r2 D), the given modes, no joint limits.
Mechanism atlas_mechanism(const DesignPoint& p, WorkingMode working_mode, AssemblyMode assembly_mode);

/// A target's shape, without its size: aspect = minor / major in (0, 1], angle (rad) of its major
/// axis from the base line O1 -> O2.
struct TargetShape {
  double aspect = 1.0;
  double angle = 0.0;
  /// The shape of `e` relative to the base line of `m` (mirrored when `mirrored`).
  static TargetShape of(const Ellipse& e, const Mechanism& m, bool mirrored = false);
};

struct AtlasOptions {
  int cells = 41;          ///< grid points along the chart's base (x in [-sqrt 3, sqrt 3]); spacing 2 sqrt(3) / cells
  TargetShape shape;       ///< the target shape of every cell
  WorkingMode working_mode{-1, +1};         ///< both elbows outward (a lower mechanism)
  AssemblyMode assembly_mode = AssemblyMode::Plus;  ///< tactor above the elbow line
  double fraction = 0.8;   ///< (b), (c) over the concentric ellipse of fraction * s*
  int heights = 16;        ///< coarse scan of the centre's height
  double rel_tol = 1e-4;   ///< relative width of the final bracket on s* (and of the height search)
  CoverageOptions coverage;  ///< rings x angles of the samples (conditioning, transmission, assembly)
  int threads = 0;         ///< cells in parallel (OpenMP); 0: the OpenMP default
  /// InputError naming the field (`cells`, `fraction`, ...) on a value out of range.
  void validate() const;
};

enum class AtlasStatus : std::uint8_t {
  ok = 0,
  no_workspace = 1,  ///< no target of any size on the design's side
  outside = 2,       ///< not a design (off the triangle)
};
std::string_view to_string(AtlasStatus status);

/// The figures of merit of one mechanism for one target shape (units: the mechanism's, mm for a
/// design's mechanism and D for an atlas mechanism).
struct InscribedTarget {
  AtlasStatus status = AtlasStatus::no_workspace;
  double scale = 0.0;       ///< s*: semi-major axis of the largest covered target
  double height = 0.0;      ///< its centre's signed height y on the symmetry axis
  Ellipse target;           ///< that ellipse (full axes 2 s*, 2 beta s*)
  std::string limited_by;   ///< "region" (the reach) or "assembly" (the assembly side)
  double min_lci = 0.0;     ///< (b) over the ellipse of fraction * s*
  Vec2 min_lci_point{0.0, 0.0};
  double min_transmission_sin = 0.0;  ///< (c) over the same ellipse
  Vec2 min_transmission_point{0.0, 0.0};
  int containments = 0;     ///< containment() calls spent (a measure of the work)
};

/// (a)-(c) for mechanism `m` (symmetric or not: the axis is the bases' perpendicular bisector;
/// joint limits, when set, are respected by containment()).
InscribedTarget inscribed_target(const Mechanism& m, const TargetShape& shape, const AtlasOptions& options = {});

/// The figures of merit over the chart.
struct AtlasCell {
  DesignPoint point;
  Vec2 chart{0.0, 0.0};
  InscribedTarget figures;  ///< in units of D
};

/// Where a station's mechanism sits in its family, and its own figures.
struct AtlasStation {
  std::string station, mechanism;
  DesignPoint point;             ///< with the mechanism's D_mm
  Vec2 chart{0.0, 0.0};
  InscribedTarget figures;       ///< of the point, in units of D (computed there, not read off the grid)
  double target_scale = 0.0;     ///< the station's own target: semi-major axis / D
  double target_min_lci = 0.0;   ///< over the station's own target (coverage())
  double target_min_transmission_sin = 0.0;  ///< over the station's own target (same samples as (c))
  bool target_covered = false;   ///< coverage() of the station's own target by this mechanism
};

/// Another design shown on the chart (a candidate of a search, the chosen design, ...).
struct AtlasMark {
  std::string label;
  DesignPoint point;       ///< with the mechanism's D_mm
  Vec2 chart{0.0, 0.0};
  InscribedTarget figures; ///< at its point with the atlas's options, in units of D
};

struct Atlas {
  AtlasOptions options;
  double x0 = 0.0, y0 = 0.0, spacing = 0.0;  ///< chart coordinates of cell (0, 0) and the grid step
  int nx = 0, ny = 0;
  std::vector<AtlasCell> cells;  ///< row-major: j * nx + i, x fastest
  std::optional<AtlasStation> station;
  std::string station_note;      ///< why the station is not on the chart (when it is not)
  std::vector<AtlasMark> marks;  ///< add_mark()
  double seconds = 0.0;          ///< wall time of the grid
  const AtlasCell& at(int i, int j) const { return cells[std::size_t(j) * std::size_t(nx) + std::size_t(i)]; }
  std::size_t count(AtlasStatus status) const;
};

/// The atlas of `options` over the chart (InputError on bad options).
Atlas performance_atlas(const AtlasOptions& options = {});
/// The atlas of a station's family: the shape of its target and the modes of its lower mechanism
/// (else its upper one, mirrored about its base line), the station marked. A station whose
/// mechanism is not symmetric gets the atlas of `options` and a note instead of a mark.
Atlas performance_atlas(const Station& station, AtlasOptions options = {});

/// Adds symmetric mechanism `m` as a mark labelled `label` (drawn as a diamond, listed in JSON and
/// the summary lines), its figures computed at its point with the atlas's options (shape, modes):
/// the family of the atlas, whatever the mechanism's own modes. False, with `why`, when `m` is not
/// symmetric.
bool add_mark(Atlas& atlas, const std::string& label, const Mechanism& m, std::string* why = nullptr);

/// JSON: normalisation, grid, shape, modes, fraction, cell counts by status, the best cell of each
/// figure (`best`) and, with a station, the best cells whose s* holds the station's own target
/// (`best_holding_station_target`), `station` and `mechanism` (names, null when no station is
/// marked; `station_note` says why) with `station_figures`, the `marks`, the wall time. The shapes follow
/// docs/conventions.md "JSON documents" (schemas/common.schema.json).
Json to_json(const Atlas& atlas);
/// Human-readable lines: the grid and its time, the best cells, where the station sits.
std::vector<std::string> summary_lines(const Atlas& atlas);
/// One row per cell of the triangle (chart_x, chart_y, r1, r2, r3, status, scale_D, height_D,
/// min_lci, min_transmission_sin, limited_by); figures empty where the status is not ok.
std::string atlas_csv(const Atlas& atlas);
/// The `.vti` image data (chart units, z = 0): point data scale_D, min_lci, min_transmission_sin,
/// height_D (NaN where not ok), status, and field data status_names (lib/src/vtk/).
std::string atlas_vti(const Atlas& atlas);
/// One panel per figure of merit over the triangle, colour bars, the station marked (lib/src/plot/).
RenderedPlot plot_atlas(const Atlas& atlas, const std::string& subtitle = {});
/// Name and bytes: `<stem>.csv`, `<stem>.vti`, `<stem>.svg`, `<stem>.png`, `<stem>.json`.
std::vector<std::pair<std::string, std::string>> atlas_files(const Atlas& atlas, const std::string& stem,
                                                             const std::string& subtitle = {});
/// Writes atlas_files() into `dir` (created when missing), each atomically; returns the paths.
std::vector<std::filesystem::path> write_atlas_files(const std::filesystem::path& dir, const Atlas& atlas,
                                                     const std::string& stem, const std::string& subtitle = {});

}  // namespace fivebar
