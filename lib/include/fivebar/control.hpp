#pragma once
/// Controller validation: the sampled-data loop of one mechanism linearised at a pose,
/// discretised exactly, closed by the exported PID with one period of delay, and its spectral
/// radius over the target ellipse (the stability map), with margins on the gains.
///
/// Units inside: SI (m, kg, s, rad, N, V, A), as fivebar/dynamics.hpp; results carry mm at the edges.
///
/// Linearised plant (continuous time)
/// ----------------------------------
/// The model of fivebar/dynamics.hpp ("Model") at an equilibrium: joint angles theta*, w = 0,
/// i = 0, duty 0, the skin anchored at the tactor (a = P(theta*), contact in stick). State
/// x = (dtheta1, dtheta2, w1, w2, i1, i2) (deviations), input u = (duty1, duty2):
///   dtheta/dt = w
///   M dw/dt   = -K_s dtheta - (C_s + B_v + B_emf) w + K_t i      (B_emf enters through di/dt below)
///   L_j di_j/dt = V_s,j u_j - R_j i_j - k_e,j N_j w_j
/// with K_s = k J^T J and C_s = c J^T J the skin's stiffness and damping mapped through the
/// Jacobian J = dP/dtheta (F = -k (P - a) - c dP/dt, tau = J^T F: its derivative at P = a, where
/// F = 0 so that dJ/dtheta does not enter), B_v = diag(b_j) the viscous friction, K_t =
/// diag(eta_j N_j k_t,j). At w = 0 the Coriolis term h(theta, w) is quadratic in w and drops out,
/// and with zero torque dM/dtheta does not enter either: these are the exact first derivatives of
/// the right-hand side (checked against its central finite differences in test/test_control.cpp).
/// Coulomb friction is left out: its smoothed sign tanh(w / w_s) has a slope tau_c / w_s at
/// w = 0 that is a regularisation of a relay, not a damper; dropping it is the conservative choice
/// for a linear stability verdict (it only dissipates while a joint moves). The driver's voltage
/// and current limits and the ADC quantisation are nonlinear and are not in the linear model
/// either (a small-signal verdict; `simulate()` has them).
///
/// Exact discretisation under zero-order hold (e.g. Franklin, Powell & Workman, "Digital Control
/// of Dynamic Systems", 3rd ed., 1998, the ZOH equivalent): with T = 1 / loop_rate_hz,
///   exp([A B; 0 0] T) = [Ad Bd; 0 I],   Ad = e^{AT},  Bd = int_0^T e^{As} ds B,
/// by Eigen's matrix exponential (unsupported/MatrixFunctions: scaling and squaring with Pade).
///
/// Closed loop, as the device samples (fivebar/dynamics.hpp "Controller", DiscretePid): at t_k the
/// error e_k = -dtheta_k (regulation about the pose), the integral s_k = s_{k-1} + T e_k, the
/// backward difference d_k = (e_k - e_{k-1}) / T and duty_k = kp e_k + ki s_k + kd d_k per joint;
/// duty_k is applied over [t_{k+1}, t_{k+2}) (one period of computation delay). The loop state
/// z = (x, u, s, e_prev) (6 + 2 + 2 + 2 = 12) then evolves as
///   x_{k+1} = Ad x_k + Bd u_k,   u_{k+1} = duty_k,   s_{k+1} = s_k + T e_k,   e_prev_{k+1} = e_k,
/// so z_{k+1} = Phi z_k, and the loop is asymptotically stable iff the spectral radius
/// rho(Phi) = max |eig(Phi)| < 1. (The integral clamp and the duty clamp are inactive for small
/// signals.) The dominant pole z* (largest modulus) maps to s* = ln(z*) / T, its damping ratio
/// zeta = -Re(s*) / |s*| and frequency |Im(s*)| / (2 pi); the least damped
/// complex pole is reported beside it (with an integral term the dominant pole is often the slow
/// real pole of the integrator, ~exp(-(ki / kp) T)).
///
/// Stability map: rho at every pose of a grid over the filled target ellipse (or over the whole
/// reachable region, as a field): the verdict is max rho < 1, the worst pose is the argmax. Gain
/// margins: the largest factor f on every joint's kp (others fixed) with max rho < 1 over the
/// poses, found by bracketing and bisection (likewise kd).

#include <Eigen/Core>

#include <array>
#include <complex>
#include <functional>
#include <map>
#include <string_view>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/json.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/rendered_plot.hpp"
#include "fivebar/sections/contact.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/workspace/region.hpp"

namespace fivebar {

/// Poses per axis of the grid over each target on which `fivebar export` checks the loop's
/// stability, and on which the tuner constrains it (the same poses, so that a tuned loop passes).
inline constexpr int kControlGateGrid = 21;

inline constexpr int kPlantStates = 6;   ///< dtheta1, dtheta2, w1, w2, i1, i2
inline constexpr int kLoopStates = 12;   ///< plant, held duty (2), integral (2), previous error (2)
using PlantMatrix = Eigen::Matrix<double, kPlantStates, kPlantStates>;
using PlantInput = Eigen::Matrix<double, kPlantStates, 2>;
using LoopMatrix = Eigen::Matrix<double, kLoopStates, kLoopStates>;

/// The continuous linear model at one pose (above).
struct LinearPlant {
  Status status = Status::unreachable;  ///< dynamics_terms()' status; matrices zero unless ok
  PlantMatrix A = PlantMatrix::Zero();
  PlantInput B = PlantInput::Zero();     ///< per unit duty
  Eigen::Matrix2d M = Eigen::Matrix2d::Zero();  ///< kg m^2
  Eigen::Matrix2d J = Eigen::Matrix2d::Zero();  ///< dP/dtheta, m/rad
  Eigen::Vector2d theta = Eigen::Vector2d::Zero();
  Vec2 P_mm{0.0, 0.0};
};

/// The linear model of `model` at joint angles `theta` (rad); `contact` null: no skin (free tactor).
LinearPlant linear_plant(const MechanismModel& model, const Eigen::Vector2d& theta, const ContactSettings* contact);

/// ZOH equivalent of dx/dt = A x + B u at period T (any sizes): {Ad, Bd}.
std::array<Eigen::MatrixXd, 2> zoh(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, double period_s);

/// The ZOH equivalent of a plant.
struct DiscretePlant {
  PlantMatrix Ad = PlantMatrix::Identity();
  PlantInput Bd = PlantInput::Zero();
  double period_s = 0.0;
};
DiscretePlant discretise(const LinearPlant& plant, double period_s);

/// Phi of the closed loop (state order above). `delay` false: the duty is applied at the sample it
/// is computed at (the u rows then only record it).
LoopMatrix closed_loop(const DiscretePlant& plant, const std::array<PidGains, 2>& gains, bool delay = true);

/// The pole of largest modulus and what it means.
struct LoopPoles {
  double rho = 0.0;                     ///< spectral radius
  std::complex<double> dominant{0.0, 0.0};
  double damping = 1.0;                 ///< zeta of the dominant pole (1 for rho = 0; negative when rho > 1)
  double frequency_hz = 0.0;            ///< |Im ln(z*)| / (2 pi T)
  /// The least damped of the complex poles (an oscillation; the dominant pole is often the
  /// integrator's slow real one): its zeta and frequency; 1 and 0 when every pole is real.
  double oscillatory_damping = 1.0;
  double oscillatory_frequency_hz = 0.0;
};
LoopPoles loop_poles(const LoopMatrix& phi, double period_s);

// --- One mechanism's loop from a design -----------------------------------------------------------

/// What the loop of one mechanism needs.
struct LoopModel {
  std::string station;
  MechanismModel model;
  std::array<PidGains, 2> gains;  ///< joint 1, joint 2
  double period_s = 0.01;
  bool contact = true;            ///< skin in stick at the tactor
  ContactSettings skin;
  bool delay = true;
};

/// The loop models of every mechanism of `station` (lower first): `motor:` and `controller:` of the
/// design with their overrides, `contact:` (or its defaults), masses from `inertia` by mechanism
/// name. InputError naming a missing section (as simulation_inputs()).
std::vector<LoopModel> loop_models(const Design& design, const Station& station,
                                   const std::map<std::string, MechanismInertia>& inertia);

/// rho and the poles at one pose, for a plant discretised once (gains vary, the plant does not).
struct PoseLoop {
  Vec2 P_mm{0.0, 0.0};
  Status status = Status::unreachable;  ///< ik()/dynamics status: not ok has no poles
  DiscretePlant plant;
  LoopPoles poles;
};

/// The discretised plant and poles at tactor point P (mm) in the working mode.
PoseLoop pose_loop(const LoopModel& loop, const Vec2& P_mm);

/// Points of an n x n lattice over the filled ellipse's bounding box (its own frame) that lie inside
/// it; n odd includes the centre. (ellipse_grid(), fivebar/collision.hpp, takes a spacing in mm.)
std::vector<Vec2> ellipse_lattice(const Ellipse& e, int n);

struct StabilityOptions {
  int grid = 41;            ///< per axis over the target ellipse's box (~1,300 points inside)
  bool margins = true;      ///< bisect the kp and kd margins
  double margin_cap = 1e3;  ///< factors searched up to this
  double margin_rel_tol = 1e-3;
};

/// The stability of one mechanism's loop over a set of poses.
struct StabilityMap {
  std::string station, mechanism;
  std::vector<PoseLoop> poses;     ///< in the order of the points given
  std::size_t not_ok = 0;          ///< poses unreachable or singular (no verdict there)
  std::size_t worst = 0;           ///< index of the largest rho among the ok poses
  double max_rho = 0.0;
  bool stable = false;             ///< max rho < 1 over every ok pose, and at least one ok pose
  double damping = 1.0;            ///< of the dominant pole at the worst pose
  double frequency_hz = 0.0;
  /// The least damped oscillatory pole over the poses (LoopPoles), and where.
  double oscillatory_damping = 1.0;
  double oscillatory_frequency_hz = 0.0;
  Vec2 oscillatory_P_mm{0.0, 0.0};
  /// Largest factor on both joints' kp (resp. kd) keeping max rho < 1 over the poses (the others
  /// at their values); 0 when the loop is unstable at factor 0 too; margin_cap when still stable there.
  double kp_margin = 0.0, kd_margin = 0.0;
  Vec2 worst_P_mm() const { return poses.empty() ? Vec2(0.0, 0.0) : poses[worst].P_mm; }
};

/// max rho over `poses` with `gains` (early exit once a pose reaches `stop_at`).
double max_spectral_radius(const std::vector<PoseLoop>& poses, const std::array<PidGains, 2>& gains, bool delay,
                           double stop_at = 1.0e300);

/// The map of `loop` at `points` (mm).
StabilityMap stability_map(const LoopModel& loop, const std::vector<Vec2>& points, const StabilityOptions& options = {});
/// The same from poses already linearised and discretised (pose_loop() of `loop`'s model at each
/// point, any gains): only the poles are recomputed with `loop.gains`, so the result equals
/// stability_map() at those points without linearising again.
StabilityMap stability_map(const LoopModel& loop, const std::vector<PoseLoop>& linearised,
                           const StabilityOptions& options = {});

/// rho over the reachable region: a grid over the mechanism's reach (the intersection of its
/// legs' outer circles, plus a cell), rho where the working-mode IK is ok and within the joint
/// limits, NaN elsewhere (status says why).
struct RhoField {
  Grid grid;
  std::vector<double> rho;           ///< row-major (j * nx + i)
  std::vector<std::uint8_t> status;  ///< Status of the pose (as std::uint8_t); 255 outside the joint limits
};
RhoField rho_field(const LoopModel& loop, int cells_per_axis);

/// JSON of a map (units at the edges; poses not listed).
Json to_json(const StabilityMap& map);

/// The `.vti` document (ParaView image data) of a field: point data `rho` and `status`.
std::string rho_field_vti(const RhoField& field);

// --- Performance over the target -------------------------------------------------------------------
//
// Bandwidth: the closed loop from the reference to the joint angles, H(z) = C (zI - Phi)^-1 G, with
// the reference entering the PID as the measurement does (the error r - theta feeds the duty, the
// integral and the previous error); for the tactor, J H J^-1 (reference and response mapped through
// the Jacobian). The -3 dB bandwidth is the lowest frequency at which the gain in the worst tactor
// direction, sigma_min(J H(e^{jwT}) J^-1), falls below 1/sqrt(2) (a log scan up to Nyquist refined by
// bisection); Nyquist when it never does.
// Resolution: the tactor step of one ADC count on one joint, max_j |J_j| dtheta_j with dtheta_j =
// |rad_per_volt_j| (range_v high - low) / 2^bits (the potentiometer through the ADC).
// Force: the largest shear force the motors hold continuously in every direction: with joint
// torques |tau_j| <= eta_j N_j k_t,j I_max,j and J^T F = tau, a force f u needs |J_j . u| f <= tau_j,
// so the direction-wise bound is min_j tau_j / |J_j . u| and its worst direction (u along a column)
// gives min_j tau_j / |J_j| (N).
// Z-width (Colgate & Schenkel, "Passivity of a class of sampled-data systems: application to haptic
// interfaces", J. Robotic Systems 14(1), 1997): a virtual wall K, B renders passively when
// b > K T / 2 + |B|, b the device's own damping. Here b is the joint damping mapped to the tactor,
// B_x = J^-T diag(b_j + eta_j N_j^2 k_t,j k_e,j / R_j) J^-1 (viscous friction plus the back-EMF damping of
// the voltage-driven motor), in the direction where it is least (its smallest eigenvalue): K_max =
// 2 (b_min - |B|) / T, and the loop rate a stiffness K needs is K / (2 (b_min - |B|)).
// With Coulomb friction and position quantisation (Abbott & Okamura, "Effects of position
// quantization and sampling rate on virtual-wall passivity", IEEE Trans. Robotics 21(5), 2005: a
// necessary and sufficient condition for a mass with Coulomb-plus-viscous friction and a quantised
// position sensor), the wall is passive iff
//   K <= min(2 b / T, 2 f_c / Delta),
// f_c the Coulomb friction and Delta the position quantum. Per tactor direction u (unit), with the
// joints' rates J^-1 u at unit tactor speed:
//   b(u)     = u^T B_x u                                  (power of the viscous terms),
//   f_c(u)   = sum_j tau_c,j |(J^-1 u)_j|                 (power of the joints' Coulomb friction,
//                                                          motor.coulomb_friction_mNm),
//   Delta(u) = max_j |u . J_j| dtheta_j                   (the tactor step along u of one ADC count
//                                                          of the coarser joint, dtheta_j as above),
// and the bound is the least over 360 directions of min(2 b(u) / T, 2 f_c(u) / Delta(u)). The loop
// rate a target stiffness K* (controller.target_stiffness_N_per_mm) needs is max over u of
// K* / (2 b(u)) where the quantisation allows K* (2 f_c(u) / Delta(u) >= K*); where it does not,
// no loop rate renders K* passively (a finer sensor or more friction would): the rate is then
// infinite and the pose "quantisation-limited".

struct PoseFigures {
  Vec2 P_mm{0.0, 0.0};
  Status status = Status::unreachable;
  double bandwidth_hz = 0.0;
  double resolution_um = 0.0;     ///< tactor step of one ADC count, worst joint
  double force_N = 0.0;           ///< continuous force in every direction
  double damping_N_s_per_mm = 0.0;  ///< least tactor damping b_min
  double zwidth_N_per_mm = 0.0;   ///< 2 b_min / T (no virtual damping): Colgate-Schenkel
  double coulomb_N = 0.0;         ///< least f_c(u) over the directions
  double quantum_um = 0.0;        ///< largest Delta(u) over the directions
  double zwidth_quantisation_N_per_mm = 0.0;  ///< least 2 f_c(u) / Delta(u)
  double zwidth_abbott_okamura_N_per_mm = 0.0;  ///< least min(2 b(u) / T, 2 f_c(u) / Delta(u))
  /// Loop rate the target stiffness needs (Hz): infinity when the quantisation forbids it.
  double rate_for_target_hz = 0.0;
};

/// The Abbott-Okamura figures of a pose (above) into `f` (its zwidth_N_per_mm and damping kept):
/// Jacobian J (m/rad), joint damping diag Bj (N m s/rad), Coulomb torques (N m), joint quanta
/// (rad per count), period T (s), target stiffness (N/mm).
void abbott_okamura(const Eigen::Matrix2d& J, const Eigen::Matrix2d& Bj, const std::array<double, 2>& coulomb_Nm,
                    const std::array<double, 2>& quantum_rad, double period_s, double target_N_per_mm, PoseFigures& f);

/// The closed-loop gain from the tactor reference to the tactor at frequency f (Hz): the
/// singular values of J H(e^{j 2 pi f T}) J^-1, smallest first.
std::array<double, 2> tactor_gain(const DiscretePlant& plant, const std::array<PidGains, 2>& gains, bool delay,
                                  const Eigen::Matrix2d& J, double frequency_hz);

/// The figures at tactor point P (mm); `adc_bits`, `adc_range_v` and the joints' potentiometers
/// from the controller of the design.
PoseFigures pose_figures(const LoopModel& loop, const Vec2& P_mm, int adc_bits, const std::array<double, 2>& adc_range_v,
                         const std::array<Potentiometer, 2>& pots, double target_N_per_mm = 1.0);

/// Worst over a set of poses: the lowest bandwidth, the coarsest resolution, the weakest force,
/// the lowest Z-width, each with its pose.
struct PerformanceMap {
  std::string station, mechanism;
  std::vector<PoseFigures> poses;
  PoseFigures worst_bandwidth, worst_resolution, worst_force, worst_zwidth;
  PoseFigures worst_zwidth_abbott_okamura;  ///< lowest Abbott-Okamura bound
  PoseFigures worst_rate;                   ///< highest loop rate for the target stiffness
  double target_N_per_mm = 1.0;             ///< controller.target_stiffness_N_per_mm
  double loop_rate_hz = 100.0;              ///< the design's
};
PerformanceMap performance_map(const Design& design, const LoopModel& loop, const std::vector<Vec2>& points);
Json to_json(const PerformanceMap& map);
/// "index lower: bandwidth >= 6.2 Hz (at ...), resolution <= 0.9 um/count, force >= 1.9 N in every
/// direction, Z-width >= 120 N/mm (hard surface 0.8-1.0 N/mm)", then the Abbott-Okamura bound and
/// the loop rate the target stiffness needs against the design's.
std::string performance_line(const PerformanceMap& map);

// --- A station's study (the `control` subcommand and product) ----------------------------------

struct ControlOptions {
  StabilityOptions stability;
  int field_cells = 81;  ///< per axis over each mechanism's reach, for the field
  int performance_grid = 15;  ///< per axis over the target, for the bandwidth, resolution, force, Z-width
};

/// Every mechanism of a station: its map over the target and its field over the reachable region.
struct StationControl {
  std::string station;
  std::vector<StabilityMap> maps;  ///< lower first
  std::vector<RhoField> fields;    ///< as maps
  std::vector<PerformanceMap> performance;  ///< as maps
  bool stable() const;             ///< every map stable
};

StationControl station_control(const Design& design, const Station& station,
                               const std::map<std::string, MechanismInertia>& inertia,
                               const ControlOptions& options = {});

/// The files of a station's study, as (name, bytes): `<station>-stability.svg` and `.png` (the
/// picture), `<station>-<mechanism>-rho.vti` (the field, ParaView), `<station>-stability.csv`
/// (every target pose: station,mechanism,x_mm,y_mm,status,rho,damping,frequency_hz) and
/// `<station>-performance.csv` (every pose of the performance grid: station,mechanism,x_mm,y_mm,
/// status,bandwidth_hz,resolution_um_per_count,force_every_direction_N,tactor_damping_N_s_per_mm,
/// zwidth_N_per_mm,coulomb_friction_N,position_quantum_um,zwidth_quantisation_N_per_mm,
/// zwidth_abbott_okamura_N_per_mm,loop_rate_for_target_hz; the last empty where the quantisation
/// forbids the target stiffness).
std::vector<std::pair<std::string, std::string>> control_files(const StationControl& study, const Station& station,
                                                               const std::string& subtitle);

/// {"station", "stable", "mechanisms": [to_json(map) ...], "performance": [to_json(performance) ...]}.
Json to_json(const StationControl& study);

/// One summary line per mechanism: "index lower: stable over the target, max rho 0.8731 at
/// (6.25, 18.10) mm (1313 poses); dominant pole damping 0.412 at 5.21 Hz; margins kp x2.31, kd x4.50",
/// then one performance_line() per mechanism.
std::vector<std::string> summary_lines(const StationControl& study);

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

/// The picture of a station's maps (one panel per mechanism, `fields[k]` for `maps[k]`): rho over
/// the reachable region on a colour ramp (red where >= 1), the target ellipse dashed, the worst
/// pose on it marked, and the verdict, damping and margins below (house style, lib/src/plot/).
RenderedPlot stability_plot(const Station& station, const std::vector<StabilityMap>& maps,
                            const std::vector<RhoField>& fields, const std::string& subtitle);

}  // namespace fivebar
