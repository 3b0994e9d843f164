// Numbers of a design by key path (fivebar/design.hpp design_number(), with_design_numbers()): the
// design is written as its file (to_yaml), the key path is followed through that tree (one
// resolution of key paths for every caller: lib/src/yaml/design_edit.cpp), and a changed tree is read
// back by the loader, so every rule of the file applies to the result.
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <optional>
#include <cmath>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "design/design_keys.hpp"
#include "yaml/key_path.hpp"
#include "fivebar/design.hpp"
#include "sections/section.hpp"

namespace fivebar {

double design_number(const Design& design, std::string_view key) { return design_key(design, key).value; }

Design with_design_numbers(const Design& design, const std::vector<std::pair<std::string, double>>& values) {
  YAML::Node root = YAML::Load(to_yaml(design));
  for (const auto& [key, value] : values) {
    DesignKey k;
    std::optional<YAML::Node> node = detail::resolve_design_key(root, key, k);  // throws naming the key
    *node = sections::Out::number(value).text;
  }
  YAML::Emitter out;
  out << root;
  Design changed = load_design_from_string(std::string(out.c_str()) + "\n", design.name + " (changed numbers)");
  changed.source = design.source;
  return changed;
}

}  // namespace fivebar
