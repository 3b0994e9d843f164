#pragma once
/// Key paths of design values ("stations.index.mechanisms.lower.links[2]"), shared by
/// Design::validate() and the YAML loader so that both spell a path the same way. Private to lib.

#include <cstddef>
#include <set>
#include <string>
#include <string_view>

namespace fivebar::detail {

/// `parent.name`, or `parent["name"]` when name is not a plain word ([A-Za-z0-9_-]+), so that a
/// station called "a.b" cannot be confused with a nested key. An empty parent gives just the name.
std::string key_child(std::string_view parent, std::string_view name);

/// `parent[i]`.
std::string key_index(std::string_view parent, std::size_t i);

/// `parent` followed by a relative key path (as thrown by a nested validate()).
std::string key_join(std::string_view parent, std::string_view relative);

/// The key path without its last component; empty for a top-level key.
std::string key_parent(std::string_view key);

/// Every key the loader accepts in the maps that `text` (a valid design file) visits, as key
/// shapes: "geometry.pin_diameter", "stations.<name>.mechanisms.lower.links" (<name> where the
/// file chooses the name). docs/design-file.md is checked against it (test/test_design.cpp).
std::set<std::string> design_file_keys(const std::string& text);

/// Text in single quotes with control characters escaped, for messages; text longer than 100
/// bytes is cut and followed by its length: 'abc...' (5000 bytes).
std::string quoted(std::string_view text);

}  // namespace fivebar::detail
