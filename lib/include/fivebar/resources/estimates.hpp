#pragma once
/// The estimates of the studies whose cost the request sets (fivebar/resources/budget.hpp's rule;
/// docs/reliability.md "Resource bounds" lists the rates and where they come from).

#include <cstdint>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/resources/budget.hpp"

namespace fivebar {

/// Per Monte Carlo device and mechanism: the draws (kToleranceParameters doubles) and the margin
/// held at once (88 bytes, rounded up), and the time measured for 1e8 devices of one two-mechanism
/// station on the reference 2-core machine: 8 min), 2.4 us per device and mechanism.
inline constexpr double kToleranceBytesPerSample = 96.0;
inline constexpr double kToleranceSecondsPerSample = 2.4e-6;
/// The tolerance study of `stations` (every station with a mechanism when empty) with the design's
/// tolerance.samples (the defaults without a tolerance: section).
ResourceEstimate tolerance_estimate(const Design& design, const std::vector<const Station*>& stations);

/// Per row of a dense time-series CSV (one mechanism at one time: 19 numbers in shortest form)
/// and per mechanism sample held in memory until it is written.
inline constexpr double kDenseCsvBytesPerRow = 240.0;
inline constexpr double kDenseBytesPerSample = 224.0;
/// The dense output every `dense_dt_s` of these runs: the rows their references' durations
/// (samples over controller.loop_rate_hz) give.
ResourceEstimate dense_output_estimate(const std::vector<SimulationInput>& runs, double dense_dt_s);

/// Per row and joint of an identification log (the log, its filtered and decimated signals, the
/// regressors): measured with `fivebar identify` on 1- and 2-joint logs of 2e5 to 8e5 rows, peak
/// memory grew by 165 B and CPU time by about 1.4 us per row and joint (rounded up below).
inline constexpr double kIdentifyBytesPerRowJoint = 170.0;
inline constexpr double kIdentifySecondsPerRowJoint = 1.5e-6;
/// An identification of `rows` log rows (estimation and validation logs together) of `joints` joints.
ResourceEstimate identify_estimate(std::size_t rows, std::size_t joints);

}  // namespace fivebar
