#pragma once
/// The design an identification patches (docs/identify.md "The patched design"): every identified
/// parameter whose key is a design key path (`motor.terminal_resistance_ohm`,
/// `motor.stations.index.lower.theta1.coulomb_friction_mNm`) written into the `motor:` section (a
/// joint's scope created when the design has none), with one provenance entry per key through the
/// writer `calibrate` uses (fivebar/provenance.hpp with_measured_values()). Rig-only quantities
/// (`inertia_kg_m2`, `offset_Nm`, ...) and held parameters are not written.

#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/identify/identify.hpp"
#include "fivebar/provenance.hpp"

namespace fivebar::identify {

/// The key paths of `results` that a patch writes, in order (identified, under `motor.`, within the
/// `motor:` section's range).
std::vector<std::string> patched_keys(const std::vector<JointIdentification>& results);

/// `design` with the identified motor keys of `results` set and a provenance entry per key
/// (`source.method` as given). An identified value outside the `motor:` section's range (a friction
/// estimated below zero within its noise, a negative rotor inertia after the load is taken off) is
/// not written: the key stays an assumption and `skipped` (when given) says why. InputError when
/// the design has no `motor:` section or a key names a joint the design does not have.
Design patched_design(const Design& design, const std::vector<JointIdentification>& results, const MeasurementSource& source,
                      std::vector<std::string>* skipped = nullptr);

}  // namespace fivebar::identify
