// The `geometry:` section (fivebar/sections/geometry.hpp): link outlines, pins and layers.
#include "fivebar/sections/geometry.hpp"

#include "fivebar/design/edit.hpp"

#include <cmath>
#include <sstream>

#include "sections/rules.hpp"
#include "sections/section.hpp"

namespace fivebar {

using rules::require_length;

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

namespace sections {
namespace {

void load(const Value& v, Design& design) {
  Geometry& g = design.set(Geometry{});
  if (v.is_null()) return;  // `geometry:` alone: every default
  const auto all = v.entries({"link_width", "link_thickness", "pin_diameter", "boss_diameter", "tactor_diameter",
                              "tactor_height", "layers", "layer_gap", "motor_shaft_diameter", "motor_shaft_flat",
                              "min_clearance"},
                             "of link geometry (link_width, link_thickness, ...)");
  if (const Value* w = find(all, "link_width")) {
    if (w->is_scalar()) {
      g.link_width.fill(w->number("mm"));
    } else {
      const auto items = w->items(4, "a width (mm) or a list of 4 widths [L1, L2, L3, L4]");
      for (std::size_t i = 0; i < 4; ++i) g.link_width[i] = items[i].number("mm");
    }
  }
  g.link_thickness = number_or(all, "link_thickness", g.link_thickness, "mm");
  g.pin_diameter = number_or(all, "pin_diameter", g.pin_diameter, "mm");
  g.boss_diameter = number_or(all, "boss_diameter", g.boss_diameter, "mm");
  g.tactor_diameter = number_or(all, "tactor_diameter", g.tactor_diameter, "mm");
  g.tactor_height = number_or(all, "tactor_height", g.tactor_height, "mm");
  if (const Value* l = find(all, "layers")) {
    const auto items = l->items(4, "a list of 4 plane indices [L1, L2, L3, L4]");
    for (std::size_t i = 0; i < 4; ++i) {
      const double layer = items[i].number("");
      if (layer != std::floor(layer)) items[i].fail_value("must be a whole number, 0 ... 7");
      if (layer < 0 || layer > 7) items[i].fail_value("must be 0 ... 7");
      g.layers[i] = int(layer);
    }
  }
  g.layer_gap = number_or(all, "layer_gap", g.layer_gap, "mm");
  g.motor_shaft_diameter = number_or(all, "motor_shaft_diameter", g.motor_shaft_diameter, "mm");
  g.motor_shaft_flat = number_or(all, "motor_shaft_flat", g.motor_shaft_flat, "mm");
  g.min_clearance = number_or(all, "min_clearance", g.min_clearance, "mm");
}

void validate(const Design& design) {
  const Geometry* g = design.get<Geometry>();
  if (g == nullptr) return;
  rules::validate_nested("geometry", [&] { g->validate(); });
  // Every link must hold its two pin bosses apart: shorter links cannot be printed (the rule is
  // stated once, in fivebar/design/edit.hpp check_printable_links, for the sweep and the optimiser too).
  for (const Station& station : design.stations) {
    try {
      check_printable_links(station, *g);
    } catch (const ValidationError& e) {
      throw ValidationError(detail::key_join(detail::key_child("stations", station.name), e.key()), e.rule());
    }
  }
}

void write(const Design& design, Out& top) {
  const Geometry* g = design.get<Geometry>();
  if (g == nullptr) return;
  Out& o = top.add("geometry", Out::map());
  Out& widths = o.add("link_width", Out::list());
  for (double w : g->link_width) widths.push(Out::number(w));
  o.add("link_thickness", Out::number(g->link_thickness));
  o.add("pin_diameter", Out::number(g->pin_diameter));
  o.add("boss_diameter", Out::number(g->boss_diameter));
  o.add("tactor_diameter", Out::number(g->tactor_diameter));
  o.add("tactor_height", Out::number(g->tactor_height));
  Out& layers = o.add("layers", Out::list());
  for (int l : g->layers) layers.push(Out::integer(l));
  o.add("layer_gap", Out::number(g->layer_gap));
  o.add("motor_shaft_diameter", Out::number(g->motor_shaft_diameter));
  o.add("motor_shaft_flat", Out::number(g->motor_shaft_flat));
  o.add("min_clearance", Out::number(g->min_clearance));
}

}  // namespace

Section geometry_section() { return {Geometry::kKey, &load, &validate, &write}; }

}  // namespace sections
}  // namespace fivebar
