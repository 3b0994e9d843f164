#pragma once
/// The device's configuration from a design (docs/runtime.md "Configuration"): the one place a
/// design becomes the runtime Config (fivebar/runtime/config.hpp) that the device loads. `fivebar
/// export` writes it (through the one key list, fivebar/runtime/config_layout.hpp, into the JSON,
/// the ROS 2 YAML and the C++ header: fivebar/export/export.hpp); `simulate`, `control --tune` and
/// the export gate run it (fivebar/dynamics.hpp simulation_inputs()). This layer sits below both:
/// it includes nothing of simulate, control or export (test/check_layers.py "device"), so the
/// export's gate can run a simulation of the configuration it is about to write without a loop.
///
/// Units: the design's mm and rad become SI (REP 103): lengths are divided by 1000 (the quotient
/// is the double nearest the true value, so 9 mm is 0.009, not 0.009000000000000001).
///
/// Design hash: SHA-256 (FIPS 180-4, fivebar/sha256.hpp) of the canonical design text
/// to_yaml(export_view(design, stations)), "sha256:<64 hex digits>" (what it covers:
/// fivebar/export/export.hpp).

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/json.hpp"
#include "fivebar/runtime/config.hpp"
#include "fivebar/sections/controller.hpp"

namespace fivebar {

/// `<station>_<mechanism>_theta<joint>`.
std::string joint_name(std::string_view station, std::string_view mechanism, int joint);

/// The stations named in `wanted` (all when empty), in the design's order; InputError naming an
/// unknown one.
std::vector<std::string> chosen_stations(const Design& design, const std::vector<std::string>& wanted);

/// The design's `controller:` section; InputError when it has none (nothing to export or run).
const ControllerSettings& require_controller(const Design& design);

/// The part of the design the export depends on (fivebar/export/export.hpp); `stations` empty = all.
Design export_view(const Design& design, const std::vector<std::string>& stations);
/// "sha256:" + 64 lower-case hex digits of sha256_hex(to_yaml(export_view(design, stations))).
std::string design_hash(const Design& design, const std::vector<std::string>& stations);

/// The branch a joint's angles are written on, one for the gate, the limits and the potentiometer
/// map: the one holding the joint's angle at the target centre normalised to (-pi, pi]
/// (`reference`). Without limits an angle is represented within pi of the reference; with limits
/// the arc starts at the representative of lo at most one turn below the reference (so the arc
/// holds the reference when the centre is within the limits), and an angle outside the arc is put
/// next to its nearer end.
struct JointBranch {
  std::optional<JointRange> limits;
  double reference = 0.0;
  double lo() const;
  double hi() const;
  double represent(double theta) const;
};

/// The branches of both joints of `m` for the target `target`.
std::array<JointBranch, 2> joint_branches(const Mechanism& m, const Ellipse& target);

/// The runtime configuration of `stations` (all when empty) of the design: the node, provenance
/// (design name, design_hash(), tool version, layout version 1), loop and PWM rates, ADC, joint
/// margin, per station the target and per mechanism the geometry, modes, min LCI, per joint the
/// usable range (fivebar/device/joint_limits.hpp, on joint_branches()), the one joint speed
/// (joint_speed_limit()), gains and potentiometer calibration; the collision outlines when the
/// design has `geometry:`. Needs `controller:` (InputError otherwise); runs no check (the export
/// gate does) and does not validate() (the runtime does when it reads the file).
runtime::Config device_config(const Design& design, const std::vector<std::string>& stations);

/// The exported document `{<node>: {ros__parameters: {...}}}` of a Config, written through the one
/// key list (fivebar/runtime/config_layout.hpp). Reading it back (runtime::parse_config_json of
/// its JSON) gives the same Config.
Json configuration_document(const runtime::Config& config);

}  // namespace fivebar
