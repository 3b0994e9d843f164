// Reads an exported ROS 2 parameters file back (fivebar/export/export.hpp, export --check) with yaml-cpp,
// keeping each scalar's ROS type: `5` is an integer, `5.0` a double, `"5"` a string.

#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cstdint>
#include <limits>
#include <string>

#include "export/export_detail.hpp"
#include "fivebar/error.hpp"

namespace fivebar::detail {

namespace {

Json scalar(const YAML::Node& node) {
  const std::string& text = node.Scalar();
  if (node.Tag() == "!") return text;  // quoted
  if (text == "true" || text == "True" || text == "TRUE") return true;
  if (text == "false" || text == "False" || text == "FALSE") return false;
  std::string_view digits = text;
  if (!digits.empty() && digits.front() == '+') digits.remove_prefix(1);
  std::int64_t i = 0;
  if (auto r = std::from_chars(digits.data(), digits.data() + digits.size(), i);
      r.ec == std::errc{} && r.ptr == digits.data() + digits.size() && !digits.empty()) {
    return i;
  }
  if (text == ".inf" || text == "+.inf") return std::numeric_limits<double>::infinity();
  if (text == "-.inf") return -std::numeric_limits<double>::infinity();
  if (text == ".nan") return std::numeric_limits<double>::quiet_NaN();
  double d = 0.0;
  if (auto r = std::from_chars(digits.data(), digits.data() + digits.size(), d);
      r.ec == std::errc{} && r.ptr == digits.data() + digits.size() && !digits.empty() &&
      digits.find_first_of(".eE") != std::string_view::npos) {
    return d;
  }
  return text;  // a plain string
}

Json convert(const YAML::Node& node, const std::string& origin) {
  switch (node.Type()) {
    case YAML::NodeType::Map: {
      Json out = Json::object();
      for (const auto& pair : node) {
        if (!pair.first.IsScalar()) {
          throw InputError(origin + ":" + std::to_string(pair.first.Mark().line + 1) + ": keys must be names");
        }
        const std::string key = pair.first.Scalar();
        if (out.contains(key)) {
          throw InputError(origin + ":" + std::to_string(pair.first.Mark().line + 1) + ": duplicate key '" + key + "'");
        }
        out[key] = convert(pair.second, origin);
      }
      return out;
    }
    case YAML::NodeType::Sequence: {
      Json out = Json::array();
      for (const auto& element : node) out.push_back(convert(element, origin));
      return out;
    }
    case YAML::NodeType::Scalar: return scalar(node);
    case YAML::NodeType::Null:
    case YAML::NodeType::Undefined: break;
  }
  return nullptr;
}

}  // namespace

Json parse_ros2_yaml(const std::string& text, const std::string& origin) {
  try {
    return convert(YAML::Load(text), origin);
  } catch (const YAML::Exception& e) {
    const int line = e.mark.is_null() ? 1 : e.mark.line + 1;
    throw InputError(origin + ":" + std::to_string(line) + ": YAML syntax error: " + e.msg);
  }
}

}  // namespace fivebar::detail
