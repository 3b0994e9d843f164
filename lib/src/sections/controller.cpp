// The `controller:` section (fivebar/sections/controller.hpp): the ROS controller of the device.
#include "fivebar/format.hpp"
#include "fivebar/sections/controller.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "sections/rules.hpp"
#include "sections/section.hpp"

namespace fivebar {

using rules::format_degrees;
using rules::plain_number;
using rules::require_range;

namespace {

using format::kDegPerRad;
using format::kRadPerDeg;

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

void require_travel(const std::string& key, double v) {
  // A potentiometer turns at most once: 360 deg is an endless (or continuous-rotation) one.
  if (!(v > 0.0) || !(v <= 2.0 * std::numbers::pi * (1.0 + 1e-15))) {
    throw ValidationError(key, "= " + format_degrees(v) + " deg: must be in (0, 360] deg (the potentiometer's electrical travel)");
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
  if (travel) require_travel("travel_deg", *travel);
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
    if (o.travel) out.potentiometer.travel = *o.travel;
  };
  apply_overrides(overrides, station, mechanism, j, apply);
  return out;
}

PidGains ControllerSettings::hand_set_pid(std::string_view station, std::string_view mechanism, int j) const {
  ControllerSettings without = *this;
  for (ControlOverride& o : without.overrides) {
    if (o.level() >= 3) o.kp = o.ki = o.kd = std::nullopt;
  }
  return without.joint(station, mechanism, j).pid;
}

void TuneSettings::validate() const {
  if (!(rho_limit > 0.0) || !(rho_limit < 1.0)) {
    throw ValidationError("rho_limit", "= " + plain_number(rho_limit) + ": must be in (0, 1) (a spectral radius below 1)");
  }
  if (evaluations < 1 || evaluations > 10000) {
    throw ValidationError("evaluations", "= " + std::to_string(evaluations) + ": must be 1 ... 10000");
  }
  if (!(max_seconds > 0.0) || !(max_seconds <= 3600.0)) {
    throw ValidationError("max_seconds", "= " + plain_number(max_seconds) + " s: must be > 0 and <= 3600 s");
  }
  if (!(min_damping >= 0.0) || !(min_damping < 1.0)) {
    throw ValidationError("min_damping", "= " + plain_number(min_damping) + ": must be in [0, 1) (a damping ratio)");
  }
  if (!(min_gain_margin >= 1.0) || !(min_gain_margin <= 100.0)) {
    throw ValidationError("min_gain_margin", "= " + plain_number(min_gain_margin) + ": must be in [1, 100] (a factor on the gains)");
  }
  if (start != "design" && start != "pole_placement" && start != "hand_set") {
    throw ValidationError("start", "= " + detail::quoted(start) + ": must be design, pole_placement or hand_set");
  }
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
  static const std::array<std::string_view, 6> groups{"kinematics", "potentiometer", "motor", "contact", "density", "tolerance"};
  for (std::size_t i = 0; i < require_measured.size(); ++i) {
    if (std::find(groups.begin(), groups.end(), require_measured[i]) == groups.end()) {
      throw ValidationError("require_measured[" + std::to_string(i) + "]",
                            "= " + detail::quoted(require_measured[i]) +
                                ": must be one of kinematics, potentiometer, motor, contact, density, tolerance");
    }
  }
  if (collision_priority != "upper") {
    throw ValidationError("collision_priority",
                          "= " + detail::quoted(collision_priority) +
                              ": must be upper (the paper's rule, the one fivebar's collision and pattern checks apply)");
  }
  if (!(min_lci >= 0.0) || !(min_lci <= 1.0)) {
    throw ValidationError("min_lci", "= " + plain_number(min_lci) + ": must be in [0, 1]");
  }
  if (!(joint_margin >= 0.0) || !(joint_margin < std::numbers::pi)) {
    throw ValidationError("joint_margin_deg", "= " + format_degrees(joint_margin) + " deg: must be >= 0 and < 180 deg");
  }
  if (!(max_tracking_error_mm > 0.0) || !(max_tracking_error_mm <= 1000.0)) {
    throw ValidationError("max_tracking_error_mm",
                          "= " + plain_number(max_tracking_error_mm) + " mm: must be > 0 and <= 1000 mm");
  }
  if (!(max_saturation_fraction >= 0.0) || !(max_saturation_fraction <= 1.0)) {
    throw ValidationError("max_saturation_fraction", "= " + plain_number(max_saturation_fraction) + ": must be in [0, 1]");
  }
  if (!(target_stiffness_N_per_mm > 0.0) || !(target_stiffness_N_per_mm <= 1e6)) {
    throw ValidationError("target_stiffness_N_per_mm",
                          "= " + plain_number(target_stiffness_N_per_mm) + " N/mm: must be > 0 and <= 1000000 N/mm");
  }
  rules::validate_nested("pid", [&] { pid.validate(); });
  rules::validate_nested("potentiometer", [&] { potentiometer.validate(); });
  if (tune) rules::validate_nested("tune", [&] { tune->validate(); });
  for (const ControlOverride& o : overrides) {
    o.validate();
    const std::string scope = o.key();
    const auto at = [&](std::string_view what) { return detail::key_join(scope, what); };
    if (o.kp) require_gain(at("pid.kp"), *o.kp, "per rad");
    if (o.ki) require_gain(at("pid.ki"), *o.ki, "per rad s");
    if (o.kd) require_gain(at("pid.kd"), *o.kd, "s per rad");
    if (o.i_clamp) require_i_clamp(at("pid.i_clamp"), *o.i_clamp);
    if (o.volts_at_zero) require_volts_at_zero(at("potentiometer.volts_at_zero"), *o.volts_at_zero);
    if (o.rad_per_volt) require_rad_per_volt(at("potentiometer.rad_per_volt"), *o.rad_per_volt);
    if (o.travel) require_travel(at("potentiometer.travel_deg"), *o.travel);
  }
}

namespace sections {
namespace {

/// The `pid:` and `potentiometer:` keys of one scope of `controller:` into `o`.
void control_keys(const std::vector<Value>& all, ControlOverride& o) {
  if (const Value* pid = find(all, "pid")) {
    for (const Value& k : pid->entries({"kp", "ki", "kd", "i_clamp"}, "of PID gains (kp, ki, kd, i_clamp)")) {
      const double v = k.number("");
      (k.name() == "kp" ? o.kp : k.name() == "ki" ? o.ki : k.name() == "kd" ? o.kd : o.i_clamp) = v;
    }
  }
  if (const Value* pot = find(all, "potentiometer")) {
    const auto keys = pot->entries({"volts_at_zero", "volts_per_rad", "rad_per_volt", "travel_deg"},
                                   "(volts_at_zero, volts_per_rad or rad_per_volt, travel_deg)");
    if (const Value* v0 = find(keys, "volts_at_zero")) o.volts_at_zero = v0->number("V");
    if (const Value* t = find(keys, "travel_deg")) o.travel = kRadPerDeg * t->number("deg");
    const Value* vpr = find(keys, "volts_per_rad");
    const Value* rpv = find(keys, "rad_per_volt");
    if (vpr != nullptr && rpv != nullptr) rpv->fail("give volts_per_rad or rad_per_volt, not both (one is 1 / the other)");
    if (rpv != nullptr) o.rad_per_volt = rpv->number("rad/V");
    if (vpr != nullptr) {
      const double v = vpr->number("V/rad");
      if (!(std::abs(v) >= 1e-6) || !(std::abs(v) <= 1e6)) vpr->fail_value("|volts_per_rad| must be in [1e-6, 1e6] (never 0)");
      o.rad_per_volt = 1.0 / v;
      // validate() names rad_per_volt; a rule broken there is this key's.
      vpr->note_as(detail::key_join(detail::key_parent(vpr->path()), "rad_per_volt"));
    }
  }
}

void load(const Value& v, Design& design) {
  ControllerSettings& c = design.set(ControllerSettings{});
  if (v.is_null()) return;  // `controller:` alone: every default
  const auto all = v.entries({"node", "loop_rate_hz", "pwm_hz", "adc", "max_velocity_deg_s", "collision_priority",
                              "min_lci", "joint_margin_deg", "max_tracking_error_mm", "max_saturation_fraction",
                              "target_stiffness_N_per_mm", "pid", "potentiometer", "tune", "mechanisms", "stations",
                              "require_measured"},
                             "(node, loop_rate_hz, pwm_hz, adc, max_velocity_deg_s, collision_priority, min_lci, "
                             "joint_margin_deg, max_tracking_error_mm, max_saturation_fraction, "
                             "target_stiffness_N_per_mm, pid, potentiometer, tune, mechanisms, stations, require_measured)");
  if (const Value* r = find(all, "require_measured")) {
    for (const Value& g : r->list("must be a list of groups (kinematics, potentiometer, motor, contact, density, tolerance)")) {
      c.require_measured.push_back(g.text("must be a group name"));
    }
  }
  if (const Value* n = find(all, "node")) c.node = n->text("must be a ROS 2 node name");
  c.loop_rate_hz = number_or(all, "loop_rate_hz", c.loop_rate_hz, "Hz");
  c.pwm_hz = number_or(all, "pwm_hz", c.pwm_hz, "Hz");
  if (const Value* adc = find(all, "adc")) {
    const auto keys = adc->entries({"bits", "range_v"}, "(bits, range_v)");
    if (const Value* b = find(keys, "bits")) c.adc_bits = int(b->whole(1, 32));
    if (const Value* r = find(keys, "range_v")) {
      const auto ends = r->items(2, "a list [low, high] (V)");
      for (std::size_t i = 0; i < 2; ++i) c.adc_range_v[i] = ends[i].number("V");
    }
  }
  if (const Value* speed = find(all, "max_velocity_deg_s")) c.max_velocity = kRadPerDeg * speed->number("deg/s");
  if (const Value* p = find(all, "collision_priority")) c.collision_priority = p->text("must be upper");
  c.min_lci = number_or(all, "min_lci", c.min_lci, "");
  if (const Value* m = find(all, "joint_margin_deg")) c.joint_margin = kRadPerDeg * m->number("deg");
  c.max_tracking_error_mm = number_or(all, "max_tracking_error_mm", c.max_tracking_error_mm, "mm");
  c.max_saturation_fraction = number_or(all, "max_saturation_fraction", c.max_saturation_fraction, "");
  c.target_stiffness_N_per_mm = number_or(all, "target_stiffness_N_per_mm", c.target_stiffness_N_per_mm, "N/mm");
  ControlOverride defaults;
  control_keys(all, defaults);
  if (defaults.kp) c.pid.kp = *defaults.kp;
  if (defaults.ki) c.pid.ki = *defaults.ki;
  if (defaults.kd) c.pid.kd = *defaults.kd;
  if (defaults.i_clamp) c.pid.i_clamp = *defaults.i_clamp;
  if (defaults.volts_at_zero) c.potentiometer.volts_at_zero = *defaults.volts_at_zero;
  if (defaults.rad_per_volt) c.potentiometer.rad_per_volt = *defaults.rad_per_volt;
  if (defaults.travel) c.potentiometer.travel = *defaults.travel;
  if (const Value* t = find(all, "tune")) {
    TuneSettings& tune = c.tune.emplace();
    if (!t->is_null()) {  // `tune:` alone: every default
      const auto keys = t->entries({"rho_limit", "evaluations", "max_seconds", "per_joint", "start", "min_damping",
                                    "min_gain_margin"},
                                   "(rho_limit, evaluations, max_seconds, per_joint, start, min_damping, min_gain_margin)");
      tune.min_damping = number_or(keys, "min_damping", tune.min_damping, "");
      tune.min_gain_margin = number_or(keys, "min_gain_margin", tune.min_gain_margin, "");
      tune.rho_limit = number_or(keys, "rho_limit", tune.rho_limit, "");
      if (const Value* n = find(keys, "evaluations")) tune.evaluations = int(n->whole(1, 10000));
      tune.max_seconds = number_or(keys, "max_seconds", tune.max_seconds, "s");
      if (const Value* pj = find(keys, "per_joint")) {
        const std::string word = pj->text("a boolean: true or false");
        if (word != "true" && word != "false") pj->fail_value("must be true or false");
        tune.per_joint = word == "true";
      }
      if (const Value* st = find(keys, "start")) tune.start = st->text("must be design, pole_placement or hand_set");
    }
  }

  // One mechanism's scope (of a station, or of every station when `station` is empty) and its joints.
  const auto mechanism_scope = [&](const Value& m, const std::string& station) {
    const auto mech_keys = m.entries({"pid", "potentiometer", "theta1", "theta2"}, "(pid, potentiometer, theta1, theta2)");
    ControlOverride mo;
    mo.station = station;
    mo.mechanism = m.name();
    control_keys(mech_keys, mo);
    c.overrides.push_back(mo);
    for (const Value& j : mech_keys) {
      if (j.name() != "theta1" && j.name() != "theta2") continue;
      ControlOverride jo = mo;
      jo.kp = jo.ki = jo.kd = jo.i_clamp = jo.volts_at_zero = jo.rad_per_volt = jo.travel = std::nullopt;
      jo.joint = j.name() == "theta1" ? 1 : 2;
      control_keys(j.entries({"pid", "potentiometer"}, "(pid, potentiometer)"), jo);
      c.overrides.push_back(jo);
    }
  };
  if (const Value* mechanisms = find(all, "mechanisms")) {
    for (const Value& m : mechanisms->entries({"lower", "upper"}, "with keys lower and/or upper (every station's)")) {
      mechanism_scope(m, "");
    }
  }
  if (const Value* stations = find(all, "stations")) {
    for (const Value& st : stations->entries({}, "of station names to their overrides", /*any_key=*/true)) {
      // An empty name would read as every station's scope (JointScope): refused here, at its line.
      if (st.name().empty()) st.fail("a station name must not be empty");
      const auto station_keys = st.entries({"pid", "potentiometer", "lower", "upper"}, "(pid, potentiometer, lower, upper)");
      ControlOverride so;
      so.station = st.name();
      control_keys(station_keys, so);
      c.overrides.push_back(so);
      for (const Value& m : station_keys) {
        if (m.name() == "lower" || m.name() == "upper") mechanism_scope(m, st.name());
      }
    }
  }
}

void validate(const Design& design) {
  const ControllerSettings* controller = design.get<ControllerSettings>();
  if (controller == nullptr) return;
  rules::validate_nested("controller", [&] { controller->validate(); });
  for (const ControlOverride& o : controller->overrides) o.validate_in(design, "controller");
}

// --- writer ----------------------------------------------------------------------------------

/// The keys a set of overrides of one scope gives, later ones winning (as ControllerSettings::joint()).
ControlOverride merged(const std::vector<const ControlOverride*>& scope) {
  ControlOverride m;
  for (const ControlOverride* o : scope) {
    for (auto [to, from] : {std::pair{&m.kp, &o->kp}, std::pair{&m.ki, &o->ki}, std::pair{&m.kd, &o->kd},
                            std::pair{&m.i_clamp, &o->i_clamp}, std::pair{&m.volts_at_zero, &o->volts_at_zero},
                            std::pair{&m.rad_per_volt, &o->rad_per_volt}, std::pair{&m.travel, &o->travel}}) {
      if (*from) *to = *from;
    }
  }
  return m;
}

bool has_keys(const ControlOverride& o) {
  return o.kp || o.ki || o.kd || o.i_clamp || o.volts_at_zero || o.rad_per_volt || o.travel;
}

/// `pid:` and `potentiometer:` of one scope, only the keys it gives.
void control_keys_out(Out& out, const ControlOverride& o) {
  if (o.kp || o.ki || o.kd || o.i_clamp) {
    Out& pid = out.add("pid", Out::map(/*flow=*/true));
    if (o.kp) pid.add("kp", Out::number(*o.kp));
    if (o.ki) pid.add("ki", Out::number(*o.ki));
    if (o.kd) pid.add("kd", Out::number(*o.kd));
    if (o.i_clamp) pid.add("i_clamp", Out::number(*o.i_clamp));
  }
  if (o.volts_at_zero || o.rad_per_volt || o.travel) {
    Out& pot = out.add("potentiometer", Out::map(/*flow=*/true));
    if (o.volts_at_zero) pot.add("volts_at_zero", Out::number(*o.volts_at_zero));
    if (o.rad_per_volt) pot.add("rad_per_volt", Out::number(*o.rad_per_volt));
    if (o.travel) pot.add("travel_deg", Out::degrees(*o.travel));
  }
}

void write(const Design& d, Out& top) {
  const ControllerSettings* cp = d.get<ControllerSettings>();
  if (cp == nullptr) return;
  const ControllerSettings& c = *cp;
  Out& out = top.add("controller", Out::map());
  out.add("node", Out::quoted(c.node));
  out.add("loop_rate_hz", Out::number(c.loop_rate_hz));
  out.add("pwm_hz", Out::number(c.pwm_hz));
  Out& adc = out.add("adc", Out::map(/*flow=*/true));
  adc.add("bits", Out::integer(c.adc_bits));
  Out& range = adc.add("range_v", Out::list());
  range.push(Out::number(c.adc_range_v[0]));
  range.push(Out::number(c.adc_range_v[1]));
  out.add("max_velocity_deg_s", Out::degrees(c.max_velocity));
  out.add("collision_priority", Out::quoted(c.collision_priority));
  out.add("min_lci", Out::number(c.min_lci));
  out.add("joint_margin_deg", Out::degrees(c.joint_margin));
  out.add("max_tracking_error_mm", Out::number(c.max_tracking_error_mm));
  out.add("max_saturation_fraction", Out::number(c.max_saturation_fraction));
  out.add("target_stiffness_N_per_mm", Out::number(c.target_stiffness_N_per_mm));
  if (!c.require_measured.empty()) {
    Out& r = out.add("require_measured", Out::list());
    for (const std::string& g : c.require_measured) r.push(Out::plain(g));
  }
  ControlOverride defaults;
  defaults.kp = c.pid.kp, defaults.ki = c.pid.ki, defaults.kd = c.pid.kd, defaults.i_clamp = c.pid.i_clamp;
  defaults.volts_at_zero = c.potentiometer.volts_at_zero, defaults.rad_per_volt = c.potentiometer.rad_per_volt;
  defaults.travel = c.potentiometer.travel;
  control_keys_out(out, defaults);
  if (c.tune) {
    Out& t = out.add("tune", Out::map(/*flow=*/true));
    t.add("rho_limit", Out::number(c.tune->rho_limit));
    t.add("evaluations", Out::integer(c.tune->evaluations));
    t.add("max_seconds", Out::number(c.tune->max_seconds));
    t.add("per_joint", Out::plain(c.tune->per_joint ? "true" : "false"));
    t.add("start", Out::plain(c.tune->start));
    t.add("min_damping", Out::number(c.tune->min_damping));
    t.add("min_gain_margin", Out::number(c.tune->min_gain_margin));
  }

  // Overrides in canonical form: every station's mechanisms, then by station (design order), then
  // mechanism, then joint.
  const auto scope = [&](const std::string& station, const std::string& mechanism, int joint) {
    std::vector<const ControlOverride*> found;
    for (const ControlOverride& o : c.overrides) {
      if (o.station == station && o.mechanism == mechanism && o.joint == joint) found.push_back(&o);
    }
    return merged(found);
  };
  // One mechanism's scope and its joints under `parent` (opened on demand); nothing when it gives none.
  const auto mechanism_scope = [&](const std::string& station, const char* mechanism, const auto& open) {
    const ControlOverride mech_keys = scope(station, mechanism, 0);
    const ControlOverride joint_keys[2] = {scope(station, mechanism, 1), scope(station, mechanism, 2)};
    if (!has_keys(mech_keys) && !has_keys(joint_keys[0]) && !has_keys(joint_keys[1])) return;
    Out& m = open().add(mechanism, Out::map());
    control_keys_out(m, mech_keys);
    for (int j = 0; j < 2; ++j) {
      if (!has_keys(joint_keys[j])) continue;
      control_keys_out(m.add("theta" + std::to_string(j + 1), Out::map()), joint_keys[j]);
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
    const ControlOverride station_keys = scope(s.name, "", 0);
    if (has_keys(station_keys)) control_keys_out(open_station(), station_keys);
    for (const char* mechanism : {"lower", "upper"}) mechanism_scope(s.name, mechanism, open_station);
  }
}

}  // namespace

Section controller_section() { return {ControllerSettings::kKey, &load, &validate, &write}; }

}  // namespace sections
}  // namespace fivebar
