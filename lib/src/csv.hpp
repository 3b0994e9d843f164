#pragma once
// CSV cells shared by the sweep's, the optimiser's and bench_replay's files (private to lib): numbers in their
// shortest round-trip form, empty for "no value"; text quoted when it holds a comma, a quote or a
// line break (RFC 4180; a line break becomes a space so that a row stays one line).

#include <cmath>
#include <string>
#include <string_view>

#include "fivebar/format.hpp"

namespace fivebar::csv {

inline std::string number(double v) { return std::isnan(v) ? std::string() : format::shortest(v); }

inline std::string field(std::string_view s) {
  if (s.find_first_of(",\"\n") == std::string_view::npos) return std::string(s);
  std::string out = "\"";
  for (char c : s) {
    if (c == '"') out += '"';
    out += c == '\n' ? ' ' : c;
  }
  return out + "\"";
}

}  // namespace fivebar::csv
