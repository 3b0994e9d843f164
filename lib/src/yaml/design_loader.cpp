// YAML design loader (docs/design-file.md). yaml-cpp stays in this file.
//
// The loader checks the shape of the file (known keys, no duplicates, types, list lengths,
// required values, finite numbers) and converts units (degrees -> radians); the value rules live
// in the one validate() of each struct (design.cpp). Every error becomes an InputError
// "FILE:LINE: KEY = VALUE: RULE" (or "FILE:LINE: KEY: RULE") with the full key path; for errors
// thrown by validate() the line comes from a key-path -> line map filled while parsing.

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <initializer_list>
#include <map>
#include <set>
#include <numbers>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/format.hpp"
#include "design/design_keys.hpp"
#include "fivebar/design.hpp"
#include "sections/section.hpp"

namespace fivebar {

namespace {

using detail::key_child;
using detail::key_index;

using format::kRadPerDeg;

constexpr std::size_t kMaxShownValue = 60;
/// Longest map key (section, field or station name) accepted, so that key paths in messages stay
/// short; every real key is far shorter (station names: at most 64 characters).
constexpr std::size_t kMaxKeyBytes = 128;

const std::string kYamlFloatTag = "tag:yaml.org,2002:float";
const std::string kYamlIntTag = "tag:yaml.org,2002:int";

std::string lower_case(std::string_view text) {
  std::string out(text);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

/// Compact one-line rendering of a node for messages: scalars as written, [a, b], {k: v}.
void render(const YAML::Node& node, std::string& out) {
  if (out.size() > kMaxShownValue) return;
  switch (node.Type()) {
    case YAML::NodeType::Null: out += "null"; break;
    case YAML::NodeType::Scalar:
      if (node.Tag() == "!") {
        out += '"' + node.Scalar() + '"';
      } else {
        out += node.Scalar();
      }
      break;
    case YAML::NodeType::Sequence: {
      out += '[';
      bool first = true;
      for (const auto& element : node) {
        if (!first) out += ", ";
        first = false;
        render(element, out);
      }
      out += ']';
      break;
    }
    case YAML::NodeType::Map: {
      out += '{';
      bool first = true;
      for (const auto& pair : node) {
        if (!first) out += ", ";
        first = false;
        render(pair.first, out);
        out += ": ";
        render(pair.second, out);
      }
      out += '}';
      break;
    }
    case YAML::NodeType::Undefined: out += "(undefined)"; break;
  }
}

std::string render(const YAML::Node& node) {
  std::string out;
  render(node, out);
  const bool cut = out.size() > kMaxShownValue;
  if (cut) {
    std::size_t keep = kMaxShownValue;
    while (keep > 0 && (static_cast<unsigned char>(out[keep]) & 0xC0u) == 0x80u) --keep;  // UTF-8 boundary
    out.resize(keep);
  }
  std::string shown = detail::quoted(out);
  shown = shown.substr(1, shown.size() - 2);  // control characters escaped, no quotes
  if (cut) shown += "...";
  return shown;
}

// --- Pre-scan ----------------------------------------------------------------------------------------
//
// yaml-cpp recurses once per nesting level (and only stops at 2000 levels), keeps every node of a
// document in memory and passes bytes through unchecked. Before it sees a file, the text is
// checked against the limits of design.hpp, with messages that name the line.

/// Length of the UTF-8 sequence at text[i] (its code point in `code`), 0 when it is not valid
/// UTF-8 (overlong forms, surrogates and values above U+10FFFF are invalid).
std::size_t utf8_sequence(std::string_view text, std::size_t i, char32_t& code) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char b0 = byte(i);
  std::size_t length = 0;
  unsigned char lo = 0x80, hi = 0xBF;  // allowed range of the second byte
  if (b0 < 0x80) {
    code = b0;
    return 1;
  } else if (b0 >= 0xC2 && b0 <= 0xDF) {
    length = 2, code = b0 & 0x1Fu;
  } else if (b0 >= 0xE0 && b0 <= 0xEF) {
    length = 3, code = b0 & 0x0Fu;
    if (b0 == 0xE0) lo = 0xA0;  // overlong
    if (b0 == 0xED) hi = 0x9F;  // surrogates
  } else if (b0 >= 0xF0 && b0 <= 0xF4) {
    length = 4, code = b0 & 0x07u;
    if (b0 == 0xF0) lo = 0x90;  // overlong
    if (b0 == 0xF4) hi = 0x8F;  // above U+10FFFF
  } else {
    return 0;
  }
  if (i + length > text.size()) return 0;
  for (std::size_t k = 1; k < length; ++k) {
    const unsigned char b = byte(i + k);
    if (b < (k == 1 ? lo : 0x80) || b > (k == 1 ? hi : 0xBF)) return 0;
    code = (code << 6) | (b & 0x3Fu);
  }
  return length;
}

/// YAML 1.2 c-printable: tab, line feed, carriage return, and printable characters.
bool yaml_printable(char32_t c) {
  return c == 0x09 || c == 0x0A || c == 0x0D || (c >= 0x20 && c <= 0x7E) || c == 0x85 || (c >= 0xA0 && c <= 0xD7FF) ||
         (c >= 0xE000 && c <= 0xFFFD) || (c >= 0x10000 && c <= 0x10FFFF);
}

class Prescan {
 public:
  explicit Prescan(const std::string& origin) : origin_(origin) {}

  void check(std::string_view text) {
    if (text.size() > kMaxDesignFileBytes) {
      throw InputError(origin_ + ": " + std::to_string(text.size()) + " bytes: a design file may have at most " +
                       std::to_string(kMaxDesignFileBytes) + " bytes (1 MiB)");
    }
    check_encoding(text);
    std::size_t start = 0;
    int line_no = 0;
    while (start <= text.size()) {
      const std::size_t end = std::min(text.find('\n', start), text.size());
      std::string_view line = text.substr(start, end - start);
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      scan_line(line, ++line_no);
      start = end + 1;
    }
    // yaml-cpp quietly ends such a string at the end of the file, swallowing the keys after it.
    if (quote_ != 0) {
      fail(quote_line_, "the quoted string that starts at column " + std::to_string(quote_column_) +
                            " is never closed");
    }
  }

 private:
  [[noreturn]] void fail(int line, const std::string& what) const {
    throw InputError(origin_ + ":" + std::to_string(line) + ": " + what);
  }

  void check_encoding(std::string_view text) const {
    const auto starts = [&](std::string_view bom) { return text.substr(0, bom.size()) == bom; };
    using namespace std::string_view_literals;
    if (starts("\x00\x00\xFE\xFF"sv) || starts("\xFF\xFE\x00\x00"sv)) {
      throw InputError(origin_ + ": the file is UTF-32 encoded: design files must be UTF-8");
    }
    if (starts("\xFE\xFF"sv) || starts("\xFF\xFE"sv)) {
      throw InputError(origin_ + ": the file is UTF-16 encoded: design files must be UTF-8");
    }
    int line = 1, column = 1;
    for (std::size_t i = 0; i < text.size(); ++column) {
      char32_t code = 0;
      const std::size_t length = utf8_sequence(text, i, code);
      if (length == 0) {
        char hex[8];
        std::snprintf(hex, sizeof hex, "0x%02X", static_cast<unsigned>(static_cast<unsigned char>(text[i])));
        fail(line, "byte " + std::string(hex) + " at column " + std::to_string(column) +
                       " is not UTF-8: design files must be UTF-8 text");
      }
      if (!yaml_printable(code)) {
        char name[16];
        std::snprintf(name, sizeof name, "U+%04X", static_cast<unsigned>(code));
        fail(line, "character " + std::string(name) + " at column " + std::to_string(column) +
                       " is a control character, which YAML does not allow (only tab and line breaks)");
      }
      if (code == '\n') ++line, column = 0;
      i += length;
    }
  }

  void deeper_than_allowed(int line, int depth) const {
    if (depth > kMaxDesignNesting) {
      fail(line, "nested more than " + std::to_string(kMaxDesignNesting) +
                     " levels deep (indentation, '- ' items and [ { brackets): refused before parsing; "
                     "a design needs fewer than 10");
    }
  }

  /// Index just past the quoted scalar whose opening quote `q` precedes `from`; npos when it does
  /// not close on this line.
  static std::size_t skip_quoted(std::string_view line, std::size_t from, char q) {
    for (std::size_t i = from; i < line.size(); ++i) {
      if (q == '"' && line[i] == '\\') {
        ++i;
      } else if (line[i] == q) {
        if (q == '\'' && i + 1 < line.size() && line[i + 1] == '\'') {
          ++i;  // '' inside a single-quoted scalar
        } else {
          return i + 1;
        }
      }
    }
    return std::string_view::npos;
  }

  void open_quote(char q, int line_no, std::size_t index) {
    quote_ = q;
    quote_line_ = line_no;
    quote_column_ = static_cast<int>(index) + 1;
  }

  static bool blank_at(std::string_view line, std::size_t i) { return i >= line.size() || line[i] == ' ' || line[i] == '\t'; }

  void scan_line(std::string_view line, int line_no) {
    std::size_t indent = 0;
    while (indent < line.size() && line[indent] == ' ') ++indent;
    const bool blank = indent == line.size();
    if (block_scalar_parent_ >= 0) {  // inside a literal / folded block scalar: content only
      if (blank || static_cast<long>(indent) > block_scalar_parent_) return;
      block_scalar_parent_ = -1;
    }
    std::size_t pos = 0;
    int depth = flow_base_;
    if (quote_ != 0) {  // a quoted scalar continued from an earlier line
      pos = skip_quoted(line, 0, quote_);
      if (pos == std::string_view::npos) return;
      quote_ = 0;
    } else if (flow_ == 0) {
      if (blank || line[indent] == '#') return;
      if (line.substr(0, 3) == "---" || line.substr(0, 3) == "...") {
        if (blank_at(line, 3)) indents_.clear();
        pos = 3;
      } else {
        while (!indents_.empty() && indents_.back() >= indent) indents_.pop_back();
        indents_.push_back(indent);
        pos = indent;
      }
      depth = static_cast<int>(indents_.size());
      // Compact nested items: "- - - x" or "? " / ": " indicators open one level each.
      while (pos < line.size()) {
        if (line[pos] == ' ') {
          ++pos;
        } else if ((line[pos] == '-' || line[pos] == '?' || line[pos] == ':') && blank_at(line, pos + 1)) {
          ++depth, ++pos;
          deeper_than_allowed(line_no, depth);
        } else {
          break;
        }
      }
      deeper_than_allowed(line_no, depth);
    }
    scan(line, pos, line_no, depth, static_cast<long>(indent));
  }

  /// The rest of a line from `pos`: flow brackets, quoted scalars, comments, block scalars.
  void scan(std::string_view line, std::size_t pos, int line_no, int block_depth, long indent) {
    bool node_start = flow_ == 0;  // where a block value may begin with [ { " ' | >
    bool token_start = true;       // in flow context: where a quoted scalar may begin
    while (pos < line.size()) {
      const char c = line[pos];
      if (c == ' ' || c == '\t') {
        ++pos;
        continue;
      }
      if (c == '#' && (pos == 0 || line[pos - 1] == ' ' || line[pos - 1] == '\t')) return;  // comment
      if (flow_ == 0) {
        if (node_start) {
          if (c == '&' || c == '!') {  // anchor or tag before the value
            while (pos < line.size() && !blank_at(line, pos)) ++pos;
            continue;
          }
          if (c == '[' || c == '{') {
            flow_ = 1, flow_base_ = block_depth;
            deeper_than_allowed(line_no, flow_base_ + flow_);
            ++pos, token_start = true;
            continue;
          }
          if (c == '"' || c == '\'') {
            const std::size_t open = pos;
            pos = skip_quoted(line, pos + 1, c);
            if (pos == std::string_view::npos) {
              open_quote(c, line_no, open);
              return;
            }
            node_start = false;
            continue;
          }
          if (c == '|' || c == '>') {
            block_scalar_parent_ = indent;
            return;
          }
          node_start = false;
        }
        if (c == ':' && blank_at(line, pos + 1)) node_start = true;  // a mapping value follows
        ++pos;
        continue;
      }
      // Flow context: every bracket outside quotes counts.
      if ((c == '"' || c == '\'') && token_start) {
        const std::size_t open = pos;
        pos = skip_quoted(line, pos + 1, c);
        if (pos == std::string_view::npos) {
          open_quote(c, line_no, open);
          return;
        }
        token_start = false;
        continue;
      }
      if (c == '[' || c == '{') {
        ++flow_;
        deeper_than_allowed(line_no, flow_base_ + flow_);
        token_start = true;
      } else if (c == ']' || c == '}') {
        if (--flow_ == 0) {
          flow_base_ = 0;
          node_start = false;
        }
        token_start = false;
      } else {
        token_start = c == ',' || c == ':' || c == '?';
      }
      ++pos;
    }
  }

  const std::string& origin_;
  std::vector<std::size_t> indents_;  ///< block indentation levels open
  int flow_ = 0;                      ///< [ { open
  int flow_base_ = 0;                 ///< block depth where the open flow collection began
  char quote_ = 0;                    ///< quoted scalar still open at the end of a line
  int quote_line_ = 0, quote_column_ = 0;  ///< where it opened (column in bytes, 1-based)
  long block_scalar_parent_ = -1;     ///< indentation of the line that opened a | or > scalar
};

class Loader {
 public:
  explicit Loader(std::string origin) : origin_(std::move(origin)) {}

  Design load(const std::string& text);

 private:
  friend class fivebar::sections::Value;
  /// One `key: value` pair of a YAML map, with its full key path and the line of its key.
  struct Entry {
    std::string name;
    std::string path;
    YAML::Node value;
    int line = 0;
  };
  using Entries = std::vector<Entry>;

  [[noreturn]] void fail(int line, const std::string& key, const std::string& rule) const {
    std::string message = origin_ + ":" + std::to_string(line) + ": ";
    message += key.empty() ? rule : ValidationError::compose(key, rule);
    throw InputError(message);
  }
  [[noreturn]] void fail_value(const YAML::Node& node, int line, const std::string& key,
                               const std::string& rule) const {
    fail(line, key, "= " + render(node) + ": " + rule);
  }

  /// 1-based line of a node; `fallback` for nodes without a position (e.g. an empty value).
  static int line_of(const YAML::Node& node, int fallback) {
    const YAML::Mark mark = node.Mark();
    if (mark.is_null() || node.IsNull()) return fallback;
    return mark.line + 1;
  }

  void note(const std::string& key, int line) { lines_.emplace(key, line); }

  static std::string shape_child(const std::string& parent, std::string_view name) {
    return parent.empty() ? std::string(name) : parent + "." + std::string(name);
  }

  /// Line of a key path, or of its nearest recorded parent.
  int line_for(std::string key) const {
    while (true) {
      const auto it = lines_.find(key);
      if (it != lines_.end()) return it->second;
      if (key.empty()) return 1;
      key = detail::key_parent(key);
    }
  }

  Entries entries(const YAML::Node& map, const std::string& path, int line,
                  const std::vector<std::string_view>& allowed, const std::string& expected,
                  bool any_key = false);
  Entries entries(const YAML::Node& map, const std::string& path, int line,
                  std::initializer_list<std::string_view> allowed, const std::string& expected,
                  bool any_key = false) {
    return entries(map, path, line, std::vector<std::string_view>(allowed), expected, any_key);
  }
  const Entry* find(const Entries& all, std::string_view name) const;
  const Entry& require(const Entries& all, std::string_view name, const std::string& path, int line) const;

  double number(const YAML::Node& node, const std::string& path, int line, std::string_view unit) const;
  std::string string(const YAML::Node& node, const std::string& path, int line, const std::string& expected) const;
  /// A list of exactly n elements; records the line of each element.
  std::vector<YAML::Node> list(const YAML::Node& node, const std::string& path, int line, std::size_t n,
                               const std::string& expected);
  Vec2 point(const YAML::Node& node, const std::string& path, int line, const std::string& expected);
  std::uint64_t whole(const YAML::Node& node, const std::string& path, int line, double lo, double hi) const;
  /// A section's value as the section modules see it (lib/src/sections/section.hpp).
  sections::Value value(const Entry& entry);

  Ellipse target(const Entry& entry);
  Mechanism mechanism(const Entry& entry);
  Station station(const Entry& entry);

  std::string origin_;
  std::map<std::string, int> lines_;
  /// Key path -> the same path with the names a file chooses (stations, sweep variables) as <name>.
  std::map<std::string, std::string> shapes_;

 public:
  /// When set, every key a visited map allows is added here, as its shape ("stations.<name>.target").
  std::set<std::string>* catalogue = nullptr;
  /// The caller's rule from a layer above the design (DesignRule), or none.
  const DesignRule* scene_rule = nullptr;
  /// The design file's path (load_design), set on the design before it is validated, so that the
  /// rules that look at files beside it (the bench files' links, docs/bench-files.md) run at load.
  std::filesystem::path source;
};

Loader::Entries Loader::entries(const YAML::Node& map, const std::string& path, int line,
                                const std::vector<std::string_view>& allowed, const std::string& expected,
                                bool any_key) {
  if (!map.IsMap()) {
    if (path.empty()) fail(line, "", "a design file must hold a map " + expected + ", not " + render(map));
    fail_value(map, line, path, "must be a map " + expected);
  }
  Entries all;
  std::map<std::string, int> first_line;
  const auto known_shape = shapes_.find(path);
  const std::string parent_shape = known_shape == shapes_.end() ? path : known_shape->second;
  if (catalogue != nullptr) {
    if (any_key) catalogue->insert(shape_child(parent_shape, "<name>"));
    for (std::string_view a : allowed) catalogue->insert(shape_child(parent_shape, a));
  }
  for (const auto& pair : map) {
    const int key_line = line_of(pair.first, line);
    if (!pair.first.IsScalar()) {
      fail(key_line, path, "key " + render(pair.first) + " is not a name: keys must be plain strings");
    }
    const std::string name = pair.first.Scalar();
    if (name.size() > kMaxKeyBytes) {
      fail(key_line, path, "key " + detail::quoted(name) + " is too long for a key of a design file (at most " +
                               std::to_string(kMaxKeyBytes) + " bytes)");
    }
    const std::string key = key_child(path, name);
    if (const auto it = first_line.find(name); it != first_line.end()) {
      fail(key_line, key, "duplicate key (first given at line " + std::to_string(it->second) + ")");
    }
    if (!any_key && std::find(allowed.begin(), allowed.end(), name) == allowed.end()) {
      std::string rule = "unknown key";
      std::string_view closest;
      std::size_t best = 3;  // suggest only near misses: up to 2 edits
      for (std::string_view candidate : allowed) {
        const std::size_t d = edit_distance(name, candidate);
        if (d < best) best = d, closest = candidate;
      }
      if (!closest.empty()) rule += "; did you mean '" + std::string(closest) + "'?";
      rule += " (allowed here: ";
      bool first = true;
      for (std::string_view candidate : allowed) {
        rule += (first ? "" : ", ") + std::string(candidate);
        first = false;
      }
      fail(key_line, key, rule + ")");
    }
    first_line.emplace(name, key_line);
    note(key, key_line);
    shapes_[key] = shape_child(parent_shape, any_key ? std::string_view("<name>") : std::string_view(name));
    all.push_back(Entry{name, key, pair.second, key_line});
  }
  return all;
}

const Loader::Entry* Loader::find(const Entries& all, std::string_view name) const {
  for (const Entry& e : all) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

const Loader::Entry& Loader::require(const Entries& all, std::string_view name, const std::string& path,
                                     int line) const {
  const Entry* e = find(all, name);
  if (e == nullptr) fail(line, key_child(path, name), "required key is missing");
  return *e;
}

double Loader::number(const YAML::Node& node, const std::string& path, int line, std::string_view unit) const {
  const std::string expected = unit.empty() ? "must be a number" : "must be a number (" + std::string(unit) + ")";
  if (!node.IsScalar()) fail_value(node, line, path, expected);
  const std::string& tag = node.Tag();
  if (tag == "!") fail_value(node, line, path, expected + ", not a quoted string");
  if (tag != "?" && tag != kYamlFloatTag && tag != kYamlIntTag) fail_value(node, line, path, expected);

  const std::string& text = node.Scalar();
  bool boolean = false;
  if (YAML::convert<bool>::decode(node, boolean)) fail_value(node, line, path, expected + ", not a boolean");
  const std::string lower = lower_case(text);
  if (lower == ".inf" || lower == "+.inf" || lower == "-.inf" || lower == ".nan") {
    fail_value(node, line, path, "must be a finite number");
  }

  std::string_view digits = text;
  if (digits.size() > 1 && digits.front() == '+' && digits[1] != '-' && digits[1] != '+') digits.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
  if (end != digits.data() + digits.size() || digits.empty()) fail_value(node, line, path, expected);
  if (ec == std::errc::result_out_of_range) {
    value = std::strtod(std::string(digits).c_str(), nullptr);  // overflow -> inf, underflow -> ~0
  } else if (ec != std::errc{}) {
    fail_value(node, line, path, expected);
  }
  if (!std::isfinite(value)) fail_value(node, line, path, "must be a finite number");
  return value;
}

std::string Loader::string(const YAML::Node& node, const std::string& path, int line,
                           const std::string& expected) const {
  if (!node.IsScalar()) fail_value(node, line, path, expected);
  return node.Scalar();
}

std::vector<YAML::Node> Loader::list(const YAML::Node& node, const std::string& path, int line, std::size_t n,
                                     const std::string& expected) {
  if (!node.IsSequence()) fail_value(node, line, path, "must be " + expected);
  if (node.size() != n) {
    fail_value(node, line, path, "must be " + expected + ", not " + std::to_string(node.size()) + " element" +
                                     (node.size() == 1 ? "" : "s"));
  }
  std::vector<YAML::Node> elements;
  for (std::size_t i = 0; i < n; ++i) {
    elements.push_back(node[i]);
    note(key_index(path, i), line_of(node[i], line));
  }
  return elements;
}

Vec2 Loader::point(const YAML::Node& node, const std::string& path, int line, const std::string& expected) {
  const auto xy = list(node, path, line, 2, expected);
  return Vec2(number(xy[0], key_index(path, 0), line_of(xy[0], line), "mm"),
              number(xy[1], key_index(path, 1), line_of(xy[1], line), "mm"));
}

Ellipse Loader::target(const Entry& entry) {
  const Entries all = entries(entry.value, entry.path, entry.line, {"center", "axes", "angle"},
                              "{center: [x, y], axes: [a, b], angle: deg}");
  Ellipse ellipse;
  const Entry& center = require(all, "center", entry.path, entry.line);
  ellipse.center = point(center.value, center.path, center.line, "a list of 2 numbers [x, y] (mm)");
  const Entry& axes = require(all, "axes", entry.path, entry.line);
  ellipse.axes = point(axes.value, axes.path, axes.line, "a list of 2 full axis lengths [a, b] (mm)");
  if (const Entry* angle = find(all, "angle")) {
    ellipse.angle = format::rad_from_deg(number(angle->value, angle->path, angle->line, "deg"));
  }
  return ellipse;
}


std::uint64_t Loader::whole(const YAML::Node& node, const std::string& path, int line, double lo, double hi) const {
  const double v = number(node, path, line, "");
  if (v != std::floor(v) || v < lo || v > hi) {
    std::ostringstream rule;
    rule << "must be a whole number from " << lo << " to " << hi;
    fail_value(node, line, path, rule.str());
  }
  return std::uint64_t(v);
}

Mechanism Loader::mechanism(const Entry& entry) {
  const Entries all = entries(entry.value, entry.path, entry.line,
                              {"bases", "links", "working_mode", "assembly_mode", "joint_limits", "min_lci"},
                              "(bases, links, working_mode, ...)");
  Mechanism m;
  m.name = entry.name;

  const Entry& bases = require(all, "bases", entry.path, entry.line);
  const std::string bases_expected = "a list of 2 base joints [[x1, y1], [x2, y2]] (mm)";
  const auto base_nodes = list(bases.value, bases.path, bases.line, 2, bases_expected);
  m.O1 = point(base_nodes[0], key_index(bases.path, 0), line_of(base_nodes[0], bases.line),
               "a point [x, y] (mm)");
  m.O2 = point(base_nodes[1], key_index(bases.path, 1), line_of(base_nodes[1], bases.line),
               "a point [x, y] (mm)");

  const Entry& links = require(all, "links", entry.path, entry.line);
  const auto link_nodes = list(links.value, links.path, links.line, 4, "a list of 4 lengths [L1, L2, L3, L4] (mm)");
  for (std::size_t i = 0; i < 4; ++i) {
    m.L[i] = number(link_nodes[i], key_index(links.path, i), line_of(link_nodes[i], links.line), "mm");
  }

  const std::string working_expected = "must be one of \"++\", \"+-\", \"-+\", \"--\"";
  const Entry& working = require(all, "working_mode", entry.path, entry.line);
  const auto working_mode = parse_working_mode(string(working.value, working.path, working.line, working_expected));
  if (!working_mode) fail_value(working.value, working.line, working.path, working_expected);
  m.working_mode = *working_mode;

  if (const Entry* assembly = find(all, "assembly_mode")) {
    const std::string expected = "must be one of \"+\", \"-\", \"any\"";
    const auto mode = parse_assembly_mode(string(assembly->value, assembly->path, assembly->line, expected));
    if (!mode) fail_value(assembly->value, assembly->line, assembly->path, expected);
    m.assembly_mode = *mode;
  }

  if (const Entry* limits = find(all, "joint_limits")) {
    const std::string expected = "a list of 2 ranges [[lo1, hi1], [lo2, hi2]] (deg)";
    const auto range_nodes = list(limits->value, limits->path, limits->line, 2, expected);
    std::array<JointRange, 2> ranges;
    for (std::size_t i = 0; i < 2; ++i) {
      const std::string path = key_index(limits->path, i);
      const int line = line_of(range_nodes[i], limits->line);
      const auto ends = list(range_nodes[i], path, line, 2, "a range [lo, hi] (deg, counter-clockwise from lo)");
      ranges[i].lo = kRadPerDeg * number(ends[0], key_index(path, 0), line_of(ends[0], line), "deg");
      ranges[i].hi = kRadPerDeg * number(ends[1], key_index(path, 1), line_of(ends[1], line), "deg");
    }
    m.joint_limits = ranges;
  }

  if (const Entry* lci = find(all, "min_lci")) m.min_lci = number(lci->value, lci->path, lci->line, "");
  return m;
}

Station Loader::station(const Entry& entry) {
  const Entries all = entries(entry.value, entry.path, entry.line, {"target", "mechanisms"}, "(target, mechanisms)");
  Station s;
  s.name = entry.name;
  s.target = target(require(all, "target", entry.path, entry.line));
  // An absent or empty `mechanisms` is left to Station::validate(), which names the rule.
  if (const Entry* mechanisms = find(all, "mechanisms")) {
    for (const Entry& m : entries(mechanisms->value, mechanisms->path, mechanisms->line, {"lower", "upper"},
                                  "with keys lower and/or upper")) {
      (m.name == "lower" ? s.lower : s.upper) = mechanism(m);
    }
  }
  return s;
}

/// Where each document of a YAML stream starts, from yaml-cpp's events (no node is built).
class DocumentStarts : public YAML::EventHandler {
 public:
  struct Start {
    YAML::Mark mark;
    bool null = false;  ///< the document is a bare null
  };
  std::vector<Start> starts;

  void OnDocumentStart(const YAML::Mark&) override { fresh_ = true; }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t) override { first(mark, true); }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { first(mark, false); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t, const std::string&) override {
    first(mark, false);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    first(mark, false);
  }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    first(mark, false);
  }
  void OnMapEnd() override {}

 private:
  void first(const YAML::Mark& mark, bool null) {
    if (fresh_) starts.push_back({mark, null});
    fresh_ = false;
  }
  bool fresh_ = false;
};

Design Loader::load(const std::string& raw) {
  // YAML's line breaks are LF, CR LF and a lone CR (old Mac files); yaml-cpp reads only the first
  // two, and a file of lone CRs looked empty to it. Every break becomes LF, so lines count alike.
  std::string text;
  text.reserve(raw.size());
  for (std::size_t i = 0; i < raw.size(); ++i) {
    if (raw[i] == '\r') {
      text += '\n';
      if (i + 1 < raw.size() && raw[i + 1] == '\n') ++i;
    } else {
      text += raw[i];
    }
  }
  Prescan(origin_).check(text);
  std::vector<YAML::Node> documents;
  try {
    // Not YAML::LoadAll: yaml-cpp 0.7 loops there forever, allocating, on a ',' outside any [ ]
    // or { } (yaml-cpp issue #1040; fixed upstream in 2024): the parser returns an empty document
    // for it again and again without moving on. So the documents are counted from the event
    // stream first, stopping at one that does not advance, and then the first is built.
    std::istringstream stream(text);
    YAML::Parser parser(stream);
    DocumentStarts counter;
    while (parser.HandleNextDocument(counter)) {
      const auto& starts = counter.starts;
      const std::size_t n = starts.size();
      if (n >= 2 && starts[n - 1].mark.pos <= starts[n - 2].mark.pos) {
        const YAML::Mark& at = starts[n - 1].mark;
        const char c = at.pos >= 0 && static_cast<std::size_t>(at.pos) < text.size() ? text[static_cast<std::size_t>(at.pos)] : '?';
        fail(at.line + 1, "", "YAML syntax error: unexpected '" + std::string(1, c) + "' (column " +
                                  std::to_string(at.column + 1) + ") outside a [ ] or { } list");
      }
      if (n > 100) break;  // enough to say there are several
    }
    if (counter.starts.size() > 1) {
      fail(counter.starts[1].mark.line + 1, "", "a design file holds one YAML document, this one has " +
                                                    std::to_string(counter.starts.size()) +
                                                    (counter.starts.size() > 100 ? " or more" : ""));
    }
    if (!counter.starts.empty()) documents.push_back(YAML::Load(text));
  } catch (const YAML::Exception& e) {
    const int line = e.mark.is_null() ? 1 : e.mark.line + 1;
    std::string rule = "YAML syntax error: " + e.msg + " (column " + std::to_string(e.mark.column + 1) + ")";
    // `assembly_mode: -` reads as the start of a list: the usual cause of this message.
    if (e.msg.find("block entry") != std::string::npos) rule += "; quote mode strings, as in \"-\"";
    fail(line, "", rule);
  }
  if (documents.empty() || (documents.size() == 1 && documents[0].IsNull())) {
    throw InputError(origin_ + ": empty design file: expected a map with at least 'name' and 'stations'");
  }
  const YAML::Node& root = documents[0];
  const int root_line = line_of(root, 1);
  note("", root_line);

  Design design;
  try {
    // The top level: name, stations, products, and one key per design section (sections.def).
    std::vector<std::string_view> allowed{"name", "stations", "products"};
    for (const sections::Section& section : sections::all()) allowed.push_back(section.key);
    std::string listing;
    for (std::string_view k : allowed) listing += (listing.empty() ? "" : ", ") + std::string(k);
    const Entries all = entries(root, "", root_line, allowed, "at the top level (" + listing + ")");
    const Entry& name = require(all, "name", "", root_line);
    design.name = string(name.value, name.path, name.line, "must be a name (letters, digits, _ . -)");

    const Entry& stations = require(all, "stations", "", root_line);
    for (const Entry& s : entries(stations.value, stations.path, stations.line, {},
                                  "of station names to stations", /*any_key=*/true)) {
      design.stations.push_back(station(s));
    }

    for (const sections::Section* section : sections::in_load_order()) {
      if (const Entry* e = find(all, section->key)) section->load(value(*e), design);
    }

    if (const Entry* products = find(all, "products")) {
      if (!products->value.IsSequence()) fail_value(products->value, products->line, products->path, "must be a list of product names");
      std::vector<std::string> names;
      for (std::size_t i = 0; i < products->value.size(); ++i) {
        const YAML::Node element = products->value[i];
        const std::string path = key_index(products->path, i);
        const int line = line_of(element, products->line);
        note(path, line);
        names.push_back(string(element, path, line, "must be a product name"));
      }
      design.products = std::move(names);
    }
  } catch (const YAML::Exception& e) {  // not expected: the walk above checks every type first
    fail(e.mark.is_null() ? root_line : e.mark.line + 1, "", "YAML error: " + e.msg);
  }

  try {
    design.source = source;
    design.validate();
    if (scene_rule != nullptr && *scene_rule) (*scene_rule)(design);
  } catch (const ValidationError& e) {
    fail(line_for(e.key()), e.key(), e.rule());
  }
  return design;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// sections::Value over yaml-cpp: the section modules read the file only through it.

namespace sections {

struct Value::Impl {
  Loader* loader;
  YAML::Node node;
  std::string name;
  std::string path;
  int line = 0;
};

namespace {
Value make(Loader* loader, YAML::Node node, std::string name, std::string path, int line) {
  return Value(std::make_shared<const Value::Impl>(Value::Impl{loader, std::move(node), std::move(name), std::move(path), line}));
}
}  // namespace

Value::Value(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}
const std::string& Value::name() const { return impl_->name; }
const std::string& Value::path() const { return impl_->path; }
int Value::line() const { return impl_->line; }
bool Value::is_null() const { return impl_->node.IsNull(); }
bool Value::is_scalar() const { return impl_->node.IsScalar(); }
bool Value::is_list() const { return impl_->node.IsSequence(); }

std::vector<Value> Value::entries(std::initializer_list<std::string_view> allowed, std::string_view expected,
                                  bool any_key) const {
  std::vector<Value> out;
  for (const auto& e : impl_->loader->entries(impl_->node, impl_->path, impl_->line, allowed, std::string(expected), any_key)) {
    out.push_back(make(impl_->loader, e.value, e.name, e.path, e.line));
  }
  return out;
}

std::vector<Value> Value::items(std::size_t n, std::string_view expected) const {
  const auto nodes = impl_->loader->list(impl_->node, impl_->path, impl_->line, n, std::string(expected));
  std::vector<Value> out;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    out.push_back(make(impl_->loader, nodes[i], "", detail::key_index(impl_->path, i), Loader::line_of(nodes[i], impl_->line)));
  }
  return out;
}

std::vector<Value> Value::list(std::string_view rule) const {
  if (!impl_->node.IsSequence()) fail_value(std::string(rule));
  std::vector<Value> out;
  for (std::size_t i = 0; i < impl_->node.size(); ++i) {
    const YAML::Node element = impl_->node[i];
    const std::string path = detail::key_index(impl_->path, i);
    const int line = Loader::line_of(element, impl_->line);
    impl_->loader->note(path, line);
    out.push_back(make(impl_->loader, element, "", path, line));
  }
  return out;
}

double Value::number(std::string_view unit) const { return impl_->loader->number(impl_->node, impl_->path, impl_->line, unit); }

std::uint64_t Value::whole(double lo, double hi) const {
  return impl_->loader->whole(impl_->node, impl_->path, impl_->line, lo, hi);
}

std::string Value::text(std::string_view rule) const {
  return impl_->loader->string(impl_->node, impl_->path, impl_->line, std::string(rule));
}

Vec2 Value::point(std::string_view expected) const {
  return impl_->loader->point(impl_->node, impl_->path, impl_->line, std::string(expected));
}

void Value::fail(const std::string& rule) const { impl_->loader->fail(impl_->line, impl_->path, rule); }

void Value::fail_value(const std::string& rule) const {
  impl_->loader->fail_value(impl_->node, impl_->line, impl_->path, rule);
}

void Value::fail_missing(std::string_view name) const {
  impl_->loader->fail(impl_->line, detail::key_child(impl_->path, name), "required key is missing");
}

void Value::note_as(const std::string& path) const { impl_->loader->note(path, impl_->line); }

}  // namespace sections

namespace {
sections::Value Loader::value(const Entry& entry) {
  return sections::Value(std::make_shared<const sections::Value::Impl>(
      sections::Value::Impl{this, entry.value, entry.name, entry.path, entry.line}));
}

}  // namespace

Design load_design_from_string(const std::string& text, const std::string& origin, const DesignRule& rule) {
  Loader loader(origin);
  loader.scene_rule = &rule;
  return loader.load(text);
}

std::set<std::string> detail::design_file_keys(const std::string& text) {
  std::set<std::string> keys;
  Loader loader("design_file_keys");
  loader.catalogue = &keys;
  (void)loader.load(text);
  return keys;
}

Design load_design(const std::filesystem::path& path, const DesignRule& rule) {
  const std::string origin = path.string();
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) throw InputError(origin + ": no such design file");
  if (std::filesystem::is_directory(status)) throw InputError(origin + ": is a directory, not a design file");

  const auto too_large = [&](std::uintmax_t bytes, const std::string& at_least) {
    return InputError(origin + ": " + at_least + std::to_string(bytes) + " bytes: a design file may have at most " +
                      std::to_string(kMaxDesignFileBytes) + " bytes (1 MiB)");
  };
  if (std::filesystem::is_regular_file(status)) {
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (!ec && size > kMaxDesignFileBytes) throw too_large(size, "");
  }

  errno = 0;
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    const int error = errno;
    throw InputError(origin + ": cannot read the design file" + (error != 0 ? std::string(": ") + std::strerror(error) : ""));
  }
  // Read at most one byte more than the limit: a device or pipe (/dev/zero) may never end.
  std::string text(kMaxDesignFileBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  if (in.bad()) throw InputError(origin + ": cannot read the design file");
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxDesignFileBytes) throw too_large(kMaxDesignFileBytes, "more than ");

  Loader loader(origin);
  loader.scene_rule = &rule;
  loader.source = path;
  return loader.load(text);
}

}  // namespace fivebar
