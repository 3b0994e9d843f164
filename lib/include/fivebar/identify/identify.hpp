#pragma once
/// Motor, friction and inertia identification from bench logs (docs/identify.md): the inverse
/// dynamic model by weighted least squares on zero-phase filtered, decimated data (IDIM-LS,
/// Gautier & Khalil), its base parameters and what the log cannot separate, then an output-error
/// refinement that simulates the model (Ceres), with the fit figures system identification reports.

#include <Eigen/Dense>

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fivebar/identify/log.hpp"
#include "fivebar/identify/model.hpp"
#include "fivebar/rendered_plot.hpp"
#include "fivebar/runtime/config.hpp"

namespace fivebar::identify {

/// The feedback a closed-loop log was recorded under (docs/identify.md "Closed loop"): stateful, one
/// call per log row, as the controller ran. IDIM-IV simulates the loop with it to build its
/// instruments; it is never given the logged (noisy) reading.
class LoopController {
 public:
  virtual ~LoopController() = default;
  /// Back to the state the log started in (integrators and derivative memories cleared).
  virtual void reset() = 0;
  /// The drive (the log's drive column's units) commanded at `row` from the angle read at it.
  virtual double drive(std::size_t row, double angle) = 0;
};

/// The device's PID (fivebar/runtime/controller.hpp `pid_update`, the one implementation the runtime
/// and `simulate` run) on reference[row] - angle at the log's period, the duty times `scale` (1 for a
/// `duty` column, motor.supply_voltage_V for a `voltage_V` one).
std::unique_ptr<LoopController> device_pid(std::vector<double> reference, const runtime::Gains& gains, double period_s,
                                           double scale);

/// The device's PID a closed-loop log of `joint` was taken under: the design's gains for the joint
/// (a bench motor: `controller.pid`) at the log's rate, commanding its duty (or duty x the motor's
/// supply_voltage_V for a voltage_V column). InputError naming `file` when the joint has no reference
/// column or another drive, or the design no controller: section.
std::unique_ptr<LoopController> design_pid(const Design& design, const JointLog& joint, double sample_time, const std::string& file);

/// One log of a joint in a fit: several logs of the same joint are fitted together (their rows
/// stacked; the filters and the edge trimming applied to each). `controller`: the feedback the log
/// was taken under (closed loop), or null (the drive was applied open loop).
struct LogSegment {
  const JointLog* joint = nullptr;
  const std::vector<double>* time = nullptr;
  LoopController* controller = nullptr;
};

struct IdentifyOptions {
  double cutoff_hz = 0.0;        ///< zero-phase low-pass on the position; 0: fs / 10
  int filter_order = 4;          ///< Butterworth order (run twice: filtfilt)
  int decimation = 0;            ///< 0: 10, less when the log would keep fewer than 50 rows per unknown
  bool per_direction = false;    ///< viscous friction per direction of motion
  /// Voltage and duty drives: leave out the rows within reversal_samples() of a reversal of the
  /// filtered speed. There the reading (after the gearbox) stalls in the backlash while the motor, whose
  /// speed the back-EMF sees, already turns; the back-EMF's damping, about 100 times the friction's
  /// with the design's motor, turns that mismatch into a viscous friction biased up and a Coulomb
  /// friction biased down (docs/identify.md "A voltage drive and its sampled current").
  bool skip_reversals = true;
  /// The logged drive is a command held over each sample (zero-order hold): the regression pairs the
  /// acceleration at t_k (two central differences) with (d_k-2 + 3 d_k-1 + 3 d_k + d_k+1) / 8, and a
  /// voltage's current is taken over each sample through the winding's lag. false: the drive is an
  /// instantaneous value.
  bool zero_order_hold = true;
  bool output_error = true;      ///< refine by simulation (Ceres) after IDIM-LS
  bool use_output_error = false; ///< report the refined values as the parameters (default: IDIM-LS)
  /// A regressor column whose distance to the span of the earlier ones, relative to its norm, is
  /// below this is not separable (its parameter is held at its prior).
  double rank_tolerance = 1e-4;
  double coulomb_smoothing = 1e-3;  ///< w_s of tanh(w / w_s) in the simulation (fivebar/dynamics.hpp)
  /// Closed loop (every estimation log has a controller): IDIM-IV stops when no parameter moved by
  /// more than this fraction of its sigma in an iteration, and is not converged after iv_max_iterations.
  /// The simulated speed's sign switching a sample earlier or later changes the instruments by a
  /// step: the iteration can end in a cycle of about 2 % of a sigma (measured), below this bound.
  double iv_tolerance = 0.05;
  int iv_max_iterations = 30;
  std::vector<std::string> require;  ///< keys the caller asked to fit: unidentifiable ones are errors
};

/// One reported parameter: the plain record `calibrate`'s patch writer takes. `key` is a design key
/// path (`motor.terminal_resistance_ohm`) in the design file's unit, or a rig-only name with its
/// unit (`inertia_kg_m2`, ...). Held parameters carry their prior, sigma 0 and a note.
struct Parameter {
  std::string key;
  double value = 0.0;
  double sigma = 0.0;
  bool identified = false;
  std::string note;
};

/// A least-squares estimate with its statistics.
struct Estimate {
  std::vector<std::string> names;
  Eigen::VectorXd value;
  Eigen::VectorXd sigma;          ///< sqrt(s^2 (W^T W)^-1_ii); 0 for held parameters
  Eigen::MatrixXd covariance;     ///< of every parameter (zero rows for held ones)
  Eigen::MatrixXd correlation;    ///< identity on held parameters
  std::vector<bool> identified;
  std::vector<std::string> notes; ///< per parameter: why held, or the combination it stands for
  double residual_sigma = 0.0;    ///< s = ||Y - W theta|| / sqrt(rows - identified)
  int rows = 0;
};

/// Fit figures: 100 (1 - ||y - yhat|| / ||y - mean y||); relative error ||y - yhat|| / ||y||.
struct Fit {
  double drive_fit_percent = 0.0;          ///< inverse model: the drive predicted from the motion
  double drive_relative_error_percent = 0.0;
  double position_fit_percent = 0.0;       ///< open-loop simulation driven by the logged drive
  double position_relative_error_percent = 0.0;
  bool simulated = false;                  ///< position figures valid
};

/// Time series for the plot.
struct Series {
  std::vector<double> time, position, position_idim, position_oe;
  std::vector<double> drive_time, drive, drive_idim;
};

struct JointIdentification {
  std::string joint;          ///< the log prefix, or "motor"
  std::string drive_column, reading_column;
  bool linear = false;
  double sample_time = 0.0, cutoff_hz = 0.0;
  int decimation = 1;
  int edge_samples = 0;       ///< full-rate samples at each end left out of the fit: the filters' settling
  /// Voltage and duty drives (IdentifyOptions::skip_reversals): full-rate samples on each side of a
  /// reversal of the speed left out (0: none), and the decimated rows that left out.
  int reversal_samples = 0;
  int reversal_rows = 0;
  int logs = 1;               ///< estimation logs fitted together
  Estimate idim;              ///< mechanical base parameters, IDIM-LS
  /// Closed loop: IDIM-IV (instruments from the loop simulated with the previous estimate),
  /// started from IDIM-LS; its status ("converged in N iterations", or why not).
  std::optional<Estimate> iv;
  std::string iv_status;
  int iv_iterations = 0;
  bool iv_converged = false;
  /// "IDIM-LS", "IDIM-IV" or "output error": the estimate `parameters` report.
  std::string method = "IDIM-LS";
  std::optional<Estimate> electrical;  ///< R, L, k_e when a voltage drive logs its current
  std::optional<Estimate> output_error;
  std::string output_error_status;     ///< "converged", "not run: ...", Ceres' message
  Fit estimation_idim, estimation_oe;
  std::optional<Fit> validation_idim, validation_oe;
  std::vector<Parameter> parameters;   ///< every key: identified, derived and held
  std::vector<std::string> unidentifiable;  ///< keys held because the log does not excite them
  Series series, validation_series;
};

/// Fits one joint of `log` (and checks it on `validation`, the same joint's columns). InputError for a
/// log too short for the unknowns. Pure: reads nothing, writes nothing.
JointIdentification identify_joint(const JointLog& joint, const std::vector<double>& time, const JointPrior& prior,
                                   const JointLog* validation, const std::vector<double>* validation_time,
                                   const IdentifyOptions& options);
/// Fits one joint over several logs at once (the same drive and reading columns; sample times within
/// 5 %). Closed loop when every estimation log has a controller: IDIM-LS, then IDIM-IV; a mix of
/// open- and closed-loop logs is an InputError. The output-error refinement simulates each open-loop
/// log and is not run on closed-loop ones. `validation` may be empty.
JointIdentification identify_joint(const std::vector<LogSegment>& logs, const JointPrior& prior,
                                   const std::vector<LogSegment>& validation, const IdentifyOptions& options);

/// The motor rig of `fivebar identify DESIGN LOG...` (and of the `identify` product and the Python
/// binding): every joint of the first log, or only `joint`.
struct MotorRig {
  const std::vector<IdentifyLog>* logs = nullptr;  ///< the estimation logs (the first names the joints)
  std::vector<std::string> names;                  ///< their files, for messages
  const IdentifyLog* validation = nullptr;         ///< or null
  std::string validation_name;
  std::string joint;           ///< only this joint (its column prefix, "motor" for none); empty: every joint
  double load_inertia = 0.0;   ///< kg m^2 at the output, known (joint_prior())
  bool closed_loop = false;    ///< the logs were taken under the design's PID (design_pid()): IDIM-IV
};
/// Each joint's columns in every log fitted together with its prior from the design (joint_prior()).
/// InputError naming the file when a log lacks a joint's columns or drives it otherwise.
std::vector<JointIdentification> identify_motor_rig(const Design& design, const MotorRig& rig, const IdentifyOptions& options);
/// The keys of `options.require` that a joint of `results` could not identify ("KEY (JOINT): why"),
/// for the caller to refuse; InputError (naming the key as `option` KEY, with the rig's parameters)
/// for a key that is not a parameter of the rig. `results` is not empty (the callers refuse that first).
std::vector<std::string> refused_fits(const std::vector<JointIdentification>& results, const IdentifyOptions& options,
                                      const std::string& option);

/// The least-squares core: Y = W theta + e with the columns of `W` named; a column not separable
/// from the earlier ones (rank_tolerance) is held at `prior` and named. Used for the mechanical and
/// electrical regressions.
Estimate least_squares(const Eigen::MatrixXd& W, const Eigen::VectorXd& Y, const std::vector<std::string>& names,
                       const Eigen::VectorXd& prior, double rank_tolerance);

/// 100 (1 - ||y - yhat|| / ||y - mean y||).
double fit_percent(const std::vector<double>& y, const std::vector<double>& yhat);

/// Open-loop simulation of the reduced model (RK4, the drive held over each sample) from q0, w0.
std::vector<double> simulate_position(const std::vector<double>& time, const std::vector<double>& drive_torque_u,
                                      double g, const Eigen::VectorXd& mechanical, bool per_direction, double q0,
                                      double w0, double coulomb_smoothing);

/// Closed-loop simulation of the reduced model: at each row the controller reads the simulated angle
/// and its drive d is held over the sample (drive torque alpha d - g w, RK4 with enough sub-steps for
/// the smoothed Coulomb term); `drive_out` (optional) the drive it commanded. Non-finite values stop it.
std::vector<double> simulate_closed_loop(const std::vector<double>& time, LoopController& controller, double alpha, double g,
                                         const Eigen::VectorXd& mechanical, bool per_direction, double q0, double w0,
                                         double coulomb_smoothing, std::vector<double>* drive_out = nullptr);

/// Measured against fitted (position above, drive below), SVG and PNG.
RenderedPlot identify_plot(const JointIdentification& r, bool validation);

}  // namespace fivebar::identify
