// The runtime configured from the exported C++ header (fivebar/runtime/header_config.hpp), compiled
// as strict C++17 against the header `fivebar export --format header` wrote for
// designs/iros2022.yaml at build time; test_runtime compares it with the JSON's.

#include <array>

#include "fivebar/runtime/header_config.hpp"
#include "iros2022_controller.hpp"

namespace fivebar_test {

fivebar::runtime::Config runtime_config_from_header() {
  return FIVEBAR_RUNTIME_CONFIG(fivebar_controller);
}

/// Some of the header's constants, read at compile time (the other copy of the values).
std::array<double, 6> header_constants() {
  namespace fc = fivebar_controller;
  return {fc::gains::index_lower_theta1::p, fc::potentiometers::thumb_upper_theta2::rad_per_volt,
          fc::stations::index::lower::link_lengths_m[2], fc::joint_limits::index_upper_theta1::max_velocity,
          fc::joint_limits::index_upper_theta1::min_position, fc::collision::tactor_diameter_m};
}

}  // namespace fivebar_test
