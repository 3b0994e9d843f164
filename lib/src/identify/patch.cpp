// The design an identification patches (fivebar/identify/patch.hpp).
#include "fivebar/identify/patch.hpp"

#include <algorithm>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/sections/motor.hpp"

namespace fivebar::identify {

namespace {

/// Splits "motor.<scope>.<field>" into the scope ("" or "stations.S.M.thetaJ") and the field.
bool split_motor_key(const std::string& key, std::string& scope, std::string& field) {
  if (key.rfind("motor.", 0) != 0) return false;
  const std::size_t dot = key.rfind('.');
  field = key.substr(dot + 1);
  scope = dot > 5 ? key.substr(6, dot - 6) : std::string();
  return true;
}

}  // namespace

std::vector<std::string> patched_keys(const std::vector<JointIdentification>& results) {
  std::vector<std::string> keys;
  const auto& fields = motor_fields();
  for (const JointIdentification& r : results) {
    for (const Parameter& p : r.parameters) {
      std::string scope, field;
      if (!p.identified || !split_motor_key(p.key, scope, field)) continue;
      const auto f = std::find_if(fields.begin(), fields.end(), [&](const MotorField& x) { return x.key == field; });
      if (f != fields.end() && !((p.value > f->lo || (f->zero_ok && p.value >= f->lo)) && p.value <= f->hi)) continue;
      keys.push_back(p.key);
    }
  }
  return keys;
}

Design patched_design(const Design& design, const std::vector<JointIdentification>& results, const MeasurementSource& source,
                      std::vector<std::string>* skipped) {
  Design d = design;
  MotorSettings* ms = d.get<MotorSettings>();
  std::vector<MeasuredValue> values;
  for (const JointIdentification& r : results) {
    for (const Parameter& p : r.parameters) {
      std::string scope, field;
      if (!p.identified || !split_motor_key(p.key, scope, field)) continue;
      if (ms == nullptr) throw InputError(design.name + ": the design has no `motor:` section to patch (" + p.key + ")");
      const auto& fields = motor_fields();
      const auto f = std::find_if(fields.begin(), fields.end(), [&](const MotorField& x) { return x.key == field; });
      if (f == fields.end()) throw InputError(p.key + ": not a key of the `motor:` section");
      // A value the `motor:` section's rules refuse (a friction estimated below zero within its
      // noise) is not written: the key stays an assumption, and the caller says why.
      const bool in_range = (p.value > f->lo || (f->zero_ok && p.value >= f->lo)) && p.value <= f->hi;
      if (!in_range) {
        if (skipped != nullptr) {
          skipped->push_back(p.key + " = " + format::shortest(p.value) + " " + std::string(f->unit) +
                             " (sigma " + format::shortest(p.sigma) + "): outside the motor: section's range, not written");
        }
        continue;
      }
      if (scope.empty()) {
        ms->defaults.*(f->member) = p.value;
      } else {
        // stations.<station>.<mechanism>.theta<j>: the joint's own scope, created when absent.
        const std::size_t a = scope.find('.'), b = scope.rfind('.');
        const std::size_t m = scope.rfind('.', b - 1);
        if (scope.rfind("stations.", 0) != 0 || a == b || m <= a || scope.compare(b + 1, 5, "theta") != 0) {
          throw InputError(p.key + ": expected motor.stations.<station>.<mechanism>.theta<j>.<key>");
        }
        MotorOverride key;
        key.station = scope.substr(a + 1, m - a - 1);
        key.mechanism = scope.substr(m + 1, b - m - 1);
        key.joint = scope.back() - '0';
        const Station* st = d.station(key.station);
        if (st == nullptr || st->mechanism(key.mechanism) == nullptr || (key.joint != 1 && key.joint != 2)) {
          throw InputError(p.key + ": the design has no joint " + key.station + "/" + key.mechanism + "/theta" + std::to_string(key.joint));
        }
        auto it = std::find_if(ms->overrides.begin(), ms->overrides.end(), [&](const MotorOverride& o) {
          return o.station == key.station && o.mechanism == key.mechanism && o.joint == key.joint;
        });
        if (it == ms->overrides.end()) {
          ms->overrides.push_back(key);
          it = std::prev(ms->overrides.end());
        }
        it->values[static_cast<std::size_t>(f - fields.begin())] = p.value;
      }
      values.push_back({p.key, p.sigma});
    }
  }
  d.validate();
  return with_measured_values(d, values, source);
}

}  // namespace fivebar::identify
