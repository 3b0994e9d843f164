// Design -> design file (YAML). yaml-cpp emits the structure; numbers are formatted here in their
// shortest round-trip form (yaml-cpp would print 0.1 as 0.10000000000000001), angles in degrees
// rounded to 12 significant digits so that a value typed in degrees reads back as typed.
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

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
    out << YAML::EndSeq << YAML::EndMap;
  }
  if (d.products) {
    out << YAML::Key << "products" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const auto& p : *d.products) out << p;
    out << YAML::EndSeq;
  }
  out << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

}  // namespace fivebar
