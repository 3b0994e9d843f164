#pragma once
/// Dynamics of the device: each five-bar as a 2-DOF closed chain driven by two DC
/// gearmotors under the exported PID, the tactor on a skin spring with Coulomb stick/slip, both
/// mechanisms of a station together, integrated by SUNDIALS CVODE (BDF, Newton, dense direct
/// solver) or, for comparison, ARKODE's explicit Runge-Kutta (lib/src/simulate/cvode.cpp and
/// arkode.cpp are the only files that see SUNDIALS).
///
/// Units inside: SI (m, kg, s, rad, N, V, A); the results carry mm, deg, N, A at the edges.
///
/// Model (every equation with its source)
/// --------------------------------------
/// Kinematics (fivebar/kinematics.hpp for the positions): A_i = O_i + L_i e(theta_i),
/// e(a) = (cos a, sin a), e_perp(a) = (-sin a, cos a); distal vectors r3 = P - A1, r4 = P - A2
/// with |r3| = L3, |r4| = L4. Differentiating the two loop constraints |P - A_i|^2 = L_{i+2}^2
/// once and twice (velocity and acceleration analysis of closed chains, e.g. Waldron & Kinzel,
/// "Kinematics, Dynamics, and Design of Machinery") gives, with G = [r3^T; r4^T]:
///   G dP/dt   = [r3 . dA1/dt, r4 . dA2/dt],                          dA_i/dt = L_i w_i e_perp(theta_i)
///   G d2P/dt2 = [r3 . d2A1/dt2 - |dr3/dt|^2, r4 . d2A2/dt2 - |dr4/dt|^2],
///                                        d2A_i/dt2 = L_i (dw_i/dt e_perp - w_i^2 e(theta_i))
/// and the distal link angles phi3, phi4 (r3 = L3 e(phi3)): dphi3/dt = (r3 x dr3/dt) / L3^2,
/// d2phi3/dt2 = (r3 x d2r3/dt2) / L3^2. G is singular exactly at a type II singularity (the
/// distal links aligned): there the simulation stops with Status singular, never a NaN.
///
/// Equations of motion by projection (Kane's method; Kane & Levinson, "Dynamics: Theory and
/// Applications", 1985; equivalently the Lagrange form of Siciliano et al., "Robotics: Modelling,
/// Planning and Control", 2009, ch. 7): every
/// body b (links L1..L4, the tactor tip as a point mass at P) has its centre-of-mass velocity
/// v_b = Jv_b(theta) w and angular rate omega_b = Jw_b(theta) w, w = dtheta/dt. Then
///   M(theta) = sum_b m_b Jv_b^T Jv_b + I_b Jw_b^T Jw_b + N_j^2 J_rotor,j (diagonal),
///   h(theta, w) = sum_b m_b Jv_b^T a0_b + I_b Jw_b^T alpha0_b,
/// where a0_b, alpha0_b are the body accelerations at d2theta/dt2 = 0 (the second line above with
/// dw/dt = 0): h = C(theta, w) w is the Coriolis and centrifugal term, computed exactly (no finite
/// difference of M), so that w^T (dM/dt / 2) w = w^T h and kinetic energy is conserved by the
/// unforced, frictionless model to the integrator's accuracy (test/test_dynamics.cpp); a second
/// formulation, the four links in absolute angles closed by Lagrange multipliers as an index-1
/// DAE under SUNDIALS IDA (test/test_dynamics_dae.cpp), gives the same joint trajectories. Gravity is
/// left out: the design file does not give the device's orientation.
///   M(theta) dw/dt + h(theta, w) = tau_motor - tau_friction + J(theta)^T F_contact
/// with J = dP/dtheta (m/rad) and F_contact the skin force on the tactor.
///
/// DC motor per joint (e.g. Franklin, Powell & Emami-Naeini, "Feedback Control of Dynamic
/// Systems", ch. 2), averaged PWM: V = duty V_supply, then
///   L di/dt = V - R i - k_e N w,   tau_motor = eta N k_t i,
///   tau_friction = b w + tau_c tanh(w / w_s)   (output shaft; w_s = kCoulombSmoothingSpeed, a
///                                               regularisation of sign(w), an assumption),
/// the driver's current limit as a voltage clamp V in [k_e N w - R I_max, k_e N w + R I_max]
/// (the averaged effect of a cycle-by-cycle limiter: the current relaxes to at most I_max in
/// L/R), then |V| <= V_supply. A locked rotor (w = 0) settles at i = V / R.
///
/// Controller: the device's own loop, fivebar::runtime::Controller (fivebar/runtime/controller.hpp,
/// docs/runtime.md), configured by the design's export (SimulationInput::runtime). Every
/// T = 1 / loop_rate_hz the potentiometer voltage v = volts_at_zero + theta / rad_per_volt is read
/// through the ADC (adc.volts_per_count = range / 2^bits: the nearest code, clamped to
/// 0 .. 2^bits - 1) and the runtime turns the codes and the pattern's reference points into duties
/// (FK of the measured joints, IK, the upper mechanism's priority rule on the commanded poses,
/// the joint limits less the margin, the PID); that duty is applied one period later (the
/// computation delay of a ROS loop) and held constant until the next (zero-order hold).
///
/// Skin contact per tactor (a reset-integrator friction model: Haessig & Friedland, "On the
/// Modeling and Simulation of Friction", ASME J. Dyn. Syst. Meas. Control 113(3), 1991; the
/// elasto-plastic family of Dupont et al., IEEE Trans. Automatic Control 47(5), 2002, without a
/// pre-sliding zone): the skin is anchored at a where the tactor first touches (its start point).
///   sticking: F = -k (P - a) - c dP/dt, da/dt = 0, until k |P - a| = mu N_preload (a root);
///   sliding:  F = -k (P - a), with |P - a| = mu N / k kept by da/dt = (u . dP/dt) u,
///             u = (P - a)/|P - a|, until u . dP/dt = 0 (a root: the tactor turns back).
/// Both switches are located by the integrator's root finding; the integration restarts there.
///
/// Switched PWM (on request, SimulationOptions::pwm): instead of its average the bridge applies
/// sign(duty) V_supply during the first |duty| T_pwm of each PWM period and 0 V for the rest
/// (sign-magnitude drive). With a locked rotor the current of the RL winding (tau = L/R) then
/// settles into the periodic ripple of a square wave (the first-order exponential response in each
/// phase, i -> V/R on and i -> 0 off, made periodic by i(p + T_pwm) = i(p)):
///   i_max = (V/R) (1 - exp(-D T_pwm / tau)) / (1 - exp(-T_pwm / tau)),
///   i_min = i_max exp(-(1 - D) T_pwm / tau),
/// whose mean is D V / R, the averaged model's current (test/test_dynamics.cpp checks both). The
/// limiter's onset at |i| = I_max is located as a root too (a kink left to error control made the
/// error at one tolerance jump by 1e-2 mm: BDF's Newton iteration straddled it).
///
/// Integration: CVODE BDF (variable order 1-5) with Newton iterations and a dense direct linear
/// solver (difference-quotient Jacobian) by default; ARKODE's explicit Runge-Kutta (ERKStep,
/// Dormand-Prince 5(4)) as the comparison (SimulationOptions::integrator). Either is restarted at
/// every controller sample (the ZOH input is discontinuous there: each sample time is a stop
/// time, never stepped over), at every switching instant of the switched PWM (likewise stop
/// times) and at every stick/slip switch (located by the integrator's root finding). Bounded by
/// a step count and a wall time: exceeding either is a status.

#include <Eigen/Core>

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/json.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/rendered_plot.hpp"
#include "fivebar/sections/contact.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/sections/print.hpp"
#include "fivebar/runtime/config.hpp"
#include "fivebar/runtime/controller.hpp"

namespace fivebar {

// --- Mass properties of the links ----------------------------------------------------------------

/// A link as a planar rigid body in its own frame: x from its first joint (a motor shaft O_i or an
/// elbow A_i) towards its second (the elbow or the tactor P), as the parts' frames are
/// (fivebar/parts.hpp).
struct LinkInertia {
  double mass_kg = 0.0;
  Vec2 com_mm{0.0, 0.0};     ///< centre of mass in the link frame
  double izz_kg_mm2 = 0.0;   ///< about the centre of mass, z axis
};

enum class MassSource : std::uint8_t {
  stl,          ///< volume integrals over the parts' STL renders (mass_properties())
  closed_form,  ///< the slab-with-bosses formula of closed_form_inertia()
};
std::string_view to_string(MassSource source);

/// The moving bodies of one mechanism.
struct MechanismInertia {
  std::array<LinkInertia, 4> links;  ///< L1 .. L4
  double tip_mass_kg = 0.0;          ///< tactor tip, a point mass at P (its axis is P's)
  double tip_izz_kg_mm2 = 0.0;       ///< turns with the link carrying it
  int carrier = 2;                   ///< index of the distal link with the tactor post (2 = L3, 3 = L4)
  MassSource source = MassSource::closed_form;
  std::string note;                  ///< which files, or which formula
};

/// Closed-form fallback when no STL render is requested: each link a slab L x w x t between its
/// pin centres with a half-disc cap of the boss diameter beyond each end (a stadium when boss =
/// width; the bosses' bulge beside a narrower slab ignored), less its pin holes (pin + 2
/// clearance) and, on a proximal link, plus its hub (boss diameter, PartsHardware::hub_height)
/// less the shaft bore; the carrying distal link adds the tactor post (boss diameter, tactor_height
/// minus the tip) at P; the tip is its flange, half its dome's height and its peg. Density
/// print.density_g_cm3. Measured against the STL renders of the paper's index links (fn 96): mass
/// and z inertia within 7 % (the D-flat and fillets), the tip within 7 %.
MechanismInertia closed_form_inertia(const Mechanism& m, const Geometry& g, const PrintSettings& print);

/// From STL files in the parts' frames: `stl_by_use` maps "L1" ... "L4" and "tactor" to a file.
/// Throws InputError when one is missing or not a closed, positive-volume mesh; IoError when it
/// cannot be read.
MechanismInertia stl_inertia(const Mechanism& m, const Geometry& g,
                             const std::map<std::string, std::filesystem::path>& stl_by_use, double density_g_cm3);

/// The bodies of each mechanism of `station` (by name): from the STL renders a parts report lists
/// (`parts` = to_json(PartsReport), its "stl" paths relative to `parts_dir`) when one is given,
/// else closed_form_inertia(). Density print.density_g_cm3 (its default without `print:`).
/// InputError when the report lacks a render of one of the station's pieces, or without `geometry:`.
std::map<std::string, MechanismInertia> station_inertia(const Design& design, const Station& station, const Json* parts,
                                                        const std::filesystem::path& parts_dir);

// --- Dynamics of one mechanism --------------------------------------------------------------------

/// Everything the equations of motion of one mechanism need.
struct MechanismModel {
  Mechanism mechanism;
  MechanismInertia inertia;
  std::array<MotorParams, 2> motors;  ///< joint 1 (at O1), joint 2 (at O2)
  /// The FK branch the motion stays on (Plus / Minus); Any: the mechanism's assembly mode as fk()
  /// picks it. simulate() pins it to the branch of the initial pose, so that P moves continuously
  /// (changing branch needs a type II singularity, where the run stops).
  AssemblyMode branch = AssemblyMode::Any;
};

/// The terms of M(theta) dw/dt + h = tau at one state (SI).
struct DynamicsTerms {
  Status status = Status::unreachable;  ///< ok, unreachable or singular_type2 (a stretched leg is harmless here)
  Eigen::Matrix2d M = Eigen::Matrix2d::Zero();   ///< kg m^2, rotors included
  Eigen::Vector2d h = Eigen::Vector2d::Zero();   ///< N m, Coriolis and centrifugal
  Eigen::Matrix2d J = Eigen::Matrix2d::Zero();   ///< dP/dtheta, m/rad
  Vec2 P{0.0, 0.0};                              ///< tactor, m
  Vec2 P_dot{0.0, 0.0};                          ///< m/s
  double type2_sin = 0.0;                        ///< |sin| of the angle between the distal links
};

/// M, h, J, P, dP/dt at joint angles `theta` (rad) and rates `w` (rad/s), by the formulas above.
/// Status unreachable or singular_type2 (|sin| < tol::kSingularSin) leaves the matrices zero.
DynamicsTerms dynamics_terms(const MechanismModel& model, const Eigen::Vector2d& theta, const Eigen::Vector2d& w);

/// Kinetic energy 1/2 w^T M w (J), rotors included.
double kinetic_energy(const MechanismModel& model, const Eigen::Vector2d& theta, const Eigen::Vector2d& w);

/// Smoothing speed of the Coulomb friction, rad/s at the output (tanh(w / w_s) for sign(w)).
inline constexpr double kCoulombSmoothingSpeed = 1e-3;

// --- The controller -------------------------------------------------------------------------------

/// The exported PID of one joint as the device runs it once per period T (the convention of
/// ros2_control's control_toolbox::Pid with an integral clamp: the integral term accumulates and
/// is clamped, so it never winds up beyond i_clamp; the derivative is a backward difference):
///   s_k = s_{k-1} + e_k T, clamped so that |ki s_k| <= i_clamp (no wind-up beyond the clamp);
///   d_k = (e_k - e_{k-1}) / T (0 at the first sample);
///   duty_k = clamp(kp e_k + ki s_k + kd d_k, -1, 1).
/// The runtime's own step (fivebar::runtime::pid_update): one implementation.
class DiscretePid {
 public:
  DiscretePid(const PidGains& gains, double period_s)
      : gains_{gains.kp, gains.ki, gains.kd, gains.i_clamp}, period_(period_s) {}
  /// The duty for error `e` (rad) at this sample.
  double update(double error_rad) { return runtime::pid_update(gains_, period_, state_, error_rad); }
  double integral() const { return state_.sum; }

 private:
  runtime::Gains gains_;
  double period_ = 0.0;
  runtime::PidState state_;
};

/// The angle the controller reads for a true angle `theta` (rad): the potentiometer voltage,
/// quantised by an ADC of `bits` over `range_v` (the export's model: 2^bits codes range / 2^bits
/// apart from range_v[0], the nearest one, clamped to 0 .. 2^bits - 1), converted back.
double adc_reading(double theta, const Potentiometer& pot, int bits, const std::array<double, 2>& range_v);

// --- Simulation -----------------------------------------------------------------------------------

/// One mechanism as simulated: its model, controller and reference.
struct SimulatedMechanism {
  std::string name;                    ///< "lower" or "upper"
  MechanismModel model;
  std::array<JointControl, 2> control;
  /// Reference joint angles at the controller's samples t_k = k T (held after the last), rad.
  std::vector<std::array<double, 2>> reference;
  /// The commanded tactor points of those samples (mm), for the tracking error.
  std::vector<Vec2> reference_point_mm;
  /// The reference points the device's runtime receives at those samples (mm), before its priority
  /// rule; empty: reference_point_mm.
  std::vector<Vec2> target_mm;
  std::array<double, 2> theta0{0.0, 0.0};  ///< initial joint angles (rad); default the first reference
  std::array<double, 2> w0{0.0, 0.0};      ///< initial joint rates (rad/s)
};

enum class Drive : std::uint8_t {
  pid,            ///< the controller (the normal case)
  constant_duty,  ///< SimulationOptions::duty on every joint from t = 0 (open loop)
  open_circuit,   ///< driver off, windings open: i = 0, no torque (free motion)
};

/// The integrator (both SUNDIALS, both restarted at every sample, PWM edge and stick/slip root).
enum class Integrator : std::uint8_t {
  bdf,  ///< CVODE BDF, variable order 1-5, Newton iterations, dense direct solver (the default)
  erk,  ///< ARKODE ERKStep, Dormand-Prince 5(4) (the explicit comparison; stability-limited when stiff)
};
std::string_view to_string(Integrator integrator);
std::optional<Integrator> parse_integrator(std::string_view text);  ///< "bdf" or "erk"

/// How the driver's PWM reaches the winding.
enum class PwmModel : std::uint8_t {
  averaged,  ///< V = duty V_supply, continuous (the default)
  /// Sign-magnitude drive: within each PWM period [p, p + T_pwm) (p a multiple of T_pwm from t = 0)
  /// the bridge applies sign(duty) V_supply for the first |duty| T_pwm and 0 V (the winding
  /// shorted through the bridge, the current recirculating) for the rest; the duty is the one the
  /// controller holds at that instant. Every switching instant is a stop time of the integrator.
  /// Sign-magnitude (not locked-antiphase) because it draws no ripple at zero duty. The current
  /// limit acts cycle by cycle: once |i| reaches I_max in an on-phase the driver holds it there
  /// (V = R I_max + back EMF) until the phase ends. Unlike the averaged clamp it cuts the ripple's
  /// peaks, so with a small L/R it acts at duties whose average current is well below I_max.
  switched,
};
std::string_view to_string(PwmModel pwm);
std::optional<PwmModel> parse_pwm_model(std::string_view text);  ///< "averaged" or "switched"

struct SimulationOptions {
  double duration_s = 0.0;      ///< 0: the reference's length plus settle_s
  double settle_s = 0.2;        ///< after the reference's last sample
  /// The integrator's relative tolerance. The default 1e-6 is chosen from the work-precision study
  /// of `fivebar report accuracy` (its "Dynamics" table, a 1 mm step on the showcase): there BDF's
  /// tactor error is 2.2e-6 mm on the averaged model (1.1e-5 mm at 1e-5, 2.3e-7 mm at 1e-7) and
  /// 1.0e-4 mm on the switched one, at least 30x below what one level of the 16-bit ADC moves the
  /// tactor (a few micrometres), for 1.9x the steps of 1e-4; tighter tolerances buy accuracy the
  /// controller cannot see, looser ones let the switched model's error reach the ADC's level.
  double rtol = 1e-6;
  Integrator integrator = Integrator::bdf;
  PwmModel pwm = PwmModel::averaged;
  double pwm_frequency_hz = 1000.0;  ///< the switched model's PWM frequency (the paper's 1 kHz PWM)
  /// > 0: also record the integrator's dense output (its interpolant within each step) at the
  /// multiples of this spacing, in SimulationResult::dense; 0: not.
  double dense_dt_s = 0.0;
  /// Absolute tolerances are rtol x these scales (rad, rad/s, A, m).
  double angle_scale = 1.0, rate_scale = 1.0, current_scale = 0.1, anchor_scale = 1e-3;
  Drive drive = Drive::pid;
  double duty = 0.0;            ///< for Drive::constant_duty
  bool contact = true;          ///< skin contact at the tactors
  bool lock_joints = false;     ///< rotors held still (locked-rotor test): w = 0
  bool quantise = true;         ///< ADC quantisation
  bool delay = true;            ///< one period of computation delay
  std::size_t max_steps = 5'000'000;  ///< integrator steps in all
  double max_wall_s = 120.0;          ///< wall time in all
  bool record = true;           ///< keep the time series (at the loop rate)
  /// Called after every controller cycle at t_k with the runtime's inputs (the readings in its
  /// joint order, their kind, the reference points in m, 2 per runtime mechanism) and the
  /// controller itself: what the device's log holds (test/test_runtime.cpp, `fivebar replay`).
  std::function<void(double t_s, const std::vector<double>& readings, runtime::Reading kind,
                     const std::vector<double>& targets_m, const runtime::Controller& controller)>
      controller_log;
};

enum class SimStatus : std::uint8_t {
  ok = 0,
  singular,        ///< the state reached a type II singularity or left the workspace
  step_limit,      ///< max_steps exceeded
  wall_time_limit, ///< max_wall_s exceeded
  solver_failure,  ///< the integrator failed (error test or convergence failures at the minimum step)
};
std::string_view to_string(SimStatus status);

/// One mechanism at one controller sample.
struct MechanismSample {
  std::array<double, 2> theta_ref{0.0, 0.0};  ///< rad
  std::array<double, 2> theta{0.0, 0.0};      ///< rad
  std::array<double, 2> w{0.0, 0.0};          ///< rad/s
  std::array<double, 2> current{0.0, 0.0};    ///< A
  std::array<double, 2> duty{0.0, 0.0};       ///< applied over the period that starts here
  std::array<double, 2> voltage{0.0, 0.0};    ///< V applied at this instant (after the limits)
  Vec2 P_ref_mm{0.0, 0.0};
  Vec2 P_mm{0.0, 0.0};
  Vec2 force_N{0.0, 0.0};                     ///< skin force on the tactor
  bool slipping = false;
  double energy_J = 0.0;                      ///< kinetic energy
};

struct TimeSample {
  double t = 0.0;
  std::vector<MechanismSample> mechanisms;  ///< as SimulationInput::mechanisms
};

/// Per mechanism, over the whole run.
struct MechanismSummary {
  std::string name;
  double max_error_mm = 0.0;     ///< tactor |P - P_ref| (reference delayed by nothing)
  double rms_error_mm = 0.0;
  double max_joint_error_deg = 0.0;
  double peak_current_A = 0.0;
  double rms_current_A = 0.0;    ///< over both joints
  double peak_duty = 0.0;
  double saturation_s = 0.0;     ///< time with |duty| = 1 or the current limit acting, either joint
  double peak_shear_N = 0.0;
  bool slipped = false;
  std::size_t slips = 0;         ///< stick-to-slip switches
};

struct SimulationInput {
  std::string station;
  std::string reference_name;    ///< "stretch", "step", ...
  std::vector<SimulatedMechanism> mechanisms;
  ControllerSettings controller;
  ContactSettings contact;
  /// The device's configuration (fivebar/device/config.hpp device_config(): the Config `fivebar
  /// export` writes); the gains and potentiometers of `mechanisms[k].control` override its joints'
  /// (a tuner varies them). simulation_inputs() always sets it. Null only for a model built
  /// without a design (tests of the dynamics): runtime_config(*this), without collision outlines
  /// or joint limits.
  std::shared_ptr<const runtime::Config> runtime;
  /// False: `runtime` as given, its gains and calibration too (`fivebar replay --sil --config`).
  bool override_runtime_joints = true;
  /// Non-empty when the reference cannot be followed (a sample unreachable or singular): the
  /// reason; such an input is reported, not simulated.
  std::string unusable;
};

struct SimulationResult {
  SimStatus status = SimStatus::ok;
  std::string reason;            ///< empty when ok: the time, state and cause otherwise
  double t_end = 0.0;            ///< s reached
  std::size_t steps = 0;         ///< integrator steps (CVODE or ARKODE)
  std::size_t rhs_evaluations = 0;
  std::size_t restarts = 0;      ///< at samples and switches
  double wall_s = 0.0;
  std::vector<TimeSample> samples;
  /// The integrator's dense output at multiples of SimulationOptions::dense_dt_s (empty when 0).
  std::vector<TimeSample> dense;
  std::vector<MechanismSummary> summary;
  bool ok() const { return status == SimStatus::ok; }
};

/// The runtime configuration of an input without an export: one station per mechanism, named
/// `<station>_<k>`, its mechanism "lower" with the model's geometry (m), the controller's ADC and
/// loop rate, the mechanisms' gains and potentiometers; no collision outlines, no joint limits.
runtime::Config runtime_config(const SimulationInput& input);

/// Runs the simulation (CVODE or ARKODE as options.integrator says). Never throws on
/// non-convergence: the status says why and where.
/// Throws InputError for an input without mechanisms or with an empty reference.
SimulationResult simulate(const SimulationInput& input, const SimulationOptions& options = {});

// --- From a design --------------------------------------------------------------------------------

/// What to drive the station with.
struct SimulationRequest {
  std::string station;
  std::optional<PatternKind> pattern;  ///< one pattern; nullopt and !step: every pattern of the station
  bool step = false;                   ///< a 1 mm step of both tactors along +x from the pattern start points
  double step_mm = 1.0;
  double step_hold_s = 0.5;
  /// A logarithmic chirp of both tactors along x from the same start points (excludes `step`):
  /// x_ref(t) = x0 + a sin(phi(t)), phi(t) = 2 pi f0 D (k^(t/D) - 1) / ln k, k = f1 / f0, so the
  /// instantaneous frequency f0 k^(t/D) sweeps f0 -> f1 over D seconds.
  bool chirp = false;
  double chirp_amplitude_mm = 0.2;  ///< a: small, so that the skin sticks (0.2 N/mm x 0.2 mm < mu N)
  double chirp_f0_hz = 0.5;
  double chirp_f1_hz = 0.0;         ///< 0: a quarter of the loop rate (25 Hz at 100 Hz)
  double chirp_duration_s = 6.0;    ///< D
};

/// The inputs of a station's simulations: one per pattern (or the step). Needs both mechanisms,
/// `geometry:`, `motor:` and `controller:`; InputError naming the missing section otherwise
/// (`contact:` and `print:` take their defaults when absent). `inertia` per mechanism name.
std::vector<SimulationInput> simulation_inputs(const Design& design, const SimulationRequest& request,
                                               const std::map<std::string, MechanismInertia>& inertia);

// --- Frequency response --------------------------------------------------------------------------

/// Bode magnitude of each tactor's x displacement per commanded x displacement, from a chirp run.
struct BodeResult {
  std::vector<std::string> mechanisms;
  std::vector<double> f_hz;                      ///< log-spaced within the chirp's band
  std::vector<std::vector<double>> magnitude;    ///< [mechanism][frequency]: |X(f) / X_ref(f)|
  std::vector<std::optional<double>> bandwidth_hz;  ///< first -3 dB crossing (log-interpolated), per mechanism
  std::string note;
};

/// The empirical transfer function estimate (Ljung, "System Identification", 1999: the ratio of
/// the output's and the input's Fourier transforms) at `points` log-spaced frequencies between
/// 1.25 f0 and f1 / 1.25, by direct DFTs of the displacements from the first sample over the
/// controller's samples. The -3 dB bandwidth is the lowest frequency where the magnitude falls
/// below 10^(-3/20) of its value at the lowest frequency. `request` is the chirp's.
BodeResult chirp_bode(const SimulationInput& input, const SimulationResult& result, const SimulationRequest& request,
                      std::size_t points = 40);
/// CSV: f_hz, then <mechanism>_magnitude and <mechanism>_magnitude_db per mechanism.
void write_bode_csv(std::ostream& out, const BodeResult& bode);
/// Log-log picture of the magnitudes with the -3 dB line, in the house style: SVG and PNG bytes.
std::string bode_svg(const BodeResult& bode, const std::string& title);
std::string bode_png(const BodeResult& bode, const std::string& title);

/// The picture of one run (lib/src/simulate/simulation_plot.cpp): the commanded and the simulated
/// tactor paths on the station's fingertip target with the reachable regions, and the motor
/// currents and skin shear forces over time.
RenderedPlot plot_simulation(const Station& station, const SimulationInput& input, const SimulationResult& result);

/// Header and rows of the time series CSV (one row per sample and mechanism):
/// t_s,mechanism,theta1_ref_deg,theta2_ref_deg,theta1_deg,theta2_deg,w1_deg_s,w2_deg_s,i1_A,i2_A,
/// duty1,duty2,x_ref_mm,y_ref_mm,x_mm,y_mm,fx_N,fy_N,slipping
void write_time_series_csv(std::ostream& out, const SimulationResult& result);

/// Summary with units at the edges (no time series).
Json to_json(const SimulationInput& input, const SimulationResult& result);

}  // namespace fivebar
