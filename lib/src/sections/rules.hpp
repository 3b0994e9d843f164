#pragma once
/// Validation rules shared by the design model (lib/src/design/design.cpp) and the section modules
/// (lib/src/sections/*.cpp): one wording for every "must be" message, values in file units.
/// Private to the library.

#include <string>
#include <string_view>

#include "design/design_keys.hpp"
#include "fivebar/design.hpp"
#include "fivebar/ranges.hpp"

namespace fivebar::rules {

/// Largest admissible length or |coordinate|, mm (fivebar/ranges.hpp).
inline constexpr double kMaxLengthMm = ranges::kMaxLengthMm;

/// Shortest text that reads back as the same double ("-3", "12.5", "1e+13", "nan").
std::string format_number(double value);
/// Radians shown in degrees, rounded so that a value typed in degrees reads back as typed.
std::string format_degrees(double radians);
/// A value for messages as a person types it: 100000, 0.15, 1e-09.
std::string plain_number(double value);

/// A length in [ranges::kMinLengthMm, ranges::kMaxLengthMm], mm.
void check_length(const std::string& key, double value_mm);
/// A coordinate within [-kMaxLengthMm, kMaxLengthMm], mm.
void check_coordinate(const std::string& key, double value_mm);
/// Both coordinates of a point (`key`[0], `key`[1]).
void check_point(const char* key, const Vec2& p_mm);
/// lo_exclusive < v <= hi, mm (message in the stream form "= 3 mm: must be > 0 and <= 1000 mm").
void require_length(const std::string& key, double v, double lo_exclusive, double hi);
/// lo_exclusive < v <= hi in `unit`.
void require_range(const std::string& key, double v, double lo_exclusive, double hi, std::string_view unit);

/// Runs a nested validate() and re-throws its error with the key prefixed by `prefix`.
template <class F>
void validate_nested(std::string_view prefix, F&& validate) {
  try {
    validate();
  } catch (const ValidationError& e) {
    throw ValidationError(detail::key_join(prefix, e.key()), e.rule());
  }
}

/// "a, b, c".
std::string joined(const std::vector<std::string>& items);
/// The design's station names, "index, thumb", for messages.
std::string station_list(const Design& design);

}  // namespace fivebar::rules
