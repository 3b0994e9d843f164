#pragma once
/// A runtime Config from the C++ header `fivebar export --format header` writes (the same content
/// as the JSON; fivebar/export/export.hpp), for firmware that compiles its configuration in. The header's
/// maps are namespaces, so the stations and mechanisms are named in the macros:
///
///   #include "iros2022_controller.hpp"
///   #include "fivebar/runtime/header_config.hpp"
///   namespace fc = fivebar_controller;
///   fivebar::runtime::Config config = FIVEBAR_RUNTIME_CONFIG(fc,
///       FIVEBAR_RUNTIME_STATION(fc, index, lower, upper), FIVEBAR_RUNTIME_STATION(fc, thumb, lower, upper));
///
/// Needs an export with `collision.checked` (the design's geometry) and joints with position
/// limits (the usable ranges); a key the header lacks is a compile error naming it. The Controller
/// validates the values as it does the JSON's.

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "fivebar/runtime/config.hpp"

namespace fivebar::runtime::header_detail {

inline std::array<std::int8_t, 2> mode(const char* s) {
  return {static_cast<std::int8_t>(s[0] == '+' ? 1 : s[0] == '-' ? -1 : 0),
          static_cast<std::int8_t>(s[0] != '\0' && s[1] == '+' ? 1 : s[0] != '\0' && s[1] == '-' ? -1 : 0)};
}
inline Assembly assembly(const char* s) {
  const std::string t(s);
  return t == "+" ? Assembly::plus : t == "-" ? Assembly::minus : Assembly::any;
}
template <class... M>
StationConfig station(const char* name, M&&... mechanisms) {
  StationConfig s;
  s.name = name;
  (s.mechanisms.push_back(std::forward<M>(mechanisms)), ...);
  return s;
}

}  // namespace fivebar::runtime::header_detail

#define FIVEBAR_RUNTIME_JOINT_(NS, J)                                                                     \
  [] {                                                                                                    \
    ::fivebar::runtime::JointConfig j;                                                                    \
    j.name = #J;                                                                                          \
    j.gains = {NS::gains::J::p, NS::gains::J::i, NS::gains::J::d, NS::gains::J::i_clamp};                 \
    j.volts_at_zero = NS::potentiometers::J::volts_at_zero;                                               \
    j.rad_per_volt = NS::potentiometers::J::rad_per_volt;                                                 \
    j.has_position_limits = NS::joint_limits::J::has_position_limits;                                     \
    j.min_position = NS::joint_limits::J::min_position;                                                   \
    j.max_position = NS::joint_limits::J::max_position;                                                   \
    return j;                                                                                             \
  }()

#define FIVEBAR_RUNTIME_JOINTS_(NS, S, M) \
  { FIVEBAR_RUNTIME_JOINT_(NS, S##_##M##_theta1), FIVEBAR_RUNTIME_JOINT_(NS, S##_##M##_theta2) }

#define FIVEBAR_RUNTIME_MECHANISM_(NS, S, M)                                                              \
  [] {                                                                                                    \
    ::fivebar::runtime::MechanismConfig c;                                                                \
    c.name = #M;                                                                                          \
    c.o1 = {NS::stations::S::M::o1_m[0], NS::stations::S::M::o1_m[1]};                                    \
    c.o2 = {NS::stations::S::M::o2_m[0], NS::stations::S::M::o2_m[1]};                                    \
    for (int k = 0; k < 4; ++k) c.L[static_cast<std::size_t>(k)] = NS::stations::S::M::link_lengths_m[k]; \
    c.working_mode = ::fivebar::runtime::header_detail::mode(NS::stations::S::M::working_mode);           \
    c.assembly = ::fivebar::runtime::header_detail::assembly(NS::stations::S::M::assembly_mode);          \
    c.joints = FIVEBAR_RUNTIME_JOINTS_(NS, S, M);                                                         \
    return c;                                                                                             \
  }()

/// One station and its mechanisms (one or two of lower, upper, in the export's order).
#define FIVEBAR_RUNTIME_STATION(NS, S, ...) \
  ::fivebar::runtime::header_detail::station(#S, FIVEBAR_RUNTIME_MECH_LIST_(NS, S, __VA_ARGS__))
#define FIVEBAR_RUNTIME_MECH_LIST_(NS, S, ...) FIVEBAR_RUNTIME_MECH_PICK_(__VA_ARGS__, FIVEBAR_RUNTIME_MECH2_, FIVEBAR_RUNTIME_MECH1_, unused)(NS, S, __VA_ARGS__)
#define FIVEBAR_RUNTIME_MECH_PICK_(A, B, MACRO, ...) MACRO
#define FIVEBAR_RUNTIME_MECH1_(NS, S, A) FIVEBAR_RUNTIME_MECHANISM_(NS, S, A)
#define FIVEBAR_RUNTIME_MECH2_(NS, S, A, B) FIVEBAR_RUNTIME_MECHANISM_(NS, S, A), FIVEBAR_RUNTIME_MECHANISM_(NS, S, B)

/// The whole configuration: the node's namespace and its stations in the export's order.
#define FIVEBAR_RUNTIME_CONFIG(NS, ...)                                                                   \
  [&] {                                                                                                   \
    ::fivebar::runtime::Config c;                                                                         \
    c.design = NS::fivebar::design;                                                                       \
    c.design_hash = NS::fivebar::design_hash;                                                             \
    c.loop_rate_hz = NS::loop_rate_hz;                                                                    \
    c.adc_bits = static_cast<int>(NS::adc::bits);                                                         \
    c.adc_range_v = {NS::adc::range_v[0], NS::adc::range_v[1]};                                           \
    c.volts_per_count = NS::adc::volts_per_count;                                                         \
    c.joint_margin = NS::joint_margin_rad;                                                                \
    c.collision.checked = NS::collision::checked;                                                         \
    c.collision.min_clearance = NS::collision::min_clearance_m;                                           \
    for (int k = 0; k < 4; ++k) {                                                                         \
      c.collision.link_widths[static_cast<std::size_t>(k)] = NS::collision::link_widths_m[k];             \
      c.collision.layers[static_cast<std::size_t>(k)] = static_cast<int>(NS::collision::layers[k]);       \
    }                                                                                                     \
    c.collision.pin_diameter = NS::collision::pin_diameter_m;                                             \
    c.collision.boss_diameter = NS::collision::boss_diameter_m;                                           \
    c.collision.tactor_diameter = NS::collision::tactor_diameter_m;                                       \
    c.collision.motor_shaft_diameter = NS::collision::motor_shaft_diameter_m;                             \
    c.stations = {__VA_ARGS__};                                                                           \
    return c;                                                                                             \
  }()
