#include "fivebar/format.hpp"
#include "sections/rules.hpp"

#include "fivebar/ranges.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>

namespace fivebar::rules {

std::string format_number(double value) { return format::shortest(value); }

std::string format_degrees(double radians) {
  if (!std::isfinite(radians)) return format_number(radians);
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.12g", radians * format::kDegPerRad);
  return buffer;
}

std::string plain_number(double v) {
  if (!std::isfinite(v)) return format_number(v);
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.12g", v);
  return buffer;
}

void check_length(const std::string& key, double value_mm) {
  if (const auto rule = ranges::length_rule(value_mm)) {
    throw ValidationError(key, "= " + format_number(value_mm) + " mm: " + *rule);
  }
}

void check_coordinate(const std::string& key, double value_mm) {
  if (const auto rule = ranges::coordinate_rule(value_mm)) {
    throw ValidationError(key, "= " + format_number(value_mm) + " mm: " + *rule);
  }
}

void check_point(const char* key, const Vec2& p_mm) {
  // Keys are built only on failure: sweeps validate millions of designs.
  auto ok = [](double v) { return std::isfinite(v) && std::abs(v) <= kMaxLengthMm; };
  if (!ok(p_mm.x())) check_coordinate(detail::key_index(key, 0), p_mm.x());
  if (!ok(p_mm.y())) check_coordinate(detail::key_index(key, 1), p_mm.y());
}

void require_length(const std::string& key, double v, double lo_exclusive, double hi) {
  if (!(v > lo_exclusive) || !(v <= hi)) {
    std::ostringstream s;
    s << "= " << v << " mm: must be > " << lo_exclusive << " and <= " << hi << " mm";
    throw ValidationError(key, s.str());
  }
}

void require_range(const std::string& key, double v, double lo_exclusive, double hi, std::string_view unit) {
  if (!(v > lo_exclusive) || !(v <= hi)) {
    std::ostringstream s;
    s << "= " << plain_number(v) << (unit.empty() ? "" : " ") << unit << ": must be > " << plain_number(lo_exclusive)
      << " and <= " << plain_number(hi) << (unit.empty() ? "" : " ") << unit;
    throw ValidationError(key, s.str());
  }
}

std::string joined(const std::vector<std::string>& items) { return format::join(items); }

std::string station_list(const Design& design) {
  std::string list;
  for (const Station& s : design.stations) list += (list.empty() ? "" : ", ") + s.name;
  return list;
}

}  // namespace fivebar::rules
