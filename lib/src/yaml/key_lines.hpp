#pragma once
// Line numbers of design keys for rules checked after loading (parts, ...): lib-private.

#include <filesystem>
#include <optional>
#include <string>

namespace fivebar::detail {

/// 1-based line of `key` ("stations.index.mechanisms.lower.links[0]", spelled as design_keys.hpp
/// spells it) in the YAML file `file`, or of its nearest parent present there; std::nullopt when
/// the file cannot be read or parsed, or no part of the key is in it.
std::optional<int> yaml_key_line(const std::filesystem::path& file, const std::string& key);

}  // namespace fivebar::detail
