#pragma once
/// Kinematic calibration of a station's mechanisms by nonlinear least squares (docs/calibrate.md):
/// the model of fivebar/calibrate/model.hpp fitted to bench measurements by Ceres Solver
/// (Levenberg-Marquardt, analytic Jacobians, optional Huber or Cauchy loss), with the
/// identifiability analysis of Borm & Menq ("Determination of optimal measurement configurations
/// for robot calibration based on observability measure", IJRR 1991) and the posterior covariance.
///
/// Scaled identification Jacobian. Column j of the stacked Jacobian (rows weighted by 1/sigma_i
/// when the measurements give sigma_mm) is multiplied by the parameter's a-priori scale s_j
/// (parameter_scale()), so that singular values compare a tenth of a millimetre of a link with a
/// degree of a potentiometer offset. Its singular values sigma_1 >= ... >= sigma_m give the
/// condition number sigma_1/sigma_m and the observability index O1 = (sigma_1 ... sigma_m)^(1/m) /
/// sqrt(N) (N the number of poses).
///
/// Identifiability. The requested parameters are taken in a fixed order of preference (links, then
/// the potentiometers, the instrument's pose, the upper mechanism's bases, then the lower's:
/// O2 - O1 x, O1, O2 - O1 y last, the station frame's own definition); a parameter whose scaled
/// column lies within kUnidentifiableRel of the span of those before it cannot be separated from
/// them: it is held at its design value and named with the combination (its column as a
/// least-squares combination of the kept ones). With the instrument's pose fitted, O1 of every
/// mechanism is one combination with the frame's translation, and the lower O2 - O1 y with its
/// rotation.
///
/// Posterior covariance C = s^2 (J^T W J)^{-1} over the fitted parameters at the solution, with
/// s = 1 when every measurement gives sigma_mm (or --sigma) and otherwise the residual estimate
/// s^2 = sum r^2 / (2N - p).

#include <Eigen/Core>

#include <optional>
#include <string>
#include <vector>

#include "fivebar/calibrate/measurements.hpp"
#include "fivebar/calibrate/model.hpp"
#include "fivebar/design.hpp"
#include "fivebar/provenance/gate.hpp"

namespace fivebar::calibrate {

/// Relative size of a scaled column's component outside the span of the parameters before it
/// below which the parameter counts as not identifiable from the poses.
inline constexpr double kUnidentifiableRel = 1e-6;

enum class Loss { none, huber, cauchy };

struct CalibrateOptions {
  std::string station;            ///< empty: the only station that has measurements
  std::vector<std::string> mechanisms;  ///< empty: every mechanism with measurements
  bool fit_frame = false;         ///< --frame fit: the instrument's planar pose per station
  /// Parameters to fit, by short name (mechanism_parameter_names(), frame_parameter_names()),
  /// applied to every mechanism; empty: all of them. A named one that the poses cannot identify
  /// makes the result's `requested_unidentifiable` true.
  std::vector<std::string> fit;
  bool fit_given = false;         ///< the user named the parameters (`fit`)
  Loss loss = Loss::none;
  double loss_scale = 2.0;        ///< in measurement sigmas (Huber / Cauchy scale)
  std::optional<double> sigma_mm; ///< overrides every row's sigma_mm
  int holdout = 0;                ///< K poses (evenly spaced) left out of the fit and checked after it
  int max_iterations = 100;
};

/// One estimated parameter.
struct Parameter {
  std::string mechanism;   ///< "lower", "upper", or "" for the instrument frame
  std::string name;        ///< short name (model.hpp)
  std::string key;         ///< design key path it patches, or "frame.rotation_deg" / "frame.x_mm" ...
  std::string unit;        ///< "mm", "V", "rad/V", "deg"
  double design = 0.0;     ///< prior (design) value, in `unit`
  double value = 0.0;      ///< estimate, in `unit`
  double sigma = 0.0;      ///< posterior standard deviation (0 when held)
  bool requested = false;  ///< asked to be fitted
  bool identified = false; ///< fitted (requested and identifiable)
  std::string note;        ///< why held
};

/// A parameter the poses cannot separate from others.
struct Unidentifiable {
  std::string parameter;    ///< "lower.O1x", "frame.x"
  std::string combination;  ///< "lower.O1x = -1.000 frame.x + ..." (scaled units) in words
};

/// Residual of one pose.
struct PoseResidual {
  int line = 0;
  std::string mechanism;
  bool holdout = false;
  double before_mm = 0.0;  ///< |y - model| at the design values
  double after_mm = 0.0;   ///< at the estimate
};

/// A pose left out of the fit: one the design's nominal model cannot assemble (skipped before the
/// fit), or an outlier of the robust fit (named, then left out of the final least squares).
struct ExcludedPose {
  int line = 0;
  std::string mechanism;
  std::string reason;         ///< "the nominal model cannot assemble it (unreachable)", "outlier: ..."
  double residual_mm = 0.0;   ///< |measured - model| at the robust estimate (outliers), 0 otherwise
  double standardized = 0.0;  ///< its residual over the robust scale (outliers), 0 otherwise
};

/// Pose residuals beyond this many robust scales (per axis, both axes as a chi-square of 2 dof)
/// make a pose an outlier of a robust fit: sqrt(-2 ln 1e-3) = 3.72, a 0.1 % tail of Gaussian noise.
inline constexpr double kOutlierScales = 3.7169221888498383;

struct Figures {
  double rms_mm = 0.0;  ///< sqrt(mean |r|^2) per pose
  double max_mm = 0.0;
};

struct CalibrationResult {
  std::string station;
  std::vector<std::string> mechanisms;
  int poses = 0;          ///< used in the fit
  int holdout_poses = 0;
  std::vector<Parameter> parameters;  ///< mechanisms in order, then the frame
  std::vector<Unidentifiable> unidentifiable;
  bool requested_unidentifiable = false;  ///< the user named one of them (exit 1)
  std::vector<double> singular_values;    ///< of the scaled Jacobian over the fitted parameters
  double condition_number = 0.0;
  double observability_index = 0.0;       ///< O1 (Borm & Menq)
  double sigma_mm = 0.0;                  ///< measurement sigma used for the covariance
  bool sigma_estimated = false;           ///< from the residuals (no sigma_mm given)
  Eigen::MatrixXd covariance;             ///< over the identified parameters, in their file units
  std::vector<std::string> covariance_names;
  /// The posterior covariance of the identified design keys (`key_covariance_keys`, the parameters'
  /// keys in their order, file units): what the patched design's provenance entries record as
  /// sigmas and correlations (docs/calibrate.md "Posterior covariance in the design").
  Eigen::MatrixXd key_covariance;
  std::vector<std::string> key_covariance_keys;
  Figures before, after, holdout_before, holdout_after;
  std::vector<PoseResidual> residuals;
  int iterations = 0;
  bool converged = false;
  std::string termination;    ///< Ceres' termination type ("CONVERGENCE", "NO_CONVERGENCE", ...)
  std::string solver_report;  ///< Ceres' one-line summary
  std::vector<ExcludedPose> skipped;   ///< poses the nominal model cannot assemble (not fitted)
  std::vector<ExcludedPose> outliers;  ///< outliers of the robust fit (not in the final fit)
  /// The quality gate (fivebar/provenance/gate.hpp): converged, the residual test (chi-square with a
  /// known sigma, the largest residual with one estimated), identifiable, sigma within the prior.
  gate::GateResult gate;
};

/// The a-priori scale of a parameter (model order; frame after the twelve): 0.1 mm for lengths and
/// positions, one degree's worth of volts for V0 (|1 deg / k|), 1 % of k, 1 deg of frame rotation.
double parameter_scale(int index, const MechanismVector& q);

/// The a-priori standard deviation of a patched key's value (its unit): the parameter's a-priori
/// scale (parameter_scale()), the one the quality gate compares the posterior sigma with.
double prior_sigma(int index, const MechanismVector& q);

/// Fits the measurements of one station (fivebar/calibrate/measurements.hpp) to the model.
/// InputError for bad requests (unknown parameter names, fewer equations than unknowns, a pose
/// the design cannot assemble, naming the file line).
CalibrationResult calibrate(const Design& design, const std::vector<Measurement>& measurements,
                            const CalibrateOptions& options, const std::string& origin);

/// The design with the identified parameters of `result` written in (links, bases, and the
/// potentiometers as `controller.stations.<station>.<mechanism>.theta<j>` overrides).
Design patched_design(const Design& design, const CalibrationResult& result);

}  // namespace fivebar::calibrate
