// The tuned gains as edits of the design file's numbers (fivebar/control/tune.hpp gain_merge()).

#include <array>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "fivebar/control.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/format.hpp"
#include "fivebar/sections/controller.hpp"

namespace fivebar {

namespace {

constexpr std::array<const char*, 3> kGains{"kp", "ki", "kd"};

double gain_of(const PidGains& g, std::size_t i) { return i == 0 ? g.kp : i == 1 ? g.ki : g.kd; }

/// Where gain `i` of a joint is written: the narrowest scope that sets it, else controller.pid.
std::string gain_key(const ControllerSettings& c, const std::string& station, const std::string& mechanism, int joint,
                     std::size_t i) {
  std::string key = std::string("controller.pid.") + kGains[i];
  apply_overrides(c.overrides, station, mechanism, joint, [&](const ControlOverride& o) {
    const std::optional<double>& v = i == 0 ? o.kp : i == 1 ? o.ki : o.kd;
    if (v) key = "controller." + o.key() + ".pid." + kGains[i];
  });
  return key;
}

/// The checks of the export gate on the loop, and the tuning's floors, for one tuned mechanism.
void gate(const TunedMechanism& t, const TuneResult& r, const ControllerSettings& c, std::vector<std::string>& refusals) {
  const std::string who = t.station + "/" + t.mechanism + ": ";
  if (!t.not_computed_after.empty()) {
    refusals.push_back(who + "figures not computed within the time bound (" + format::join(t.not_computed_after) +
                       "): nothing to check them against");
    return;
  }
  if (!(t.rho_after < 1.0)) refusals.push_back(who + "unstable, max rho " + format::fixed(t.rho_after, 4) + " >= 1 (export gate: stability)");
  if (!(t.error_after_mm <= c.max_tracking_error_mm)) {
    refusals.push_back(who + "tracking error " + format::fixed(t.error_after_mm, 3) + " mm > controller.max_tracking_error_mm " +
                       format::shortest(c.max_tracking_error_mm) + " (export gate: tracking)");
  }
  if (!(t.saturation_after <= c.max_saturation_fraction)) {
    refusals.push_back(who + "saturated " + format::fixed(100.0 * t.saturation_after, 1) +
                       " % of the time > controller.max_saturation_fraction " + format::shortest(c.max_saturation_fraction) +
                       " (export gate: saturation)");
  }
  if (!t.feasible) {
    std::vector<std::string> missed;
    if (!(t.rho_after <= r.rho_limit)) missed.push_back("max rho " + format::fixed(t.rho_after, 4) + " > " + format::shortest(r.rho_limit));
    if (!(t.damping_after >= r.min_damping)) missed.push_back("least zeta " + format::fixed(t.damping_after, 3) + " < " + format::shortest(r.min_damping));
    if (!(t.kp_margin_after >= r.min_gain_margin)) missed.push_back("kp margin x" + format::fixed(t.kp_margin_after, 2));
    if (!(t.kd_margin_after >= r.min_gain_margin)) missed.push_back("kd margin x" + format::fixed(t.kd_margin_after, 2));
    if (!(t.overshoot_after_mm <= r.max_overshoot_fraction * SimulationRequest{}.step_mm)) {
      missed.push_back("1 mm step overshoot " + format::fixed(t.overshoot_after_mm, 3) + " mm");
    }
    refusals.push_back(who + "misses the tuning's floors" + (missed.empty() ? std::string() : " (" + format::join(missed) + ")"));
  }
}

}  // namespace

GainMerge gain_merge(const Design& design, const TuneResult& result) {
  GainMerge out;
  const ControllerSettings* c = design.get<ControllerSettings>();
  if (c == nullptr) {
    out.refusals.push_back("the design has no controller: section");
    return out;
  }
  std::map<std::string, const TunedMechanism*> tuned;
  for (const TunedMechanism& t : result.mechanisms) {
    tuned[t.station + "/" + t.mechanism] = &t;
    gate(t, result, *c, out.refusals);
  }
  // Per key: the value every joint it sets must get (the tuned one, or its own when not tuned).
  struct Wanted {
    double value = 0.0, now = 0.0;
    std::string first;  // the joint that set `value`
    bool refused = false;
  };
  std::map<std::string, Wanted> keys;
  std::vector<std::string> order;
  for (const Station& s : design.stations) {
    for (const Mechanism* m : s.mechanisms()) {
      const auto it = tuned.find(s.name + "/" + m->name);
      for (int j = 1; j <= 2; ++j) {
        const PidGains now = c->joint(s.name, m->name, j).pid;
        for (std::size_t i = 0; i < 3; ++i) {
          const std::string key = gain_key(*c, s.name, m->name, j, i);
          const double want = it != tuned.end() ? gain_of(it->second->after[std::size_t(j - 1)], i) : gain_of(now, i);
          const std::string who = s.name + "/" + m->name + " theta" + std::to_string(j) +
                                  (it != tuned.end() ? " (tuned)" : " (not tuned)");
          const auto k = keys.find(key);
          if (k == keys.end()) {
            keys[key] = {want, gain_of(now, i), who, false};
            order.push_back(key);
          } else if (k->second.value != want && !k->second.refused) {
            k->second.refused = true;
            out.refusals.push_back(key + " sets both " + k->second.first + " (" + format::shortest(k->second.value) + ") and " +
                                   who + " (" + format::shortest(want) +
                                   "): the merge changes numbers only and adds no scope (write the scopes of "
                                   "tuned-controller.yaml into the design first)");
          }
        }
      }
    }
  }
  for (const std::string& key : order) {
    const Wanted& w = keys[key];
    if (w.value != w.now) out.edits.push_back({key, w.value});
  }
  return out;
}

}  // namespace fivebar
