// Design -> design file (YAML): the stations here, each section through its writer hook
// (lib/src/sections/). yaml-cpp emits the structure; numbers are formatted here in their
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
#include "sections/section.hpp"

namespace fivebar {

namespace {

std::string num(double v) { return sections::Out::number(v).text; }
std::string deg(double rad) { return sections::Out::degrees(rad).text; }

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

/// Emits a tree built by a section's writer (lib/src/sections/section.hpp).
void emit(YAML::Emitter& out, const sections::Out& o) {
  using Kind = sections::Out::Kind;
  switch (o.kind) {
    case Kind::plain: out << o.text; return;
    case Kind::quoted: out << YAML::DoubleQuoted << o.text; return;
    case Kind::list:
      if (o.flow) out << YAML::Flow;
      out << YAML::BeginSeq;
      for (const auto& item : o.entries) emit(out, item.second);
      out << YAML::EndSeq;
      return;
    case Kind::map:
      if (o.flow) out << YAML::Flow;
      out << YAML::BeginMap;
      for (const auto& [key, value] : o.entries) {
        out << YAML::Key << key << YAML::Value;
        emit(out, value);
      }
      out << YAML::EndMap;
      return;
  }
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
  // The sections, in the order of sections.def, each through its own writer.
  sections::Out top = sections::Out::map();
  for (const sections::Section& section : sections::all()) section.write(d, top);
  for (const auto& [key, value] : top.entries) {
    out << YAML::Key << key << YAML::Value;
    emit(out, value);
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
