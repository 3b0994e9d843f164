// The device's configuration from a design (fivebar/device/config.hpp): the design hash and its
// view, the joints' branches, the design -> runtime Config mapping, and the writer of the one key
// list (fivebar/runtime/config_layout.hpp) into the exported document.

#include "fivebar/device/config.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "fivebar/design/angles.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/error.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/runtime/config_layout.hpp"
#include "fivebar/sections/bench.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/optimize.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/sections/sweep.hpp"
#include "fivebar/sha256.hpp"
#include "fivebar/version.hpp"

namespace fivebar {

namespace {

using angles::kPi;
using angles::kTwoPi;
/// Lengths leave in metres (REP 103). Divided, not multiplied by 1e-3: the quotient is the double
/// nearest the true value, so 9 mm is written 0.009 rather than 0.009000000000000001.
constexpr double kMmPerMetre = 1000.0;
/// Version of the exported layout; a controller may refuse a layout it does not know.
constexpr int kFormatVersion = 1;

double metres(double mm) { return mm / kMmPerMetre; }
std::array<double, 2> metres(const Vec2& p) { return {metres(p.x()), metres(p.y())}; }

runtime::MechanismConfig mechanism_config(const Design& d, const Station& s, const Mechanism& m, const ControllerSettings& c) {
  runtime::MechanismConfig mc;
  mc.name = m.name;
  mc.o1 = metres(m.O1);
  mc.o2 = metres(m.O2);
  for (std::size_t i = 0; i < 4; ++i) mc.L[i] = metres(m.L[i]);
  mc.working_mode = {m.working_mode.sign1, m.working_mode.sign2};
  mc.assembly = m.assembly_mode == AssemblyMode::Plus    ? runtime::Assembly::plus
                : m.assembly_mode == AssemblyMode::Minus ? runtime::Assembly::minus
                                                         : runtime::Assembly::any;
  mc.min_lci = m.min_lci;
  const std::array<JointBranch, 2> branch = joint_branches(m, s.target);
  for (int j = 1; j <= 2; ++j) {
    runtime::JointConfig& jc = mc.joints[static_cast<std::size_t>(j - 1)];
    jc.name = joint_name(s.name, m.name, j);
    jc.has_position_limits = m.joint_limits.has_value();
    if (m.joint_limits) {
      jc.min_position = branch[static_cast<std::size_t>(j - 1)].lo();
      jc.max_position = branch[static_cast<std::size_t>(j - 1)].hi();
    }
    jc.has_velocity_limits = true;
    jc.max_velocity = joint_speed_limit(d, s, m, j);  // the one joint speed (fivebar/device/joint_limits.hpp)
    const JointControl ctl = c.joint(s.name, m.name, j);
    jc.gains = {ctl.pid.kp, ctl.pid.ki, ctl.pid.kd, ctl.pid.i_clamp};
    jc.volts_at_zero = ctl.potentiometer.volts_at_zero;
    jc.rad_per_volt = ctl.potentiometer.rad_per_volt;
  }
  return mc;
}

runtime::CollisionConfig collision_config(const Design& d, const ControllerSettings& c) {
  runtime::CollisionConfig out;
  out.priority = c.collision_priority;
  const Geometry* g = d.get<Geometry>();
  out.checked = g != nullptr;
  if (g == nullptr) return out;
  out.min_clearance = metres(g->min_clearance);
  for (std::size_t i = 0; i < 4; ++i) {
    out.link_widths[i] = metres(g->link_width[i]);
    out.layers[i] = g->layers[i];
  }
  out.link_thickness = metres(g->link_thickness);
  out.layer_gap = metres(g->layer_gap);
  out.pin_diameter = metres(g->pin_diameter);
  out.boss_diameter = metres(g->boss_diameter);
  out.tactor_diameter = metres(g->tactor_diameter);
  out.tactor_height = metres(g->tactor_height);
  out.motor_shaft_diameter = metres(g->motor_shaft_diameter);
  return out;
}

/// The layout's writer (fivebar/runtime/config_layout.hpp) into an ordered JSON tree.
class LayoutWriter {
 public:
  static constexpr bool reading = false;
  explicit LayoutWriter(Json& root) { stack_.push_back(&root); }
  template <class F>
  void object(const std::string& key, F&& inside) {
    Json& child = (*stack_.back())[key] = Json::object();
    stack_.push_back(&child);
    inside();
    stack_.pop_back();
  }
  template <class T>
  void value(const std::string& key, const T& v) {
    (*stack_.back())[key] = v;
  }
  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw std::logic_error("configuration_document: " + key + ": " + what);
  }

 private:
  std::vector<Json*> stack_;
};

}  // namespace

std::string joint_name(std::string_view station, std::string_view mechanism, int joint) {
  return std::string(station) + "_" + std::string(mechanism) + "_theta" + std::to_string(joint);
}

std::vector<std::string> chosen_stations(const Design& d, const std::vector<std::string>& wanted) {
  std::vector<std::string> out;
  for (const std::string& w : wanted) d.require_station(w);  // throws for an unknown name
  for (const Station& s : d.stations) {
    if (wanted.empty() || std::find(wanted.begin(), wanted.end(), s.name) != wanted.end()) out.push_back(s.name);
  }
  return out;
}

const ControllerSettings& require_controller(const Design& d) {
  if (!d.get<ControllerSettings>()) {
    throw InputError("design '" + d.name +
                     "' has no controller: section (loop rate, PWM, PID gains, potentiometer calibration): "
                     "nothing to export; see designs/iros2022.yaml");
  }
  return *d.get<ControllerSettings>();
}

Design export_view(const Design& d, const std::vector<std::string>& wanted) {
  const std::vector<std::string> stations = chosen_stations(d, wanted);
  const auto kept = [&](const std::string& s) { return std::find(stations.begin(), stations.end(), s) != stations.end(); };
  // Every section stays (kinematics, geometry, print, patterns, controller, motor, contact,
  // tolerance, provenance, ...) but the three no exported byte or gate figure reads: sweep: and
  // optimize: (studies that propose designs) and bench: (the bench files' names; what was fitted
  // from them is in the design's values and provenance:). `products:` only chooses what `fivebar
  // run` builds. test_export's walk over every number of the showcase holds this list.
  Design v = d;
  v.source.clear();
  v.products.reset();
  v.reset<SweepSettings>();
  v.reset<OptimizeSettings>();
  v.reset<BenchSettings>();
  std::erase_if(v.stations, [&](const Station& s) { return !kept(s.name); });
  if (PatternSettings* p = v.get<PatternSettings>()) {
    std::erase_if(p->overrides, [&](const PatternOverride& o) { return !kept(o.station); });
  }
  if (ControllerSettings* c = v.get<ControllerSettings>()) {
    std::erase_if(c->overrides, [&](const ControlOverride& o) { return !o.station.empty() && !kept(o.station); });
  }
  return v;
}

std::string design_hash(const Design& d, const std::vector<std::string>& stations) {
  return "sha256:" + sha256_hex(to_yaml(export_view(d, stations)));
}

double JointBranch::lo() const { return reference - angles::wrap_two_pi(reference - limits->lo); }
double JointBranch::hi() const { return lo() + limits->span(); }
double JointBranch::represent(double theta) const {
  if (!limits) return reference + std::remainder(theta - reference, kTwoPi);
  const double offset = angles::wrap_two_pi(theta - lo());
  const double span = limits->span();
  if (offset <= span) return lo() + offset;
  return (offset - span) < (kTwoPi - offset) ? lo() + offset : lo() + offset - kTwoPi;
}

std::array<JointBranch, 2> joint_branches(const Mechanism& m, const Ellipse& e) {
  std::array<JointBranch, 2> b;
  const Pose centre = ik(m, e.center);
  for (std::size_t j = 0; j < 2; ++j) {
    if (m.joint_limits) b[j].limits = (*m.joint_limits)[j];
    // An unreachable centre fails the gate anyway; the limits then start at lo in (-pi, pi].
    b[j].reference = centre.status == Status::unreachable ? (m.joint_limits ? angles::wrap_pi((*m.joint_limits)[j].lo) : 0.0)
                                                          : angles::wrap_pi(j == 0 ? centre.theta1 : centre.theta2);
  }
  return b;
}

runtime::Config device_config(const Design& d, const std::vector<std::string>& wanted) {
  const ControllerSettings& c = require_controller(d);
  const std::vector<std::string> stations = chosen_stations(d, wanted);
  runtime::Config out;
  out.node = c.node;
  out.design = d.name;
  out.design_hash = design_hash(d, stations);
  out.hash_algorithm = "sha256 of the canonical design text (fivebar/export/export.hpp)";
  out.tool_version = std::string(version());
  out.format_version = kFormatVersion;
  out.units = "SI (REP 103): m, rad, s, V, Hz";
  out.loop_rate_hz = c.loop_rate_hz;
  out.pwm_hz = c.pwm_hz;
  out.adc_bits = c.adc_bits;
  out.adc_range_v = c.adc_range_v;
  out.volts_per_count = (c.adc_range_v[1] - c.adc_range_v[0]) / std::ldexp(1.0, c.adc_bits);
  out.joint_margin = c.joint_margin;
  out.collision = collision_config(d, c);
  for (const std::string& name : stations) {
    const Station s = with_usable_limits(d, *d.station(name));  // hardware limits (fivebar/device/joint_limits.hpp)
    runtime::StationConfig sc;
    sc.name = name;
    sc.target.center = metres(s.target.center);
    sc.target.axes = metres(s.target.axes);
    sc.target.angle = s.target.angle;
    for (const Mechanism* m : s.mechanisms()) sc.mechanisms.push_back(mechanism_config(d, s, *m, c));
    out.stations.push_back(std::move(sc));
  }
  return out;
}

Json configuration_document(const runtime::Config& config) {
  runtime::Config c = config;  // layout() takes a mutable Config (the same list reads one)
  Json params = Json::object();
  LayoutWriter io(params);
  runtime::layout(io, c);
  Json root = Json::object();
  root[c.node] = {{"ros__parameters", params}};
  return root;
}

}  // namespace fivebar
