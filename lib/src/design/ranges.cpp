#include "fivebar/ranges.hpp"

#include <cmath>

namespace fivebar::ranges {

std::optional<std::string> length_rule(double v) {
  if (!std::isfinite(v)) return "must be finite";
  if (!(v > 0.0)) return "must be > 0";
  if (v < kMinLengthMm) return "must be >= 1e-09 mm (the smallest length fivebar computes with)";
  if (v > kMaxLengthMm) return "must be <= 1e12";
  return std::nullopt;
}

std::optional<std::string> coordinate_rule(double v) {
  if (!std::isfinite(v)) return "must be finite";
  if (std::abs(v) > kMaxLengthMm) return "must be within [-1e12, 1e12]";
  return std::nullopt;
}

}  // namespace fivebar::ranges
