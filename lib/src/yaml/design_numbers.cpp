// Numbers of a design by key path (fivebar/design.hpp design_number(), with_design_numbers()): the
// design is written as its file (to_yaml), the key path is followed through that tree, and a
// changed tree is read back by the loader, so every rule of the file applies to the result.
#include <yaml-cpp/yaml.h>

#include <charconv>
#include <optional>
#include <cmath>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "design_keys.hpp"
#include "fivebar/design.hpp"
#include "sections/section.hpp"

namespace fivebar {

namespace {

/// Follows `key` from `root`: map keys separated by '.', list indices as [i]. A map key may
/// itself contain '.' (station names may): the longest key of the map that the path continues
/// with wins. Returns the node (invalid when the path leads nowhere) and, on failure, why.
std::optional<YAML::Node> follow(YAML::Node root, std::string_view key, std::string& why) {
  YAML::Node node;
  node.reset(root);
  std::string_view rest = key;
  std::string walked;
  while (!rest.empty()) {
    if (rest.front() == '[') {
      const auto close = rest.find(']');
      std::size_t i = 0;
      const auto r = std::from_chars(rest.data() + 1, rest.data() + (close == std::string_view::npos ? 1 : close), i);
      if (close == std::string_view::npos || r.ec != std::errc{} || r.ptr != rest.data() + close) {
        why = "malformed index after '" + walked + "'";
        return std::nullopt;
      }
      if (!node.IsSequence() || i >= node.size()) {
        why = "'" + walked + "' has no element [" + std::to_string(i) + "]";
        return std::nullopt;
      }
      node.reset(node[i]);  // rebind: Node::operator= would assign the child into the tree
      walked += std::string(rest.substr(0, close + 1));
      rest.remove_prefix(close + 1);
      continue;
    }
    if (!walked.empty()) {
      if (rest.front() != '.') {
        why = "expected '.' or '[' after '" + walked + "'";
        return std::nullopt;
      }
      rest.remove_prefix(1);
    }
    if (!node.IsMap()) {
      why = "'" + (walked.empty() ? std::string("the design") : walked) + "' is not a map";
      return std::nullopt;
    }
    std::string best;
    for (const auto& entry : node) {
      const std::string k = entry.first.as<std::string>();
      if (rest.substr(0, k.size()) != k) continue;
      const char next = rest.size() > k.size() ? rest[k.size()] : '\0';
      if ((next == '\0' || next == '.' || next == '[') && k.size() > best.size()) best = k;
    }
    if (best.empty()) {
      const auto end = rest.find_first_of(".[");
      why = "'" + (walked.empty() ? std::string("the design") : walked) + "' has no key '" +
            std::string(rest.substr(0, end)) + "'";
      return std::nullopt;
    }
    node.reset(node[best]);
    walked += (walked.empty() ? "" : ".") + best;
    rest.remove_prefix(best.size());
  }
  return node;
}

bool scalar_number(const YAML::Node& node, double& value) {
  if (!node.IsScalar()) return false;
  const std::string& text = node.Scalar();
  const auto r = std::from_chars(text.data(), text.data() + text.size(), value);
  return r.ec == std::errc{} && r.ptr == text.data() + text.size() && std::isfinite(value);
}

}  // namespace

double design_number(const Design& design, std::string_view key) {
  YAML::Node root = YAML::Load(to_yaml(design));
  std::string why;
  const std::optional<YAML::Node> node = follow(root, key, why);
  if (!node) throw ValidationError(std::string(key), "not a key path of the design: " + why);
  double v = 0.0;
  if (!scalar_number(*node, v)) {
    throw ValidationError(std::string(key), "is not a number of the design (the key holds " +
                                                std::string(node->IsMap() ? "a map" : node->IsSequence() ? "a list" : "text") + ")");
  }
  return v;
}

Design with_design_numbers(const Design& design, const std::vector<std::pair<std::string, double>>& values) {
  YAML::Node root = YAML::Load(to_yaml(design));
  for (const auto& [key, value] : values) {
    std::string why;
    std::optional<YAML::Node> node = follow(root, key, why);
    double old = 0.0;
    if (!node || !scalar_number(*node, old)) {
      throw ValidationError(key, node ? "is not a number of the design" : "not a key path of the design: " + why);
    }
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
  } else if (scalar_number(node, v)) {
    out.push_back(path);
  }
}
}  // namespace

std::vector<std::string> design_number_keys(const Design& design, std::string_view prefix) {
  YAML::Node root = YAML::Load(to_yaml(design));
  std::string why;
  std::optional<YAML::Node> node = follow(root, prefix, why);
  std::vector<std::string> out;
  if (node) number_leaves(*node, std::string(prefix), out);
  return out;
}

}  // namespace fivebar
