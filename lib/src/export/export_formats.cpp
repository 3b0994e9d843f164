// The three exported formats of one parameter tree (fivebar/export/export.hpp): ROS 2 parameters YAML and
// the C++17 header written here by hand (every double through format_double), JSON by nlohmann;
// and the readers that turn each back into the tree (the YAML one, which needs yaml-cpp, is in
// yaml/export_yaml_reader.cpp).

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "fivebar/format.hpp"
#include "export/export_detail.hpp"
#include "fivebar/error.hpp"
#include "fivebar/export/export.hpp"

namespace fivebar {

std::string format_double(double value) {
  if (!std::isfinite(value)) return format::shortest(value);
  std::string s = format::shortest(value);
  // A '.' in every mantissa: "5" -> "5.0", "3e-04" -> "3.0e-04". YAML 1.1 readers (PyYAML) take
  // a number without one for an integer or a string; the value is unchanged.
  const std::size_t e = s.find('e');
  if (s.find('.') == std::string::npos) s.insert(e == std::string::npos ? s.size() : e, ".0");
  return s;
}

namespace {

void require_finite(double v, const std::string& path) {
  if (!std::isfinite(v)) throw std::logic_error("export: " + path + " = " + format_double(v) + " is not finite");
}

/// A scalar of the tree as YAML (flow context).
std::string yaml_scalar(const Json& v, const std::string& path) {
  if (v.is_number_float()) {
    require_finite(v.get<double>(), path);
    return format_double(v.get<double>());
  }
  if (v.is_number_integer()) return std::to_string(v.get<std::int64_t>());
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_string()) {
    std::string out = "\"";
    for (unsigned char c : v.get<std::string>()) {
      if (c == '"' || c == '\\') {
        out += '\\';
        out += char(c);
      } else if (c < 0x20 || c == 0x7f) {
        static const char* hex = "0123456789abcdef";
        out += "\\x";
        out += hex[c >> 4];
        out += hex[c & 15];
      } else {
        out += char(c);
      }
    }
    return out + "\"";
  }
  throw std::logic_error("export: " + path + " is not a scalar ROS can hold");
}

/// ROS 2 parameters are scalars or non-empty lists of one scalar type.
void require_ros_list(const Json& list, const std::string& path) {
  if (list.empty()) throw std::logic_error("export: " + path + " is an empty list (ROS cannot type it)");
  const auto kind = [](const Json& v) {
    return v.is_number_float() ? 0 : v.is_number_integer() ? 1 : v.is_boolean() ? 2 : v.is_string() ? 3 : 4;
  };
  for (const Json& e : list) {
    if (kind(e) == 4 || kind(e) != kind(list.front())) {
      throw std::logic_error("export: " + path + " mixes types or nests lists (ROS cannot hold it)");
    }
  }
}

/// A map key as YAML 1.1 reads it back as the same string (docs/reliability.md): a station named
/// `on`, `yes` or `off` must not become a boolean key, nor `null`/`~` a null or `1e3` a number.
/// Names are is_safe_name() ([A-Za-z0-9_.-]); those YAML would read as anything but a string are
/// written as quoted strings.
std::string yaml_key(const std::string& key) {
  std::string lower;
  for (unsigned char c : key) lower += char(std::tolower(c));
  static const char* const special[] = {"y", "n", "yes", "no", "on", "off", "true", "false", "null", "~", ""};
  bool quote = std::find(std::begin(special), std::end(special), lower) != std::end(special);
  quote = quote || (!key.empty() && (std::isdigit(static_cast<unsigned char>(key[0])) || key[0] == '-' || key[0] == '+' || key[0] == '.'));
  return quote ? yaml_scalar(Json(key), key) : key;
}

void yaml_map(std::string& out, const Json& map, int indent, const std::string& path) {
  for (const auto& [key, value] : map.items()) {
    const std::string at = path.empty() ? key : path + "." + key;
    out.append(std::size_t(indent), ' ');
    out += yaml_key(key) + ":";
    if (value.is_object()) {
      out += "\n";
      yaml_map(out, value, indent + 2, at);
    } else if (value.is_array()) {
      require_ros_list(value, at);
      out += " [";
      for (std::size_t i = 0; i < value.size(); ++i) out += (i ? ", " : "") + yaml_scalar(value[i], at);
      out += "]\n";
    } else {
      out += " " + yaml_scalar(value, at) + "\n";
    }
  }
}

/// fivebar.<key> of the tree, for the comments at the top of a file.
std::string info(const Json& parameters, const char* key) {
  const Json& p = parameters.begin().value().at("ros__parameters").at("fivebar");
  return p.at(key).get<std::string>();
}

void require_tree(const Json& parameters) {
  if (!parameters.is_object() || parameters.size() != 1 || !parameters.begin().value().contains("ros__parameters")) {
    throw std::logic_error("export: the tree must be {node: {ros__parameters: {...}}}");
  }
}

/// The header's copy of the JSON document (render_header()).
constexpr const char* kRuntimeJson = "runtime_json";

std::string cpp_string(const std::string& s) {
  std::string out = "\"";
  for (unsigned char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += char(c);
    } else if (c < 0x20 || c >= 0x7f) {
      const char oct[5] = {'\\', char('0' + (c >> 6)), char('0' + ((c >> 3) & 7)), char('0' + (c & 7)), 0};
      out += oct;  // three octal digits: never swallows a following digit
    } else {
      out += char(c);
    }
  }
  return out + "\"";
}

std::string cpp_scalar(const Json& v, const std::string& path) {
  if (v.is_number_float()) {
    require_finite(v.get<double>(), path);
    return format_double(v.get<double>());
  }
  if (v.is_number_integer()) return std::to_string(v.get<std::int64_t>());
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_string()) return cpp_string(v.get<std::string>());
  throw std::logic_error("export: " + path + " is not a scalar");
}

std::string cpp_type(const Json& v) {
  if (v.is_number_float()) return "double";
  if (v.is_number_integer()) return "long long";
  if (v.is_boolean()) return "bool";
  return "const char*";
}

void header_namespace(std::string& out, const Json& map, const std::string& path) {
  for (const auto& [key, value] : map.items()) {
    const std::string at = path + "." + key;
    if (value.is_object()) {
      out += "namespace " + key + " {\n";
      header_namespace(out, value, at);
      out += "}  // namespace " + key + "\n";
    } else if (value.is_array()) {
      require_ros_list(value, at);
      out += "inline constexpr " + cpp_type(value.front()) + " " + key + "[" + std::to_string(value.size()) + "] = {";
      for (std::size_t i = 0; i < value.size(); ++i) out += (i ? ", " : "") + cpp_scalar(value[i], at);
      out += "};\n";
    } else if (value.is_string()) {
      out += "inline constexpr char " + key + "[] = " + cpp_string(value.get<std::string>()) + ";\n";
    } else {
      out += "inline constexpr " + cpp_type(value) + " " + key + " = " + cpp_scalar(value, at) + ";\n";
    }
  }
}

// --- Reading back ------------------------------------------------------------------------------

[[noreturn]] void bad_line(const std::string& origin, std::size_t line, const std::string& why) {
  throw InputError(origin + ":" + std::to_string(line) + ": " + why);
}

std::string trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string_view::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return std::string(s.substr(b, e - b + 1));
}

/// A C++ string literal as render_header() writes it; npos on failure, else the index after it.
std::size_t read_cpp_string(const std::string& s, std::size_t i, std::string& out) {
  if (i >= s.size() || s[i] != '"') return std::string::npos;
  for (++i; i < s.size(); ++i) {
    if (s[i] == '"') return i + 1;
    if (s[i] == '\\') {
      if (i + 1 >= s.size()) return std::string::npos;
      const char n = s[i + 1];
      if (n >= '0' && n <= '7') {
        if (i + 3 >= s.size()) return std::string::npos;
        int v = 0;
        for (int k = 1; k <= 3; ++k) {
          const char d = s[i + k];
          if (d < '0' || d > '7') return std::string::npos;
          v = v * 8 + (d - '0');
        }
        out += char(v);
        i += 3;
      } else {
        out += n;
        ++i;
      }
    } else {
      out += s[i];
    }
  }
  return std::string::npos;
}

/// One value of `type` from its text; std::nullopt when it is not one.
std::optional<Json> cpp_value(const std::string& type, const std::string& text) {
  if (type == "double") {
    double v = 0.0;
    const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
    if (r.ec != std::errc{} || r.ptr != text.data() + text.size()) return std::nullopt;
    return Json(v);
  }
  if (type == "long long") {
    std::int64_t v = 0;
    const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
    if (r.ec != std::errc{} || r.ptr != text.data() + text.size()) return std::nullopt;
    return Json(v);
  }
  if (type == "bool") {
    if (text == "true") return Json(true);
    if (text == "false") return Json(false);
    return std::nullopt;
  }
  if (type == "const char*") {
    std::string s;
    if (read_cpp_string(text, 0, s) != text.size()) return std::nullopt;
    return Json(s);
  }
  return std::nullopt;
}

/// Splits "a, b, "c, d"" at the commas outside string literals.
std::vector<std::string> split_list(const std::string& s) {
  std::vector<std::string> items;
  std::string current;
  bool in_string = false;
  for (std::size_t i = 0; i < s.size(); ++i) {
    const char c = s[i];
    if (in_string && c == '\\' && i + 1 < s.size()) {
      current += c;
      current += s[++i];
      continue;
    }
    if (c == '"') in_string = !in_string;
    if (c == ',' && !in_string) {
      items.push_back(trim(current));
      current.clear();
    } else {
      current += c;
    }
  }
  items.push_back(trim(current));
  return items;
}

bool is_identifier(const std::string& s) {
  if (s.empty() || std::isdigit(static_cast<unsigned char>(s[0]))) return false;
  return std::all_of(s.begin(), s.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; });
}

Json parse_header(const std::string& text, const std::string& origin) {
  Json root = Json::object();
  std::vector<std::string> names;   // open namespaces
  std::vector<Json*> stack{&root};  // root, then one object per namespace
  std::size_t line_no = 0;
  std::size_t begin = 0;
  static const std::string kDecl = "inline constexpr ";
  std::size_t runtime_json_line = 0;
  while (begin <= text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    const std::string line = trim(std::string_view(text).substr(begin, end - begin));
    begin = end + 1;
    ++line_no;
    if (line.empty() || line.starts_with("//") || line == "#pragma once") continue;
    if (line.starts_with("namespace ") && line.ends_with(" {")) {
      const std::string name = trim(line.substr(10, line.size() - 12));
      if (!is_identifier(name)) bad_line(origin, line_no, "namespace name '" + name + "' is not an identifier");
      Json& parent = *stack.back();
      if (parent.contains(name)) bad_line(origin, line_no, "namespace " + name + " opened twice");
      if (names.empty() && !root.empty()) bad_line(origin, line_no, "a second top-level namespace");
      parent[name] = names.empty() ? Json{{"ros__parameters", Json::object()}} : Json::object();
      stack.push_back(names.empty() ? &parent[name]["ros__parameters"] : &parent[name]);
      names.push_back(name);
      continue;
    }
    if (line.starts_with("}")) {
      if (names.empty()) bad_line(origin, line_no, "'}' without an open namespace");
      const std::string rest = trim(line.substr(1));
      if (!rest.empty() && rest != "// namespace " + names.back()) {
        bad_line(origin, line_no, "expected '}  // namespace " + names.back() + "'");
      }
      names.pop_back();
      stack.pop_back();
      continue;
    }
    if (!line.starts_with(kDecl) || !line.ends_with(";")) {
      bad_line(origin, line_no, "not a line fivebar export writes: " + line.substr(0, 60));
    }
    if (names.empty()) bad_line(origin, line_no, "a value outside the node's namespace");
    const std::string decl = line.substr(kDecl.size(), line.size() - kDecl.size() - 1);
    const std::size_t eq = decl.find(" = ");
    if (eq == std::string::npos) bad_line(origin, line_no, "expected 'TYPE NAME = VALUE;'");
    const std::string lhs = decl.substr(0, eq);
    const std::string rhs = trim(decl.substr(eq + 3));
    std::string type;
    for (const char* t : {"const char*", "long long", "double", "bool", "char"}) {
      if (lhs.starts_with(std::string(t) + " ")) {
        type = t;
        break;
      }
    }
    if (type.empty()) bad_line(origin, line_no, "unknown type in '" + lhs + "'");
    std::string name = trim(lhs.substr(type.size()));
    Json& scope = *stack.back();
    if (type == "char") {  // inline constexpr char NAME[] = "...";
      if (!name.ends_with("[]")) bad_line(origin, line_no, "a string is declared 'char NAME[]'");
      name = name.substr(0, name.size() - 2);
      const auto value = cpp_value("const char*", rhs);
      if (!value) bad_line(origin, line_no, name + ": not a string literal");
      if (names.size() == 1 && name == kRuntimeJson) {  // the document again, checked below
        if (runtime_json_line != 0) bad_line(origin, line_no, "a second " + name);
        runtime_json_line = line_no;
        continue;
      }
      if (!is_identifier(name) || scope.contains(name)) bad_line(origin, line_no, "bad or repeated name " + name);
      scope[name] = *value;
      continue;
    }
    if (name.ends_with("]")) {  // an array: NAME[N] = {a, b, ...}
      const auto open = name.find('[');
      if (open == std::string::npos) bad_line(origin, line_no, "bad array declaration");
      std::size_t n = 0;
      const std::string count = name.substr(open + 1, name.size() - open - 2);
      const auto r = std::from_chars(count.data(), count.data() + count.size(), n);
      if (r.ec != std::errc{} || r.ptr != count.data() + count.size()) bad_line(origin, line_no, "bad array size");
      name = name.substr(0, open);
      if (rhs.size() < 2 || rhs.front() != '{' || rhs.back() != '}') bad_line(origin, line_no, name + ": expected {...}");
      Json list = Json::array();
      for (const std::string& item : split_list(rhs.substr(1, rhs.size() - 2))) {
        const auto value = cpp_value(type, item);
        if (!value) bad_line(origin, line_no, name + ": '" + item + "' is not a " + type);
        list.push_back(*value);
      }
      if (list.size() != n) bad_line(origin, line_no, name + ": " + std::to_string(list.size()) + " values for [" + count + "]");
      if (!is_identifier(name) || scope.contains(name)) bad_line(origin, line_no, "bad or repeated name " + name);
      scope[name] = list;
      continue;
    }
    if (type == "const char*") bad_line(origin, line_no, "a single string is declared 'char NAME[]'");
    const auto value = cpp_value(type, rhs);
    if (!value) bad_line(origin, line_no, name + ": '" + rhs + "' is not a " + type);
    if (!is_identifier(name) || scope.contains(name)) bad_line(origin, line_no, "bad or repeated name " + name);
    scope[name] = *value;
  }
  if (!names.empty()) throw InputError(origin + ": namespace " + names.back() + " is not closed");
  // The embedded JSON is what the runtime reads (fivebar/runtime/header_config.hpp); check_export()
  // compares it with the design as it compares the constants (header_runtime_json()).
  if (runtime_json_line == 0) throw InputError(origin + ": no " + std::string(kRuntimeJson) + " (the values as JSON, which the runtime reads)");
  return root;
}

}  // namespace

namespace detail {

Json header_runtime_json(const std::string& text, const std::string& origin) {
  const std::string decl = "inline constexpr char " + std::string(kRuntimeJson) + "[] = ";
  std::size_t line_no = 0, begin = 0;
  while (begin < text.size()) {
    std::size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    const std::string line = trim(std::string_view(text).substr(begin, end - begin));
    begin = end + 1;
    ++line_no;
    if (!line.starts_with(decl) || !line.ends_with(";")) continue;
    const auto value = cpp_value("const char*", line.substr(decl.size(), line.size() - decl.size() - 1));
    if (!value) bad_line(origin, line_no, std::string(kRuntimeJson) + ": not a string literal");
    try {
      return Json::parse(value->get<std::string>());
    } catch (const Json::parse_error& e) {
      bad_line(origin, line_no, std::string(kRuntimeJson) + " is not JSON: " + e.what());
    }
  }
  throw InputError(origin + ": no " + std::string(kRuntimeJson) + " (the values as JSON, which the runtime reads)");
}

}  // namespace detail

std::string render_ros2_yaml(const Json& parameters) {
  require_tree(parameters);
  std::string out;
  out += "# ROS 2 parameters of the fivebar controller for design \"" + info(parameters, "design") + "\"\n";
  out += "# written by fivebar " + info(parameters, "tool_version") + " (`fivebar export`) after the export gate passed.\n";
  out += "# design_hash " + info(parameters, "design_hash") + ": `fivebar export --check THIS_FILE DESIGN` confirms\n";
  out += "# that the file matches the design. Units SI (m, rad, s, V, Hz); joints <station>_<mechanism>_theta<1|2>.\n";
  yaml_map(out, parameters, 0, "");
  return out;
}

std::string render_json(const Json& parameters) {
  require_tree(parameters);
  // nlohmann writes doubles in their shortest round-trip form and keeps ".0" on whole ones.
  return parameters.dump(2) + "\n";
}

std::string render_header(const Json& parameters) {
  require_tree(parameters);
  const std::string node = parameters.begin().key();
  std::string out;
  out += "// fivebar controller parameters for design \"" + info(parameters, "design") + "\", written by fivebar " +
         info(parameters, "tool_version") + "\n";
  out += "// (`fivebar export --format header`) after the export gate passed. Do not edit:\n";
  out += "// `fivebar export --check THIS_FILE DESIGN` confirms that it matches the design.\n";
  out += "// design_hash " + info(parameters, "design_hash") + " is also in the ROS parameters file: a controller\n";
  out += "// built with this header refuses parameters with another hash.\n";
  out += "// The ROS parameter tree as C++17: maps are namespaces, values `inline constexpr`; SI units\n";
  out += "// (m, rad, s, V, Hz); joints <station>_<mechanism>_theta<1|2>.\n";
  out += "#pragma once\n\n";
  out += "namespace " + node + " {\n";
  header_namespace(out, parameters.begin().value().at("ros__parameters"), node);
  // The same document as the JSON export, for the runtime's one reader of the one key list
  // (fivebar/runtime/header_config.hpp, fivebar/runtime/config_layout.hpp).
  out += "// " + std::string(kRuntimeJson) + ": the values above as the JSON export writes them (FIVEBAR_RUNTIME_CONFIG reads it).\n";
  out += "inline constexpr char " + std::string(kRuntimeJson) + "[] = " + cpp_string(render_json(parameters)) + ";\n";
  out += "}  // namespace " + node + "\n";
  return out;
}

std::string render(ExportFormat format, const Json& parameters) {
  switch (format) {
    case ExportFormat::ros2: return render_ros2_yaml(parameters);
    case ExportFormat::json: return render_json(parameters);
    case ExportFormat::header: return render_header(parameters);
  }
  return render_ros2_yaml(parameters);
}

Json parse_export(ExportFormat format, const std::string& text, const std::string& origin) {
  switch (format) {
    case ExportFormat::ros2: return detail::parse_ros2_yaml(text, origin);
    case ExportFormat::header: return parse_header(text, origin);
    case ExportFormat::json: break;
  }
  try {
    return Json::parse(text);
  } catch (const Json::parse_error& e) {
    const std::size_t upto = std::min<std::size_t>(e.byte > 0 ? e.byte - 1 : 0, text.size());
    const auto line = 1 + std::count(text.begin(), text.begin() + std::ptrdiff_t(upto), '\n');
    throw InputError(origin + ":" + std::to_string(line) + ": not valid JSON: " + e.what());
  } catch (const Json::exception& e) {  // e.g. a number beyond a double (1e999): bad input, not internal
    throw InputError(origin + ": not a file fivebar exports: " + e.what());
  }
}

ExportFormat detect_export_format(const std::filesystem::path& path, const std::string& text) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".yaml" || ext == ".yml") return ExportFormat::ros2;
  if (ext == ".json") return ExportFormat::json;
  if (ext == ".hpp" || ext == ".h" || ext == ".hh" || ext == ".hxx") return ExportFormat::header;
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && text[first] == '{') return ExportFormat::json;
  if (first != std::string::npos && (text.compare(first, 2, "//") == 0 || text.compare(first, 7, "#pragma") == 0)) {
    return ExportFormat::header;
  }
  return ExportFormat::ros2;
}

}  // namespace fivebar
