#pragma once
// The values of the exported C++17 header (test/export_header/values_cpp17.cpp, compiled as
// C++17 against the header the build generated) handed to test_export_header.cpp, which compares
// them with the design at run time. Plain C++17: both sides include it.

#include <string>
#include <vector>

namespace fivebar_test {

struct HeaderJoint {
  std::string name;
  bool has_position_limits = true;
  bool has_velocity_limits = false;
  double max_velocity = 0.0;
  double p = 0.0, i = 0.0, d = 0.0, i_clamp = 0.0;
  double volts_at_zero = 0.0, rad_per_volt = 0.0;
};

struct HeaderMechanism {
  std::string station, name;
  std::vector<std::string> joint_names;
  double o1[2] = {0.0, 0.0}, o2[2] = {0.0, 0.0};
  double links[4] = {0.0, 0.0, 0.0, 0.0};
  std::string working_mode, assembly_mode;
  double min_lci = -1.0;
};

struct HeaderStation {
  std::string name;
  double center[2] = {0.0, 0.0}, axes[2] = {0.0, 0.0};
  double angle = 0.0;
};

struct HeaderValues {
  std::string node, design, design_hash, tool_version;
  long long format_version = 0;
  double loop_rate_hz = 0.0, pwm_hz = 0.0;
  long long adc_bits = 0;
  double adc_range[2] = {0.0, 0.0};
  double volts_per_count = 0.0;
  std::vector<std::string> station_names, joint_names;
  std::vector<HeaderStation> stations;
  std::vector<HeaderMechanism> mechanisms;
  std::vector<HeaderJoint> joints;
  std::string collision_priority;
  double min_clearance = 0.0, link_widths[4] = {0.0, 0.0, 0.0, 0.0};
  long long layers[4] = {0, 0, 0, 0};
};

/// Every value of the generated header, read through its C++17 declarations.
HeaderValues header_values();

}  // namespace fivebar_test
