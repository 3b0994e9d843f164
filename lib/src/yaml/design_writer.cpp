// Design -> design file (YAML). yaml-cpp emits the structure; numbers are formatted here in their
// shortest round-trip form (yaml-cpp would print 0.1 as 0.10000000000000001), angles in degrees
// rounded to 12 significant digits so that a value typed in degrees reads back as typed.
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <algorithm>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "fivebar/design.hpp"

namespace fivebar {

namespace {

std::string num(double v) {
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

/// Degrees with the fewest significant digits (from 12) that the loader converts back to the
/// same radians: typed values ("10") stay as typed, computed ones keep every bit.
std::string deg(double rad) {
  for (int digits = 12; digits <= 17; ++digits) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.*g", digits, rad * 180.0 / std::numbers::pi);
    double v = std::strtod(buf, nullptr);
    if (v == 0.0) v = 0.0;  // no "-0"
    if (v * (std::numbers::pi / 180.0) == rad || digits == 17) return num(v);
  }
  return num(rad * 180.0 / std::numbers::pi);
}

void point(YAML::Emitter& out, const Vec2& p) {
  out << YAML::Flow << YAML::BeginSeq << num(p.x()) << num(p.y()) << YAML::EndSeq;
}

void mechanism(YAML::Emitter& out, const Mechanism& m) {
  out << YAML::BeginMap;
  out << YAML::Key << "bases" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  point(out, m.O1);
  point(out, m.O2);
  out << YAML::EndSeq;
  out << YAML::Key << "links" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (double l : m.L) out << num(l);
  out << YAML::EndSeq;
  out << YAML::Key << "working_mode" << YAML::Value << YAML::DoubleQuoted << to_string(m.working_mode);
  out << YAML::Key << "assembly_mode" << YAML::Value << YAML::DoubleQuoted << to_string(m.assembly_mode);
  if (m.joint_limits) {
    out << YAML::Key << "joint_limits" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const JointRange& r : *m.joint_limits) {
      out << YAML::Flow << YAML::BeginSeq << deg(r.lo) << deg(r.lo + r.span()) << YAML::EndSeq;
    }
    out << YAML::EndSeq;
  }
  if (m.min_lci != 0.0) out << YAML::Key << "min_lci" << YAML::Value << num(m.min_lci);
  out << YAML::EndMap;
}

void pattern(YAML::Emitter& out, const PatternSpec& p) {
  out << YAML::Flow << YAML::BeginMap;
  if (p.kind == PatternKind::pivot) {
    out << YAML::Key << "amplitude_deg" << YAML::Value << deg(p.pivot_amplitude);
    out << YAML::Key << "frequency_hz" << YAML::Value << num(p.pivot_frequency_hz);
  } else {
    out << YAML::Key << "amplitude_mm" << YAML::Value << num(p.amplitude_mm);
  }
  out << YAML::Key << "duration_s" << YAML::Value << num(p.duration_s);
  out << YAML::Key << "rate_hz" << YAML::Value << num(p.rate_hz);
  if (p.centre) {
    out << YAML::Key << "center" << YAML::Value;
    point(out, *p.centre);
  }
  if (p.kind == PatternKind::pivot && p.contact_points) {  // the loader takes one or the other
    out << YAML::Key << "contact_points" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    point(out, (*p.contact_points)[0]);
    point(out, (*p.contact_points)[1]);
    out << YAML::EndSeq;
  } else {
    out << YAML::Key << "separation_mm" << YAML::Value << num(p.separation_mm);
  }
  out << YAML::EndMap;
}

void patterns(YAML::Emitter& out, const PatternSettings& ps, bool speed_from_controller) {
  out << YAML::Key << "patterns" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "rate_hz" << YAML::Value << num(ps.rate_hz);
  if (!speed_from_controller) {
    out << YAML::Key << "max_joint_speed_deg_s" << YAML::Value << deg(ps.max_joint_speed);
  }
  for (const PatternSpec& spec : ps.global) {
    out << YAML::Key << std::string(to_string(spec.kind)) << YAML::Value;
    pattern(out, spec);
  }
  if (!ps.per_station.empty()) {
    out << YAML::Key << "stations" << YAML::Value << YAML::BeginMap;
    std::vector<std::string> names;  // first-appearance order; entries of one station together
    for (const auto& [station, spec] : ps.per_station) {
      if (std::find(names.begin(), names.end(), station) == names.end()) names.push_back(station);
    }
    for (const std::string& station : names) {
      out << YAML::Key << station << YAML::Value << YAML::BeginMap;
      for (PatternKind kind : all_pattern_kinds()) {
        const PatternSpec* last = nullptr;  // a later entry of the same kind replaces an earlier one
        for (const auto& [name, spec] : ps.per_station) {
          if (name == station && spec.kind == kind) last = &spec;
        }
        if (last == nullptr) continue;
        out << YAML::Key << std::string(to_string(kind)) << YAML::Value;
        pattern(out, *last);
      }
      out << YAML::EndMap;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
}

/// The keys a set of overrides of one scope gives, later ones winning (as ControllerSettings::joint()).
ControlOverride merged(const std::vector<const ControlOverride*>& scope) {
  ControlOverride m;
  for (const ControlOverride* o : scope) {
    for (auto [to, from] : {std::pair{&m.kp, &o->kp}, std::pair{&m.ki, &o->ki}, std::pair{&m.kd, &o->kd},
                            std::pair{&m.i_clamp, &o->i_clamp}, std::pair{&m.volts_at_zero, &o->volts_at_zero},
                            std::pair{&m.rad_per_volt, &o->rad_per_volt}}) {
      if (*from) *to = *from;
    }
  }
  return m;
}

bool has_keys(const ControlOverride& o) {
  return o.kp || o.ki || o.kd || o.i_clamp || o.volts_at_zero || o.rad_per_volt;
}

/// `pid:` and `potentiometer:` of one scope, only the keys it gives.
void control_keys(YAML::Emitter& out, const ControlOverride& o) {
  if (o.kp || o.ki || o.kd || o.i_clamp) {
    out << YAML::Key << "pid" << YAML::Value << YAML::Flow << YAML::BeginMap;
    if (o.kp) out << YAML::Key << "kp" << YAML::Value << num(*o.kp);
    if (o.ki) out << YAML::Key << "ki" << YAML::Value << num(*o.ki);
    if (o.kd) out << YAML::Key << "kd" << YAML::Value << num(*o.kd);
    if (o.i_clamp) out << YAML::Key << "i_clamp" << YAML::Value << num(*o.i_clamp);
    out << YAML::EndMap;
  }
  if (o.volts_at_zero || o.rad_per_volt) {
    out << YAML::Key << "potentiometer" << YAML::Value << YAML::Flow << YAML::BeginMap;
    if (o.volts_at_zero) out << YAML::Key << "volts_at_zero" << YAML::Value << num(*o.volts_at_zero);
    if (o.rad_per_volt) out << YAML::Key << "rad_per_volt" << YAML::Value << num(*o.rad_per_volt);
    out << YAML::EndMap;
  }
}

void controller(YAML::Emitter& out, const Design& d, const ControllerSettings& c) {
  out << YAML::Key << "controller" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "node" << YAML::Value << YAML::DoubleQuoted << c.node;
  out << YAML::Key << "loop_rate_hz" << YAML::Value << num(c.loop_rate_hz);
  out << YAML::Key << "pwm_hz" << YAML::Value << num(c.pwm_hz);
  out << YAML::Key << "adc" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "bits" << YAML::Value << c.adc_bits;
  out << YAML::Key << "range_v" << YAML::Value << YAML::Flow << YAML::BeginSeq << num(c.adc_range_v[0])
      << num(c.adc_range_v[1]) << YAML::EndSeq;
  out << YAML::EndMap;
  out << YAML::Key << "max_velocity_deg_s" << YAML::Value << deg(c.max_velocity);
  out << YAML::Key << "collision_priority" << YAML::Value << YAML::DoubleQuoted << c.collision_priority;
  out << YAML::Key << "min_lci" << YAML::Value << num(c.min_lci);
  ControlOverride defaults;
  defaults.kp = c.pid.kp, defaults.ki = c.pid.ki, defaults.kd = c.pid.kd, defaults.i_clamp = c.pid.i_clamp;
  defaults.volts_at_zero = c.potentiometer.volts_at_zero, defaults.rad_per_volt = c.potentiometer.rad_per_volt;
  control_keys(out, defaults);

  // Overrides in canonical form: every station's mechanisms, then by station (design order), then
  // mechanism, then joint.
  const auto scope = [&](const std::string& station, const std::string& mechanism, int joint) {
    std::vector<const ControlOverride*> found;
    for (const ControlOverride& o : c.overrides) {
      if (o.station == station && o.mechanism == mechanism && o.joint == joint) found.push_back(&o);
    }
    return merged(found);
  };
  // One mechanism's scope and its joints under an open map; false when it gives nothing.
  const auto mechanism_scope = [&](const std::string& station, const char* mechanism, const auto& open) {
    const ControlOverride mech_keys = scope(station, mechanism, 0);
    const ControlOverride joint_keys[2] = {scope(station, mechanism, 1), scope(station, mechanism, 2)};
    if (!has_keys(mech_keys) && !has_keys(joint_keys[0]) && !has_keys(joint_keys[1])) return;
    open();
    out << YAML::Key << mechanism << YAML::Value << YAML::BeginMap;
    control_keys(out, mech_keys);
    for (int j = 0; j < 2; ++j) {
      if (!has_keys(joint_keys[j])) continue;
      out << YAML::Key << ("theta" + std::to_string(j + 1)) << YAML::Value << YAML::BeginMap;
      control_keys(out, joint_keys[j]);
      out << YAML::EndMap;
    }
    out << YAML::EndMap;
  };
  bool mechanisms_open = false;
  for (const char* mechanism : {"lower", "upper"}) {
    mechanism_scope("", mechanism, [&] {
      if (!mechanisms_open) out << YAML::Key << "mechanisms" << YAML::Value << YAML::BeginMap, mechanisms_open = true;
    });
  }
  if (mechanisms_open) out << YAML::EndMap;

  bool any = false;
  for (const Station& s : d.stations) {
    const ControlOverride station_keys = scope(s.name, "", 0);
    bool station_open = false;
    const auto open_station = [&] {
      if (!any) out << YAML::Key << "stations" << YAML::Value << YAML::BeginMap, any = true;
      if (!station_open) out << YAML::Key << s.name << YAML::Value << YAML::BeginMap, station_open = true;
    };
    if (has_keys(station_keys)) {
      open_station();
      control_keys(out, station_keys);
    }
    for (const char* mechanism : {"lower", "upper"}) mechanism_scope(s.name, mechanism, open_station);
    if (station_open) out << YAML::EndMap;
  }
  if (any) out << YAML::EndMap;
  out << YAML::EndMap;
}

}  // namespace

std::string to_yaml(const Design& d) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "name" << YAML::Value << d.name;
  out << YAML::Key << "stations" << YAML::Value << YAML::BeginMap;
  for (const Station& s : d.stations) {
    out << YAML::Key << s.name << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "target" << YAML::Value << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "center" << YAML::Value;
    point(out, s.target.center);
    out << YAML::Key << "axes" << YAML::Value;
    point(out, s.target.axes);
    out << YAML::Key << "angle" << YAML::Value << deg(s.target.angle);
    out << YAML::EndMap;
    out << YAML::Key << "mechanisms" << YAML::Value << YAML::BeginMap;
    if (s.lower) {
      out << YAML::Key << "lower" << YAML::Value;
      mechanism(out, *s.lower);
    }
    if (s.upper) {
      out << YAML::Key << "upper" << YAML::Value;
      mechanism(out, *s.upper);
    }
    out << YAML::EndMap << YAML::EndMap;
  }
  out << YAML::EndMap;
  if (d.geometry) {
    const Geometry& g = *d.geometry;
    out << YAML::Key << "geometry" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "link_width" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (double w : g.link_width) out << num(w);
    out << YAML::EndSeq;
    out << YAML::Key << "link_thickness" << YAML::Value << num(g.link_thickness);
    out << YAML::Key << "pin_diameter" << YAML::Value << num(g.pin_diameter);
    out << YAML::Key << "boss_diameter" << YAML::Value << num(g.boss_diameter);
    out << YAML::Key << "tactor_diameter" << YAML::Value << num(g.tactor_diameter);
    out << YAML::Key << "tactor_height" << YAML::Value << num(g.tactor_height);
    out << YAML::Key << "layers" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (int l : g.layers) out << l;
    out << YAML::EndSeq;
    out << YAML::Key << "layer_gap" << YAML::Value << num(g.layer_gap);
    out << YAML::Key << "motor_shaft_diameter" << YAML::Value << num(g.motor_shaft_diameter);
    out << YAML::Key << "motor_shaft_flat" << YAML::Value << num(g.motor_shaft_flat);
    out << YAML::Key << "min_clearance" << YAML::Value << num(g.min_clearance);
    out << YAML::EndMap;
  }
  if (d.print) {
    const PrintSettings& p = *d.print;
    out << YAML::Key << "print" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "material" << YAML::Value << YAML::DoubleQuoted << p.material;
    out << YAML::Key << "pin_clearance" << YAML::Value << num(p.pin_clearance);
    out << YAML::Key << "min_wall" << YAML::Value << num(p.min_wall);
    out << YAML::Key << "layer_height" << YAML::Value << num(p.layer_height);
    out << YAML::Key << "fn" << YAML::Value << p.fn;
    out << YAML::EndMap;
  }
  if (d.sweep) {
    const SweepSettings& sw = *d.sweep;
    out << YAML::Key << "sweep" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "station" << YAML::Value << sw.station;
    if (!sw.mechanism.empty()) out << YAML::Key << "mechanism" << YAML::Value << sw.mechanism;
    out << YAML::Key << "vary" << YAML::Value << YAML::BeginMap;
    for (const SweepVariable& v : sw.vary) {
      out << YAML::Key << v.name << YAML::Value << YAML::Flow << YAML::BeginSeq << num(v.lo) << num(v.hi) << v.n
          << YAML::EndSeq;
    }
    out << YAML::EndMap;
    out << YAML::Key << "sample" << YAML::Value << sw.sample;
    if (sw.count) out << YAML::Key << "count" << YAML::Value << sw.count;
    out << YAML::Key << "seed" << YAML::Value << sw.seed;
    out << YAML::Key << "objectives" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const auto& o : sw.objectives) out << o;
    out << YAML::EndSeq;
    out << YAML::Key << "collision_spacing_mm" << YAML::Value << num(sw.collision_spacing_mm);
    out << YAML::EndMap;
  }
  if (d.patterns) patterns(out, *d.patterns, d.controller.has_value());
  if (d.controller) controller(out, d, *d.controller);
  if (d.products) {
    out << YAML::Key << "products" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const auto& p : *d.products) out << p;
    out << YAML::EndSeq;
  }
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

}  // namespace fivebar
