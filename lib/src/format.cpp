#include "fivebar/format.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>

namespace fivebar::format {

double rad_from_deg(double deg) {
  // Up to one turn the plain product (bit-identical to what every angle gave before); beyond it
  // the exact remainder, so that no multiple of 360 deg is rounded into a different pose.
  return (std::abs(deg) <= 360.0 ? deg : std::remainder(deg, 360.0)) * kRadPerDeg;
}

std::string shortest(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

std::string fixed(double value, int digits) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
  std::string s = buffer;
  if (s.front() == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

namespace {
/// printf of one double; a result that reads as zero (every digit 0) never carries a sign.
std::string unsigned_zero(const char* spec, int digits, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, spec, digits, value);
  std::string s = buffer;
  if (s.front() == '-') {
    const std::size_t e = s.find_first_of("eE");
    const std::string mantissa = s.substr(0, e);
    if (mantissa.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  }
  return s;
}
}  // namespace

std::string general(double value, int significant) { return unsigned_zero("%.*g", significant, value); }

std::string sci(double value, int digits) { return unsigned_zero("%.*e", digits, value); }

std::string join(const std::vector<std::string>& items, std::string_view separator) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (i > 0) out += separator;
    out += items[i];
  }
  return out;
}

std::string xml_escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

std::uint64_t fnv1a64(std::string_view bytes, std::uint64_t hash) {
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
  return hash;
}

}  // namespace fivebar::format
