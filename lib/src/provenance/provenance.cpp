// Measured or assumed (fivebar/provenance.hpp).
#include "fivebar/provenance.hpp"

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/print.hpp"
#include "fivebar/sections/provenance.hpp"

namespace fivebar {

const std::vector<std::string>& provenance_groups() {
  static const std::vector<std::string> groups{"kinematics", "potentiometer", "motor", "contact", "density", "tolerance"};
  return groups;
}

bool is_measured(const Design& design, std::string_view key) {
  const ProvenanceSettings* p = design.get<ProvenanceSettings>();
  if (p == nullptr) return false;
  for (const auto& [k, entry] : p->entries) {
    if (key == k) return true;
    if (key.size() > k.size() && key.substr(0, k.size()) == k && (key[k.size()] == '.' || key[k.size()] == '[')) return true;
  }
  return false;
}

std::vector<std::string> assumed_values(const Design& design, std::string_view group) {
  std::vector<std::string> keys;
  if (group == "kinematics") {
    for (const Station& s : design.stations) {
      for (const Mechanism* m : s.mechanisms()) {
        const std::string k = "stations." + s.name + ".mechanisms." + m->name + ".";
        for (int i = 0; i < 4; ++i) keys.push_back(k + "links[" + std::to_string(i) + "]");
        for (const char* b : {"bases[0][0]", "bases[0][1]", "bases[1][0]", "bases[1][1]"}) keys.push_back(k + b);
      }
    }
  } else if (group == "potentiometer") {
    const ControllerSettings* c = design.get<ControllerSettings>();
    if (c != nullptr) {
      for (const Station& s : design.stations) {
        for (const Mechanism* m : s.mechanisms()) {
          for (int j = 1; j <= 2; ++j) {
            // The narrowest scope that sets each value (ControlOverride levels; file order within one).
            std::string v0 = "controller.potentiometer.volts_at_zero", k = "controller.potentiometer.rad_per_volt";
            int l0 = -1, lk = -1;
            for (const ControlOverride& o : c->overrides) {
              const bool applies = (o.station.empty() || o.station == s.name) && (o.mechanism.empty() || o.mechanism == m->name) &&
                                   (o.joint == 0 || o.joint == j);
              if (!applies) continue;
              if (o.volts_at_zero && o.level() >= l0) l0 = o.level(), v0 = "controller." + o.key() + ".potentiometer.volts_at_zero";
              if (o.rad_per_volt && o.level() >= lk) lk = o.level(), k = "controller." + o.key() + ".potentiometer.rad_per_volt";
            }
            for (const std::string& key : {v0, k}) {
              if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
            }
          }
        }
      }
    }
  } else if (group == "motor" || group == "contact" || group == "tolerance") {
    keys = design_number_keys(design, group);
  } else if (group == "density") {
    if (design.has<PrintSettings>()) keys.push_back("print.density_g_cm3");
  } else {
    throw InputError("unknown provenance group '" + std::string(group) + "' (known: " + format::join(provenance_groups()) + ")");
  }
  std::erase_if(keys, [&](const std::string& k) { return is_measured(design, k); });
  return keys;
}

std::vector<std::string> assumed_groups(const Design& design) {
  std::vector<std::string> out;
  for (const std::string& g : provenance_groups()) {
    if (!assumed_values(design, g).empty()) out.push_back(g);
  }
  return out;
}

}  // namespace fivebar
