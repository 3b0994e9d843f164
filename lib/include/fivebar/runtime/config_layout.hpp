#pragma once
/// The one list of the device configuration's keys (docs/runtime.md "Configuration"): where each
/// field of a runtime Config (fivebar/runtime/config.hpp) sits in the exported document
/// `{<node>: {ros__parameters: {...}}}`. Everything that writes or reads that document goes through
/// layout(): `fivebar export` writes the JSON, the ROS 2 YAML and the C++ header from a Config
/// through it (lib/src/export), the runtime reads a Config back through it
/// (fivebar/runtime/json_config.hpp, and so the header's embedded JSON,
/// fivebar/runtime/header_config.hpp), and `simulate`, `control --tune` and the export gate run
/// the Config the export writes (fivebar/device/config.hpp). A field added here is written,
/// read and simulated at once; a key named nowhere else cannot drift.
///
/// An Io is a writer or a reader of one document:
///
///   static constexpr bool reading;                       // true: fill the Config from the document
///   template <class F> void object(const std::string& key, F&& inside);  // a map: inside() runs in it
///   void value(const std::string& key, T& v);           // T: double, int, bool, std::string,
///                                                        // std::array<double, N>, std::array<int, 4>,
///                                                        // std::vector<std::string>
///   [[noreturn]] void fail(const std::string& key, const std::string& what);  // reading: names the key
///
/// A writer adds the keys in the order of the calls (the file's order); a reader requires each key
/// with the value's kind and names the key path when it is missing or wrong. Fields written only
/// under a condition (a joint's position range, the collision outlines) are read under the same
/// condition, read before them. C++17, standard library only.

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "fivebar/runtime/config.hpp"

namespace fivebar::runtime {

/// "-+" for working-mode signs {-1, +1}.
inline std::string working_mode_text(const std::array<std::int8_t, 2>& signs) {
  std::string s;
  for (std::int8_t v : signs) s += v > 0 ? '+' : v < 0 ? '-' : '?';
  return s;
}
inline std::string assembly_text(Assembly a) { return a == Assembly::plus ? "+" : a == Assembly::minus ? "-" : "any"; }

/// Every joint of every station's mechanisms, in the file's order.
inline std::vector<std::string> joint_names(const Config& c) {
  std::vector<std::string> out;
  for (const StationConfig& s : c.stations)
    for (const MechanismConfig& m : s.mechanisms)
      for (const JointConfig& j : m.joints) out.push_back(j.name);
  return out;
}

namespace layout_detail {

/// Reading: the list of names gives the vector its length and each element its name.
template <class Io, class T>
void names(Io& io, const std::string& key, std::vector<T>& items) {
  std::vector<std::string> list;
  if constexpr (!Io::reading) {
    for (const T& item : items) list.push_back(item.name);
  }
  io.value(key, list);
  if constexpr (Io::reading) {
    items.assign(list.size(), T{});
    for (std::size_t i = 0; i < list.size(); ++i) items[i].name = list[i];
  }
}

template <class Io>
void mechanism(Io& io, MechanismConfig& m) {
  std::vector<std::string> joints;
  if constexpr (!Io::reading) joints = {m.joints[0].name, m.joints[1].name};
  io.value("joint_names", joints);
  if constexpr (Io::reading) {
    if (joints.size() != 2) io.fail("joint_names", "expected 2 values");
    m.joints[0].name = joints[0], m.joints[1].name = joints[1];
  }
  io.value("o1_m", m.o1);
  io.value("o2_m", m.o2);
  io.value("link_lengths_m", m.L);
  std::string mode = working_mode_text(m.working_mode);
  io.value("working_mode", mode);
  std::string assembly = assembly_text(m.assembly);
  io.value("assembly_mode", assembly);
  if constexpr (Io::reading) {
    if (mode.size() != 2) io.fail("working_mode", "expected two signs (\"-+\"), found \"" + mode + "\"");
    for (std::size_t i = 0; i < 2; ++i) {
      if (mode[i] != '+' && mode[i] != '-') io.fail("working_mode", "expected two signs (\"-+\"), found \"" + mode + "\"");
      m.working_mode[i] = mode[i] == '+' ? 1 : -1;
    }
    if (assembly == "+") m.assembly = Assembly::plus;
    else if (assembly == "-") m.assembly = Assembly::minus;
    else if (assembly == "any") m.assembly = Assembly::any;
    else io.fail("assembly_mode", "expected \"+\", \"-\" or \"any\", found \"" + assembly + "\"");
  }
  io.value("min_lci", m.min_lci);
}

template <class Io>
void station(Io& io, StationConfig& s) {
  io.object("target", [&] {
    io.value("center_m", s.target.center);
    io.value("axes_m", s.target.axes);
    io.value("angle_rad", s.target.angle);
  });
  names(io, "mechanisms", s.mechanisms);
  if constexpr (Io::reading) {
    if (s.mechanisms.empty() || s.mechanisms.size() > 2) io.fail("mechanisms", "expected one or two mechanisms");
    for (const MechanismConfig& m : s.mechanisms)
      if (m.name != "lower" && m.name != "upper") io.fail("mechanisms", "expected \"lower\" or \"upper\", found \"" + m.name + "\"");
  }
  for (MechanismConfig& m : s.mechanisms) io.object(m.name, [&] { mechanism(io, m); });
}

template <class Io>
void collision(Io& io, CollisionConfig& c) {
  io.value("priority", c.priority);
  if constexpr (Io::reading) {
    if (c.priority != "upper") io.fail("priority", "only \"upper\" (the paper's rule) is implemented, found \"" + c.priority + "\"");
  }
  io.value("checked", c.checked);
  if (!c.checked) return;  // a design without geometry: no outlines
  io.value("min_clearance_m", c.min_clearance);
  io.value("link_widths_m", c.link_widths);
  io.value("link_thickness_m", c.link_thickness);
  io.value("layers", c.layers);
  io.value("layer_gap_m", c.layer_gap);
  io.value("pin_diameter_m", c.pin_diameter);
  io.value("boss_diameter_m", c.boss_diameter);
  io.value("tactor_diameter_m", c.tactor_diameter);
  io.value("tactor_height_m", c.tactor_height);
  io.value("motor_shaft_diameter_m", c.motor_shaft_diameter);
}

template <class Io>
void joint_limits(Io& io, JointConfig& j) {
  io.value("has_position_limits", j.has_position_limits);
  if (j.has_position_limits) {
    io.value("min_position", j.min_position);
    io.value("max_position", j.max_position);
  }
  io.value("has_velocity_limits", j.has_velocity_limits);
  if (j.has_velocity_limits) io.value("max_velocity", j.max_velocity);
  io.value("has_acceleration_limits", j.has_acceleration_limits);
  io.value("has_jerk_limits", j.has_jerk_limits);
  io.value("has_effort_limits", j.has_effort_limits);
}

/// Every joint of the stations read so far, each in its own map under `key`.
template <class Io, class F>
void per_joint(Io& io, const std::string& key, Config& c, F&& field) {
  io.object(key, [&] {
    for (StationConfig& s : c.stations)
      for (MechanismConfig& m : s.mechanisms)
        for (JointConfig& j : m.joints) io.object(j.name, [&] { field(j); });
  });
}

}  // namespace layout_detail

/// The document's `ros__parameters` map, in the file's order (the node's name is Config::node).
template <class Io>
void layout(Io& io, Config& c) {
  using namespace layout_detail;
  io.object("fivebar", [&] {
    io.value("design", c.design);
    io.value("design_hash", c.design_hash);
    io.value("hash_algorithm", c.hash_algorithm);
    io.value("tool_version", c.tool_version);
    io.value("format_version", c.format_version);
    io.value("units", c.units);
  });
  io.value("loop_rate_hz", c.loop_rate_hz);
  io.value("pwm_hz", c.pwm_hz);
  io.object("adc", [&] {
    io.value("bits", c.adc_bits);
    io.value("range_v", c.adc_range_v);
    io.value("volts_per_count", c.volts_per_count);
  });
  // The runtime keeps commanded joint angles this far inside the usable ranges.
  io.value("joint_margin_rad", c.joint_margin);
  names(io, "station_names", c.stations);
  if constexpr (Io::reading) {
    if (c.stations.empty()) io.fail("station_names", "no station");
  }
  // Every joint, station and mechanism order: written from the stations, checked against them.
  std::vector<std::string> all_joints;
  if constexpr (!Io::reading) all_joints = joint_names(c);
  io.value("joint_names", all_joints);
  io.object("stations", [&] {
    for (StationConfig& s : c.stations) io.object(s.name, [&] { station(io, s); });
  });
  if constexpr (Io::reading) {
    if (all_joints != joint_names(c)) io.fail("joint_names", "not the joints of stations.<station>.<mechanism>.joint_names in order");
  }
  io.object("collision", [&] { collision(io, c.collision); });
  per_joint(io, "joint_limits", c, [&](JointConfig& j) { joint_limits(io, j); });
  per_joint(io, "gains", c, [&](JointConfig& j) {
    io.value("p", j.gains.p);
    io.value("i", j.gains.i);
    io.value("d", j.gains.d);
    io.value("i_clamp", j.gains.i_clamp);
  });
  per_joint(io, "potentiometers", c, [&](JointConfig& j) {
    io.value("volts_at_zero", j.volts_at_zero);
    io.value("rad_per_volt", j.rad_per_volt);
  });
}

}  // namespace fivebar::runtime
