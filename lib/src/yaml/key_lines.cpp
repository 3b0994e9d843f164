// Line numbers of design keys, re-read from the file: the loader's own key -> line map lives only
// while it parses, and rules checked later (printable parts) still want FILE:LINE: key messages.

#include "yaml/key_lines.hpp"

#include "fivebar/csv_reader.hpp"
#include "fivebar/design.hpp"

#include <yaml-cpp/yaml.h>

#include <map>

#include "design/design_keys.hpp"

namespace fivebar::detail {

namespace {

void collect(const YAML::Node& node, const std::string& path, std::map<std::string, int>& lines) {
  if (node.IsMap()) {
    for (const auto& pair : node) {
      if (!pair.first.IsScalar()) continue;
      const std::string key = key_child(path, pair.first.Scalar());
      if (!pair.first.Mark().is_null()) lines.emplace(key, pair.first.Mark().line + 1);
      collect(pair.second, key, lines);
    }
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) {
      const std::string key = key_index(path, i);
      if (!node[i].Mark().is_null()) lines.emplace(key, node[i].Mark().line + 1);
      collect(node[i], key, lines);
    }
  }
}

}  // namespace

std::optional<int> yaml_key_line(const std::filesystem::path& file, const std::string& key) {
  std::map<std::string, int> lines;
  try {
    // Bounded as the loader bounds a design file (a file swapped since it was loaded included).
    collect(YAML::Load(csv::read_bounded(file, kMaxDesignFileBytes, "design file")), "", lines);
  } catch (const std::exception&) {
    return std::nullopt;
  }
  std::string k = key;
  while (!k.empty()) {
    if (const auto it = lines.find(k); it != lines.end()) return it->second;
    k = key_parent(k);
  }
  return std::nullopt;
}

}  // namespace fivebar::detail
