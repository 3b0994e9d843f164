#pragma once
/// One way to edit a design: a number set by its key path (docs/reliability.md "Key paths"),
/// shared by the sweep, the optimiser and the tests, with the minimum-length rules in one place.
///
/// A key path has one canonical spelling, the one messages print: map keys joined by '.', a name
/// that is not a plain word ([A-Za-z0-9_-]+) quoted as ["a.b"], list indices as [i] in decimal
/// without leading zeros. Accepted spellings of the same number: indices with leading zeros or
/// blanks ([02], [ 2 ]), quoted plain names (["index"], ['index']), and a dotted name written
/// bare (stations.a.b.target.angle for a station named "a.b"; the longest name wins). Two
/// spellings of one number resolve to one DesignKey with the same `path`.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"

namespace fivebar {

struct Geometry;

/// A key path resolved against a design: its canonical spelling, the number it holds now (file
/// units) and, for a station's own numbers, where that number lives (so it can be set without
/// writing and re-reading the design file).
struct DesignKey {
  enum class Field : unsigned char { other, link, base, center, axes, angle };
  std::string path;        ///< canonical spelling
  double value = 0.0;      ///< the number at the key, file units (mm, deg)
  Field field = Field::other;
  std::string station;     ///< the station whose number it is (empty: a number outside `stations:`)
  bool upper = false;      ///< link, base: the upper mechanism
  int i = 0, j = 0;        ///< link i; base i coordinate j; center / axes i
};

/// `key` resolved against `design`. ValidationError naming the key when the path is malformed,
/// leads nowhere or to something that is not a number.
DesignKey design_key(const Design& design, std::string_view key);
/// Every key resolved against one reading of the design: time linear in the design and the keys.
std::vector<DesignKey> design_keys(const Design& design, const std::vector<std::string>& keys);
/// The canonical spelling of `key` (design_key(design, key).path).
std::string canonical_design_key(const Design& design, std::string_view key);

/// Sets one station number (key.field != other) in `station`, file units; no rule checked.
void set_station_number(Station& station, const DesignKey& key, double value);
/// The rules an edited station must keep: Station::validate() and, with link geometry, the
/// printable-link rule (check_printable_links). Keys relative to the station ("links[2]" under
/// "mechanisms.lower", "target.axes[0]").
void check_station_edit(const Station& station, const Geometry* geometry);
/// Every link at least as long as geometry.boss_diameter (the pin bosses at its ends would
/// overlap otherwise). ValidationError with the key relative to the station
/// ("mechanisms.lower.links[2]"). The one statement of this rule.
void check_printable_links(const Station& station, const Geometry& geometry);

/// Sets the number at `key` (file units). A station's number is set in place and the whole
/// design's rules are checked (Design::validate() and the sections' rules through the loader's
/// writer and reader are not needed for it); any other number goes through the design file
/// (to_yaml, the loader), so every rule of the file applies. InputError / ValidationError on a
/// broken rule; `design` is unchanged then.
void set_design_number(Design& design, std::string_view key, double value);

}  // namespace fivebar
