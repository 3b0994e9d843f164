#pragma once
/// The design-section plug-in (docs/architecture.md "Design sections"). A section is a top-level
/// key of a design file beside `name`, `stations` and `products`; each is one module:
///   - its settings type in fivebar/sections/<key>.hpp, with `kKey` and validate();
///   - lib/src/sections/<key>.cpp defining `Section <key>_section()`: how to read it, which rules
///     need the rest of the design, and how to write it back;
///   - one line in lib/src/sections/sections.def (the order in which files list them).
/// The loader and the writer (lib/src/yaml/) go through these hooks only, so neither they nor
/// Design know any section's type. yaml-cpp stays behind Value and Out. Private to the library.

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fivebar/design.hpp"

namespace fivebar::sections {

/// One value of a design file at a key path, as a section's loader reads it. Every failure
/// throws InputError naming the file, the line, the full key path and the value
/// ("d.yaml:12: geometry.pin_diameter = abc: must be a number (mm)").
class Value {
 public:
  struct Impl;  ///< defined next to the YAML parser (lib/src/yaml/design_loader.cpp)
  explicit Value(std::shared_ptr<const Impl> impl);

  const std::string& name() const;  ///< the key of this value (empty for a list element)
  const std::string& path() const;  ///< full key path ("controller.pid.kp")
  int line() const;                 ///< 1-based line of the key (or element)
  bool is_null() const;             ///< `key:` with nothing after it
  bool is_scalar() const;
  bool is_list() const;

  /// The entries of a map, in file order; every name must be in `allowed` (unless `any_key`),
  /// none may repeat. `expected` completes "must be a map ..." in messages.
  std::vector<Value> entries(std::initializer_list<std::string_view> allowed, std::string_view expected,
                             bool any_key = false) const;
  /// The elements of a list of exactly `n` elements (`expected` describes it).
  std::vector<Value> items(std::size_t n, std::string_view expected) const;
  /// The elements of a list of any length (`rule` is the message when it is not a list).
  std::vector<Value> list(std::string_view rule) const;
  /// A finite number; `unit` is named in messages ("mm", "deg", "" for none).
  double number(std::string_view unit) const;
  /// A whole number in [lo, hi].
  std::uint64_t whole(double lo, double hi) const;
  /// A scalar as text; `rule` is the message when it is not a scalar.
  std::string text(std::string_view rule) const;
  /// A list [x, y] of two numbers (mm).
  Vec2 point(std::string_view expected) const;

  /// Throws "file:line: path: rule".
  [[noreturn]] void fail(const std::string& rule) const;
  /// Throws "file:line: path = value: rule".
  [[noreturn]] void fail_value(const std::string& rule) const;
  /// Throws "file:line: path.name: required key is missing" at this map's line.
  [[noreturn]] void fail_missing(std::string_view name) const;
  /// Records that validate()'s key `path` is spelt by this value in the file (an alias such as
  /// volts_per_rad for rad_per_volt), so that a rule broken there points at this line.
  void note_as(const std::string& path) const;

 private:
  std::shared_ptr<const Impl> impl_;
};

/// The entry called `name`, or nullptr.
const Value* find(const std::vector<Value>& entries, std::string_view name);
/// The entry called `name`; fails at `map` when it is missing.
const Value& require(const std::vector<Value>& entries, std::string_view name, const Value& map);
/// The number of entry `name` in `unit`, or `fallback` when absent.
double number_or(const std::vector<Value>& entries, std::string_view name, double fallback, std::string_view unit);

/// A YAML tree to write, built by a section's writer and emitted by lib/src/yaml/design_writer.cpp.
struct Out {
  enum class Kind { plain, quoted, list, map };
  struct Entry;  ///< a map entry (key, value) or a list item (empty key)
  Kind kind = Kind::map;
  bool flow = false;  ///< [a, b] / {k: v} on one line
  std::string text;   ///< plain or quoted scalar
  std::vector<Entry> entries;  ///< map entries, or list items

  static Out map(bool flow = false);
  static Out list(bool flow = true);
  /// A number in its shortest round-trip form (0.1, not 0.10000000000000001).
  static Out number(double v);
  static Out integer(long long v);
  /// Radians as degrees with the fewest digits (from 12) that read back as the same radians.
  static Out degrees(double radians);
  static Out plain(std::string text);
  static Out quoted(std::string text);
  /// [x, y] (mm).
  static Out point(const Vec2& p);

  /// Adds `key: value` to a map.
  Out& add(std::string key, Out value);
  /// Appends an item to a list.
  Out& push(Out value);
};

struct Out::Entry {
  std::string first;  ///< the key (empty for a list item)
  Out second;
};

inline Out Out::map(bool flow) { Out o; o.kind = Kind::map; o.flow = flow; return o; }
inline Out Out::list(bool flow) { Out o; o.kind = Kind::list; o.flow = flow; return o; }
inline Out Out::plain(std::string text) { Out o; o.kind = Kind::plain; o.text = std::move(text); return o; }
inline Out Out::quoted(std::string text) { Out o; o.kind = Kind::quoted; o.text = std::move(text); return o; }

/// One design section's hooks.
struct Section {
  std::string_view key;  ///< the top-level key, T::kKey
  /// Reads `value` (the section's entry) into the design; the section named `reads` (if any) is
  /// already there (patterns read the controller's rate and speed limit).
  void (*load)(const Value& value, Design& design) = nullptr;
  /// The section's own validate() and the rules that need the rest of the design; does nothing
  /// when the design lacks the section. Throws ValidationError with the full key path.
  void (*validate)(const Design& design) = nullptr;
  /// Adds `key: ...` to the top-level map when the design has the section.
  void (*write)(const Design& design, Out& top) = nullptr;
  /// Another section this one reads while loading; it is loaded and validated first.
  std::string_view reads = {};
};

/// Every section, in the order of sections.def (the order a written design file lists them).
const std::vector<Section>& all();
/// Every section, each after the one it `reads`: the order of loading and validation.
const std::vector<const Section*>& in_load_order();

// One per line of sections.def.
#define FIVEBAR_SECTION(key) Section key##_section();
#include "sections/sections.def"
#undef FIVEBAR_SECTION

}  // namespace fivebar::sections
