#pragma once
/// Key paths followed through a design file's YAML tree (lib/src/yaml/design_edit.cpp), for the
/// functions that change that tree (lib/src/yaml/design_numbers.cpp). Private to lib.

#include <yaml-cpp/yaml.h>

#include <optional>
#include <string>
#include <string_view>

#include "fivebar/design/edit.hpp"

namespace fivebar::detail {

/// Follows `key` from `root` (to_yaml of a design), fills `k` (canonical path, number, station
/// field) and returns the number's node. ValidationError naming `key` when it leads nowhere or
/// to something that is not a number.
std::optional<YAML::Node> resolve_design_key(const YAML::Node& root, std::string_view key, DesignKey& k);
/// Follows `key` from `root` to any node (a map, a list or a number); its canonical spelling in
/// `canonical`; std::nullopt when it leads nowhere.
std::optional<YAML::Node> follow_design_key(const YAML::Node& root, std::string_view key, std::string& canonical);
/// True, with the value, when `node` is a number as the design file reads one.
bool yaml_number(const YAML::Node& node, double& value);

}  // namespace fivebar::detail
