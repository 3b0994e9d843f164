// The studies' resource estimates (fivebar/resources/estimates.hpp).
#include "fivebar/resources/estimates.hpp"

#include <algorithm>
#include <string>

#include "fivebar/format.hpp"
#include "fivebar/sections/tolerance.hpp"

namespace fivebar {

ResourceEstimate tolerance_estimate(const Design& design, const std::vector<const Station*>& stations) {
  const ToleranceSettings* given = design.get<ToleranceSettings>();
  const double samples = double(given ? given->samples : ToleranceSettings{}.samples);
  std::size_t mechanisms = 0;
  if (stations.empty()) {
    for (const Station& s : design.stations) mechanisms += s.mechanisms().size();
  } else {
    for (const Station* s : stations) mechanisms += s->mechanisms().size();
  }
  ResourceEstimate e;
  e.what = "the tolerance study (tolerance.samples = " + std::to_string(given ? given->samples : ToleranceSettings{}.samples) +
           " devices, " + std::to_string(mechanisms) + " mechanism" + (mechanisms == 1 ? "" : "s") + ")";
  e.seconds = kToleranceSecondsPerSample * samples * double(mechanisms);
  e.memory_bytes = kToleranceBytesPerSample * samples;  // one mechanism at a time
  return e;
}

ResourceEstimate dense_output_estimate(const std::vector<SimulationInput>& runs, double dense_dt_s) {
  ResourceEstimate e;
  double rows = 0.0, peak = 0.0, seconds = 0.0;
  for (const SimulationInput& in : runs) {
    std::size_t samples = 0;
    for (const SimulatedMechanism& m : in.mechanisms) samples = std::max(samples, m.reference.size());
    const double duration = double(samples) / std::max(in.controller.loop_rate_hz, 1e-9);
    seconds += duration;
    const double here = (duration / dense_dt_s + 1.0) * double(in.mechanisms.size());
    rows += here;
    peak = std::max(peak, here);
  }
  e.what = "the dense output (every " + format::shortest(dense_dt_s) + " s over " + std::to_string(runs.size()) +
           " run" + (runs.size() == 1 ? "" : "s") + " of " + format::shortest(seconds) + " s in all)";
  e.disk_bytes = kDenseCsvBytesPerRow * rows;
  e.memory_bytes = kDenseBytesPerSample * peak;
  return e;
}

ResourceEstimate identify_estimate(std::size_t rows, std::size_t joints) {
  ResourceEstimate e;
  const double cells = double(rows) * double(std::max<std::size_t>(joints, 1));
  e.what = "the identification (" + std::to_string(rows) + " log rows of " + std::to_string(joints) + " joint" +
           (joints == 1 ? "" : "s") + ")";
  e.memory_bytes = kIdentifyBytesPerRowJoint * cells;
  e.seconds = kIdentifySecondsPerRowJoint * cells;
  return e;
}

}  // namespace fivebar
