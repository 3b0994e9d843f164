// The scope of a per-joint override (fivebar/sections/scope.hpp).

#include "fivebar/sections/scope.hpp"

#include "fivebar/design.hpp"
#include "fivebar/error.hpp"
#include "sections/rules.hpp"

namespace fivebar {

std::string JointScope::key() const {
  std::string k = station.empty() ? std::string("mechanisms") : detail::key_child("stations", station);
  if (!mechanism.empty()) k = detail::key_join(k, mechanism);
  if (joint != 0) k = detail::key_join(k, "theta" + std::to_string(joint));
  return k;
}

int JointScope::level() const {
  if (station.empty()) return joint == 0 ? 0 : 1;
  if (mechanism.empty()) return 2;
  return joint == 0 ? 3 : 4;
}

bool JointScope::covers(std::string_view s, std::string_view m, int j) const {
  return (station.empty() || station == s) && (mechanism.empty() || mechanism == m) && (joint == 0 || joint == j);
}

void JointScope::validate() const {
  const std::string scope = key();
  if (!mechanism.empty() && mechanism != "lower" && mechanism != "upper") {
    throw ValidationError(scope, "mechanism " + detail::quoted(mechanism) + " must be lower or upper");
  }
  if (station.empty() && mechanism.empty()) {
    throw ValidationError(scope, "an override names a station, a mechanism (lower, upper) or both");
  }
  if (joint < 0 || joint > 2 || (joint != 0 && mechanism.empty())) {
    throw ValidationError(scope, "joint " + std::to_string(joint) + " must be 1 or 2 within a mechanism");
  }
}

void JointScope::validate_in(const Design& design, std::string_view section) const {
  // Every station's lower / upper: none is fine. A scope with neither is a station named "" (a
  // `patterns:` entry, which has no mechanism; validate() refuses one of controller: or motor:).
  if (station.empty() && !mechanism.empty()) return;
  const Station* st = design.station(station);
  if (st == nullptr) {
    throw ValidationError(detail::key_join(section, detail::key_child("stations", station)),
                          "no such station in this design (stations: " + rules::station_list(design) + ")");
  }
  if (!mechanism.empty() && st->mechanism(mechanism) == nullptr) {
    throw ValidationError(detail::key_join(section, key()),
                          "station " + detail::quoted(station) + " has no " + mechanism + " mechanism");
  }
}

}  // namespace fivebar
