#pragma once
/// How accurate is each answer, what does the accuracy cost, and does the tool stay sound where
/// mechanisms are hard: `fivebar report accuracy` (work-precision) and `fivebar report stability`
/// (a catalogue of extreme cases).
///
/// References. Kinematics, closed-form areas and ellipse margins are recomputed in IEEE binary128
/// (__float128, lib/src/report_quad.hpp) by formulas written independently of the library's; the
/// reachable area's reference is the exact CGAL region; sampled (assembly- and LCI-restricted)
/// regions are measured against the same method on a 16x finer grid; the sampled coverage
/// quantities against coverage().
///
/// Work-precision. Every approximate method is run at increasing resolution; each point is the
/// median wall time of repeated runs after a warm-up and the error against the reference. The
/// convergence order is the least-squares slope of log(error) against log(resolution).
///
/// Stability. Each case states the library's status, its error against the quad reference, and
/// the error the problem's conditioning allows (the bound; derivations in report_stability.cpp).
/// It passes when every number is finite, the status is one the reference allows and the error is
/// within the bound. A case whose bound is large (few correct digits are possible in double
/// precision) is flagged ill_conditioned with the reason; it can still pass.

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/json.hpp"

namespace fivebar {

// --- Work-precision ------------------------------------------------------------------------------

/// One run of an approximate method.
struct WorkPoint {
  double resolution = 0.0;  ///< grid spacing or sample spacing (mm), or unit roundoff (precision series)
  double time_s = 0.0;      ///< median wall time of one run (s) over the repeats after a warm-up
  double value = 0.0;       ///< the method's answer, in the series' unit
  double error = 0.0;       ///< |value - reference|, in the series' unit
  std::optional<double> estimate;  ///< the method's own error estimate, where it gives one
};

/// A method at increasing resolution.
struct WorkSeries {
  std::string method;      ///< "cell counting", "marching squares", ...
  std::string resolution;  ///< what WorkPoint::resolution is: "h_mm" or "unit_roundoff"
  std::string unit;        ///< of value and error: "mm2", "mm" or "1"
  std::vector<WorkPoint> points;
  /// Observed order p in error ~ resolution^p (least squares on the points above the reference's
  /// own accuracy); absent with fewer than two such points or for single-point series.
  std::optional<double> order;
  /// Slope of log(error) against log(time) on the same points (negative: more work, less error).
  std::optional<double> time_slope;
  std::string note;
};

/// Least-squares slope of log(y) against log(x) over the pairs with x, y > 0 and y > floor.
std::optional<double> fit_log_slope(const std::vector<double>& x, const std::vector<double>& y, double floor = 0.0);

/// Work-precision of the areas and coverage numbers of one mechanism.
struct MechanismAccuracy {
  std::string station;
  std::string mechanism;
  // Reachable workspace.
  double exact_area_mm2 = 0.0;                 ///< exact CGAL region (reachable_region)
  std::optional<double> closed_form_area_mm2;  ///< annuli_intersection_area (no joint limits)
  std::optional<double> quad_area_mm2;         ///< the annuli closed form in quad (no joint limits)
  std::vector<WorkSeries> area;  ///< cell counting and marching squares vs exact; exact and closed form vs quad
  // Coverage of the station's target.
  double margin_mm = 0.0;                  ///< coverage()
  std::optional<double> margin_quad_mm;    ///< quad reference (no joint limits)
  double min_lci = 0.0;                    ///< coverage()
  double min_lci_reference = 0.0;          ///< finest sampling refined by a local search
  std::vector<WorkSeries> coverage;        ///< sampled margin, sampled min LCI, coverage() itself
  // Restricted (sampled) regions.
  double lci_threshold = 0.0;              ///< min LCI of the LCI-restricted region
  bool lci_threshold_from_design = false;  ///< false: the design sets none, an illustrative one is used
  double reference_spacing_mm = 0.0;       ///< h of the reference grid (finest h / 16)
  double assembly_area_reference_mm2 = 0.0;
  double lci_area_reference_mm2 = 0.0;
  std::vector<WorkSeries> restricted;      ///< assembly-restricted and LCI-restricted areas
};

/// Error statistics of one method over one stratum of singularity distance.
struct PrecisionCell {
  std::size_t samples = 0;    ///< cases with a reference solution
  std::size_t failed = 0;     ///< cases where the method returned no solution (not in the errors)
  double max_error_mm = 0.0;  ///< FK: |P - P_ref|; IK: max_i L_i |theta_i - theta_i,ref|
  double rms_error_mm = 0.0;
  double max_error_ulp = 0.0;  ///< the same in ulps of the length scale in the method's arithmetic
  double rms_error_ulp = 0.0;
  double ns_per_call = 0.0;    ///< median over repeats after a warm-up
};

struct PrecisionMethod {
  std::string name;           ///< "float", "double", "long double", "fk()", "fk_point()", "fk_batch()", ...
  double unit_roundoff = 0.0; ///< epsilon of its arithmetic
  bool library = false;       ///< one of the library's own double paths
  std::vector<PrecisionCell> cells;  ///< one per stratum
};

/// FK or IK in several precisions against the quad reference, stratified by |sin| of the angle
/// that conditions the problem (FK: the tactor angle, type II; IK: the smaller elbow angle, type I).
struct PrecisionStudy {
  std::string problem;        ///< "fk" or "ik"
  std::string stratified_by;  ///< what the strata measure
  std::vector<std::array<double, 2>> strata;  ///< |sin| in [lo, hi)
  std::vector<PrecisionMethod> methods;
  /// Per stratum: slope of log(rms error) against log(unit roundoff) over float, double and
  /// long double (1 when the error is rounding amplified by a fixed conditioning).
  std::vector<std::optional<double>> order;
};

struct AccuracyOptions {
  bool quick = false;        ///< coarser series and fewer samples (tests, `fivebar run`)
  std::string station;       ///< empty: every station
  std::uint64_t seed = 20220707;  ///< of the random kinematic samples
  std::function<void(std::string_view)> progress;  ///< may be empty
};

struct AccuracyReport {
  std::string design;
  bool quick = false;
  std::vector<MechanismAccuracy> mechanisms;
  PrecisionStudy fk, ik;
  double seconds = 0.0;  ///< wall time of the whole report
};

/// Work-precision of one mechanism's areas and coverage numbers (`target` is the station's).
MechanismAccuracy mechanism_accuracy(const Mechanism& m, const Ellipse& target, const AccuracyOptions& options = {});
/// FK (`problem` "fk") or IK ("ik") precision study over the given mechanisms (samples pooled).
PrecisionStudy precision_study(const std::vector<const Mechanism*>& mechanisms, std::string_view problem,
                               const AccuracyOptions& options = {});
/// The whole accuracy report of a design (or of one station). InputError for an unknown station.
AccuracyReport accuracy_report(const Design& design, const AccuracyOptions& options = {});

/// JSON document (units in the keys), human-readable tables, and the work-precision plots (one SVG
/// and one PNG per station and method, plus FK and IK) written atomically into `dir`; returns the
/// written paths relative to `dir`.
Json to_json(const AccuracyReport& report);
std::string to_text(const AccuracyReport& report);
std::vector<std::filesystem::path> write_accuracy_plots(const AccuracyReport& report, const std::filesystem::path& dir);

// --- Stability -----------------------------------------------------------------------------------

struct StabilityCase {
  std::string mechanism;  ///< "index/lower", or the label given to stability_catalogue()
  std::string group;      ///< "type I distance", "type II distance", "link ratio", "scale", ...
  std::string name;       ///< the case within its group, e.g. "stretched, distance 1e-08"
  std::string operation;  ///< "ik", "fk", "jacobian", "lci", "area", "closed-form area", "margin", ...
  double parameter = 0.0; ///< the swept value (distance / length scale, ratio, scale, condition number)
  std::string status;     ///< what the library reported
  std::string expected;   ///< the statuses the reference allows, "|"-separated
  std::optional<double> error;  ///< against the quad reference, in `unit` (absent: status-only case)
  std::optional<double> bound;  ///< the error the conditioning allows, in `unit`
  std::string unit;       ///< "mm", "rel" (relative), "mm2", "1"
  double conditioning = 0.0;  ///< the reference's |sin| (or LCI) governing the case; 1 when irrelevant
  bool finite = true;     ///< every number the library returned is finite
  bool passed = true;
  bool ill_conditioned = false;
  std::string explanation;  ///< why ill-conditioned, why it failed, or what was checked
};

struct StabilityReport {
  std::string design;
  std::vector<StabilityCase> cases;
  std::size_t failed() const;
  std::size_t ill_conditioned() const;
  bool passed() const { return failed() == 0; }
};

struct StabilityOptions {
  std::string station;  ///< empty: every station
  std::function<void(std::string_view)> progress;  ///< may be empty
};

/// The catalogue for one mechanism and target ellipse; cases are labelled `label`. Its cases are
/// built from the mechanism without joint limits (the extremes are those of the kinematics; limits
/// only cut the workspace), with lengths rounded to a dyadic grid where exact singular points need
/// it (no change for lengths such as the paper's), in frames that make the sensitive input exact.
StabilityReport stability_catalogue(const Mechanism& m, const Ellipse& target, const std::string& label);
/// The catalogue for every mechanism of the design (or of one station).
StabilityReport stability_report(const Design& design, const StabilityOptions& options = {});

Json to_json(const StabilityReport& report);
std::string to_text(const StabilityReport& report);

}  // namespace fivebar
