// `fivebar export --check` of the robot descriptions (fivebar/export/export.hpp check_robot_export):
// the URDF or MJCF of a station read back by a small XML reader (the subset render_urdf() and
// render_mjcf() write: a declaration, comments, elements, attributes in double or single quotes,
// the five predefined entities) and compared element by element with the design's rendering.

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <regex>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/error.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/export/mjcf.hpp"
#include "fivebar/export/urdf.hpp"
#include "fivebar/format.hpp"

namespace fivebar {

namespace {

struct XmlElement {
  std::string tag;
  std::size_t line = 0;
  std::vector<std::pair<std::string, std::string>> attributes;  ///< in file order
  std::vector<XmlElement> children;
  std::string text;  ///< character data, blanks collapsed
};

struct XmlDocument {
  XmlElement root;
  std::vector<std::string> comments;  ///< before the root element
};

class XmlReader {
 public:
  XmlReader(std::string_view text, std::string origin) : t_(text), origin_(std::move(origin)) {}

  XmlDocument document() {
    XmlDocument doc;
    misc(&doc.comments);
    if (!at("<")) fail("expected the root element");
    doc.root = element(0);
    misc(nullptr);
    if (i_ != t_.size()) fail("text after the root element");
    return doc;
  }

 private:
  [[noreturn]] void fail(const std::string& why) const {
    const auto line = 1 + std::count(t_.begin(), t_.begin() + std::ptrdiff_t(std::min(i_, t_.size())), '\n');
    throw InputError(origin_ + ":" + std::to_string(line) + ": not an XML document fivebar export writes: " + why);
  }
  std::size_t line() const { return std::size_t(1 + std::count(t_.begin(), t_.begin() + std::ptrdiff_t(i_), '\n')); }
  bool at(std::string_view s) const { return t_.substr(i_, s.size()) == s; }
  void blanks() {
    while (i_ < t_.size() && std::isspace(static_cast<unsigned char>(t_[i_]))) ++i_;
  }
  std::string until(std::string_view end) {
    const std::size_t e = t_.find(end, i_);
    if (e == std::string_view::npos) fail("'" + std::string(end) + "' missing");
    std::string out(t_.substr(i_, e - i_));
    i_ = e + end.size();
    return out;
  }
  /// Blanks, comments and the declaration between elements.
  void misc(std::vector<std::string>* comments) {
    while (true) {
      blanks();
      if (at("<!--")) {
        i_ += 4;
        std::string c = until("-->");
        if (comments) comments->push_back(std::move(c));
      } else if (at("<?")) {
        i_ += 2;
        until("?>");
      } else {
        return;
      }
    }
  }
  std::string name() {
    const std::size_t b = i_;
    while (i_ < t_.size() && (std::isalnum(static_cast<unsigned char>(t_[i_])) || t_[i_] == '_' || t_[i_] == ':' ||
                              t_[i_] == '-' || t_[i_] == '.')) {
      ++i_;
    }
    if (b == i_) fail("expected a name");
    return std::string(t_.substr(b, i_ - b));
  }
  std::string unescape(const std::string& s) {
    std::string out;
    for (std::size_t k = 0; k < s.size(); ++k) {
      if (s[k] != '&') {
        out += s[k];
        continue;
      }
      static const std::pair<const char*, char> kEntities[] = {{"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}};
      bool known = false;
      for (const auto& [entity, c] : kEntities) {
        if (s.compare(k, std::strlen(entity), entity) == 0) {
          out += c;
          k += std::strlen(entity) - 1;
          known = true;
          break;
        }
      }
      if (!known) fail("an entity other than &amp; &lt; &gt; &quot; &apos;");
    }
    return out;
  }
  XmlElement element(int depth) {
    if (depth > 64) fail("nested too deeply");
    XmlElement e;
    e.line = line();
    ++i_;  // '<'
    e.tag = name();
    while (true) {
      blanks();
      if (at("/>")) {
        i_ += 2;
        return e;
      }
      if (at(">")) {
        ++i_;
        break;
      }
      std::string key = name();
      blanks();
      if (!at("=")) fail("expected '=' after " + key);
      ++i_;
      blanks();
      if (i_ >= t_.size() || (t_[i_] != '"' && t_[i_] != '\'')) fail("expected a quoted value of " + key);
      const char quote = t_[i_++];
      std::string value = unescape(until(std::string_view(&quote, 1)));
      for (const auto& a : e.attributes) {
        if (a.first == key) fail("attribute " + key + " twice");
      }
      e.attributes.emplace_back(std::move(key), std::move(value));
    }
    std::string text;
    while (true) {
      if (i_ >= t_.size()) fail("element <" + e.tag + "> not closed");
      if (at("<!--")) {
        i_ += 4;
        until("-->");
      } else if (at("</")) {
        i_ += 2;
        const std::string end = name();
        blanks();
        if (end != e.tag || !at(">")) fail("expected </" + e.tag + ">");
        ++i_;
        break;
      } else if (at("<")) {
        e.children.push_back(element(depth + 1));
      } else {
        const std::size_t b = i_;
        while (i_ < t_.size() && t_[i_] != '<') ++i_;
        text += unescape(std::string(t_.substr(b, i_ - b))) + " ";
      }
    }
    std::istringstream words(text);
    for (std::string w; words >> w;) e.text += (e.text.empty() ? "" : " ") + w;
    return e;
  }

  std::string_view t_;
  std::string origin_;
  std::size_t i_ = 0;
};

/// Equal numbers (every blank-separated word that reads fully as a double compared as one), or
/// equal text.
bool same_value(const std::string& a, const std::string& b) {
  std::istringstream sa(a), sb(b);
  std::string wa, wb;
  while (true) {
    const bool ha = static_cast<bool>(sa >> wa), hb = static_cast<bool>(sb >> wb);
    if (ha != hb) return false;
    if (!ha) return true;
    double x = 0.0, y = 0.0;
    const auto rx = std::from_chars(wa.data(), wa.data() + wa.size(), x);
    const auto ry = std::from_chars(wb.data(), wb.data() + wb.size(), y);
    const bool nx = rx.ec == std::errc{} && rx.ptr == wa.data() + wa.size();
    const bool ny = ry.ec == std::errc{} && ry.ptr == wb.data() + wb.size();
    if (nx && ny ? x != y : wa != wb) return false;
  }
}

/// A child's key among its siblings: `tag[name]` when it has a name (or a joint / actuator
/// reference, as MJCF's equalities and actuators do), else `tag[k]`, k counting that tag.
std::vector<std::string> child_keys(const XmlElement& e) {
  std::vector<std::string> keys;
  for (const XmlElement& c : e.children) {
    std::string id;
    for (const char* attribute : {"name", "joint", "joint1", "body1", "link"}) {
      const auto it = std::find_if(c.attributes.begin(), c.attributes.end(), [&](const auto& a) { return a.first == attribute; });
      if (it != c.attributes.end()) {
        id = it->second;
        break;
      }
    }
    if (id.empty()) {
      int k = 0;
      for (const std::string& previous : keys) k += previous.starts_with(c.tag + "[#");
      id = "#" + std::to_string(k);
    }
    std::string key = c.tag + "[" + id + "]";
    while (std::find(keys.begin(), keys.end(), key) != keys.end()) key += "'";
    keys.push_back(key);
  }
  return keys;
}

bool skipped(const XmlElement& e, bool masses_from_renders) {
  if (!masses_from_renders) return false;
  // Masses and meshes from the parts' STL renders: not what the closed form gives.
  return e.tag == "inertial" || e.tag == "visual" || e.tag == "asset" || (e.tag == "geom" && std::any_of(e.attributes.begin(), e.attributes.end(), [](const auto& a) { return a.first == "mesh"; }));
}

void diff_xml(const XmlElement& expected, const XmlElement& found, const std::string& path, bool renders,
              std::vector<ExportDifference>& out) {
  // Named pairs, not structured bindings: clang 14 (the fuzz build) cannot capture a binding.
  for (const auto& attribute : expected.attributes) {
    const std::string& key = attribute.first;
    const std::string& value = attribute.second;
    const auto it = std::find_if(found.attributes.begin(), found.attributes.end(), [&](const auto& a) { return a.first == key; });
    if (it == found.attributes.end()) out.push_back({path + "@" + key, value, "(absent)"});
    else if (!same_value(value, it->second)) out.push_back({path + "@" + key, value, it->second});
  }
  for (const auto& attribute : found.attributes) {
    const std::string& key = attribute.first;
    const std::string& value = attribute.second;
    const auto it = std::find_if(expected.attributes.begin(), expected.attributes.end(), [&](const auto& a) { return a.first == key; });
    if (it == expected.attributes.end()) out.push_back({path + "@" + key, "(absent)", value});
  }
  if (!same_value(expected.text, found.text)) out.push_back({path + "#text", expected.text, found.text});
  const std::vector<std::string> ek = child_keys(expected), fk = child_keys(found);
  for (std::size_t k = 0; k < ek.size(); ++k) {
    if (skipped(expected.children[k], renders)) continue;
    const auto it = std::find(fk.begin(), fk.end(), ek[k]);
    if (it == fk.end()) {
      out.push_back({path + "/" + ek[k], "<" + expected.children[k].tag + ">", "(absent)"});
    } else {
      diff_xml(expected.children[k], found.children[std::size_t(it - fk.begin())], path + "/" + ek[k], renders, out);
    }
  }
  for (std::size_t k = 0; k < fk.size(); ++k) {
    if (skipped(found.children[k], renders)) continue;
    if (std::find(ek.begin(), ek.end(), fk[k]) == ek.end()) out.push_back({path + "/" + fk[k], "(absent)", "<" + found.children[k].tag + ">"});
  }
}

bool names_meshes(const XmlElement& e) {
  if (e.tag == "mesh") return true;
  return std::any_of(e.children.begin(), e.children.end(), names_meshes);
}

}  // namespace

ExportCheck check_robot_export(const std::string& text, const Design& d, const std::string& origin) {
  const XmlDocument found = XmlReader(text, origin).document();
  const bool urdf = found.root.tag == "robot";
  if (!urdf && found.root.tag != "mujoco") {
    throw InputError(origin + ": not a fivebar export: the root element is <" + found.root.tag + ">, not <robot> or <mujoco>");
  }
  // The stamp: "Generated by fivebar V from design D, station S (design hash H)."
  static const std::regex kStamp(R"(Generated by fivebar (\S+) from design (.+), station (\S+) \(design hash (\S+)\))");
  std::smatch m;
  const auto stamp = std::find_if(found.comments.begin(), found.comments.end(),
                                  [&](const std::string& c) { return std::regex_search(c, m, kStamp); });
  if (stamp == found.comments.end()) {
    throw InputError(origin + ": not a fivebar export: no comment \"Generated by fivebar ... (design hash ...)\" before the root");
  }
  ExportCheck check;
  check.format = urdf ? "urdf" : "mjcf";
  check.file_tool_version = m[1].str();
  check.file_design = m[2].str();
  check.stations = {m[3].str()};
  check.file_hash = m[4].str();
  const Station* station = d.station(check.stations.front());
  if (station == nullptr) {
    throw InputError(origin + ": the file describes station " + check.stations.front() + ", which design " + d.name + " does not have");
  }
  check.design_hash = design_hash(d, {station->name});
  if (!check.hash_matches()) check.differences.push_back({"(stamp) design hash", check.design_hash, check.file_hash});
  const bool renders = names_meshes(found.root);
  if (renders) {
    check.not_compared.push_back("masses, inertias and meshes: the file's come from the parts' STL renders (fivebar run), "
                                 "which the design alone does not give");
  }
  const std::string expected_text = urdf ? render_urdf(d, *station) : render_mjcf(d, *station);
  const XmlDocument expected = XmlReader(expected_text, "the design's rendering").document();
  diff_xml(expected.root, found.root, expected.root.tag, renders, check.differences);
  return check;
}

}  // namespace fivebar
