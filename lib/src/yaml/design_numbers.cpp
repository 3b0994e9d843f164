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

namespace fivebar {

namespace {
void number_leaves(const YAML::Node& node, const std::string& path, std::vector<std::string>& out) {
  double v = 0.0;
  if (node.IsMap()) {
    for (const auto& e : node) number_leaves(e.second, path + (path.empty() ? "" : ".") + e.first.as<std::string>(), out);
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) number_leaves(node[i], path + "[" + std::to_string(i) + "]", out);
  } else if (detail::yaml_number(node, v)) {
    out.push_back(path);
  }
}
}  // namespace

std::vector<std::string> design_number_keys(const Design& design, std::string_view prefix) {
  YAML::Node root = YAML::Load(to_yaml(design));
  std::string canonical;
  std::optional<YAML::Node> node = prefix.empty() ? std::optional<YAML::Node>(root)
                                                  : detail::follow_design_key(root, prefix, canonical);
  std::vector<std::string> out;
  if (node) number_leaves(*node, prefix.empty() ? std::string() : canonical, out);
  return out;
}

}  // namespace fivebar
