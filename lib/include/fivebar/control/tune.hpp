#pragma once
/// Tuning of the PID gains per mechanism under the constraints an engineer sets (below).

#include <array>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/control/loop.hpp"
#include "fivebar/control/stability.hpp"
#include "fivebar/json.hpp"

namespace fivebar {

// --- Tuning ---------------------------------------------------------------------------------------
//
// Gains per mechanism (the same kp, ki, kd on both joints; or per joint with `per_joint`; i_clamp
// kept) that minimise the worst tracking error over the station's patterns, simulated with this
// mechanism alone under the new gains (fivebar/dynamics.hpp, CVODE at TuneOptions::rtol), subject
// to the constraints an engineer sets, all over the export gate's 21 x 21 grid of the target:
// max rho <= rho_limit; the least damping ratio of any oscillatory pole >= min_damping (0.3); max
// rho < 1 with kp, and with kd, multiplied by min_gain_margin (2: the margins then reach it, since
// gain_margin() brackets from factor 1 up); and, for what the linear model does not see, the
// simulated 1 mm step of the tactor (with the duty saturation and the integral clamp) overshooting
// by at most the second-order bound at min_damping, exp(-pi zeta / sqrt(1 - zeta^2)) of the step.
// The saturation limit is a penalty of 10 mm per unit of saturated-time fraction beyond
// controller.max_saturation_fraction. Before and after, each mechanism also runs the chirp of
// SimulationRequest: the -3 dB bandwidth, and the frequency at which the motors first saturate,
// the smaller being the bandwidth to report. The mechanisms are tuned in parallel (std::thread).
//
// Start: pole placement on the linearised model at the target's centre. Each joint j of the plant
// above, with the current taken as settled (L/R = 0.1 ms with the motor defaults, far below
// T = 10 ms: i_j = (V_s,j u_j - k_e,j N_j w_j) / R_j) and the cross terms of M, K_s, C_s left out,
// is the second-order SISO model
//   m_j theta'' + c_j theta' + k_j theta = b_j u,   m_j = M_jj, k_j = K_s,jj,
//   c_j = C_s,jj + b_v,j + eta_j N_j^2 k_t,j k_e,j / R_j,   b_j = eta_j N_j k_t,j V_s,j / R_j,
// and the continuous PID u = -(kp theta + ki int theta + kd theta') closes it with the
// characteristic polynomial m s^3 + (c + b kd) s^2 + (k + b kp) s + b ki. Placing its three roots at
// -omega, (s + omega)^3 = s^3 + 3 omega s^2 + 3 omega^2 s + omega^3, gives
//   kp = (3 m omega^2 - k) / b,   ki = m omega^3 / b,   kd = (3 m omega - c) / b
// (e.g. Astrom & Murray, "Feedback Systems", 2008, Sec. 10.3 on PID pole placement for a
// second-order process); a gain that comes out below 1e-3 is raised to it. With one set of gains for
// both joints, m, c, k and b are the two joints' means. omega is the one of a geometric scan from
// 0.2 Hz to a quarter of the loop rate (60 values, the best refined by golden section) that
// minimises the exact sampled-data max rho over the target (the continuous design does not see the
// sample-and-hold and the period of delay; the exact check does). TuneOptions::start = hand_set
// starts from the hand-set gains instead.
//
// Refinement: NLopt's COBYLA (Powell's derivative-free linear-approximation method with
// constraints; Powell, "A direct search optimization method that models the objective and
// constraint functions by linear interpolation", 1994) over (ln kp, ln ki, ln kd) (per joint: six)
// within a factor e^5 (~148) of the start, an initial step of a factor 2, the constraint aimed 0.003
// inside its limit. The result is the best evaluated point that meets the constraints (COBYLA's own
// last point may lie just outside), else COBYLA's point. No random element: the same design and
// options give the same gains, unless the wall-time bound stops a run first (the result says so).

enum class TuneStart { pole_placement, hand_set };

/// PID gains placing the three closed-loop roots of each joint's reduced model (above) of `plant`
/// at -omega (rad/s); i_clamp from `base`. `per_joint` false: one set from the joints' means.
std::array<PidGains, 2> pole_placement_gains(const LinearPlant& plant, const std::array<MotorParams, 2>& motors,
                                             double omega_rad_s, bool per_joint, const std::array<PidGains, 2>& base);

/// The start of the tuning: pole_placement_gains() at the omega minimising max rho over `poses`.
struct PolePlacement {
  Status status = Status::unreachable;  ///< of the centre pose; gains = base unless ok
  double omega_rad_s = 0.0;
  std::array<PidGains, 2> gains;
  double max_rho = 0.0;                 ///< over the poses
};
PolePlacement pole_placement(const LoopModel& loop, const Vec2& centre_mm, const std::vector<PoseLoop>& poses,
                             bool per_joint, const std::array<PidGains, 2>& base);

struct TuneOptions {
  double rho_limit = 0.9;       ///< max spectral radius allowed over the target
  TuneStart start = TuneStart::pole_placement;
  bool per_joint = false;       ///< kp, ki, kd per joint (six unknowns) instead of per mechanism
  int grid = kControlGateGrid;  ///< per axis over the target for the constraint: the export gate's grid
  int max_evaluations = 60;     ///< objective evaluations per mechanism
  double max_seconds = 30.0;    ///< wall time for the whole tuning, shared among the mechanisms
  double rtol = 1e-3;           ///< CVODE tolerance of the tracking runs
  double min_damping = 0.3;     ///< controller.tune.min_damping: least oscillatory zeta over the target
  double min_gain_margin = 2.0; ///< controller.tune.min_gain_margin: kp and kd factors keeping rho < 1
  bool chirp = true;            ///< run the before/after chirps (bandwidth, saturation onset)
  /// Mechanisms tuned at once (std::thread; 0: std::thread::hardware_concurrency()). The result
  /// does not depend on it (each mechanism's search is deterministic and independent) unless the
  /// wall-time bound stops a search.
  unsigned threads = 0;
  std::function<void(std::string_view)> progress;  ///< one line per evaluation; may be empty
};

/// The options of a design's `controller.tune` (its defaults when the key is absent).
TuneOptions tune_options(const ControllerSettings& controller);

/// Before and after, for one mechanism.
struct TunedMechanism {
  std::string station, mechanism;
  /// before: the hand-set gains (ControllerSettings::hand_set_pid(): the file's PID without the
  /// per-station-mechanism scopes a patch writes), the start; design: the gains the design runs
  /// with (the hand-set ones, or an earlier patch's); after: the tuned ones.
  std::array<PidGains, 2> before, design, after;
  std::array<PidGains, 2> start;   ///< where COBYLA started (the pole placement or the hand-set gains)
  double start_omega_rad_s = 0.0;  ///< the pole placement's omega (0 when started from the hand-set gains)
  double rho_start = 0.0;
  double rho_before = 0.0, rho_after = 0.0;        ///< max over the constraint's grid
  double error_before_mm = 0.0, error_after_mm = 0.0;  ///< worst tracking error over the patterns
  double saturation_before = 0.0, saturation_after = 0.0;  ///< worst saturated-time fraction
  /// Least damping ratio of an oscillatory pole over the constraint's grid (LoopPoles).
  double damping_before = 1.0, damping_after = 1.0;
  double damping_hz_before = 0.0, damping_hz_after = 0.0;  ///< that pole's frequency
  /// Gain margins over the constraint's grid (StabilityMap::kp_margin, kd_margin; capped at 1e3).
  double kp_margin_before = 0.0, kp_margin_after = 0.0, kd_margin_before = 0.0, kd_margin_after = 0.0;
  /// Largest overshoot of the 1 mm step along x (the simulation, with the duty saturation and the
  /// integral clamp), mm; the constraint allows step * exp(-pi zeta / sqrt(1 - zeta^2)).
  double overshoot_before_mm = 0.0, overshoot_after_mm = 0.0;
  /// The chirp (SimulationRequest's defaults: 0.2 mm, 0.5 Hz to a quarter of the loop rate):
  /// its -3 dB bandwidth (the chirp's top frequency when it never falls 3 dB), the instantaneous
  /// frequency at which a motor's duty first saturates (inf: never), and the bandwidth to report,
  /// the smaller of the two: above it the motors saturate or the gain has fallen.
  double chirp_bandwidth_before_hz = 0.0, chirp_bandwidth_after_hz = 0.0;
  double chirp_saturation_before_hz = 0.0, chirp_saturation_after_hz = 0.0;
  double bandwidth_before_hz = 0.0, bandwidth_after_hz = 0.0;
  int evaluations = 0;
  /// rho_after <= rho_limit, the saturation within its limit, the damping and gain margin floors
  /// met and the step's overshoot within its bound.
  bool feasible = false;
  std::string stop;        ///< why the optimiser stopped
  /// The design already runs with the tuned gains (to 6 significant digits on every joint).
  bool applied() const;
};

struct TuneResult {
  std::vector<TunedMechanism> mechanisms;
  double rho_limit = 0.9;
  double min_damping = 0.3, min_gain_margin = 2.0;
  double max_overshoot_fraction = 0.0;  ///< of the step: exp(-pi zeta / sqrt(1 - zeta^2)) at min_damping
  double wall_s = 0.0;
};

/// Tunes every mechanism of `stations` (each with both mechanisms and patterns); `inertia` per
/// station name, then mechanism name. InputError as simulation_inputs().
TuneResult tune_controller(const Design& design, const std::vector<const Station*>& stations,
                           const std::map<std::string, std::map<std::string, MechanismInertia>>& inertia,
                           const TuneOptions& options = {});

/// The tuned gains as a YAML patch of the design file: `controller: {stations: {<s>: {<m>: {pid:
/// {kp, ki, kd}}}}}` (the narrowest scope but the joints, so that it wins over the file's own).
std::string tuned_patch_yaml(const TuneResult& result);
Json to_json(const TuneResult& result);
/// One row per mechanism: station,mechanism,kp_before,ki_before,kd_before,kp_after,ki_after,
/// kd_after,max_rho_before,max_rho_after,max_tracking_error_before_mm,max_tracking_error_after_mm,
/// saturation_before,saturation_after,evaluations,feasible,applied,stop, then before and after each:
/// min_damping, kp_margin, kd_margin, step_overshoot_mm, chirp_bandwidth_hz, chirp_saturation_hz
/// (empty: never saturates), bandwidth_hz.
std::string tuning_csv(const TuneResult& result);

}  // namespace fivebar
