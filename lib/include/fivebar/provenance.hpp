#pragma once
/// Measured or assumed (docs/calibrate.md): which values of a design rest on
/// a measurement (a `provenance:` entry, fivebar/sections/provenance.hpp) and which are
/// assumptions, by group:
///   kinematics     every mechanism's links and bases (`stations.<s>.mechanisms.<m>.links`, `bases`)
///   potentiometer  each joint's volts_at_zero and rad_per_volt, at the narrowest `controller` scope
///                  that sets it (fivebar/sections/controller.hpp ControlOverride), else the defaults
///   motor          every number of `motor:`
///   contact        every number of `contact:`
///   density        `print.density_g_cm3`
///   tolerance      every number of `tolerance:`
/// A group the design does not have (no `motor:`) has no values and so no assumptions.

#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"

namespace fivebar {

/// The group names above, in that order.
const std::vector<std::string>& provenance_groups();
/// True when `key` or a key path above it has a provenance entry.
bool is_measured(const Design& design, std::string_view key);
/// The key paths of `group` that the design has and that are assumptions. InputError for an
/// unknown group.
std::vector<std::string> assumed_values(const Design& design, std::string_view group);
/// The groups (provenance_groups() order) with at least one assumed value.
std::vector<std::string> assumed_groups(const Design& design);

}  // namespace fivebar
