// The design model: mode strings, joint ranges, and the validate() of stations, mechanisms and the
// whole design. The sections beside the stations validate themselves (lib/src/sections/).
// Validation messages name the key relative to the validated struct, the value (in file units:
// mm and degrees) and the limit; Station and Design prefix the keys of what they contain.

#include "fivebar/design.hpp"

#include <sstream>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "design/design_keys.hpp"
#include "fivebar/design/angles.hpp"
#include "fivebar/numerics.hpp"
#include "fivebar/ranges.hpp"
#include "sections/rules.hpp"
#include "sections/section.hpp"

namespace fivebar {

using rules::check_length;
using rules::check_point;
using rules::format_degrees;
using rules::format_number;
using rules::validate_nested;
using rules::kMaxLengthMm;

namespace {

using angles::kTwoPi;

/// Two joint-limit angles are the same (mod 2 pi) when their ccw difference is within this many
/// ulps of the largest magnitude involved: degree -> radian conversion rounds each one by ~1 ulp,
/// so lo = 10 deg, hi = 370 deg must still count as equal.
constexpr double kAngleEqualUlps = 16.0;

constexpr std::size_t kMaxNameLength = 64;

constexpr const char* kSafeNameRule =
    "must be a safe file name: 1 to 64 characters from A-Z a-z 0-9 _ . -, "
    "not starting with '.' or '-'";

bool is_plain_word(std::string_view name) {
  return !name.empty() && std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-';
  });
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Key paths

namespace detail {

std::string key_child(std::string_view parent, std::string_view name) {
  std::string key(parent);
  if (is_plain_word(name)) {
    if (!key.empty()) key += '.';
    key += name;
    return key;
  }
  key += "[\"";
  for (char c : name) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) {  // a name from a file must not bring line breaks or terminal escapes
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\x%02x", static_cast<unsigned>(u));
      key += escaped;
      continue;
    }
    if (c == '"' || c == '\\') key += '\\';
    key += c;
  }
  key += "\"]";
  return key;
}

std::string key_index(std::string_view parent, std::size_t i) {
  return std::string(parent) + "[" + std::to_string(i) + "]";
}

std::string key_join(std::string_view parent, std::string_view relative) {
  if (parent.empty()) return std::string(relative);
  if (relative.empty()) return std::string(parent);
  if (relative.front() == '[') return std::string(parent) + std::string(relative);
  return std::string(parent) + "." + std::string(relative);
}

std::string key_parent(std::string_view key) {
  // Scan forward: components are `name`, `.name`, `[digits]` and `["text"]` (with \" escapes).
  std::size_t last_start = 0;
  std::size_t i = 0;
  while (i < key.size()) {
    last_start = i;
    if (key[i] == '[') {
      if (i + 1 < key.size() && key[i + 1] == '"') {
        i += 2;
        while (i < key.size() && key[i] != '"') i += (key[i] == '\\') ? 2 : 1;
        i += 2;  // closing quote and bracket
      } else {
        while (i < key.size() && key[i] != ']') ++i;
        ++i;
      }
    } else {
      if (key[i] == '.') ++i;
      while (i < key.size() && key[i] != '.' && key[i] != '[') ++i;
    }
  }
  return std::string(key.substr(0, std::min(last_start, key.size())));
}

std::string quoted(std::string_view text) {
  // Messages stay readable whatever a file holds: long text is cut and its length given.
  constexpr std::size_t kShown = 100;
  std::string suffix;
  if (text.size() > kShown) {
    suffix = "...' (" + std::to_string(text.size()) + " bytes)";
    std::size_t cut = kShown - 3;
    while (cut > 0 && (static_cast<unsigned char>(text[cut]) & 0xC0u) == 0x80u) --cut;  // UTF-8 boundary
    text = text.substr(0, cut);
  }
  std::string out = "'";
  for (char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) {
      char buffer[8];
      std::snprintf(buffer, sizeof buffer, "\\x%02x", static_cast<unsigned>(u));
      out += buffer;
    } else {
      out += c;
    }
  }
  out += suffix.empty() ? "'" : suffix;
  return out;
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------
// Modes

std::optional<WorkingMode> parse_working_mode(std::string_view text) {
  if (text.size() != 2) return std::nullopt;
  auto sign = [](char c) -> std::optional<std::int8_t> {
    if (c == '+') return std::int8_t{+1};
    if (c == '-') return std::int8_t{-1};
    return std::nullopt;
  };
  const auto s1 = sign(text[0]);
  const auto s2 = sign(text[1]);
  if (!s1 || !s2) return std::nullopt;
  return WorkingMode{*s1, *s2};
}

std::string to_string(WorkingMode mode) {
  std::string text;
  text += mode.sign1 > 0 ? '+' : '-';
  text += mode.sign2 > 0 ? '+' : '-';
  return text;
}

std::array<WorkingMode, 4> all_working_modes() {
  return {WorkingMode{+1, +1}, WorkingMode{+1, -1}, WorkingMode{-1, +1}, WorkingMode{-1, -1}};
}

std::optional<AssemblyMode> parse_assembly_mode(std::string_view text) {
  if (text == "+") return AssemblyMode::Plus;
  if (text == "-") return AssemblyMode::Minus;
  if (text == "any") return AssemblyMode::Any;
  return std::nullopt;
}

std::string to_string(AssemblyMode mode) {
  switch (mode) {
    case AssemblyMode::Plus: return "+";
    case AssemblyMode::Minus: return "-";
    case AssemblyMode::Any: break;
  }
  return "any";
}

// ---------------------------------------------------------------------------------------------
// JointRange

double JointRange::span() const {
  const double d = angles::wrap_two_pi(hi - lo);
  return d > 0.0 ? d : kTwoPi;
}

bool JointRange::contains(double angle, double tol) const {
  const double offset = angles::wrap_two_pi(angle - lo);  // ccw from lo, in [0, 2 pi)
  return offset <= span() + tol || offset >= kTwoPi - tol;
}

// ---------------------------------------------------------------------------------------------
// Mechanism

double Mechanism::length_scale() const {
  return std::max({L[0], L[1], L[2], L[3], (O2 - O1).norm()});
}

void Mechanism::validate() const {
  // Coincident base joints are allowed: degenerate, but valid (extreme-case tests use them).
  check_point("bases[0]", O1);
  check_point("bases[1]", O2);
  for (std::size_t i = 0; i < L.size(); ++i) {
    if (!(L[i] >= ranges::kMinLengthMm && L[i] <= kMaxLengthMm)) check_length(detail::key_index("links", i), L[i]);
  }

  auto valid_sign = [](std::int8_t s) { return s == 1 || s == -1; };
  if (!valid_sign(working_mode.sign1) || !valid_sign(working_mode.sign2)) {
    throw ValidationError("working_mode", "= (" + std::to_string(working_mode.sign1) + ", " +
                                              std::to_string(working_mode.sign2) +
                                              "): both signs must be +1 or -1");
  }
  if (assembly_mode != AssemblyMode::Plus && assembly_mode != AssemblyMode::Minus &&
      assembly_mode != AssemblyMode::Any) {
    throw ValidationError("assembly_mode", "= " + std::to_string(static_cast<int>(assembly_mode)) +
                                               ": must be \"+\", \"-\" or \"any\"");
  }

  if (joint_limits) {
    for (std::size_t i = 0; i < 2; ++i) {
      const JointRange& range = (*joint_limits)[i];
      const auto key_of = [i] { return detail::key_index("joint_limits", i); };
      for (std::size_t j = 0; j < 2; ++j) {
        const double angle = j == 0 ? range.lo : range.hi;
        if (!std::isfinite(angle)) {
          throw ValidationError(detail::key_index(key_of(), j), "= " + format_number(angle) + " deg: must be finite");
        }
      }
      const double d = angles::wrap_two_pi(range.hi - range.lo);
      const double tol = kAngleEqualUlps * tol::kEps * std::max({kTwoPi, std::abs(range.lo), std::abs(range.hi)});
      if (d <= tol || d >= kTwoPi - tol) {
        throw ValidationError(key_of(), "= [" + format_degrees(range.lo) + ", " + format_degrees(range.hi) +
                                            "] deg: lo and hi must differ (mod 360)");
      }
    }
  }

  if (!(min_lci >= 0.0 && min_lci <= 1.0)) {  // also rejects NaN
    throw ValidationError("min_lci", "= " + format_number(min_lci) + ": must be in [0, 1]");
  }
}

// ---------------------------------------------------------------------------------------------
// Ellipse

void Ellipse::validate() const {
  check_point("center", center);
  check_length("axes[0]", axes.x());
  check_length("axes[1]", axes.y());
  if (!std::isfinite(angle)) throw ValidationError("angle", "= " + format_number(angle) + " deg: must be finite");
}

Vec2 Ellipse::boundary_point(double t) const {
  const Vec2 p_ellipse(0.5 * axes.x() * std::cos(t), 0.5 * axes.y() * std::sin(t));
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  return center + Vec2(c * p_ellipse.x() - s * p_ellipse.y(), s * p_ellipse.x() + c * p_ellipse.y());
}

// ---------------------------------------------------------------------------------------------
// Station

void Station::validate() const {
  validate_nested("target", [&] { target.validate(); });
  if (!lower && !upper) throw ValidationError("mechanisms", "must contain at least one of lower, upper");
  if (lower) validate_nested("mechanisms.lower", [&] { lower->validate(); });
  if (upper) validate_nested("mechanisms.upper", [&] { upper->validate(); });
}

std::vector<const Mechanism*> Station::mechanisms() const {
  std::vector<const Mechanism*> present;
  if (lower) present.push_back(&*lower);
  if (upper) present.push_back(&*upper);
  return present;
}

const Mechanism* Station::mechanism(std::string_view which) const {
  if (which == "lower") return lower ? &*lower : nullptr;
  if (which == "upper") return upper ? &*upper : nullptr;
  return nullptr;
}

// ---------------------------------------------------------------------------------------------
// Design

bool is_safe_name(std::string_view name) {
  if (name.empty() || name.size() > kMaxNameLength) return false;
  if (name.front() == '.' || name.front() == '-') return false;  // also excludes "." and ".."
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '.' || c == '-';
  });
}

void Design::validate() const {
  if (!is_safe_name(name)) throw ValidationError("name", "= " + detail::quoted(name) + ": " + kSafeNameRule);

  if (stations.empty()) throw ValidationError("stations", "must contain at least one station");
  for (std::size_t i = 0; i < stations.size(); ++i) {
    const Station& station = stations[i];
    const std::string key = detail::key_child("stations", station.name);
    if (!is_safe_name(station.name)) {
      throw ValidationError(key, "station name " + detail::quoted(station.name) + " " + kSafeNameRule);
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (stations[j].name == station.name) {
        throw ValidationError(key, "station name " + detail::quoted(station.name) + " is used twice (stations " +
                                       std::to_string(j) + " and " + std::to_string(i) + ")");
      }
    }
    validate_nested(key, [&] { station.validate(); });
  }

  for (const sections::Section* section : sections::in_load_order()) section->validate(*this);
  if (products) {
    // Which names exist is the scene's to say (fivebar/scene.hpp validate_products()).
    for (std::size_t i = 0; i < products->size(); ++i) {
      const std::string& product = (*products)[i];
      const std::string key = detail::key_index("products", i);
      for (std::size_t j = 0; j < i; ++j) {
        if ((*products)[j] == product) {
          throw ValidationError(key, "= " + detail::quoted(product) + ": listed twice (also products[" +
                                         std::to_string(j) + "])");
        }
      }
    }
  }
}

const Station* Design::station(std::string_view wanted) const {
  for (const Station& s : stations) {
    if (s.name == wanted) return &s;
  }
  return nullptr;
}

const Station& Design::require_station(std::string_view wanted) const {
  if (const Station* s = station(wanted)) return *s;
  std::string names;
  for (const Station& s : stations) names += (names.empty() ? "" : ", ") + s.name;
  throw InputError("unknown station " + detail::quoted(wanted) + " in design '" + name + "' (it has: " + names + ")");
}

std::vector<const Station*> Design::select_stations(std::string_view wanted) const {
  if (!wanted.empty()) return {&require_station(wanted)};
  std::vector<const Station*> out;
  for (const Station& s : stations) {
    if (!s.mechanisms().empty()) out.push_back(&s);
  }
  return out;
}

}  // namespace fivebar
