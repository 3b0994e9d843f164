// The exported JSON into a runtime Config (fivebar/runtime/json_config.hpp): a small recursive
// descent JSON reader (RFC 8259; numbers by std::from_chars, so no locale) and the reader of the
// one key list (fivebar/runtime/config_layout.hpp). Initialisation only: it allocates and throws.

#include "fivebar/runtime/json_config.hpp"

#include "fivebar/runtime/config_layout.hpp"

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

/// The layout's reader (fivebar/runtime/config_layout.hpp) over a parsed document.
class LayoutReader {
 public:
  static constexpr bool reading = true;
  LayoutReader(const Reader& r, const Value& params, const std::string& path) : r_(r) { stack_.push_back({&params, path}); }

  template <class F>
  void object(const std::string& key, F&& inside) {
    const Value& v = r_.member(top(), path(), key);
    const std::string at = Reader::join(path(), key);
    if (v.kind != Value::Kind::object) r_.fail(at, std::string("expected an object, found ") + kind_name(v.kind));
    stack_.push_back({&v, at});
    inside();
    stack_.pop_back();
  }
  void value(const std::string& key, double& x) { x = r_.number(top(), path(), key); }
  void value(const std::string& key, int& x) { x = r_.integer(top(), path(), key); }
  void value(const std::string& key, bool& x) { x = r_.boolean(top(), path(), key); }
  void value(const std::string& key, std::string& x) { x = r_.string(top(), path(), key); }
  template <std::size_t N>
  void value(const std::string& key, std::array<double, N>& x) { x = r_.numbers<N>(top(), path(), key); }
  void value(const std::string& key, std::array<int, 4>& x) {
    const auto v = r_.numbers<4>(top(), path(), key);
    for (std::size_t i = 0; i < 4; ++i) {
      if (v[i] != std::floor(v[i]) || std::fabs(v[i]) > 1e9) r_.fail(Reader::join(path(), key) + "[" + std::to_string(i) + "]", "expected an integer");
      x[i] = static_cast<int>(v[i]);
    }
  }
  void value(const std::string& key, std::vector<std::string>& x) {
    const auto& items = r_.array(top(), path(), key, 0);
    x.clear();
    for (std::size_t i = 0; i < items.size(); ++i) x.push_back(r_.string(items[i], Reader::join(path(), key) + "[" + std::to_string(i) + "]"));
  }
  [[noreturn]] void fail(const std::string& key, const std::string& what) const { r_.fail(Reader::join(path(), key), what); }

 private:
  const Value& top() const { return *stack_.back().first; }
  const std::string& path() const { return stack_.back().second; }
  const Reader& r_;
  std::vector<std::pair<const Value*, std::string>> stack_;
};

}  // namespace

Config parse_config_json(std::string_view text, const std::string& origin) {
  const Value doc = Parser(text, origin).document();
  const Reader r(origin);
  if (doc.kind != Value::Kind::object || doc.members.size() != 1) {
    r.fail("(document)", "expected one ROS 2 node {<node>: {ros__parameters: {...}}}");
  }
  Config c;
  c.node = doc.members.front().first;
  const Value& p = r.member(doc.members.front().second, c.node, "ros__parameters");
  const std::string root = c.node + ".ros__parameters";
  LayoutReader io(r, p, root);
  layout(io, c);
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
