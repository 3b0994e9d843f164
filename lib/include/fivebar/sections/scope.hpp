#pragma once
/// Where an override of a per-joint section applies (`controller:` and `motor:`): every station's
/// lower or upper mechanism (`mechanisms.lower`), one station (`stations.index`), one of its
/// mechanisms (`stations.index.upper`) or one joint of a mechanism (`...theta1`). Narrower scopes
/// win over wider ones whatever their order in the file. One definition of the scope rule for every
/// section that has one (docs/design-file.md, `controller.<scope>` and `motor.<scope>`, and
/// `patterns.stations.<station>`, whose overrides are at station level and looked up for a
/// station's pair: mechanism "" and joint 0).

#include <string>
#include <string_view>
#include <vector>

namespace fivebar {

struct Design;

struct JointScope {
  std::string station;    ///< empty: every station (then `mechanism` is set)
  std::string mechanism;  ///< "lower", "upper", or empty: every mechanism of the station
  int joint = 0;          ///< 1 or 2 (theta1, theta2), or 0: both joints

  /// Key path of this scope relative to its section ("stations.index.lower.theta1",
  /// "mechanisms.upper").
  std::string key() const;
  /// 0 ... 4, widest first: mechanisms.M, mechanisms.M.thetaJ, stations.S, stations.S.M,
  /// stations.S.M.thetaJ.
  int level() const;
  /// Whether the scope covers joint `joint` (1, 2) of mechanism `mechanism` of station `station`.
  bool covers(std::string_view station, std::string_view mechanism, int joint) const;
  /// Throws ValidationError(key(), rule) unless the scope is well formed (a known mechanism name,
  /// a joint only within a mechanism, not every station and mechanism at once).
  void validate() const;
  /// Throws ValidationError("<section>.<key>", rule) when the scope names a station or a
  /// mechanism the design does not have (a station "", when no mechanism is set, is one).
  void validate_in(const Design& design, std::string_view section) const;
};

/// Calls `apply(o)` for each override of `overrides` (types derived from JointScope) covering the
/// joint, widest scope first, so that narrower keys win.
template <class Override, class Apply>
void apply_overrides(const std::vector<Override>& overrides, std::string_view station, std::string_view mechanism,
                     int joint, Apply&& apply) {
  for (int level = 0; level <= 4; ++level) {
    for (const Override& o : overrides) {
      if (o.level() == level && o.covers(station, mechanism, joint)) apply(o);
    }
  }
}

}  // namespace fivebar
