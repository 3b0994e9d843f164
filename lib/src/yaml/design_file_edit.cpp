// Edits of a design file's text (fivebar/design/file_edit.hpp): the key path is followed through
// the file's own YAML tree (the resolution of lib/src/yaml/design_edit.cpp), whose nodes carry
// their place in the text, and only the characters of that scalar are replaced.
#include "fivebar/design/file_edit.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "yaml/key_path.hpp"

namespace fivebar {

namespace {

/// End (exclusive) of the scalar token that starts at `pos`: a quoted scalar to its closing
/// quote, a plain one to the end of its line, a flow separator (`,`, `]`, `}`) or a comment,
/// trailing blanks excluded. std::nullopt when a quoted scalar is not closed on its line.
std::optional<std::size_t> scalar_end(std::string_view text, std::size_t pos) {
  const char q = text[pos];
  if (q == '"' || q == '\'') {
    for (std::size_t i = pos + 1; i < text.size(); ++i) {
      const char c = text[i];
      if (c == '\n' || c == '\r') return std::nullopt;
      if (q == '"' && c == '\\') {
        ++i;
        continue;
      }
      if (c == q) {
        if (q == '\'' && i + 1 < text.size() && text[i + 1] == '\'') {
          ++i;
          continue;
        }
        return i + 1;
      }
    }
    return std::nullopt;
  }
  std::size_t i = pos;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '\n' || c == '\r' || c == ',' || c == ']' || c == '}') break;
    if (c == '#' && i > pos && (text[i - 1] == ' ' || text[i - 1] == '\t')) break;
    ++i;
  }
  while (i > pos && (text[i - 1] == ' ' || text[i - 1] == '\t')) --i;
  return i;
}

std::string double_quoted(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) throw InputError("a control character cannot be written in a mode");
    out += c;
  }
  return out + "\"";
}

}  // namespace

std::string edit_design_text(std::string_view text, std::string_view origin, const std::vector<FileEdit>& edits) {
  const std::string where(origin);
  YAML::Node root;
  try {
    root = YAML::Load(std::string(text));
  } catch (const YAML::Exception& e) {
    throw InputError(where + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  // One replacement per scalar, by its offset in the text; the last edit of a key wins.
  std::map<std::size_t, std::pair<std::size_t, std::string>> replacements;
  for (const FileEdit& e : edits) {
    std::string canonical;
    const std::optional<YAML::Node> node = detail::follow_design_key(root, e.key, canonical);
    const std::string key = canonical.empty() ? e.key : canonical;
    if (!node) throw InputError(where + ": key '" + e.key + "' is not in the file");
    const int line = node->Mark().is_null() ? 0 : node->Mark().line + 1;
    const std::string at = where + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": key '" + key + "'";
    if (!node->IsScalar()) throw InputError(at + ": not a single value");
    if (node->Mark().is_null() || node->Mark().pos < 0 || std::size_t(node->Mark().pos) >= text.size()) {
      throw InputError(at + ": its place in the file is unknown (an alias?)");
    }
    const std::size_t pos = std::size_t(node->Mark().pos);
    if (text[pos] == '*' || text[pos] == '&' || text[pos] == '!') throw InputError(at + ": an alias, anchor or tag cannot be edited in place");
    const std::optional<std::size_t> end = scalar_end(text, pos);
    if (!end || *end <= pos) throw InputError(at + ": its value could not be delimited in the file");
    std::string written;
    if (const double* v = std::get_if<double>(&e.value)) {
      double old = 0.0;
      if (!detail::yaml_number(*node, old)) throw InputError(at + " = " + node->Scalar() + ": not a number");
      if (!std::isfinite(*v)) throw InputError(at + ": the new value is not a finite number");
      written = format::shortest(*v);
    } else {
      written = double_quoted(std::get<std::string>(e.value));
    }
    replacements[pos] = {*end, std::move(written)};
  }
  std::string out;
  out.reserve(text.size() + 16 * replacements.size());
  std::size_t from = 0;
  for (const auto& [pos, rep] : replacements) {
    out.append(text.substr(from, pos - from));
    out += rep.second;
    from = rep.first;
  }
  out.append(text.substr(from));
  return out;
}

}  // namespace fivebar
