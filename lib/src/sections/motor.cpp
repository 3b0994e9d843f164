// The `motor:` section (fivebar/sections/motor.hpp): DC gearmotor and driver of every joint, with
// overrides scoped as controller.cpp scopes its PID overrides.
#include "fivebar/sections/motor.hpp"

#include <numbers>

#include "sections/rules.hpp"
#include "sections/section.hpp"

namespace fivebar {

namespace {

// The keys of MotorParams, for the loader's lists of allowed keys.
#define FIVEBAR_MOTOR_KEYS                                                                                   \
  "terminal_resistance_ohm", "inductance_mH", "torque_constant_mNm_per_A", "back_emf_mV_per_rpm",            \
      "rotor_inertia_g_cm2", "gear_ratio", "gearbox_efficiency", "viscous_friction_mNm_s_per_rad",           \
      "coulomb_friction_mNm", "supply_voltage_V", "current_limit_A"

const std::array<MotorField, kMotorFieldCount> kFields{{
    {"terminal_resistance_ohm", "ohm", &MotorParams::terminal_resistance_ohm, 0.0, 1e6, false},
    {"inductance_mH", "mH", &MotorParams::inductance_mH, 0.0, 1e6, false},
    {"torque_constant_mNm_per_A", "mNm/A", &MotorParams::torque_constant_mNm_per_A, 0.0, 1e6, false},
    {"back_emf_mV_per_rpm", "mV/rpm", &MotorParams::back_emf_mV_per_rpm, 0.0, 1e6, false},
    {"rotor_inertia_g_cm2", "g cm^2", &MotorParams::rotor_inertia_g_cm2, 0.0, 1e6, true},
    {"gear_ratio", "", &MotorParams::gear_ratio, 0.0, 1e6, false},
    {"gearbox_efficiency", "", &MotorParams::gearbox_efficiency, 0.0, 1.0, false},
    {"viscous_friction_mNm_s_per_rad", "mNm s/rad", &MotorParams::viscous_friction_mNm_s_per_rad, 0.0, 1e6, true},
    {"coulomb_friction_mNm", "mNm", &MotorParams::coulomb_friction_mNm, 0.0, 1e6, true},
    {"supply_voltage_V", "V", &MotorParams::supply_voltage_V, 0.0, 1000.0, false},
    {"current_limit_A", "A", &MotorParams::current_limit_A, 0.0, 1000.0, false},
}};

void check_field(const MotorField& f, const std::string& key, double v) {
  if (f.zero_ok) {
    if (!(v >= 0.0) || !(v <= f.hi)) {
      throw ValidationError(key, "= " + rules::plain_number(v) + (f.unit.empty() ? "" : " ") + std::string(f.unit) +
                                     ": must be >= 0 and <= " + rules::plain_number(f.hi));
    }
    return;
  }
  rules::require_range(key, v, f.lo, f.hi, f.unit);
}

}  // namespace

const std::array<MotorField, kMotorFieldCount>& motor_fields() { return kFields; }

double MotorParams::back_emf_constant() const { return back_emf_mV_per_rpm * 1e-3 * 60.0 / (2.0 * std::numbers::pi); }

void MotorParams::validate() const {
  for (const MotorField& f : kFields) check_field(f, std::string(f.key), this->*f.member);
}

MotorParams MotorSettings::joint(std::string_view station, std::string_view mechanism, int j) const {
  MotorParams out = defaults;
  apply_overrides(overrides, station, mechanism, j, [&](const MotorOverride& o) {
    for (std::size_t i = 0; i < kMotorFieldCount; ++i) {
      if (o.values[i]) out.*kFields[i].member = *o.values[i];
    }
  });
  return out;
}

void MotorSettings::validate() const {
  if (model.empty() || model.size() > 200) throw ValidationError("model", "must be 1 ... 200 characters");
  defaults.validate();
  for (const MotorOverride& o : overrides) {
    o.validate();
    const std::string scope = o.key();
    for (std::size_t i = 0; i < kMotorFieldCount; ++i) {
      if (o.values[i]) check_field(kFields[i], detail::key_join(scope, kFields[i].key), *o.values[i]);
    }
  }
}

namespace sections {
namespace {

/// The motor keys of one scope.
void motor_keys(const std::vector<Value>& all, MotorOverride& o) {
  for (std::size_t i = 0; i < kMotorFieldCount; ++i) {
    if (const Value* v = find(all, kFields[i].key)) o.values[i] = v->number(kFields[i].unit);
  }
}

void load(const Value& v, Design& design) {
  MotorSettings& m = design.set(MotorSettings{});
  if (v.is_null()) return;  // `motor:` alone: every default
  const auto all = v.entries({"model", FIVEBAR_MOTOR_KEYS, "mechanisms", "stations"},
                             "of motor data (model, terminal_resistance_ohm, inductance_mH, ..., mechanisms, stations)");
  if (const Value* model = find(all, "model")) m.model = model->text("must be the motor's name");
  MotorOverride top;
  motor_keys(all, top);
  for (std::size_t i = 0; i < kMotorFieldCount; ++i) {
    if (top.values[i]) m.defaults.*kFields[i].member = *top.values[i];
  }
  const auto mechanism_scope = [&](const Value& mech, const std::string& station) {
    const auto keys = mech.entries({FIVEBAR_MOTOR_KEYS, "theta1", "theta2"}, "of motor keys, theta1, theta2");
    MotorOverride mo;
    mo.station = station;
    mo.mechanism = mech.name();
    motor_keys(keys, mo);
    m.overrides.push_back(mo);
    for (const Value& j : keys) {
      if (j.name() != "theta1" && j.name() != "theta2") continue;
      MotorOverride jo;
      jo.station = station;
      jo.mechanism = mech.name();
      jo.joint = j.name() == "theta1" ? 1 : 2;
      motor_keys(j.entries({FIVEBAR_MOTOR_KEYS}, "of motor keys"), jo);
      m.overrides.push_back(jo);
    }
  };
  if (const Value* mechanisms = find(all, "mechanisms")) {
    for (const Value& mech : mechanisms->entries({"lower", "upper"}, "with keys lower and/or upper (every station's)")) {
      mechanism_scope(mech, "");
    }
  }
  if (const Value* stations = find(all, "stations")) {
    for (const Value& st : stations->entries({}, "of station names to their overrides", /*any_key=*/true)) {
      // An empty name would read as every station's scope (JointScope): refused here, at its line.
      if (st.name().empty()) st.fail("a station name must not be empty");
      const auto keys = st.entries({FIVEBAR_MOTOR_KEYS, "lower", "upper"}, "of motor keys, lower, upper");
      MotorOverride so;
      so.station = st.name();
      motor_keys(keys, so);
      m.overrides.push_back(so);
      for (const Value& mech : keys) {
        if (mech.name() == "lower" || mech.name() == "upper") mechanism_scope(mech, st.name());
      }
    }
  }
}

void validate(const Design& design) {
  const MotorSettings* motor = design.get<MotorSettings>();
  if (motor == nullptr) return;
  rules::validate_nested("motor", [&] { motor->validate(); });
  for (const MotorOverride& o : motor->overrides) o.validate_in(design, "motor");
}

bool has_values(const MotorOverride& o) {
  for (const auto& v : o.values)
    if (v) return true;
  return false;
}

/// The keys of every override of one scope, later ones winning.
MotorOverride merged(const MotorSettings& m, const std::string& station, const std::string& mechanism, int joint) {
  MotorOverride out;
  for (const MotorOverride& o : m.overrides) {
    if (o.station != station || o.mechanism != mechanism || o.joint != joint) continue;
    for (std::size_t i = 0; i < kMotorFieldCount; ++i)
      if (o.values[i]) out.values[i] = o.values[i];
  }
  return out;
}

void keys_out(Out& out, const MotorOverride& o) {
  for (std::size_t i = 0; i < kMotorFieldCount; ++i) {
    if (o.values[i]) out.add(std::string(kFields[i].key), Out::number(*o.values[i]));
  }
}

void write(const Design& d, Out& top) {
  const MotorSettings* mp = d.get<MotorSettings>();
  if (mp == nullptr) return;
  const MotorSettings& m = *mp;
  Out& out = top.add("motor", Out::map());
  out.add("model", Out::quoted(m.model));
  for (const MotorField& f : kFields) out.add(std::string(f.key), Out::number(m.defaults.*f.member));
  const auto mechanism_scope = [&](const std::string& station, const char* mechanism, const auto& open) {
    const MotorOverride keys = merged(m, station, mechanism, 0);
    const MotorOverride joints[2] = {merged(m, station, mechanism, 1), merged(m, station, mechanism, 2)};
    if (!has_values(keys) && !has_values(joints[0]) && !has_values(joints[1])) return;
    Out& mo = open().add(mechanism, Out::map());
    keys_out(mo, keys);
    for (int j = 0; j < 2; ++j) {
      if (has_values(joints[j])) keys_out(mo.add("theta" + std::to_string(j + 1), Out::map()), joints[j]);
    }
  };
  Out* mechanisms = nullptr;
  for (const char* mechanism : {"lower", "upper"}) {
    mechanism_scope("", mechanism, [&]() -> Out& {
      if (mechanisms == nullptr) mechanisms = &out.add("mechanisms", Out::map());
      return *mechanisms;
    });
  }
  Out* stations = nullptr;
  for (const Station& s : d.stations) {
    Out* station = nullptr;
    const auto open_station = [&]() -> Out& {
      if (stations == nullptr) stations = &out.add("stations", Out::map());
      if (station == nullptr) station = &stations->add(s.name, Out::map());
      return *station;
    };
    const MotorOverride keys = merged(m, s.name, "", 0);
    if (has_values(keys)) keys_out(open_station(), keys);
    for (const char* mechanism : {"lower", "upper"}) mechanism_scope(s.name, mechanism, open_station);
  }
}

}  // namespace

Section motor_section() { return {MotorSettings::kKey, &load, &validate, &write}; }

}  // namespace sections
}  // namespace fivebar
