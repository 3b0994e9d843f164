#pragma once
/// JSON at the edges (docs/conventions.md "Units"): millimetres and degrees, keys ending in
/// `_mm` / `_deg`; the library's radians never leave through here. Used by `--json` output and by
/// the scene summaries.

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>

#include "fivebar/design.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/kinematics.hpp"

namespace fivebar {

/// The JSON type of fivebar's output: keys keep their insertion order, so documents read in a
/// sensible order (status first) rather than alphabetically.
using Json = nlohmann::ordered_json;

/// Radians to degrees, normalised to (-180, 180]; -0 becomes 0.
double angle_deg(double angle_rad);

/// A realised sign (+1, -1, 0) as "+", "-" or "0".
char sign_char(int sign);
/// A realised working mode as two sign characters, e.g. "-+", "0+" on a type I singularity.
std::string mode_string(const WorkingMode& mode);

/// A pose with units at the edges:
///   status (to_string), point_mm [x,y], theta_deg [t1,t2], elbows_mm [[x,y],[x,y]],
///   mode ("+-", realised signs, 0 printed as "0"), assembly ("+", "-", "0"),
///   jacobian (2x2 rows, mm/rad; null unless jacobian_valid), lci, force_capability (N per N*mm),
///   transmission_deg [elbow1, elbow2, tactor], singularity {type1_sin [2], type2_sin,
///   type1_distance_mm}, closure_error_mm, within_joint_limits.
/// For an unreachable pose every geometric field (point, angles, elbows, modes, Jacobian,
/// transmission, singularity, closure, joint limits) is null: there is no configuration to describe.
Json to_json(const Pose& pose);
/// Mechanism data: name, bases_mm, links_mm [L1..L4], working_mode, assembly_mode ("+", "-",
/// "any"), joint_limits_deg ([[lo, hi], [lo, hi]] with lo in (-180, 180] and hi = lo + span, or
/// null), min_lci, length_scale_mm.
Json to_json(const Mechanism& mechanism);
/// Target ellipse: center_mm, axes_mm (full lengths), angle_deg.
Json to_json(const Ellipse& ellipse);

/// nlohmann's ADL hooks, so that `Json j = pose;` works.
void to_json(Json& j, const Pose& pose);
void to_json(Json& j, const Mechanism& mechanism);
void to_json(Json& j, const Ellipse& ellipse);

}  // namespace fivebar
