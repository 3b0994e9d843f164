#pragma once
/// The design an identification patches (docs/identify.md "The patched design"): every identified
/// parameter whose key is a design key path (`motor.terminal_resistance_ohm`,
/// `motor.stations.index.lower.theta1.coulomb_friction_mNm`) written into the `motor:` section (a
/// joint's scope created when the design has none), with one provenance entry per key through the
/// writer `calibrate` uses (fivebar/provenance.hpp with_measured_values()), each value only after it
/// passed the quality gate (identification_gate()). Rig-only quantities (`inertia_kg_m2`,
/// `offset_Nm`, ...) and held parameters are not written.

#include <optional>
#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/identify/identify.hpp"
#include "fivebar/provenance.hpp"
#include "fivebar/provenance/gate.hpp"

namespace fivebar::identify {

/// The floor of an identification's drive fit (fit_percent(), the inverse model's drive predicted
/// from the motion): below it the model leaves more than a fifth of the drive's variation
/// unexplained (an unmodelled effect, a wrong drive column, a log the model does not describe) and
/// no value of the fit is written as measured (docs/identify.md "The quality gate").
inline constexpr double kDriveFitFloorPercent = 80.0;
/// A design key is written as measured only when its sigma is at most this fraction of its value
/// (two sigmas from zero): the `motor:` section's values state no prior sigma (datasheet values and
/// assumptions), so the gate asks the log to fix at least their size.
inline constexpr double kMaxRelativeSigma = 0.5;

/// The quality gate of an identification (fivebar/provenance/gate.hpp), the one every fit passes
/// before the design is patched: the solver (IDIM-LS is a closed form; with `use_output_error` the
/// output-error refinement must have converged), one residual test per joint (its drive fit on the
/// validation log, on the estimation log when there is none, at least kDriveFitFloorPercent), and per
/// identified design key under `motor.` its identifiability and kMaxRelativeSigma. A whiteness test
/// is stated as not applicable: the residuals of a zero-phase filtered, decimated regression are
/// correlated by construction.
gate::GateResult identification_gate(const std::vector<JointIdentification>& results, bool use_output_error);

/// What an identification writes into a design.
struct Patch {
  gate::GateResult gate;
  /// The design with the keys of `patched` set and one provenance entry each (its gate record
  /// included); absent when the gate refused the fit as a whole or no key passed.
  std::optional<Design> design;
  std::vector<std::string> patched;      ///< design keys written, in order
  std::vector<std::string> not_patched;  ///< "key = value unit (sigma s): why" for each key left as it was
};

/// `design` patched with the identified motor keys of `results` that pass identification_gate():
/// when the gate's fit-wide conditions fail (the solver, a joint's drive fit) nothing is written;
/// otherwise each key that fails its own conditions, or whose value the `motor:` section's rules
/// refuse (a friction estimated below zero within its noise, a negative rotor inertia after the load
/// is taken off), stays an assumption and is named in `not_patched`. The others are written with a
/// provenance entry per key through the writer `calibrate` uses (fivebar/provenance.hpp
/// with_measured_values()), `source.method` as given. InputError when the design has no `motor:`
/// section or a key names a joint the design does not have.
Patch patch_design(const Design& design, const std::vector<JointIdentification>& results, const MeasurementSource& source,
                   bool use_output_error);

}  // namespace fivebar::identify
