// One way to edit a design (fivebar/design/edit.hpp): key paths resolved and canonicalised once,
// a station's numbers set in place, every other number through the design file, and the
// printable-link rule stated once.
#include "fivebar/design/edit.hpp"

#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "yaml/key_path.hpp"
#include "design/design_keys.hpp"
#include "fivebar/format.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/suggest.hpp"

namespace fivebar {

namespace {


/// One component of a resolved path: a map key or a list index.
using Component = std::variant<std::string, std::size_t>;

bool is_blank(char c) { return c == ' ' || c == '\t'; }

/// `[...]` at the front of `rest`: an index (digits, blanks around them allowed) or a quoted name
/// ("..." with \" and \\ escapes, or '...' with '' for a quote). Consumes it on success.
std::optional<Component> bracket(std::string_view& rest, std::string& why) {
  std::size_t i = 1;
  while (i < rest.size() && is_blank(rest[i])) ++i;
  if (i < rest.size() && (rest[i] == '"' || rest[i] == '\'')) {
    const char q = rest[i++];
    std::string name;
    bool closed = false;
    while (i < rest.size()) {
      const char c = rest[i++];
      if (q == '"' && c == '\\' && i < rest.size()) {
        name += rest[i++];
      } else if (q == '\'' && c == '\'' && i < rest.size() && rest[i] == '\'') {
        name += '\'';
        ++i;
      } else if (c == q) {
        closed = true;
        break;
      } else {
        name += c;
      }
    }
    while (i < rest.size() && is_blank(rest[i])) ++i;
    if (!closed || i >= rest.size() || rest[i] != ']') {
      why = "unclosed quoted name";
      return std::nullopt;
    }
    rest.remove_prefix(i + 1);
    return Component{std::move(name)};
  }
  const std::size_t begin = i;
  while (i < rest.size() && rest[i] >= '0' && rest[i] <= '9') ++i;
  const std::size_t end = i;
  while (i < rest.size() && is_blank(rest[i])) ++i;
  std::size_t index = 0;
  const auto r = std::from_chars(rest.data() + begin, rest.data() + end, index);
  if (begin == end || i >= rest.size() || rest[i] != ']' || r.ec != std::errc{}) {
    why = "malformed index";
    return std::nullopt;
  }
  rest.remove_prefix(i + 1);
  return Component{index};
}

/// Follows `key` from `root`, building its canonical spelling in `canonical` and its components
/// in `parts`. A bare map key may itself contain '.' (station names may): the longest key of the
/// map that the path continues with wins. Returns the node, or nullopt with `why`.
std::optional<YAML::Node> follow(const YAML::Node& root, std::string_view key, std::string& canonical,
                                 std::vector<Component>& parts, std::string& why) {
  YAML::Node node;
  node.reset(root);
  std::string_view rest = key;
  canonical.clear();
  parts.clear();
  auto where = [&] { return canonical.empty() ? std::string("the design") : "'" + canonical + "'"; };
  while (!rest.empty()) {
    std::optional<Component> c;
    if (rest.front() == '[') {
      c = bracket(rest, why);
      if (!c) {
        why += " after " + where();
        return std::nullopt;
      }
    } else {
      if (!canonical.empty()) {
        if (rest.front() != '.') {
          why = "expected '.' or '[' after " + where();
          return std::nullopt;
        }
        rest.remove_prefix(1);
      }
      if (!node.IsMap()) {
        why = where() + " is not a map";
        return std::nullopt;
      }
      std::string best;
      bool found = false;
      for (const auto& entry : node) {
        if (!entry.first.IsScalar()) continue;
        const std::string& k = entry.first.Scalar();
        if (rest.substr(0, k.size()) != k) continue;
        const char next = rest.size() > k.size() ? rest[k.size()] : '\0';
        if ((next == '\0' || next == '.' || next == '[') && (!found || k.size() > best.size())) best = k, found = true;
      }
      if (!found) {
        const std::string_view wanted = rest.substr(0, rest.find_first_of(".["));
        std::vector<std::string> keys;
        for (const auto& entry : node) {
          if (entry.first.IsScalar()) keys.push_back(entry.first.Scalar());
        }
        why = where() + " has no key " + detail::quoted(wanted);
        if (const std::string near = nearest_name(wanted, keys); !near.empty()) why += " (did you mean " + detail::quoted(near) + "?)";
        return std::nullopt;
      }
      rest.remove_prefix(best.size());
      c = Component{std::move(best)};
    }
    if (const std::size_t* index = std::get_if<std::size_t>(&*c)) {
      if (!node.IsSequence() || *index >= node.size()) {
        why = where() + " has no element [" + std::to_string(*index) + "]";
        return std::nullopt;
      }
      node.reset(node[*index]);  // rebind: Node::operator= would assign the child into the tree
      canonical = detail::key_index(canonical, *index);
    } else {
      const std::string& name = std::get<std::string>(*c);
      const YAML::Node& view = node;  // const: a missing key is not created
      if (!view.IsMap() || !view[name]) {
        why = where() + " has no key " + detail::quoted(name);
        return std::nullopt;
      }
      node.reset(view[name]);
      canonical = detail::key_child(canonical, name);
    }
    parts.push_back(std::move(*c));
  }
  if (parts.empty()) {
    why = "empty key path";
    return std::nullopt;
  }
  return node;
}

bool scalar_number(const YAML::Node& node, double& value) {
  if (!node.IsScalar()) return false;
  const std::string& text = node.Scalar();
  const auto r = std::from_chars(text.data(), text.data() + text.size(), value);
  return r.ec == std::errc{} && r.ptr == text.data() + text.size() && std::isfinite(value);
}

const std::string* name_at(const std::vector<Component>& p, std::size_t i) {
  return i < p.size() ? std::get_if<std::string>(&p[i]) : nullptr;
}
std::optional<int> index_at(const std::vector<Component>& p, std::size_t i, int below) {
  const std::size_t* v = i < p.size() ? std::get_if<std::size_t>(&p[i]) : nullptr;
  if (!v || *v >= std::size_t(below)) return std::nullopt;
  return int(*v);
}

/// Where a station number lives, from the components of its path (stations.<name>. ...).
void locate(DesignKey& k, const std::vector<Component>& p) {
  const std::string* top = name_at(p, 0);
  const std::string* station = name_at(p, 1);
  if (!top || *top != "stations" || !station) return;
  auto is = [&](std::size_t i, std::string_view s) { const std::string* n = name_at(p, i); return n && *n == s; };
  DesignKey::Field field = DesignKey::Field::other;
  if (is(2, "target")) {
    if (p.size() == 4 && is(3, "angle")) field = DesignKey::Field::angle;
    if (p.size() == 5 && (is(3, "center") || is(3, "axes")) && index_at(p, 4, 2)) {
      field = is(3, "center") ? DesignKey::Field::center : DesignKey::Field::axes;
      k.i = *index_at(p, 4, 2);
    }
  } else if (is(2, "mechanisms") && (is(3, "lower") || is(3, "upper"))) {
    k.upper = is(3, "upper");
    if (p.size() == 6 && is(4, "links") && index_at(p, 5, 4)) {
      field = DesignKey::Field::link;
      k.i = *index_at(p, 5, 4);
    }
    if (p.size() == 7 && is(4, "bases") && index_at(p, 5, 2) && index_at(p, 6, 2)) {
      field = DesignKey::Field::base;
      k.i = *index_at(p, 5, 2);
      k.j = *index_at(p, 6, 2);
    }
  }
  k.field = field;
  k.station = *station;  // any number under a station names it (optimize_station_names)
}

}  // namespace

namespace detail {

std::optional<YAML::Node> resolve_design_key(const YAML::Node& root, std::string_view key, DesignKey& k) {
  std::vector<Component> parts;
  std::string why;
  std::optional<YAML::Node> node = follow(root, key, k.path, parts, why);
  if (!node) throw ValidationError(std::string(key), "not a key path of the design: " + why);
  if (!scalar_number(*node, k.value)) {
    throw ValidationError(std::string(key), "is not a number of the design (the key holds " +
                                                std::string(node->IsMap() ? "a map" : node->IsSequence() ? "a list" : "text") + ")");
  }
  locate(k, parts);
  return node;
}

std::optional<YAML::Node> follow_design_key(const YAML::Node& root, std::string_view key, std::string& canonical) {
  std::vector<Component> parts;
  std::string why;
  return follow(root, key, canonical, parts, why);
}

bool yaml_number(const YAML::Node& node, double& value) { return scalar_number(node, value); }

}  // namespace detail

namespace {

DesignKey resolve(const YAML::Node& root, std::string_view key) {
  DesignKey k;
  (void)detail::resolve_design_key(root, key, k);
  return k;
}

}  // namespace

std::vector<DesignKey> design_keys(const Design& design, const std::vector<std::string>& keys) {
  const YAML::Node root = YAML::Load(to_yaml(design));
  std::vector<DesignKey> out;
  out.reserve(keys.size());
  for (const std::string& key : keys) out.push_back(resolve(root, key));
  return out;
}

DesignKey design_key(const Design& design, std::string_view key) {
  return resolve(YAML::Load(to_yaml(design)), key);
}

std::string canonical_design_key(const Design& design, std::string_view key) { return design_key(design, key).path; }

void set_station_number(Station& st, const DesignKey& k, double v) {
  switch (k.field) {
    case DesignKey::Field::other: throw ValidationError(k.path, "is not a number of a station");
    case DesignKey::Field::angle: st.target.angle = format::rad_from_deg(v); return;  // as the loader converts
    case DesignKey::Field::center: st.target.center[k.i] = v; return;
    case DesignKey::Field::axes: st.target.axes[k.i] = v; return;
    case DesignKey::Field::link:
    case DesignKey::Field::base: {
      std::optional<Mechanism>& m = k.upper ? st.upper : st.lower;
      if (!m) throw ValidationError(k.path, "the station has no " + std::string(k.upper ? "upper" : "lower") + " mechanism");
      if (k.field == DesignKey::Field::link) m->L[std::size_t(k.i)] = v;
      else (k.i == 0 ? m->O1 : m->O2)[k.j] = v;
      return;
    }
  }
}

void check_printable_links(const Station& station, const Geometry& g) {
  for (const Mechanism* m : station.mechanisms()) {
    for (std::size_t i = 0; i < 4; ++i) {
      if (m->L[i] < g.boss_diameter) {
        throw ValidationError(detail::key_index("mechanisms." + m->name + ".links", i),
                              "= " + format::shortest(m->L[i]) + " mm: shorter than geometry.boss_diameter (" +
                                  format::shortest(g.boss_diameter) + " mm): the pin bosses at its ends would overlap");
      }
    }
  }
}

void check_station_edit(const Station& station, const Geometry* geometry) {
  station.validate();
  if (geometry) check_printable_links(station, *geometry);
}

void set_design_number(Design& design, std::string_view key, double value) {
  const DesignKey k = design_key(design, key);
  if (k.field == DesignKey::Field::other) {
    design = with_design_numbers(design, {{k.path, value}});
    return;
  }
  Design changed = design;
  for (Station& st : changed.stations) {
    if (st.name == k.station) set_station_number(st, k, value);
  }
  changed.validate();
  design = std::move(changed);
}

}  // namespace fivebar
