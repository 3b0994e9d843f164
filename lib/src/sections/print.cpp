// The `print:` section (fivebar/sections/print.hpp): resin printing clearances and minimums.
#include "fivebar/sections/print.hpp"

#include <cmath>
#include <sstream>

#include "fivebar/sections/geometry.hpp"
#include "sections/rules.hpp"
#include "sections/section.hpp"

namespace fivebar {

void PrintSettings::validate() const {
  if (!(pin_clearance >= 0.0) || !(pin_clearance <= 1.0)) {
    std::ostringstream s;
    s << "= " << pin_clearance << " mm: must be >= 0 and <= 1 mm (resin guides: 0.1 - 0.25)";
    throw ValidationError("pin_clearance", s.str());
  }
  rules::require_length("min_wall", min_wall, 0.0, 100.0);
  if (fn < 8 || fn > 1024) throw ValidationError("fn", "= " + std::to_string(fn) + ": must be 8 ... 1024");
  rules::require_length("layer_height", layer_height, 0.0, 1.0);
  if (material.empty() || material.size() > 200) throw ValidationError("material", "must be 1 ... 200 characters");
  rules::require_range("density_g_cm3", density_g_cm3, 0.0, 25.0, "g/cm^3");
}

namespace sections {
namespace {

void load(const Value& v, Design& design) {
  PrintSettings& p = design.set(PrintSettings{});
  if (v.is_null()) return;
  const auto all = v.entries({"pin_clearance", "min_wall", "fn", "layer_height", "material", "density_g_cm3"},
                             "of print settings (pin_clearance, min_wall, fn, layer_height, material, density_g_cm3)");
  p.pin_clearance = number_or(all, "pin_clearance", p.pin_clearance, "mm");
  p.min_wall = number_or(all, "min_wall", p.min_wall, "mm");
  if (const Value* fn = find(all, "fn")) {
    const double n = fn->number("");
    if (n != std::floor(n)) fn->fail_value("must be a whole number, 8 ... 1024");
    if (n < 8 || n > 1024) fn->fail_value("must be 8 ... 1024");
    p.fn = int(n);
  }
  p.layer_height = number_or(all, "layer_height", p.layer_height, "mm");
  if (const Value* m = find(all, "material")) p.material = m->text("must be a material name");
  p.density_g_cm3 = number_or(all, "density_g_cm3", p.density_g_cm3, "g/cm^3");
}

void validate(const Design& design) {
  const PrintSettings* p = design.get<PrintSettings>();
  if (p == nullptr) return;
  rules::validate_nested("print", [&] { p->validate(); });
  const Geometry* given = design.get<Geometry>();
  const Geometry g = given ? *given : Geometry{};
  const double wall = 0.5 * (g.boss_diameter - g.pin_diameter) - p->pin_clearance;
  if (wall < p->min_wall) {
    std::ostringstream s;
    s << "= " << p->min_wall << " mm: the wall around each pin hole is only " << wall
      << " mm ((boss_diameter - pin_diameter)/2 - pin_clearance); raise geometry.boss_diameter";
    throw ValidationError("print.min_wall", s.str());
  }
}

void write(const Design& design, Out& top) {
  const PrintSettings* p = design.get<PrintSettings>();
  if (p == nullptr) return;
  Out& o = top.add("print", Out::map());
  o.add("material", Out::quoted(p->material));
  o.add("pin_clearance", Out::number(p->pin_clearance));
  o.add("min_wall", Out::number(p->min_wall));
  o.add("layer_height", Out::number(p->layer_height));
  o.add("fn", Out::integer(p->fn));
  o.add("density_g_cm3", Out::number(p->density_g_cm3));
}

}  // namespace

Section print_section() { return {PrintSettings::kKey, &load, &validate, &write}; }

}  // namespace sections
}  // namespace fivebar
