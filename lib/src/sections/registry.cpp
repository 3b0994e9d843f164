// The list of design sections (sections.def) and the Out tree's scalar forms.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>

#include "fivebar/format.hpp"
#include "sections/section.hpp"

namespace fivebar::sections {

const std::vector<Section>& all() {
  static const std::vector<Section> list = {
#define FIVEBAR_SECTION(key) key##_section(),
#include "sections/sections.def"
#undef FIVEBAR_SECTION
  };
  return list;
}

const std::vector<const Section*>& in_load_order() {
  static const std::vector<const Section*> order = [] {
    std::vector<const Section*> out;
    const auto visit = [&out](const Section& s, const auto& self) -> void {
      if (std::find(out.begin(), out.end(), &s) != out.end()) return;
      for (const Section& other : all()) {
        if (other.key == s.reads) self(other, self);
      }
      out.push_back(&s);
    };
    for (const Section& s : all()) visit(s, visit);
    return out;
  }();
  return order;
}

const Value* find(const std::vector<Value>& entries, std::string_view name) {
  for (const Value& e : entries) {
    if (e.name() == name) return &e;
  }
  return nullptr;
}

const Value& require(const std::vector<Value>& entries, std::string_view name, const Value& map) {
  const Value* e = find(entries, name);
  if (e == nullptr) map.fail_missing(name);
  return *e;
}

double number_or(const std::vector<Value>& entries, std::string_view name, double fallback, std::string_view unit) {
  const Value* e = find(entries, name);
  return e ? e->number(unit) : fallback;
}

Out Out::number(double v) { return plain(format::shortest(v)); }

Out Out::integer(long long v) { return plain(std::to_string(v)); }

Out Out::degrees(double rad) {
  for (int digits = 12; digits <= 17; ++digits) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.*g", digits, rad * format::kDegPerRad);
    double v = std::strtod(buf, nullptr);
    if (v == 0.0) v = 0.0;  // no "-0"
    if (v * format::kRadPerDeg == rad || digits == 17) return number(v);
  }
  return number(rad * format::kDegPerRad);
}

Out Out::point(const Vec2& p) {
  Out o = list(true);
  o.push(number(p.x()));
  o.push(number(p.y()));
  return o;
}

Out& Out::add(std::string key, Out value) {
  entries.push_back(Entry{std::move(key), std::move(value)});
  return entries.back().second;
}

Out& Out::push(Out value) {
  entries.push_back(Entry{std::string(), std::move(value)});
  return entries.back().second;
}

}  // namespace fivebar::sections
