#pragma once
/// One control cycle of the device (paper Sec. II-D, Fig. 5; docs/runtime.md), for every mechanism
/// of every exported station at once, in this order per station:
///   1. readings (ADC counts, volts or radians) -> joint angles through the exported calibration
///      theta = rad_per_volt (V - volts_at_zero), V = range_v[0] + counts volts_per_count; a reading
///      outside the ADC's range, at one of its rails (code 0 or 2^bits - 1, or within half a count
///      of the range's ends) or not finite is a sensor fault: zero duty for that mechanism;
///   2. FK of the measured joints (the design's assembly mode): the measured tactor points and,
///      with `collision.checked`, the measured clearance between the station's two mechanisms;
///   3. IK of the reference points in the design's working mode (unreachable, singular, on the wrong
///      assembly side, or outside the joint limits shrunk by joint_margin_rad: the mechanism holds
///      its last valid command; before any, zero duty);
///   4. the priority rule on the commanded poses: when the lower mechanism's outline comes closer
///      than min_clearance to the upper's, the lower target moves to the closest collision-free
///      point: closed-form exits of rays from the forbidden capsules of its tactor point, checked
///      by at most kPriorityMaxProbes pose evaluations (a march and a bisection where links block);
///   5. the slew limit: per joint the target theta_f the PID follows moves toward the command by at
///      most max_velocity T per cycle (joints with has_velocity_limits; from the measured angle after
///      init, a reset or zero duty), then the PID with the integral clamp and a backward-difference
///      derivative:
///        s_k = clamp(s_{k-1} + e_k T, -i_clamp / i, i_clamp / i)   (no clamp when i <= 0),
///        d_k = (e_k - e_{k-1}) / T (0 at the first sample after init, a reset or a fault),
///        duty_k = clamp(p e_k + i s_k + d d_k, -1, 1),  T = 1 / loop_rate_hz,
///      e_k = theta_f - theta_measured taken within half a turn.
/// Every number it returns is finite. No allocation and no exception after construction; the work
/// of a cycle is bounded (docs/runtime.md "Real-time"); the same inputs give the same outputs.

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fivebar/runtime/config.hpp"

namespace fivebar::runtime {

/// Outcome per mechanism and cycle (worst first wins within a cycle: sensor_fault, then the
/// command's problem, then moved_by_priority).
enum class Status : std::uint8_t {
  ok = 0,
  moved_by_priority = 1,  ///< the lower target was moved to the closest collision-free point
  unreachable = 2,        ///< the reference point has no pose in the design's modes (or no free point): last command held
  singular = 3,           ///< the reference pose is singular (type I or II): last command held
  limit = 4,              ///< the reference pose leaves the joint limits less the margin: last command held
  sensor_fault = 5,       ///< a reading outside the ADC range, at a rail, not finite, or no FK: zero duty
};
const char* to_string(Status status) noexcept;

/// What the readings are.
enum class Reading : std::uint8_t {
  counts = 0,   ///< ADC codes, 0 .. 2^bits - 1
  volts = 1,    ///< potentiometer volts (already converted by the DAQ's driver)
  radians = 2,  ///< joint angles (an encoder, or a simulation without the ADC)
};

/// Priority-rule bounds (docs/runtime.md "Priority rule"): the exits of kPriorityRays fixed
/// directions and of the projections onto the forbidden capsules of the tactor point are closed
/// forms; a ray whose exit the links block advances conservatively (at least kPriorityMinStepRel
/// length scales), at most kPriorityAdvances times, and its first free point is bisected
/// kPriorityBisections times. At most kPriorityMaxProbes pose evaluations (IK, outline,
/// clearance) per station and cycle.
inline constexpr int kPriorityRays = 32;
inline constexpr double kPriorityMinStepRel = 0.0005;
inline constexpr int kPriorityAdvances = 24;
inline constexpr int kPriorityBisections = 10;
inline constexpr int kPriorityMaxProbes = 128;

/// One mechanism after a cycle.
struct MechanismState {
  Status status = Status::ok;
  std::array<double, 2> theta_measured{};  ///< rad (0 when the reading failed)
  bool measured_pose = false;              ///< FK of the measured joints exists
  std::array<double, 2> point_measured{};  ///< m
  std::array<double, 2> target{};          ///< the reference point given, m
  bool command = false;                    ///< a commanded pose exists (else zero duty)
  std::array<double, 2> point_command{};   ///< m
  std::array<double, 2> theta_command{};   ///< rad, on the joint's branch
  /// rad: the joint targets the PIDs followed this cycle (the slew limit: theta_command approached
  /// at most max_velocity / loop_rate_hz per cycle from the measured angles after construction,
  /// reset() or zero duty; within a turn of theta_command); 0 with zero duty.
  std::array<double, 2> theta_follow{};
  bool slew_limited = false;               ///< theta_follow is not yet theta_command
  double moved = 0.0;                      ///< |point_command - target| after the priority rule, m
  std::array<double, 2> duty{};            ///< in [-1, 1]
};

/// A station's measured interference (FK of the measured joints), when checked.
struct StationState {
  bool checked = false;           ///< both mechanisms, collision geometry, both measured poses
  double measured_clearance = 0.0;  ///< m, smallest over the shared planes (negative: overlap)
  bool measured_collision = false;  ///< measured_clearance < min_clearance
};

/// State of one joint's PID between cycles.
struct PidState {
  double sum = 0.0;       ///< integral of the error, rad s (clamped)
  double previous = 0.0;  ///< last error, rad
  bool first = true;      ///< no derivative at the first sample
};
/// One PID step (the formula above); the one implementation the runtime, fivebar::DiscretePid and
/// therefore `fivebar simulate` and `control` use.
double pid_update(const Gains& gains, double period_s, PidState& state, double error_rad) noexcept;

/// The ADC code of `volts` (nearest of 2^bits codes volts_per_count apart from range_v[0],
/// clamped to 0 .. 2^bits - 1): what a DAQ reports; the simulator's sensor model.
double adc_code(double volts, int bits, const std::array<double, 2>& range_v, double volts_per_count) noexcept;

namespace detail {
struct Plan;
}

class Controller {
 public:
  /// Validates `config` (ConfigError naming the key) and allocates everything a cycle needs.
  explicit Controller(Config config);
  ~Controller();
  Controller(const Controller&) = delete;
  Controller& operator=(const Controller&) = delete;
  Controller(Controller&&) noexcept;
  Controller& operator=(Controller&&) noexcept;

  const Config& config() const noexcept;
  std::size_t mechanism_count() const noexcept;
  std::size_t joint_count() const noexcept { return 2 * mechanism_count(); }

  /// One cycle. `readings`: joint_count() values in the export's joint order (joint_names);
  /// `targets_m`: 2 per mechanism (x, y in the station frame, m), same order. Null pointers or
  /// non-finite targets are handled as faults, never read past. noexcept, allocation-free.
  void cycle(const double* readings, Reading kind, const double* targets_m) noexcept;
  /// Duties of the last cycle, 2 per mechanism (joint order).
  const double* duties() const noexcept;
  const MechanismState& mechanism(std::size_t k) const noexcept;
  const StationState& station(std::size_t s) const noexcept;
  /// Integrators, derivative memories and held commands back to their state after construction.
  void reset() noexcept;

 private:
  detail::Plan* plan_ = nullptr;
};

}  // namespace fivebar::runtime
