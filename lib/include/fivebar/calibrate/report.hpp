#pragma once
/// What `fivebar calibrate` prints and writes (docs/calibrate.md): the result as JSON
/// (docs/schemas/calibrate.schema.json), as a markdown report, the patched design with its
/// provenance entries, and the plan as a CSV of joint targets.

#include <string>
#include <vector>

#include "fivebar/calibrate/fit.hpp"
#include "fivebar/calibrate/plan.hpp"
#include "fivebar/design.hpp"
#include "fivebar/json.hpp"

namespace fivebar::calibrate {

/// Where the measurements came from, for provenance entries.
struct Source {
  std::string file;    ///< as given
  std::string sha256;  ///< of its bytes
  std::string date;    ///< YYYY-MM-DD, UTC
};

/// `{"parameter": KEY, "value", "sigma", "identified", ...}` per parameter, the identification
/// figures, residuals and unidentifiable combinations.
Json to_json(const CalibrationResult& result);
/// A markdown report of the result.
std::string report_markdown(const CalibrationResult& result, const Source& source);
/// `patched` with a provenance entry for every identified parameter's key (method, sigma in the
/// key's file unit).
Design with_provenance(const Design& patched, const CalibrationResult& result, const Source& source);

/// The plans as JSON.
Json to_json(const std::vector<MechanismPlan>& plans, const PlanOptions& options);
/// CSV `station,mechanism,pose,theta1_deg,theta2_deg,volts1,volts2,x_mm,y_mm` of every plan.
std::string plan_csv(const std::vector<MechanismPlan>& plans);

}  // namespace fivebar::calibrate
