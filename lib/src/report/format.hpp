#pragma once
// Number formatting shared by the report's text tables and summaries (private).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "fivebar/format.hpp"

namespace fivebar::report_fmt {

/// Scientific with `digits` decimals ("1.2e-15"); "0" for zero.
inline std::string sci(double v, int digits = 1) {
  return v == 0.0 ? "0" : format::sci(v, digits);
}
inline std::string sci(const std::optional<double>& v, int digits = 1) { return v ? sci(*v, digits) : "—"; }

/// Fixed-point with `digits` decimals ("-0.000" printed as "0.000").
inline std::string fixed(double v, int digits = 3) { return format::fixed(v, digits); }

/// A number with the significant digits that an uncertainty `err` leaves (at least 1 decimal
/// place of the error's leading digit), e.g. value 512.3412, err 0.02 -> "512.34".
inline std::string with_error_digits(double value, double err, int max_decimals = 12) {
  int decimals = 3;
  if (err > 0.0 && std::isfinite(err)) decimals = std::clamp(int(std::ceil(-std::log10(err))) + 1, 0, max_decimals);
  return fixed(value, decimals);
}

/// "[1e-3, 1e-1)"
inline std::string range(double lo, double hi) {
  auto f = [](double v) {
    if (v == 0.0) return std::string("0");
    if (v >= 1.0) return std::string("1");
    char buf[16];
    std::snprintf(buf, sizeof buf, "1e%d", int(std::lround(std::log10(v))));
    return std::string(buf);
  };
  return "[" + f(lo) + ", " + f(hi) + (hi >= 1.0 ? "]" : ")");
}

/// Pads or cuts to width (left-aligned, or right-aligned when right).
inline std::string pad(const std::string& s, std::size_t width, bool right = false) {
  // Count UTF-8 code points so that "mm²" and "—" align.
  std::size_t cps = 0;
  for (unsigned char c : s) cps += (c & 0xC0) != 0x80;
  if (cps >= width) return s;
  const std::string fill(width - cps, ' ');
  return right ? fill + s : s + fill;
}

}  // namespace fivebar::report_fmt
