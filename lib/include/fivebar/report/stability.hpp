#pragma once
/// `fivebar report stability`: a catalogue of extreme cases, each with its status, its error
/// against the quad reference and the error its conditioning allows. See fivebar/report.hpp.

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/json.hpp"

namespace fivebar {

// --- Stability -----------------------------------------------------------------------------------

struct StabilityCase {
  std::string mechanism;  ///< "index/lower", the label given to stability_catalogue(), or the station ("index") of a dynamic case
  std::string group;      ///< "type I distance", "type II distance", "link ratio", "scale", ...
  std::string name;       ///< the case within its group, e.g. "stretched, distance 1e-08"
  std::string operation;  ///< "ik", "fk", "jacobian", "lci", "area", "closed-form area", "margin", ...
  double parameter = 0.0; ///< the swept value (distance / length scale, ratio, scale, condition number)
  std::string status;     ///< what the library reported
  std::string expected;   ///< the statuses the reference allows, "|"-separated
  std::optional<double> error;  ///< against the quad reference, in `unit` (absent: status-only case)
  std::optional<double> bound;  ///< the error the conditioning allows, in `unit`
  std::string unit;       ///< "mm", "rel" (relative), "mm2", "1"
  double conditioning = 0.0;  ///< the reference's |sin| (or LCI) governing the case; 1 when irrelevant
  bool finite = true;     ///< every number the library returned is finite
  bool passed = true;
  bool ill_conditioned = false;
  std::string explanation;  ///< why ill-conditioned, why it failed, or what was checked
};

struct StabilityReport {
  std::string design;
  std::vector<StabilityCase> cases;
  std::size_t failed() const;
  std::size_t ill_conditioned() const;
  bool passed() const { return failed() == 0; }
};

struct StabilityOptions {
  std::string station;  ///< empty: every station
  std::function<void(std::string_view)> progress;  ///< may be empty
};

/// The catalogue for one mechanism and target ellipse; cases are labelled `label`. Its cases are
/// built from the mechanism without joint limits (the extremes are those of the kinematics; limits
/// only cut the workspace), with lengths rounded to a dyadic grid where exact singular points need
/// it (no change for lengths such as the paper's), in frames that make the sensitive input exact.
StabilityReport stability_catalogue(const Mechanism& m, const Ellipse& target, const std::string& label);
/// The dynamic cases of a station with both mechanisms (group "dynamics", operation "simulate",
/// labelled by the station): fivebar/dynamics.hpp's simulation with the motors' stiffness ratio
/// T_loop R / L at 1e8, the skin 1000x stiffer, a reference ramped to within 1e-6 of the length
/// scale of the workspace boundary, zero friction (motors and skin) and a current limit that is
/// hit; each passes when it finishes with finite numbers and an expected status (and the limit
/// case saturates). Empty without `motor:` and `controller:`.
std::vector<StabilityCase> dynamics_stability_cases(const Design& design, const Station& station);
/// The catalogue for every mechanism of the design (or of one station), then the dynamic cases of
/// each station with both mechanisms.
StabilityReport stability_report(const Design& design, const StabilityOptions& options = {});

Json to_json(const StabilityReport& report);
std::string to_text(const StabilityReport& report);

}  // namespace fivebar
