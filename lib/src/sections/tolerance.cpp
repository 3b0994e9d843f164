// The `tolerance:` section (fivebar/sections/tolerance.hpp): manufacturing and sensing errors.
#include "fivebar/sections/tolerance.hpp"

#include <cmath>
#include <sstream>
#include <string>

#include "fivebar/design.hpp"
#include "sections/rules.hpp"
#include "sections/section.hpp"

namespace fivebar {
namespace {

void require_sigma(const char* key, double v, double hi, const char* unit) {
  if (!(v >= 0.0) || !(v <= hi)) {
    std::ostringstream s;
    s << "= " << v << " " << unit << ": must be >= 0 and <= " << hi << " " << unit;
    throw ValidationError(key, s.str());
  }
}

}  // namespace

void ToleranceSettings::validate() const {
  require_sigma("link_sigma_mm", link_sigma_mm, 10.0, "mm");
  require_sigma("pin_sigma_mm", pin_sigma_mm, 10.0, "mm");
  require_sigma("base_sigma_mm", base_sigma_mm, 10.0, "mm");
  require_sigma("angle_sigma_deg", angle_sigma_deg, 10.0, "deg");
  if (adc_bits && (*adc_bits < 1 || *adc_bits > 32)) {
    throw ValidationError("adc_bits", "= " + std::to_string(*adc_bits) + ": must be 1 ... 32");
  }
  if (pin_play_mm) require_sigma("pin_play_mm", *pin_play_mm, 10.0, "mm");
  require_sigma("shaft_play_mm", shaft_play_mm, 10.0, "mm");
  require_sigma("backlash_deg", backlash_deg, 30.0, "deg");
  require_sigma("linearity_percent", linearity_percent, 20.0, "%");
  if (!(pot_travel_deg > 0.0 && pot_travel_deg <= 3600.0)) {
    std::ostringstream s;
    s << "= " << pot_travel_deg << " deg: must be > 0 and <= 3600 deg";
    throw ValidationError("pot_travel_deg", s.str());
  }
  if (!(robust_fraction >= 0.5 && robust_fraction < 1.0)) {
    std::ostringstream s;
    s << "= " << robust_fraction << ": must be >= 0.5 and < 1";
    throw ValidationError("robust_fraction", s.str());
  }
  if (samples < 2 || samples > 100000000) {
    throw ValidationError("samples", "= " + std::to_string(samples) + ": must be 2 ... 1e8");
  }
}

namespace sections {
namespace {

void load(const Value& v, Design& design) {
  ToleranceSettings& t = design.set(ToleranceSettings{});
  if (v.is_null()) return;
  const auto all = v.entries({"link_sigma_mm", "pin_sigma_mm", "base_sigma_mm", "angle_sigma_deg", "adc_bits",
                              "pin_play_mm", "shaft_play_mm", "backlash_deg", "linearity_percent", "pot_travel_deg",
                              "robust_fraction", "export_gate", "samples", "seed"},
                             "of tolerances (link_sigma_mm, pin_sigma_mm, base_sigma_mm, angle_sigma_deg, "
                             "adc_bits, pin_play_mm, shaft_play_mm, backlash_deg, linearity_percent, pot_travel_deg, "
                             "robust_fraction, export_gate, samples, seed)");
  t.link_sigma_mm = number_or(all, "link_sigma_mm", t.link_sigma_mm, "mm");
  t.pin_sigma_mm = number_or(all, "pin_sigma_mm", t.pin_sigma_mm, "mm");
  t.base_sigma_mm = number_or(all, "base_sigma_mm", t.base_sigma_mm, "mm");
  t.angle_sigma_deg = number_or(all, "angle_sigma_deg", t.angle_sigma_deg, "deg");
  if (const Value* bits = find(all, "adc_bits")) t.adc_bits = int(bits->whole(1, 32));
  if (find(all, "pin_play_mm") != nullptr) t.pin_play_mm = number_or(all, "pin_play_mm", 0.0, "mm");
  t.shaft_play_mm = number_or(all, "shaft_play_mm", t.shaft_play_mm, "mm");
  t.backlash_deg = number_or(all, "backlash_deg", t.backlash_deg, "deg");
  t.linearity_percent = number_or(all, "linearity_percent", t.linearity_percent, "%");
  t.pot_travel_deg = number_or(all, "pot_travel_deg", t.pot_travel_deg, "deg");
  t.robust_fraction = number_or(all, "robust_fraction", t.robust_fraction, "");
  if (const Value* gate = find(all, "export_gate")) {
    const std::string word = gate->text("a boolean: true or false");
    if (word != "true" && word != "false") gate->fail_value("must be true or false");
    t.export_gate = word == "true";
  }
  if (const Value* n = find(all, "samples")) t.samples = n->whole(2, 1e8);
  if (const Value* seed = find(all, "seed")) t.seed = seed->whole(0, 9007199254740992.0);
}

void validate(const Design& design) {
  const ToleranceSettings* t = design.get<ToleranceSettings>();
  if (t == nullptr) return;
  rules::validate_nested("tolerance", [&] { t->validate(); });
}

void write(const Design& design, Out& top) {
  const ToleranceSettings* t = design.get<ToleranceSettings>();
  if (t == nullptr) return;
  Out& o = top.add("tolerance", Out::map());
  o.add("link_sigma_mm", Out::number(t->link_sigma_mm));
  o.add("pin_sigma_mm", Out::number(t->pin_sigma_mm));
  o.add("base_sigma_mm", Out::number(t->base_sigma_mm));
  o.add("angle_sigma_deg", Out::number(t->angle_sigma_deg));
  if (t->adc_bits) o.add("adc_bits", Out::integer(*t->adc_bits));
  if (t->pin_play_mm) o.add("pin_play_mm", Out::number(*t->pin_play_mm));
  o.add("shaft_play_mm", Out::number(t->shaft_play_mm));
  o.add("backlash_deg", Out::number(t->backlash_deg));
  o.add("linearity_percent", Out::number(t->linearity_percent));
  o.add("pot_travel_deg", Out::number(t->pot_travel_deg));
  o.add("robust_fraction", Out::number(t->robust_fraction));
  o.add("export_gate", Out::plain(t->export_gate ? "true" : "false"));
  o.add("samples", Out::integer(static_cast<long long>(t->samples)));
  o.add("seed", Out::integer(static_cast<long long>(t->seed)));
}

}  // namespace

Section tolerance_section() { return {ToleranceSettings::kKey, &load, &validate, &write}; }

}  // namespace sections
}  // namespace fivebar
