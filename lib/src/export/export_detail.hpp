#pragma once
// Private to lib: the ROS 2 YAML reader of the export (yaml-cpp stays in lib/src/yaml/) and the
// header's embedded JSON.

#include <string>

#include "fivebar/json.hpp"

namespace fivebar::detail {

/// A ROS 2 parameters file as a tree: maps, lists, and scalars typed as ROS types them (quoted:
/// string; true/false: bool; digits only: integer; with '.', 'e' or .inf/.nan: double; else
/// string). InputError "ORIGIN:LINE: ..." on a YAML error.
Json parse_ros2_yaml(const std::string& text, const std::string& origin);

/// The JSON document an exported C++ header carries as `runtime_json` (render_header()), parsed.
/// InputError "ORIGIN:LINE: ..." when it is missing or not JSON.
Json header_runtime_json(const std::string& text, const std::string& origin);

}  // namespace fivebar::detail
