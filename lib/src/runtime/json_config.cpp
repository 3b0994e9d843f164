// The exported JSON into a runtime Config (fivebar/runtime/json_config.hpp): a small recursive
// descent JSON reader (RFC 8259; numbers by std::from_chars, so no locale) and the key walk of
// the export's layout (fivebar/export/export.hpp). Initialisation only: it allocates and throws.

#include "fivebar/runtime/json_config.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <vector>

namespace fivebar::runtime {

namespace {

struct Value {
  enum class Kind { null, boolean, number, string, array, object } kind = Kind::null;
  bool b = false;
  double n = 0.0;
  bool integer = false;  ///< written without '.', 'e' or 'E'
  std::string s;
  std::vector<Value> items;
  std::vector<std::pair<std::string, Value>> members;  ///< in file order
};

const char* kind_name(Value::Kind k) {
  switch (k) {
    case Value::Kind::null: return "null";
    case Value::Kind::boolean: return "a boolean";
    case Value::Kind::number: return "a number";
    case Value::Kind::string: return "a string";
    case Value::Kind::array: return "an array";
    case Value::Kind::object: return "an object";
  }
  return "?";
}

class Parser {
 public:
  Parser(std::string_view text, const std::string& origin) : t_(text), origin_(origin) {}
  Value document() {
    Value v = value(0);
    skip();
    if (i_ != t_.size()) fail("trailing characters after the document");
    return v;
  }

 private:
  [[noreturn]] void fail(const std::string& what) const {
    std::size_t line = 1;
    for (std::size_t k = 0; k < i_ && k < t_.size(); ++k) line += t_[k] == '\n';
    throw ConfigError(origin_ + ":" + std::to_string(line) + ": " + what);
  }
  void skip() {
    while (i_ < t_.size() && (t_[i_] == ' ' || t_[i_] == '\n' || t_[i_] == '\r' || t_[i_] == '\t')) ++i_;
  }
  bool eat(char c) {
    skip();
    if (i_ < t_.size() && t_[i_] == c) {
      ++i_;
      return true;
    }
    return false;
  }
  void expect(char c) {
    if (!eat(c)) fail(std::string("expected '") + c + "'");
  }
  bool word(std::string_view w) {
    if (t_.substr(i_, w.size()) == w) {
      i_ += w.size();
      return true;
    }
    return false;
  }
  std::string string() {
    expect('"');
    std::string out;
    while (true) {
      if (i_ >= t_.size()) fail("unterminated string");
      const char c = t_[i_++];
      if (c == '"') return out;
      if (static_cast<unsigned char>(c) < 0x20) fail("control character in a string");
      if (c != '\\') {
        out.push_back(c);
        continue;
      }
      if (i_ >= t_.size()) fail("unterminated escape");
      const char e = t_[i_++];
      switch (e) {
        case '"': out.push_back('"'); break;
        case '\\': out.push_back('\\'); break;
        case '/': out.push_back('/'); break;
        case 'b': out.push_back('\b'); break;
        case 'f': out.push_back('\f'); break;
        case 'n': out.push_back('\n'); break;
        case 'r': out.push_back('\r'); break;
        case 't': out.push_back('\t'); break;
        case 'u': {
          if (i_ + 4 > t_.size()) fail("short \\u escape");
          unsigned code = 0;
          const auto r = std::from_chars(t_.data() + i_, t_.data() + i_ + 4, code, 16);
          if (r.ptr != t_.data() + i_ + 4) fail("bad \\u escape");
          i_ += 4;
          // Keys and names of an export are ASCII; other code points are kept as UTF-8 (BMP only).
          if (code < 0x80) {
            out.push_back(static_cast<char>(code));
          } else if (code < 0x800) {
            out.push_back(static_cast<char>(0xC0 | (code >> 6)));
            out.push_back(static_cast<char>(0x80 | (code & 0x3F)));
          } else {
            out.push_back(static_cast<char>(0xE0 | (code >> 12)));
            out.push_back(static_cast<char>(0x80 | ((code >> 6) & 0x3F)));
            out.push_back(static_cast<char>(0x80 | (code & 0x3F)));
          }
          break;
        }
        default: fail("bad escape in a string");
      }
    }
  }
  Value value(int depth) {
    if (depth > 64) fail("nested too deeply");
    skip();
    if (i_ >= t_.size()) fail("unexpected end of the document");
    Value v;
    const char c = t_[i_];
    if (c == '{') {
      ++i_;
      v.kind = Value::Kind::object;
      if (eat('}')) return v;
      do {
        skip();
        std::string key = string();
        expect(':');
        for (const auto& m : v.members)
          if (m.first == key) fail("duplicate key \"" + key + "\"");
        v.members.emplace_back(std::move(key), value(depth + 1));
      } while (eat(','));
      expect('}');
    } else if (c == '[') {
      ++i_;
      v.kind = Value::Kind::array;
      if (eat(']')) return v;
      do v.items.push_back(value(depth + 1));
      while (eat(','));
      expect(']');
    } else if (c == '"') {
      v.kind = Value::Kind::string;
      v.s = string();
    } else if (word("true")) {
      v.kind = Value::Kind::boolean;
      v.b = true;
    } else if (word("false")) {
      v.kind = Value::Kind::boolean;
    } else if (word("null")) {
      v.kind = Value::Kind::null;
    } else if (c == '-' || (c >= '0' && c <= '9')) {
      // RFC 8259: -? (0 | [1-9][0-9]*) (. [0-9]+)? ([eE] [+-]? [0-9]+)?  (no `05`, `5.`, `.5`, `+5`).
      std::size_t j = i_;
      bool integer = true;
      const auto digit = [&](std::size_t at) { return at < t_.size() && t_[at] >= '0' && t_[at] <= '9'; };
      const auto digits = [&] {
        if (!digit(j)) fail("bad number");
        while (digit(j)) ++j;
      };
      if (t_[j] == '-') ++j;
      if (j < t_.size() && t_[j] == '0') {
        ++j;
        if (digit(j)) fail("bad number: a leading zero");
      } else {
        digits();
      }
      if (j < t_.size() && t_[j] == '.') {
        integer = false;
        ++j;
        digits();
      }
      if (j < t_.size() && (t_[j] == 'e' || t_[j] == 'E')) {
        integer = false;
        ++j;
        if (j < t_.size() && (t_[j] == '+' || t_[j] == '-')) ++j;
        digits();
      }
      double x = 0.0;
      const auto r = std::from_chars(t_.data() + i_, t_.data() + j, x);
      if (r.ec != std::errc() || r.ptr != t_.data() + j) fail("bad number");
      v.kind = Value::Kind::number;
      v.n = x;
      v.integer = integer;
      i_ = j;
    } else {
      fail(std::string("unexpected character '") + c + "' (NaN and infinity are not JSON)");
    }
    return v;
  }
  std::string_view t_;
  const std::string& origin_;
  std::size_t i_ = 0;
};

/// Typed access that names the key path in every error.
class Reader {
 public:
  explicit Reader(std::string origin) : origin_(std::move(origin)) {}
  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw ConfigError(origin_ + ": " + key + ": " + what);
  }
  const Value& member(const Value& obj, const std::string& path, const std::string& key) const {
    if (obj.kind != Value::Kind::object) fail(path, std::string("expected an object, found ") + kind_name(obj.kind));
    for (const auto& m : obj.members)
      if (m.first == key) return m.second;
    fail(join(path, key), "missing key");
  }
  const Value* optional(const Value& obj, const std::string& key) const {
    for (const auto& m : obj.members)
      if (m.first == key) return &m.second;
    return nullptr;
  }
  static std::string join(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }
  double number(const Value& v, const std::string& path) const {
    if (v.kind != Value::Kind::number) fail(path, std::string("expected a number, found ") + kind_name(v.kind));
    if (!std::isfinite(v.n)) fail(path, "not a finite number");
    return v.n;
  }
  double number(const Value& obj, const std::string& path, const std::string& key) const {
    return number(member(obj, path, key), join(path, key));
  }
  int integer(const Value& obj, const std::string& path, const std::string& key) const {
    const double x = number(obj, path, key);
    if (x != std::floor(x) || std::fabs(x) > 1e9) fail(join(path, key), "expected an integer");
    return static_cast<int>(x);
  }
  bool boolean(const Value& obj, const std::string& path, const std::string& key) const {
    const Value& v = member(obj, path, key);
    if (v.kind != Value::Kind::boolean) fail(join(path, key), std::string("expected a boolean, found ") + kind_name(v.kind));
    return v.b;
  }
  const std::string& string(const Value& v, const std::string& path) const {
    if (v.kind != Value::Kind::string) fail(path, std::string("expected a string, found ") + kind_name(v.kind));
    return v.s;
  }
  const std::string& string(const Value& obj, const std::string& path, const std::string& key) const {
    return string(member(obj, path, key), join(path, key));
  }
  const std::vector<Value>& array(const Value& obj, const std::string& path, const std::string& key, std::size_t n) const {
    const Value& v = member(obj, path, key);
    if (v.kind != Value::Kind::array) fail(join(path, key), std::string("expected an array, found ") + kind_name(v.kind));
    if (n > 0 && v.items.size() != n) fail(join(path, key), "expected " + std::to_string(n) + " values");
    return v.items;
  }
  template <std::size_t N>
  std::array<double, N> numbers(const Value& obj, const std::string& path, const std::string& key) const {
    const auto& items = array(obj, path, key, N);
    std::array<double, N> out{};
    for (std::size_t i = 0; i < N; ++i) out[i] = number(items[i], join(path, key) + "[" + std::to_string(i) + "]");
    return out;
  }

 private:
  std::string origin_;
};

std::array<std::int8_t, 2> parse_mode(const Reader& r, const std::string& text, const std::string& key) {
  if (text.size() != 2) r.fail(key, "expected two signs (\"-+\"), found \"" + text + "\"");
  std::array<std::int8_t, 2> out{};
  for (std::size_t i = 0; i < 2; ++i) {
    if (text[i] == '+') out[i] = 1;
    else if (text[i] == '-') out[i] = -1;
    else r.fail(key, "expected two signs (\"-+\"), found \"" + text + "\"");
  }
  return out;
}

}  // namespace

Config parse_config_json(std::string_view text, const std::string& origin) {
  const Value doc = Parser(text, origin).document();
  const Reader r(origin);
  if (doc.kind != Value::Kind::object || doc.members.size() != 1) {
    r.fail("(document)", "expected one ROS 2 node {<node>: {ros__parameters: {...}}}");
  }
  const std::string node = doc.members.front().first;
  const Value& p = r.member(doc.members.front().second, node, "ros__parameters");
  const std::string root = node + ".ros__parameters";
  const auto at = [&](const std::string& key) { return Reader::join(root, key); };

  Config c;
  if (const Value* f = r.optional(p, "fivebar")) {
    if (const Value* d = r.optional(*f, "design")) c.design = r.string(*d, at("fivebar.design"));
    if (const Value* h = r.optional(*f, "design_hash")) c.design_hash = r.string(*h, at("fivebar.design_hash"));
  }
  c.loop_rate_hz = r.number(p, root, "loop_rate_hz");
  const Value& adc = r.member(p, root, "adc");
  c.adc_bits = r.integer(adc, at("adc"), "bits");
  c.adc_range_v = r.numbers<2>(adc, at("adc"), "range_v");
  c.volts_per_count = r.number(adc, at("adc"), "volts_per_count");
  c.joint_margin = r.number(p, root, "joint_margin_rad");

  const Value& col = r.member(p, root, "collision");
  const std::string cp = at("collision");
  const std::string priority = r.string(col, cp, "priority");
  if (priority != "upper") r.fail(cp + ".priority", "only \"upper\" (the paper's rule) is implemented, found \"" + priority + "\"");
  c.collision.checked = r.boolean(col, cp, "checked");
  if (c.collision.checked) {
    c.collision.min_clearance = r.number(col, cp, "min_clearance_m");
    c.collision.link_widths = r.numbers<4>(col, cp, "link_widths_m");
    const auto layers = r.numbers<4>(col, cp, "layers");
    for (std::size_t i = 0; i < 4; ++i) {
      if (layers[i] != std::floor(layers[i])) r.fail(cp + ".layers[" + std::to_string(i) + "]", "expected an integer");
      c.collision.layers[i] = static_cast<int>(layers[i]);
    }
    c.collision.pin_diameter = r.number(col, cp, "pin_diameter_m");
    c.collision.boss_diameter = r.number(col, cp, "boss_diameter_m");
    c.collision.tactor_diameter = r.number(col, cp, "tactor_diameter_m");
    c.collision.motor_shaft_diameter = r.number(col, cp, "motor_shaft_diameter_m");
  }

  const Value& limits = r.member(p, root, "joint_limits");
  const Value& gains = r.member(p, root, "gains");
  const Value& pots = r.member(p, root, "potentiometers");
  const Value& stations = r.member(p, root, "stations");
  const auto& station_names = r.array(p, root, "station_names", 0);
  if (station_names.empty()) r.fail(at("station_names"), "no station");
  for (std::size_t si = 0; si < station_names.size(); ++si) {
    StationConfig sc;
    sc.name = r.string(station_names[si], at("station_names") + "[" + std::to_string(si) + "]");
    const std::string sp = at("stations." + sc.name);
    const Value& st = r.member(stations, at("stations"), sc.name);
    const auto& mnames = r.array(st, sp, "mechanisms", 0);
    if (mnames.empty() || mnames.size() > 2) r.fail(sp + ".mechanisms", "expected one or two mechanisms");
    for (std::size_t mi = 0; mi < mnames.size(); ++mi) {
      MechanismConfig mc;
      mc.name = r.string(mnames[mi], sp + ".mechanisms[" + std::to_string(mi) + "]");
      if (mc.name != "lower" && mc.name != "upper") r.fail(sp + ".mechanisms[" + std::to_string(mi) + "]", "expected \"lower\" or \"upper\"");
      const std::string mp = sp + "." + mc.name;
      const Value& m = r.member(st, sp, mc.name);
      mc.o1 = r.numbers<2>(m, mp, "o1_m");
      mc.o2 = r.numbers<2>(m, mp, "o2_m");
      mc.L = r.numbers<4>(m, mp, "link_lengths_m");
      mc.working_mode = parse_mode(r, r.string(m, mp, "working_mode"), mp + ".working_mode");
      const std::string& asm_text = r.string(m, mp, "assembly_mode");
      if (asm_text == "+") mc.assembly = Assembly::plus;
      else if (asm_text == "-") mc.assembly = Assembly::minus;
      else if (asm_text == "any") mc.assembly = Assembly::any;
      else r.fail(mp + ".assembly_mode", "expected \"+\", \"-\" or \"any\", found \"" + asm_text + "\"");
      const auto& jnames = r.array(m, mp, "joint_names", 2);
      for (std::size_t j = 0; j < 2; ++j) {
        JointConfig& jc = mc.joints[j];
        jc.name = r.string(jnames[j], mp + ".joint_names[" + std::to_string(j) + "]");
        const std::string gp = at("gains");
        const Value& g = r.member(gains, gp, jc.name);
        const std::string gj = gp + "." + jc.name;
        jc.gains = {r.number(g, gj, "p"), r.number(g, gj, "i"), r.number(g, gj, "d"), r.number(g, gj, "i_clamp")};
        const std::string pp = at("potentiometers");
        const Value& pot = r.member(pots, pp, jc.name);
        jc.volts_at_zero = r.number(pot, pp + "." + jc.name, "volts_at_zero");
        jc.rad_per_volt = r.number(pot, pp + "." + jc.name, "rad_per_volt");
        const std::string lp = at("joint_limits");
        const Value& lim = r.member(limits, lp, jc.name);
        jc.has_position_limits = r.boolean(lim, lp + "." + jc.name, "has_position_limits");
        if (jc.has_position_limits) {
          jc.min_position = r.number(lim, lp + "." + jc.name, "min_position");
          jc.max_position = r.number(lim, lp + "." + jc.name, "max_position");
        }
      }
      sc.mechanisms.push_back(std::move(mc));
    }
    c.stations.push_back(std::move(sc));
  }
  try {
    c.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(origin + ": " + root + "." + e.what());
  }
  return c;
}

Config load_config_json(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path + ": cannot be read");
  // Bounded while reading (docs/reliability.md): an exported configuration is a few kilobytes;
  // /dev/zero or a wrong file is refused after kMaxBytes + 1 bytes, not read whole.
  constexpr std::size_t kMaxBytes = std::size_t{16} << 20;
  std::string text;
  char chunk[65536];
  while (in.read(chunk, sizeof chunk) || in.gcount() > 0) {
    if (text.size() + static_cast<std::size_t>(in.gcount()) > kMaxBytes) {
      throw ConfigError(path + ": larger than " + std::to_string(kMaxBytes) + " bytes: not a runtime configuration");
    }
    text.append(chunk, static_cast<std::size_t>(in.gcount()));
  }
  if (in.bad()) throw ConfigError(path + ": read error");
  return parse_config_json(text, path);
}

}  // namespace fivebar::runtime
