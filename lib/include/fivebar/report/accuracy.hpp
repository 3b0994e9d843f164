#pragma once
/// `fivebar report accuracy`: how accurate each answer is and what the accuracy costs
/// (work-precision series against higher-precision references). See fivebar/report.hpp.

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
  /// "station/mechanism" of an earlier mechanism of the report whose exact mirror image this one
  /// is (bases, working and assembly modes, joint limits and target reflected across a line
  /// y = const, links and min_lci equal): the same regions, margins and conditioning, so its
  /// figures are that mechanism's, not measured again. Empty when measured.
  std::string mirror_of;
  double mirror_line_y_mm = 0.0;  ///< the mirror line's y when mirror_of is set
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
  std::vector<WorkSeries> restricted;      ///< assembly-restricted, LCI-restricted and thin LCI areas
  double thin_lci_threshold = 0.0;         ///< LCI threshold of the thin series (98 % of the largest)
  double thin_lci_area_reference_mm2 = 0.0;
  // Tolerance estimates at the target centre (fivebar/tolerance.hpp), with illustrative tolerances
  // (kAccuracyToleranceSigmas): the first order and the Monte Carlo 3-sigma against a Monte Carlo
  // of many more devices (another seed), and the play set's extent: first order and sampled
  // devices against the exact set.
  double tolerance_reference_3sigma_mm = 0.0;
  std::size_t tolerance_reference_samples = 0;
  double play_extent_mm = 0.0;             ///< the exact set's
  std::vector<WorkSeries> tolerance;
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

/// One run of the dynamics at one tolerance (work-precision of fivebar/dynamics.hpp).
struct DynamicsPoint {
  double rtol = 0.0;
  double time_s = 0.0;       ///< wall time of the run (the median of three under 0.05 s; quick: one run)
  double error_mm = 0.0;     ///< max over the controller's samples and both tactors of |P - P_reference|
  std::size_t steps = 0;     ///< integrator steps
  std::size_t rhs_evaluations = 0;
  std::string status;        ///< SimStatus; not "ok": error_mm covers the samples reached
};

/// One integrator on one model at increasing tolerance.
struct DynamicsSeries {
  std::string integrator;       ///< "bdf" or "erk"
  std::string pwm;              ///< "averaged" or "switched"
  double stiffness_ratio = 0.0; ///< S = T_loop R / L (see DynamicsAccuracy)
  std::vector<DynamicsPoint> points;
  std::optional<double> time_slope;  ///< slope of log(error) against log(time)
};

/// BDF against explicit RK at one stiffness ratio, both at the default rtol, on the same step
/// started 1 deg off its reference without the computation delay (the motors work from t = 0).
struct StiffnessPoint {
  double stiffness_ratio = 0.0;
  double l_over_r_s = 0.0;                        ///< the motors' electrical time constant
  std::array<double, 2> steps_per_s{0.0, 0.0};    ///< integrator steps per simulated second: bdf, erk
  std::array<double, 2> wall_per_s{0.0, 0.0};     ///< wall seconds per simulated second: bdf, erk
  std::array<std::string, 2> status;              ///< bdf, erk (step_limit: the rates are over the part run)
};

/// Work-precision of the dynamics on stiff cases (fivebar/dynamics.hpp), on the first station with
/// both mechanisms: its 1 mm step (ADC quantisation off: a rounding level flipped by a tiny
/// difference changes the next duty, a discontinuity no tolerance removes). The stiffness ratio
/// S = T_loop R / L is the winding's rate R/L over the controller's (the fastest mode the model
/// carries against the slowest rate at which its input changes); the showcase's motors sit at
/// S = 1e2 (L/R = 100 us, T_loop = 10 ms), and S grows as L shrinks.
struct DynamicsAccuracy {
  std::string station;
  std::string scenario;         ///< what was simulated
  double duration_s = 0.0;
  double reference_rtol = 0.0;  ///< the reference: BDF at this rtol on the same model
  double default_rtol = 0.0;    ///< SimulationOptions{}.rtol
  std::vector<DynamicsSeries> series;
  std::vector<StiffnessPoint> stiffness;
  /// The smallest S where ERK takes more steps per simulated second than BDF (interpolated in log
  /// S between the bracketing points; the first S when ERK takes more from the start).
  std::optional<double> crossover_ratio;
  std::string skipped;          ///< non-empty: why there is no study (no station with both mechanisms, no motor:)
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
  DynamicsAccuracy dynamics;
  double seconds = 0.0;  ///< wall time of the whole report
};

/// Work-precision of one mechanism's areas and coverage numbers (`target` is the station's).
MechanismAccuracy mechanism_accuracy(const Mechanism& m, const Ellipse& target, const AccuracyOptions& options = {});
/// The line y = c across which mechanism `b` with target `tb` is the exact mirror image of `a` with
/// `ta` (every number of b the reflection of a's, compared exactly), if it is one.
std::optional<double> mirror_line(const Mechanism& a, const Ellipse& ta, const Mechanism& b, const Ellipse& tb);
/// FK (`problem` "fk") or IK ("ik") precision study over the given mechanisms (samples pooled).
PrecisionStudy precision_study(const std::vector<const Mechanism*>& mechanisms, std::string_view problem,
                               const AccuracyOptions& options = {});
/// Work-precision of the dynamics of `design` (`station` empty: the first station with both mechanisms).
DynamicsAccuracy dynamics_accuracy(const Design& design, const AccuracyOptions& options = {});
/// The whole accuracy report of a design (or of one station). InputError for an unknown station.
AccuracyReport accuracy_report(const Design& design, const AccuracyOptions& options = {});

/// JSON document (units in the keys), human-readable tables, and the work-precision plots (one SVG
/// and one PNG per station and method, plus FK and IK) written atomically into `dir`; returns the
/// written paths relative to `dir`.
Json to_json(const AccuracyReport& report);
std::string to_text(const AccuracyReport& report);
std::vector<std::filesystem::path> write_accuracy_plots(const AccuracyReport& report, const std::filesystem::path& dir);

}  // namespace fivebar
