// The `contact:` section (fivebar/sections/contact.hpp): skin under the tactors.
#include "fivebar/sections/contact.hpp"

#include "sections/rules.hpp"
#include "sections/section.hpp"

namespace fivebar {

void ContactSettings::validate() const {
  rules::require_range("shear_stiffness_N_per_mm", shear_stiffness_N_per_mm, 0.0, 1e6, "N/mm");
  if (!(damping_N_s_per_mm >= 0.0) || !(damping_N_s_per_mm <= 1e6)) {
    throw ValidationError("damping_N_s_per_mm",
                          "= " + rules::plain_number(damping_N_s_per_mm) + " N s/mm: must be >= 0 and <= 1000000");
  }
  rules::require_range("friction_coefficient", friction_coefficient, 0.0, 100.0, "");
  rules::require_range("normal_preload_N", normal_preload_N, 0.0, 1e4, "N");
}

namespace sections {
namespace {

void load(const Value& v, Design& design) {
  ContactSettings& c = design.set(ContactSettings{});
  if (v.is_null()) return;
  const auto all = v.entries({"shear_stiffness_N_per_mm", "damping_N_s_per_mm", "friction_coefficient", "normal_preload_N"},
                             "of skin contact data (shear_stiffness_N_per_mm, damping_N_s_per_mm, "
                             "friction_coefficient, normal_preload_N)");
  c.shear_stiffness_N_per_mm = number_or(all, "shear_stiffness_N_per_mm", c.shear_stiffness_N_per_mm, "N/mm");
  c.damping_N_s_per_mm = number_or(all, "damping_N_s_per_mm", c.damping_N_s_per_mm, "N s/mm");
  c.friction_coefficient = number_or(all, "friction_coefficient", c.friction_coefficient, "");
  c.normal_preload_N = number_or(all, "normal_preload_N", c.normal_preload_N, "N");
}

void validate(const Design& design) {
  const ContactSettings* c = design.get<ContactSettings>();
  if (c == nullptr) return;
  rules::validate_nested("contact", [&] { c->validate(); });
}

void write(const Design& design, Out& top) {
  const ContactSettings* c = design.get<ContactSettings>();
  if (c == nullptr) return;
  Out& o = top.add("contact", Out::map());
  o.add("shear_stiffness_N_per_mm", Out::number(c->shear_stiffness_N_per_mm));
  o.add("damping_N_s_per_mm", Out::number(c->damping_N_s_per_mm));
  o.add("friction_coefficient", Out::number(c->friction_coefficient));
  o.add("normal_preload_N", Out::number(c->normal_preload_N));
}

}  // namespace

Section contact_section() { return {ContactSettings::kKey, &load, &validate, &write}; }

}  // namespace sections
}  // namespace fivebar
