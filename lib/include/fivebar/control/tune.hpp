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
#include "fivebar/design/file_edit.hpp"
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
// Start (TuneOptions::start): by default the gains the design runs (ControllerSettings::joint(),
// per joint: a design with other gains on theta2 starts there too). The unknowns are the natural
// logarithms of factors on the start's gains, (ln f_kp, ln f_ki, ln f_kd) for both joints (the
// joints keep the ratio of the start's gains) or per joint (six): x = 0 is the start exactly, and
// a zero gain starts at 1e-3.
//
// Alternatively (start = pole_placement) pole placement on the linearised model at the target's
// centre. Each joint j of the plant
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
// sample-and-hold and the period of delay; the exact check does). start = hand_set starts from the
// hand-set gains (ControllerSettings::hand_set_pid()).
//
// Refinement: NLopt's COBYLA (Powell's derivative-free linear-approximation method with
// constraints; Powell, "A direct search optimization method that models the objective and
// constraint functions by linear interpolation", 1994) over those factors within e^5 (~148) of the
// start, an initial step of a factor 2, the constraint aimed 0.003 inside its limit. The candidate
// is the best evaluated point that meets the constraints (COBYLA's own last point may lie just
// outside). No random element: the same design and options give the same gains, unless the
// wall-time bound stops a run first (the result says so).
//
// Never worse than the design: "before" is always the design's gains, evaluated on the same
// objective (the worst tracking error plus the saturation and step penalties below) and the same
// constraints as every candidate. The tuned gains replace them only when they meet every
// constraint and either the design's gains do not or the tuned objective is lower; otherwise the
// result keeps the design's gains exactly (TunedMechanism::improved false) and says so.
//
// Budget (TuneOptions::max_seconds): it bounds the whole of tune_controller(), the figures before
// and after included. Every simulation is cut at the bound; the search stops early enough to leave
// the after figures the time the before figures took. A figure that could not be computed within
// the bound is NaN (JSON null) and the tracking records how many seconds of the patterns were
// simulated (TuneFigures::simulated_s of patterns_s): a tracking error is given only for the whole
// patterns. The tuning then ends at most one simulation step (or one linearised stability map of
// the target) past the bound.
enum class TuneStart { design, pole_placement, hand_set };

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
  TuneStart start = TuneStart::design;
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

/// Before and after, for one mechanism. A figure the time bound left uncomputed is NaN (JSON null).
struct TunedMechanism {
  std::string station, mechanism;
  /// before: the gains the design runs (ControllerSettings::joint(), per joint), what the result is
  /// compared with; design: the same (kept for the JSON's `design` record); after: the tuned ones,
  /// or exactly the design's when the search found nothing better (improved false).
  std::array<PidGains, 2> before, design, after;
  std::array<PidGains, 2> start;   ///< where COBYLA started (by default the design's gains)
  double start_omega_rad_s = 0.0;  ///< the pole placement's omega (0 when started from other gains)
  /// The tuned gains beat the design's on the objective (both measured within the bound): after
  /// holds them. False: after is exactly the design's gains (nothing better found, or not measured).
  bool improved = false;
  /// The objective (worst tracking error plus the saturation and step penalties, mm) of the gains
  /// before and after; NaN when not measured within the bound.
  double objective_before_mm = 0.0, objective_after_mm = 0.0;
  /// What the tracking figures cover: the seconds of the station's patterns simulated before and
  /// after, of patterns_s in all. A tracking error is given (not NaN) only when the whole
  /// patterns were simulated.
  double simulated_before_s = 0.0, simulated_after_s = 0.0, patterns_s = 0.0;
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
  /// met and the step's overshoot within its bound, every one of these figures computed.
  bool feasible = false;
  /// The figures before (after) the time bound left uncomputed, by name ("tracking", "step",
  /// "margins", "chirp"); empty: every figure computed in full.
  std::vector<std::string> not_computed_before, not_computed_after;
  std::string stop;        ///< why the optimiser stopped
  /// The design already runs with the tuned gains (to 6 significant digits on every joint).
  bool applied() const;
};

struct TuneResult {
  std::vector<TunedMechanism> mechanisms;
  double rho_limit = 0.9;
  double min_damping = 0.3, min_gain_margin = 2.0;
  double max_overshoot_fraction = 0.0;  ///< of the step: exp(-pi zeta / sqrt(1 - zeta^2)) at min_damping
  double budget_s = 0.0;  ///< TuneOptions::max_seconds: the bound of the whole tuning
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

/// Merging the tuned gains into the design file (`fivebar control --tune --merge`, docs/tour.md):
/// the edits of numbers already written in the file that give every tuned mechanism's joints
/// their tuned gains (TunedMechanism::after), and nothing else. Each joint's kp, ki and kd live at
/// the narrowest `controller:` scope that sets them (ControllerSettings::joint()), else
/// `controller.pid`; that number is edited when its value changes. Refusals (the merge writes
/// nothing then), each one line:
///  - a tuned mechanism that misses a check the export gate applies to the loop (stable, i.e. max
///    rho < 1; tracking error at most controller.max_tracking_error_mm; saturated time at most
///    controller.max_saturation_fraction) or the tuning's own floors (TunedMechanism::feasible:
///    max rho <= rho_limit, damping, kp and kd margins, the step's overshoot), or whose figures the
///    time bound left uncomputed;
///  - a number that also sets a joint the tuning did not tune (another station, or one left out)
///    or two tuned joints to different values: only new scopes could hold the gains, and the merge
///    adds none (merge tuned-controller.yaml by hand, or write the scopes first).
/// A number the file does not hold (a default) is refused by edit_design_text() when applied.
struct GainMerge {
  std::vector<FileEdit> edits;
  std::vector<std::string> refusals;
};
GainMerge gain_merge(const Design& design, const TuneResult& result);
/// One row per mechanism: station,mechanism,kp_before,ki_before,kd_before,kp_after,ki_after,
/// kd_after,max_rho_before,max_rho_after,max_tracking_error_before_mm,max_tracking_error_after_mm,
/// saturation_before,saturation_after,evaluations,feasible,applied,stop, then before and after each:
/// min_damping, kp_margin, kd_margin, step_overshoot_mm, chirp_bandwidth_hz, chirp_saturation_hz
/// (empty: never saturates), bandwidth_hz; then improved, objective_before_mm, objective_after_mm,
/// simulated_before_s, simulated_after_s, patterns_s. A figure not computed is empty.
std::string tuning_csv(const TuneResult& result);

}  // namespace fivebar
