#pragma once
/// The numeric ranges fivebar accepts, one rule for design files and the command line
/// (docs/reliability.md "Numeric ranges"). Inside them every answer is exact to the accuracy the
/// accuracy report states: the kinematics scale by exact powers of two, squared lengths stay far
/// from overflow (1e24) and from underflow (1e-18), and conditioning figures are scale-free. Outside
/// them a value is bad input (exit 2), never a NaN or a wrong verdict.

#include <optional>
#include <string>

namespace fivebar::ranges {

/// Smallest length (link, axis, spacing) a design or command may give, mm: a nanometre, six orders
/// below any printable part.
inline constexpr double kMinLengthMm = 1e-9;
/// Largest length, and largest |coordinate| of a point, mm.
inline constexpr double kMaxLengthMm = 1e12;

/// Why `v` is not an admissible length ("must be >= 1e-09 mm"), or nothing when it is.
std::optional<std::string> length_rule(double v_mm);
/// Why `v` is not an admissible coordinate ("must be within [-1e12, 1e12] mm"), or nothing.
std::optional<std::string> coordinate_rule(double v_mm);

}  // namespace fivebar::ranges
