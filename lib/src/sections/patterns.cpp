// The `patterns:` section (fivebar/sections/patterns.hpp): which skin-deformation patterns to check.
#include "fivebar/format.hpp"
#include "fivebar/sections/patterns.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <utility>

#include "fivebar/sections/controller.hpp"
#include "sections/rules.hpp"
#include "sections/section.hpp"

namespace fivebar {

using rules::format_degrees;
using rules::plain_number;
using rules::require_range;

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

using format::kDegPerRad;
using format::kRadPerDeg;

/// Most samples one pattern may have (10 minutes at 1 kHz is 600000).
constexpr double kMaxPatternSamples = 1e6;

/// duration * rate within this many intervals of a whole number counts as that number: 0.29 s at
/// 100 Hz is 28.999999999999996 intervals in doubles and must give 29, not 28.
constexpr double kSampleCountSlack = 1e-9;

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
  if (centre) rules::check_point("centre", *centre);
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
      for (std::size_t i = 0; i < 2; ++i) {
        rules::check_point(detail::key_index("contact_points", i).c_str(), (*contact_points)[i]);
      }
    }
  }
}

PatternOverride::PatternOverride(std::string station_name, PatternSpec pattern)
    : JointScope{std::move(station_name), "", 0}, spec(std::move(pattern)) {}

std::vector<PatternSpec> PatternSettings::for_station(std::string_view station) const {
  std::vector<PatternSpec> out;
  for (PatternKind kind : all_pattern_kinds()) {
    const PatternSpec* chosen = nullptr;
    for (const PatternSpec& spec : global) {
      if (spec.kind == kind) chosen = &spec;
    }
    // The station's pair: no mechanism, no joint; its own entries are narrower than the top level.
    apply_overrides(overrides, station, "", 0, [&](const PatternOverride& o) {
      if (o.spec.kind == kind) chosen = &o.spec;
    });
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
    rules::validate_nested(std::string(to_string(spec.kind)), [&] { spec.validate(); });
  }
  for (const PatternOverride& o : overrides) {
    rules::validate_nested(detail::key_join(detail::key_child("stations", o.station), to_string(o.spec.kind)),
                           [&] { o.spec.validate(); });
  }
}

namespace sections {
namespace {

/// One `<kind>:` map of patterns, over `base` (the defaults, or the top-level entry of the kind).
PatternSpec load_spec(const Value& v, const PatternSpec& base) {
  PatternSpec spec = base;
  if (v.is_null()) return spec;  // `stretch:` alone: the defaults (or the top-level entry)
  const bool pivot = spec.kind == PatternKind::pivot;
  const auto all = pivot ? v.entries({"amplitude_deg", "frequency_hz", "duration_s", "rate_hz", "center",
                                      "separation_mm", "contact_points", "amplitude_mm"},
                                     "of pivot parameters (amplitude_deg, frequency_hz, duration_s, contact_points, ...)")
                         : v.entries({"amplitude_mm", "duration_s", "rate_hz", "center", "separation_mm"},
                                     "of pattern parameters (amplitude_mm, duration_s, rate_hz, center, separation_mm)");
  if (!pivot) spec.amplitude_mm = number_or(all, "amplitude_mm", spec.amplitude_mm, "mm");
  if (const Value* a = find(all, "amplitude_mm"); a != nullptr && pivot) {
    a->fail_value("a pivot's amplitude is the object's angle: use amplitude_deg");
  }
  spec.duration_s = number_or(all, "duration_s", spec.duration_s, "s");
  spec.rate_hz = number_or(all, "rate_hz", spec.rate_hz, "Hz");
  if (const Value* c = find(all, "center")) spec.centre = c->point("a point [x, y] (mm)");
  spec.separation_mm = number_or(all, "separation_mm", spec.separation_mm, "mm");
  if (pivot) {
    if (const Value* a = find(all, "amplitude_deg")) spec.pivot_amplitude = kRadPerDeg * a->number("deg");
    spec.pivot_frequency_hz = number_or(all, "frequency_hz", spec.pivot_frequency_hz, "Hz");
    if (const Value* cp = find(all, "contact_points")) {
      if (const Value* sep = find(all, "separation_mm")) {
        sep->fail("give contact_points or separation_mm, not both (separation_mm only places the "
                  "default contact points at (0, +-separation/2))");
      }
      const auto items = cp->items(2, "a list of 2 points [[x, y] upper, [x, y] lower] relative to the center (mm)");
      std::array<Vec2, 2> points;
      for (std::size_t i = 0; i < 2; ++i) points[i] = items[i].point("a point [x, y] (mm)");
      spec.contact_points = points;
    }
  }
  return spec;
}

void load(const Value& v, Design& design) {
  PatternSettings ps;
  const ControllerSettings* controller = design.get<ControllerSettings>();
  if (controller) {  // the patterns run at the controller's rate and speed limit
    ps.rate_hz = controller->loop_rate_hz;
    ps.max_joint_speed = controller->max_velocity;
  }
  const auto defaults = [&](PatternKind kind) {
    PatternSpec spec;
    spec.kind = kind;
    spec.rate_hz = ps.rate_hz;
    if (kind == PatternKind::pivot) spec.duration_s = 2.0;  // one period of the default 0.5 Hz
    return spec;
  };
  if (v.is_null()) {  // `patterns:` alone: the four patterns with their defaults
    for (PatternKind kind : all_pattern_kinds()) ps.global.push_back(defaults(kind));
    design.set(std::move(ps));
    return;
  }
  const auto all = v.entries({"rate_hz", "max_joint_speed_deg_s", "stretch", "slip", "twist", "pivot", "stations"},
                             "(rate_hz, max_joint_speed_deg_s, stretch, slip, twist, pivot, stations)");
  ps.rate_hz = number_or(all, "rate_hz", ps.rate_hz, "Hz");
  if (const Value* speed = find(all, "max_joint_speed_deg_s")) {
    if (controller) {
      speed->fail("the joint speed limit of a design with a controller: section is "
                  "controller.max_velocity_deg_s (patterns take it from there): remove this key");
    }
    ps.max_joint_speed = kRadPerDeg * speed->number("deg/s");
  }
  for (PatternKind kind : all_pattern_kinds()) {
    if (const Value* e = find(all, to_string(kind))) ps.global.push_back(load_spec(*e, defaults(kind)));
  }
  if (const Value* stations = find(all, "stations")) {
    for (const Value& st : stations->entries({}, "of station names to their patterns", /*any_key=*/true)) {
      for (const Value& k : st.entries({"stretch", "slip", "twist", "pivot"},
                                       "of pattern kinds (stretch, slip, twist, pivot)")) {
        const PatternKind kind = *parse_pattern_kind(k.name());
        PatternSpec base = defaults(kind);
        for (const PatternSpec& g : ps.global) {
          if (g.kind == kind) base = g;
        }
        ps.overrides.emplace_back(st.name(), load_spec(k, base));
      }
    }
  }
  design.set(std::move(ps));
}

void validate(const Design& design) {
  const PatternSettings* patterns = design.get<PatternSettings>();
  if (patterns == nullptr) return;
  rules::validate_nested("patterns", [&] { patterns->validate(); });
  for (const PatternOverride& o : patterns->overrides) o.validate_in(design, "patterns");
  // One source of truth for the joint speed limit (ControllerSettings).
  const ControllerSettings* controller = design.get<ControllerSettings>();
  if (controller && patterns->max_joint_speed != controller->max_velocity) {
    throw ValidationError("patterns.max_joint_speed_deg_s",
                          "= " + format_degrees(patterns->max_joint_speed) +
                              " deg/s: differs from controller.max_velocity_deg_s (" +
                              format_degrees(controller->max_velocity) +
                              " deg/s), the one joint speed limit of a design with a controller");
  }
}

Out spec_out(const PatternSpec& p) {
  Out o = Out::map(/*flow=*/true);
  if (p.kind == PatternKind::pivot) {
    o.add("amplitude_deg", Out::degrees(p.pivot_amplitude));
    o.add("frequency_hz", Out::number(p.pivot_frequency_hz));
  } else {
    o.add("amplitude_mm", Out::number(p.amplitude_mm));
  }
  o.add("duration_s", Out::number(p.duration_s));
  o.add("rate_hz", Out::number(p.rate_hz));
  if (p.centre) o.add("center", Out::point(*p.centre));
  if (p.kind == PatternKind::pivot && p.contact_points) {  // the loader takes one or the other
    Out& points = o.add("contact_points", Out::list());
    points.push(Out::point((*p.contact_points)[0]));
    points.push(Out::point((*p.contact_points)[1]));
  } else {
    o.add("separation_mm", Out::number(p.separation_mm));
  }
  return o;
}

void write(const Design& design, Out& top) {
  const PatternSettings* ps = design.get<PatternSettings>();
  if (ps == nullptr) return;
  Out& o = top.add("patterns", Out::map());
  o.add("rate_hz", Out::number(ps->rate_hz));
  if (design.get<ControllerSettings>() == nullptr) {
    o.add("max_joint_speed_deg_s", Out::degrees(ps->max_joint_speed));
  }
  for (const PatternSpec& spec : ps->global) o.add(std::string(to_string(spec.kind)), spec_out(spec));
  if (!ps->overrides.empty()) {
    Out& stations = o.add("stations", Out::map());
    std::vector<std::string> names;  // first-appearance order; entries of one station together
    for (const PatternOverride& e : ps->overrides) {
      if (std::find(names.begin(), names.end(), e.station) == names.end()) names.push_back(e.station);
    }
    for (const std::string& station : names) {
      Out& kinds = stations.add(station, Out::map());
      for (PatternKind kind : all_pattern_kinds()) {
        const PatternSpec* last = nullptr;  // a later entry of the same kind replaces an earlier one
        for (const PatternOverride& e : ps->overrides) {
          if (e.station == station && e.spec.kind == kind) last = &e.spec;
        }
        if (last != nullptr) kinds.add(std::string(to_string(kind)), spec_out(*last));
      }
    }
  }
}

}  // namespace

Section patterns_section() { return {PatternSettings::kKey, &load, &validate, &write, ControllerSettings::kKey}; }

}  // namespace sections
}  // namespace fivebar
