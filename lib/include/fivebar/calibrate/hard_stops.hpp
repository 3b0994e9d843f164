#pragma once
/// Potentiometer calibration without a camera (docs/calibrate.md "Hard stops"): readings taken
/// with a proximal link resting on a hard stop whose angle the geometry gives
/// (fivebar/device/joint_limits.hpp usable_ranges(): an end of the usable range set by a hard stop).
/// CSV `station,mechanism,joint,stop,volts` (joint 1 or 2, stop lo or hi; repeated readings are
/// averaged). One stop of a joint gives volts_at_zero at the design's rad_per_volt,
/// V0 = V - theta_stop / k; both stops give both, k = (theta_hi - theta_lo) / (V_hi - V_lo).
/// The stop angles are taken as exact (they are the design's geometry); the sigma is that of the
/// mean reading (the readings' standard deviation over sqrt(n); 0 for a single reading).

#include <filesystem>
#include <string>

#include "fivebar/calibrate/fit.hpp"
#include "fivebar/design.hpp"

namespace fivebar::calibrate {

/// The potentiometer parameters the readings give, as a CalibrationResult whose parameters are
/// the potentiometer keys (identified or not) and nothing else; InputError naming the file and
/// line for bad rows or a stop that the geometry does not define.
CalibrationResult hard_stop_calibration(const Design& design, const std::string& text, const std::string& origin);

}  // namespace fivebar::calibrate
