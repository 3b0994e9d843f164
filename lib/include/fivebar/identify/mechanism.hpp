#pragma once
/// `fivebar identify --rig mechanism STATION/MECHANISM` (docs/identify.md "The assembled mechanism"):
/// the log of both motors of an assembled five-bar. The closed chain's inertia and Coriolis terms come
/// from the design (fivebar/dynamics.hpp dynamics_terms(): the links' masses from the closed form,
/// the parts' density), evaluated on the filtered motion, and are subtracted from each joint's drive
/// torque; what is left is each joint's own model (its reflected rotor inertia N^2 J_r, viscous and
/// Coulomb friction, an offset), identified by IDIM-LS as for a motor on the bench, with the
/// parameters the log does not excite named and held.

#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/identify/identify.hpp"
#include "fivebar/identify/log.hpp"

namespace fivebar::identify {

/// Identifies joints 1 and 2 of `station`/`mechanism` from their columns
/// (`<station>_<mechanism>_theta1_*`, `..._theta2_*`). InputError when a joint's columns are missing,
/// the design lacks `geometry:` (the links' inertia), or the logged motion leaves the mechanism's
/// workspace or meets a type II singularity (naming the time). The output-error refinement is not
/// run (a joint of a closed chain is not simulated alone).
/// InputError "PATH:LINE: column N 'NAME': the design has no station 'S'" (or no mechanism) for a
/// joint of `log` whose column prefix names a station or mechanism the design lacks: a typo in a
/// column is named where it is, not reported as the joint it was meant for being missing.
void require_log_joints_in(const Design& design, const IdentifyLog& log);

std::vector<JointIdentification> identify_mechanism(const Design& design, const IdentifyLog& log, const std::string& station,
                                                    const std::string& mechanism, const IdentifyOptions& options);

}  // namespace fivebar::identify
