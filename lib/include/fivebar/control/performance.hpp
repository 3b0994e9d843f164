#pragma once
/// What the loop of one mechanism renders over its target: bandwidth, resolution per ADC count,
/// force in every direction and the Z-width (fivebar/control/loop.hpp gives the loop).

#include <string>
#include <vector>

#include "fivebar/control/loop.hpp"
#include "fivebar/json.hpp"

namespace fivebar {

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

}  // namespace fivebar
