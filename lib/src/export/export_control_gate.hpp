#pragma once
// Private to lib: the loop checks of the export gate (fivebar/export/export.hpp "stability", "tracking",
// "saturation"), kept apart from the geometric checks of lib/src/export/export.cpp.

#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/json.hpp"

namespace fivebar::detail {

struct ControlGate {
  std::vector<GateCheck> checks;
  /// The figures the export was validated with, per station and mechanism (SI units, as the
  /// exported files): {<station>: {<mechanism>: {max_rho, kp_margin, kd_margin, worst_pose_m,
  /// oscillatory_damping, oscillatory_frequency_hz, min_bandwidth_hz, max_tracking_error_m, max_saturation_fraction}}}.
  Json figures = Json::object();
};

/// Runs only for a design with `geometry:`, `motor:` and `controller:` (empty otherwise): per
/// mechanism of each station the stability map over its target (masses from the closed form), and
/// per station with both mechanisms every pattern simulated (CVODE at rtol 1e-4), each against
/// the controller's max_tracking_error_mm and max_saturation_fraction.
ControlGate control_gate(const Design& design, const std::vector<std::string>& stations,
                         const std::function<void(std::string_view)>& progress);

}  // namespace fivebar::detail
