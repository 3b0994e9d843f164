// The design model: mode strings, joint ranges, and the one validate() of each design struct.
// Validation messages name the key relative to the validated struct, the value (in file units:
// mm and degrees) and the limit; Station and Design prefix the keys of what they contain.

#include "fivebar/design.hpp"

#include <sstream>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "design_keys.hpp"
#include "fivebar/tolerances.hpp"

namespace fivebar {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kDegPerRad = 180.0 / std::numbers::pi;

/// Largest admissible length or |coordinate|, mm. Far beyond any device, it keeps squared lengths
/// (1e24) and sums of them far from overflow, so every later formula stays finite.
constexpr double kMaxLengthMm = 1e12;

/// Two joint-limit angles are the same (mod 2 pi) when their ccw difference is within this many
/// ulps of the largest magnitude involved: degree -> radian conversion rounds each one by ~1 ulp,
/// so lo = 10 deg, hi = 370 deg must still count as equal.
constexpr double kAngleEqualUlps = 16.0;

constexpr std::size_t kMaxNameLength = 64;

constexpr const char* kSafeNameRule =
    "must be a safe file name: 1 to 64 characters from A-Z a-z 0-9 _ . -, "
    "not starting with '.' or '-'";

/// Shortest text that reads back as the same double ("-3", "12.5", "1e+13", "nan").
std::string format_number(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

/// Radians shown in degrees, rounded so that a value typed in degrees reads back as typed.
std::string format_degrees(double radians) {
  if (!std::isfinite(radians)) return format_number(radians);
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.12g", radians * kDegPerRad);
  return buffer;
}

/// Angle reduced to [0, 2 pi).
double wrap_two_pi(double angle) {
  double r = std::fmod(angle, kTwoPi);
  if (r < 0.0) r += kTwoPi;
  if (r >= kTwoPi) r = 0.0;  // r was a tiny negative number
  return r;
}

void check_length(const std::string& key, double value_mm) {
  if (!std::isfinite(value_mm)) throw ValidationError(key, "= " + format_number(value_mm) + " mm: must be finite");
  if (!(value_mm > 0.0)) throw ValidationError(key, "= " + format_number(value_mm) + " mm: must be > 0");
  if (value_mm > kMaxLengthMm) throw ValidationError(key, "= " + format_number(value_mm) + " mm: must be <= 1e12");
}

void check_coordinate(const std::string& key, double value_mm) {
  if (!std::isfinite(value_mm)) throw ValidationError(key, "= " + format_number(value_mm) + " mm: must be finite");
  if (std::abs(value_mm) > kMaxLengthMm) {
    throw ValidationError(key, "= " + format_number(value_mm) + " mm: must be within [-1e12, 1e12]");
  }
}

void check_point(const char* key, const Vec2& p_mm) {
  // Keys are built only on failure: sweeps validate millions of designs.
  auto ok = [](double v) { return std::isfinite(v) && std::abs(v) <= kMaxLengthMm; };
  if (!ok(p_mm.x())) check_coordinate(detail::key_index(key, 0), p_mm.x());
  if (!ok(p_mm.y())) check_coordinate(detail::key_index(key, 1), p_mm.y());
}

/// Runs a nested validate() and re-throws its error with the key prefixed by `prefix`.
template <class F>
void validate_nested(std::string_view prefix, F&& validate) {
  try {
    validate();
  } catch (const ValidationError& e) {
    throw ValidationError(detail::key_join(prefix, e.key()), e.rule());
  }
}

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
  const double d = wrap_two_pi(hi - lo);
  return d > 0.0 ? d : kTwoPi;
}

bool JointRange::contains(double angle, double tol) const {
  const double offset = wrap_two_pi(angle - lo);  // ccw from lo, in [0, 2 pi)
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
    if (!(L[i] > 0.0 && L[i] <= kMaxLengthMm)) check_length(detail::key_index("links", i), L[i]);
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
      const double d = wrap_two_pi(range.hi - range.lo);
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
// Geometry and print settings

namespace {
void require_length(const std::string& key, double v, double lo_exclusive, double hi) {
  if (!(v > lo_exclusive) || !(v <= hi)) {
    std::ostringstream s;
    s << "= " << v << " mm: must be > " << lo_exclusive << " and <= " << hi << " mm";
    throw ValidationError(key, s.str());
  }
}
}  // namespace

void Geometry::validate() const {
  for (std::size_t i = 0; i < 4; ++i) require_length(detail::key_index("link_width", i), link_width[i], 0.0, 1e3);
  require_length("link_thickness", link_thickness, 0.0, 1e3);
  require_length("pin_diameter", pin_diameter, 0.0, 1e3);
  require_length("boss_diameter", boss_diameter, 0.0, 1e3);
  if (!(boss_diameter > pin_diameter)) {
    std::ostringstream s;
    s << "= " << boss_diameter << " mm: must be larger than pin_diameter (" << pin_diameter << " mm)";
    throw ValidationError("boss_diameter", s.str());
  }
  require_length("tactor_diameter", tactor_diameter, 0.0, 1e3);
  require_length("tactor_height", tactor_height, 0.0, 1e3);
  for (std::size_t i = 0; i < 4; ++i) {
    if (layers[i] < 0 || layers[i] > 7) {
      throw ValidationError(detail::key_index("layers", i), "= " + std::to_string(layers[i]) + ": must be 0 ... 7");
    }
  }
  if (!(layer_gap >= 0.0) || !(layer_gap <= 100.0)) {
    throw ValidationError("layer_gap", "= " + std::to_string(layer_gap) + " mm: must be >= 0 and <= 100 mm");
  }
  require_length("motor_shaft_diameter", motor_shaft_diameter, 0.0, 1e3);
  if (!(motor_shaft_flat >= 0.0) || !(motor_shaft_flat < 0.5 * motor_shaft_diameter)) {
    std::ostringstream s;
    s << "= " << motor_shaft_flat << " mm: must be >= 0 and less than the shaft radius ("
      << 0.5 * motor_shaft_diameter << " mm)";
    throw ValidationError("motor_shaft_flat", s.str());
  }
  if (!(min_clearance >= 0.0) || !(min_clearance <= 100.0)) {
    throw ValidationError("min_clearance", "= " + std::to_string(min_clearance) + " mm: must be >= 0 and <= 100 mm");
  }
}

void PrintSettings::validate() const {
  if (!(pin_clearance >= 0.0) || !(pin_clearance <= 1.0)) {
    std::ostringstream s;
    s << "= " << pin_clearance << " mm: must be >= 0 and <= 1 mm (resin guides: 0.1 - 0.25)";
    throw ValidationError("pin_clearance", s.str());
  }
  require_length("min_wall", min_wall, 0.0, 100.0);
  if (fn < 8 || fn > 1024) throw ValidationError("fn", "= " + std::to_string(fn) + ": must be 8 ... 1024");
  require_length("layer_height", layer_height, 0.0, 1.0);
  if (material.empty() || material.size() > 200) throw ValidationError("material", "must be 1 ... 200 characters");
}

// ---------------------------------------------------------------------------------------------
// Sweep settings

const std::vector<std::string>& sweep_variable_names() {
  static const std::vector<std::string> names{"L1", "L2", "L3", "L4", "L12", "L34",
                                              "spacing", "upper_height", "ellipse_a", "ellipse_b"};
  return names;
}

const std::vector<std::string>& sweep_objective_names() {
  static const std::vector<std::string> names{"margin", "min_lci", "force", "footprint", "collision"};
  return names;
}

namespace {
std::string joined(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}
}  // namespace

void SweepSettings::validate() const {
  if (station.empty()) throw ValidationError("station", "is required: the station to sweep");
  if (!mechanism.empty() && mechanism != "lower" && mechanism != "upper") {
    throw ValidationError("mechanism", "= " + detail::quoted(mechanism) + ": must be lower or upper");
  }
  if (vary.empty()) throw ValidationError("vary", "must name at least one variable");
  const auto& names = sweep_variable_names();
  long double grid = 1.0L;
  for (std::size_t i = 0; i < vary.size(); ++i) {
    const SweepVariable& v = vary[i];
    const std::string key = detail::key_child("vary", v.name);
    if (std::find(names.begin(), names.end(), v.name) == names.end()) {
      throw ValidationError(key, "unknown variable (known: " + joined(names) + ")");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (vary[j].name == v.name) throw ValidationError(key, "is varied twice");
    }
    if (!(v.lo > 0.0) || !(v.hi >= v.lo) || !(v.hi <= kMaxLengthMm)) {
      throw ValidationError(key, "= [" + format_number(v.lo) + ", " + format_number(v.hi) +
                                     "] mm: needs 0 < lo <= hi <= 1e12");
    }
    if (v.n < 1 || v.n > 100000000) {
      throw ValidationError(key, "= " + std::to_string(v.n) + " points: must be 1 ... 1e8");
    }
    if (v.lo == v.hi && v.n > 1) throw ValidationError(key, "lo = hi: use n = 1");
    grid *= v.n;
  }
  // Tied and single names must not both move the same link.
  auto has = [&](const char* n) {
    return std::any_of(vary.begin(), vary.end(), [&](const SweepVariable& v) { return v.name == n; });
  };
  if (has("L12") && (has("L1") || has("L2"))) throw ValidationError("vary.L12", "conflicts with L1 / L2");
  if (has("L34") && (has("L3") || has("L4"))) throw ValidationError("vary.L34", "conflicts with L3 / L4");
  if (sample != "grid" && sample != "random" && sample != "sobol") {
    throw ValidationError("sample", "= " + detail::quoted(sample) + ": must be grid, random or sobol");
  }
  if (sample == "grid" && grid > 1e15L) throw ValidationError("vary", "the grid has more than 1e15 designs");
  if (sample != "grid" && count == 0) throw ValidationError("count", "is required for " + sample + " sampling");
  if (count > std::uint64_t(1e15)) throw ValidationError("count", "must be at most 1e15");
  if (!(collision_spacing_mm == 0.0 || (collision_spacing_mm >= 0.05 && collision_spacing_mm <= 1e6))) {
    throw ValidationError("collision_spacing_mm", "= " + format_number(collision_spacing_mm) +
                                                      " mm: must be 0 (off) or 0.05 ... 1e6");
  }
  if (objectives.empty()) throw ValidationError("objectives", "must name at least one objective");
  const auto& known = sweep_objective_names();
  for (std::size_t i = 0; i < objectives.size(); ++i) {
    if (std::find(known.begin(), known.end(), objectives[i]) == known.end()) {
      throw ValidationError(detail::key_index("objectives", i),
                            "= " + detail::quoted(objectives[i]) + ": unknown objective (known: " + joined(known) + ")");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (objectives[j] == objectives[i]) {
        throw ValidationError(detail::key_index("objectives", i), "= " + detail::quoted(objectives[i]) + ": listed twice");
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Patterns

std::string_view to_string(PatternKind kind) {
  switch (kind) {
    case PatternKind::stretch: return "stretch";
    case PatternKind::slip: return "slip";
    case PatternKind::twist: return "twist";
    case PatternKind::pivot: return "pivot";
  }
  return "stretch";
}

std::optional<PatternKind> parse_pattern_kind(std::string_view text) {
  for (PatternKind kind : all_pattern_kinds()) {
    if (text == to_string(kind)) return kind;
  }
  return std::nullopt;
}

std::array<PatternKind, 4> all_pattern_kinds() {
  return {PatternKind::stretch, PatternKind::slip, PatternKind::twist, PatternKind::pivot};
}

namespace {

/// Most samples one pattern may have (10 minutes at 1 kHz is 600000).
constexpr double kMaxPatternSamples = 1e6;

/// duration * rate within this many intervals of a whole number counts as that number: 0.29 s at
/// 100 Hz is 28.999999999999996 intervals in doubles and must give 29, not 28.
constexpr double kSampleCountSlack = 1e-9;

/// A value for messages as a person types it: 100000, 0.15, 1e-09.
std::string plain_number(double v) {
  if (!std::isfinite(v)) return format_number(v);
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.12g", v);
  return buffer;
}

void require_range(const std::string& key, double v, double lo_exclusive, double hi, std::string_view unit) {
  if (!(v > lo_exclusive) || !(v <= hi)) {
    std::ostringstream s;
    s << "= " << plain_number(v) << (unit.empty() ? "" : " ") << unit << ": must be > " << plain_number(lo_exclusive)
      << " and <= " << plain_number(hi) << (unit.empty() ? "" : " ") << unit;
    throw ValidationError(key, s.str());
  }
}

}  // namespace

std::size_t PatternSpec::samples() const {
  return static_cast<std::size_t>(std::floor(duration_s * rate_hz + kSampleCountSlack)) + 1;
}

void PatternSpec::validate() const {
  if (kind != PatternKind::pivot) require_range("amplitude_mm", amplitude_mm, 0.0, 1e3, "mm");
  require_range("duration_s", duration_s, 0.0, 3600.0, "s");
  require_range("rate_hz", rate_hz, 0.0, 1e4, "Hz");
  if (duration_s * rate_hz > kMaxPatternSamples) {
    std::ostringstream s;
    s << "= " << plain_number(duration_s) << " s: at rate_hz " << plain_number(rate_hz)
      << " that is more than 1000000 samples";
    throw ValidationError("duration_s", s.str());
  }
  if (centre) check_point("centre", *centre);
  if (!(separation_mm >= 0.0) || !(separation_mm <= 1e3)) {
    throw ValidationError("separation_mm", "= " + plain_number(separation_mm) + " mm: must be >= 0 and <= 1000 mm");
  }
  if (kind == PatternKind::twist && !(separation_mm > 0.0)) {
    throw ValidationError("separation_mm", "= " + plain_number(separation_mm) +
                                               " mm: twist turns the tactors on a circle of diameter separation_mm: "
                                               "must be > 0");
  }
  if (kind == PatternKind::pivot) {
    if (!(pivot_amplitude > 0.0) || !(pivot_amplitude <= std::numbers::pi * (1.0 + 1e-12))) {
      throw ValidationError("amplitude_deg", "= " + format_degrees(pivot_amplitude) + " deg: must be > 0 and <= 180 deg");
    }
    require_range("frequency_hz", pivot_frequency_hz, 0.0, 1e3, "Hz");
    if (contact_points) {
      for (std::size_t i = 0; i < 2; ++i) check_point(detail::key_index("contact_points", i).c_str(), (*contact_points)[i]);
    }
  }
}

std::vector<PatternSpec> PatternSettings::for_station(std::string_view station) const {
  std::vector<PatternSpec> out;
  for (PatternKind kind : all_pattern_kinds()) {
    const PatternSpec* chosen = nullptr;
    for (const auto& [name, spec] : per_station) {
      if (name == station && spec.kind == kind) chosen = &spec;
    }
    if (chosen == nullptr) {
      for (const PatternSpec& spec : global) {
        if (spec.kind == kind) chosen = &spec;
      }
    }
    if (chosen != nullptr) out.push_back(*chosen);
  }
  return out;
}

void PatternSettings::validate() const {
  require_range("rate_hz", rate_hz, 0.0, 1e4, "Hz");
  if (!(max_joint_speed > 0.0) || !(max_joint_speed * kDegPerRad <= 1e6)) {
    throw ValidationError("max_joint_speed_deg_s", "= " + format_degrees(max_joint_speed) +
                                                       " deg/s: must be > 0 and <= 1000000 deg/s");
  }
  for (const PatternSpec& spec : global) {
    validate_nested(std::string(to_string(spec.kind)), [&] { spec.validate(); });
  }
  for (const auto& entry : per_station) {  // no structured binding: clang 14 cannot capture one
    const PatternSpec& spec = entry.second;
    validate_nested(detail::key_join(detail::key_child("stations", entry.first), to_string(spec.kind)),
                    [&] { spec.validate(); });
  }
}

// ---------------------------------------------------------------------------------------------
// Controller

namespace {

/// Largest gain accepted: far beyond any duty-per-radian a motor loop uses, it keeps every product
/// of a gain and an angle (or rate) finite.
constexpr double kMaxGain = 1e6;

void require_gain(const std::string& key, double v, std::string_view unit) {
  if (!(v >= 0.0) || !(v <= kMaxGain)) {
    throw ValidationError(key, "= " + plain_number(v) + " " + std::string(unit) + ": must be >= 0 and <= 1000000");
  }
}

void require_i_clamp(const std::string& key, double v) {
  if (!(v >= 0.0) || !(v <= 1.0)) {
    throw ValidationError(key, "= " + plain_number(v) + ": must be in [0, 1] (a PWM duty cycle)");
  }
}

void require_volts_at_zero(const std::string& key, double v) {
  if (!(std::abs(v) <= 1000.0)) throw ValidationError(key, "= " + plain_number(v) + " V: must be within [-1000, 1000] V");
}

void require_rad_per_volt(const std::string& key, double v) {
  // Zero would read every voltage as the same angle; the bounds keep 1/v finite and meaningful.
  if (!(std::abs(v) >= 1e-6) || !(std::abs(v) <= 1e6)) {
    throw ValidationError(key, "= " + plain_number(v) + " rad/V: |rad_per_volt| must be in [1e-6, 1e6] "
                                   "(negative when the potentiometer is wired reversed, never 0)");
  }
}

}  // namespace

void PidGains::validate() const {
  require_gain("kp", kp, "per rad");
  require_gain("ki", ki, "per rad s");
  require_gain("kd", kd, "s per rad");
  require_i_clamp("i_clamp", i_clamp);
}

void Potentiometer::validate() const {
  require_volts_at_zero("volts_at_zero", volts_at_zero);
  require_rad_per_volt("rad_per_volt", rad_per_volt);
}

std::string ControlOverride::key() const {
  std::string k = station.empty() ? std::string("mechanisms") : detail::key_child("stations", station);
  if (!mechanism.empty()) k = detail::key_join(k, mechanism);
  if (joint != 0) k = detail::key_join(k, "theta" + std::to_string(joint));
  return k;
}

int ControlOverride::level() const {
  if (station.empty()) return joint == 0 ? 0 : 1;
  if (mechanism.empty()) return 2;
  return joint == 0 ? 3 : 4;
}

JointControl ControllerSettings::joint(std::string_view station, std::string_view mechanism, int j) const {
  JointControl out{pid, potentiometer};
  const auto apply = [&out](const ControlOverride& o) {
    if (o.kp) out.pid.kp = *o.kp;
    if (o.ki) out.pid.ki = *o.ki;
    if (o.kd) out.pid.kd = *o.kd;
    if (o.i_clamp) out.pid.i_clamp = *o.i_clamp;
    if (o.volts_at_zero) out.potentiometer.volts_at_zero = *o.volts_at_zero;
    if (o.rad_per_volt) out.potentiometer.rad_per_volt = *o.rad_per_volt;
  };
  // Widest scope first, so that the narrower keys win whatever the order of the list.
  for (int level = 0; level <= 4; ++level) {
    for (const ControlOverride& o : overrides) {
      if (o.level() != level) continue;
      if (!o.station.empty() && o.station != station) continue;
      if (!o.mechanism.empty() && o.mechanism != mechanism) continue;
      if (o.joint != 0 && o.joint != j) continue;
      apply(o);
    }
  }
  return out;
}

bool is_ros_node_name(std::string_view name) {
  if (name.empty() || name.size() > 255) return false;
  const auto alpha = [](char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_'; };
  if (!alpha(name.front())) return false;
  return std::all_of(name.begin(), name.end(), [&](char c) { return alpha(c) || (c >= '0' && c <= '9'); });
}

void ControllerSettings::validate() const {
  if (!is_ros_node_name(node)) {
    throw ValidationError("node", "= " + detail::quoted(node) +
                                      ": must be a ROS 2 node name: letters, digits and _, not starting with a digit");
  }
  require_range("loop_rate_hz", loop_rate_hz, 0.0, 1e5, "Hz");
  require_range("pwm_hz", pwm_hz, 0.0, 1e7, "Hz");
  if (pwm_hz < loop_rate_hz) {
    throw ValidationError("pwm_hz", "= " + plain_number(pwm_hz) + " Hz: must be >= loop_rate_hz (" +
                                        plain_number(loop_rate_hz) +
                                        " Hz): every control step needs at least one PWM period");
  }
  if (adc_bits < 1 || adc_bits > 32) {
    throw ValidationError("adc.bits", "= " + std::to_string(adc_bits) + ": must be 1 ... 32");
  }
  for (std::size_t i = 0; i < 2; ++i) {
    if (!(std::abs(adc_range_v[i]) <= 1000.0)) {
      throw ValidationError(detail::key_index("adc.range_v", i),
                            "= " + plain_number(adc_range_v[i]) + " V: must be within [-1000, 1000] V");
    }
  }
  if (!(adc_range_v[0] < adc_range_v[1])) {
    throw ValidationError("adc.range_v", "= [" + plain_number(adc_range_v[0]) + ", " + plain_number(adc_range_v[1]) +
                                             "] V: the low end must be below the high end");
  }
  if (!(max_velocity > 0.0) || !(max_velocity * kDegPerRad <= 1e6)) {
    throw ValidationError("max_velocity_deg_s", "= " + format_degrees(max_velocity) +
                                                    " deg/s: must be > 0 and <= 1000000 deg/s");
  }
  if (collision_priority != "upper") {
    throw ValidationError("collision_priority",
                          "= " + detail::quoted(collision_priority) +
                              ": must be upper (the paper's rule, the one fivebar's collision and pattern checks apply)");
  }
  if (!(min_lci >= 0.0) || !(min_lci <= 1.0)) {
    throw ValidationError("min_lci", "= " + plain_number(min_lci) + ": must be in [0, 1]");
  }
  validate_nested("pid", [&] { pid.validate(); });
  validate_nested("potentiometer", [&] { potentiometer.validate(); });
  for (const ControlOverride& o : overrides) {
    const std::string scope = o.key();
    if (!o.mechanism.empty() && o.mechanism != "lower" && o.mechanism != "upper") {
      throw ValidationError(scope, "mechanism " + detail::quoted(o.mechanism) + " must be lower or upper");
    }
    if (o.station.empty() && o.mechanism.empty()) {
      throw ValidationError(scope, "an override names a station, a mechanism (lower, upper) or both");
    }
    if (o.joint < 0 || o.joint > 2 || (o.joint != 0 && o.mechanism.empty())) {
      throw ValidationError(scope, "joint " + std::to_string(o.joint) + " must be 1 or 2 within a mechanism");
    }
    const auto at = [&](std::string_view what) { return detail::key_join(scope, what); };
    if (o.kp) require_gain(at("pid.kp"), *o.kp, "per rad");
    if (o.ki) require_gain(at("pid.ki"), *o.ki, "per rad s");
    if (o.kd) require_gain(at("pid.kd"), *o.kd, "s per rad");
    if (o.i_clamp) require_i_clamp(at("pid.i_clamp"), *o.i_clamp);
    if (o.volts_at_zero) require_volts_at_zero(at("potentiometer.volts_at_zero"), *o.volts_at_zero);
    if (o.rad_per_volt) require_rad_per_volt(at("potentiometer.rad_per_volt"), *o.rad_per_volt);
  }
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

const std::vector<std::string>& known_products() {
  // In build order; each capability appends its product here.
  static const std::vector<std::string> products{
      "kinematics",
      "workspace",
      "coverage",
      "collision",
      "pattern",
      "sweep",
      "parts",
      "export",
      "report",
  };
  return products;
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

  if (geometry) {
    validate_nested("geometry", [&] { geometry->validate(); });
    // Every link must hold its two pin bosses apart: shorter links cannot be printed.
    for (const Station& station : stations) {
      for (const Mechanism* m : station.mechanisms()) {
        for (std::size_t i = 0; i < 4; ++i) {
          if (m->L[i] < geometry->boss_diameter) {
            std::ostringstream s;
            s << "= " << m->L[i] << " mm: shorter than geometry.boss_diameter (" << geometry->boss_diameter
              << " mm): the pin bosses at its ends would overlap";
            throw ValidationError(detail::key_index(detail::key_join(detail::key_child("stations", station.name),
                                                                     "mechanisms." + m->name + ".links"),
                                                    i),
                                  s.str());
          }
        }
      }
    }
  }
  if (print) {
    validate_nested("print", [&] { print->validate(); });
    const Geometry g = geometry.value_or(Geometry{});
    const double wall = 0.5 * (g.boss_diameter - g.pin_diameter) - print->pin_clearance;
    if (wall < print->min_wall) {
      std::ostringstream s;
      s << "= " << print->min_wall << " mm: the wall around each pin hole is only " << wall
        << " mm ((boss_diameter - pin_diameter)/2 - pin_clearance); raise geometry.boss_diameter";
      throw ValidationError("print.min_wall", s.str());
    }
  }

  if (sweep) {
    validate_nested("sweep", [&] { sweep->validate(); });
    const Station* st = station(sweep->station);
    if (st == nullptr) {
      throw ValidationError("sweep.station", "= " + detail::quoted(sweep->station) + ": no such station in the design");
    }
    if (!sweep->mechanism.empty() && st->mechanism(sweep->mechanism) == nullptr) {
      throw ValidationError("sweep.mechanism", "= " + detail::quoted(sweep->mechanism) + ": station " +
                                                   detail::quoted(sweep->station) + " has no such mechanism");
    }
    const auto& obj = sweep->objectives;
    const auto it = std::find(obj.begin(), obj.end(), "collision");
    if (it != obj.end()) {
      const std::string key = detail::key_index("sweep.objectives", std::size_t(it - obj.begin()));
      if (!geometry) throw ValidationError(key, "= \"collision\": needs the geometry: section (link outlines)");
      if (!st->lower || !st->upper) {
        throw ValidationError(key, "= \"collision\": station " + detail::quoted(sweep->station) +
                                       " needs both a lower and an upper mechanism");
      }
      if (sweep->collision_spacing_mm == 0.0) {
        throw ValidationError(key, "= \"collision\": sweep.collision_spacing_mm is 0 (collision fraction off)");
      }
    }
  }

  if (patterns) {
    validate_nested("patterns", [&] { patterns->validate(); });
    for (const auto& [station_name, spec] : patterns->per_station) {
      if (station(station_name) == nullptr) {
        std::string list;
        for (const Station& s : stations) list += (list.empty() ? "" : ", ") + s.name;
        throw ValidationError(detail::key_child("patterns.stations", station_name),
                              "no such station in this design (stations: " + list + ")");
      }
    }
  }
  if (controller) {
    validate_nested("controller", [&] { controller->validate(); });
    for (const ControlOverride& o : controller->overrides) {
      if (o.station.empty()) continue;  // every station's lower / upper: none is fine
      const Station* st = station(o.station);
      const std::string key = detail::key_join("controller", o.key());
      if (st == nullptr) {
        std::string list;
        for (const Station& s : stations) list += (list.empty() ? "" : ", ") + s.name;
        throw ValidationError(detail::key_join("controller", detail::key_child("stations", o.station)),
                              "no such station in this design (stations: " + list + ")");
      }
      if (!o.mechanism.empty() && st->mechanism(o.mechanism) == nullptr) {
        throw ValidationError(key, "station " + detail::quoted(o.station) + " has no " + o.mechanism + " mechanism");
      }
    }
    // One source of truth for the joint speed limit (ControllerSettings).
    if (patterns && patterns->max_joint_speed != controller->max_velocity) {
      throw ValidationError("patterns.max_joint_speed_deg_s",
                            "= " + format_degrees(patterns->max_joint_speed) +
                                " deg/s: differs from controller.max_velocity_deg_s (" +
                                format_degrees(controller->max_velocity) +
                                " deg/s), the one joint speed limit of a design with a controller");
    }
  }
  if (products) {
    const auto& known = known_products();
    for (std::size_t i = 0; i < products->size(); ++i) {
      const std::string& product = (*products)[i];
      const std::string key = detail::key_index("products", i);
      if (std::find(known.begin(), known.end(), product) == known.end()) {
        std::string list;
        for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
        throw ValidationError(key, "= " + detail::quoted(product) + ": unknown product (known: " + list + ")");
      }
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
  throw InputError("unknown station '" + std::string(wanted) + "' in design '" + name + "' (it has: " + names + ")");
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
