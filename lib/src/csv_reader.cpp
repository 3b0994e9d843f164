// The bench's one bounded CSV reader (fivebar/csv_reader.hpp).
#include "fivebar/csv_reader.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <system_error>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"

namespace fivebar::csv {

std::string shown(std::string_view text) {
  std::string out;
  const bool cut = text.size() > 40;
  for (const char c : text.substr(0, 40)) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) {
      char hex[5];
      std::snprintf(hex, sizeof hex, "\\x%02x", u);
      out += hex;
    } else {
      out += c;
    }
  }
  return cut ? out + "..." : out;
}

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

bool skipped(std::string_view line) {
  const std::string_view t = trim(line);
  return t.empty() || t.front() == '#';
}

}  // namespace

Reader::Reader(std::istream& in, std::string origin, Limits limits) : in_(in), origin_(std::move(origin)), limits_(limits) {
  std::string line;
  bool found = false;
  while (read_line(line)) {
    if (line_ == 1 && line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
    if (skipped(line)) continue;
    found = true;
    break;
  }
  if (!found) throw InputError(origin_ + ":" + std::to_string(line_ + 1) + ": empty file (a header line naming the columns is needed)");
  header_line_ = line_;
  header_ = split(line);
  std::map<std::string_view, std::size_t> seen;
  for (std::size_t c = 0; c < header_.size(); ++c) {
    const std::string pre = where() + "column " + std::to_string(c + 1);
    if (header_[c].empty()) throw InputError(pre + ": empty column name");
    if (const auto it = seen.find(header_[c]); it != seen.end()) {
      throw InputError(pre + " '" + shown(header_[c]) + "': duplicate of column " + std::to_string(it->second + 1) +
                       " (a duplicated column would be read as one of them)");
    }
    seen.emplace(header_[c], c);
  }
}

bool Reader::read_line(std::string& out) {
  out.clear();
  std::streambuf* buf = in_.rdbuf();
  if (buf == nullptr || !in_.good()) return false;
  bool any = false;
  const auto fail = [&](const std::string& what) { throw InputError(origin_ + ":" + std::to_string(line_ + 1) + ": " + what); };
  while (true) {
    const auto c = buf->sbumpc();
    if (std::char_traits<char>::eq_int_type(c, std::char_traits<char>::eof())) {
      in_.setstate(std::ios::eofbit);
      if (any) ++line_;
      return any;
    }
    any = true;
    if (++bytes_ > limits_.max_bytes) fail("more than " + std::to_string(limits_.max_bytes) + " bytes: refused (docs/bench-files.md)");
    const char ch = std::char_traits<char>::to_char_type(c);
    if (ch == '\n') break;
    if (out.size() >= limits_.max_line) fail("line longer than " + std::to_string(limits_.max_line) + " bytes: refused (docs/bench-files.md)");
    out.push_back(ch);
  }
  ++line_;
  if (!out.empty() && out.back() == '\r') out.pop_back();
  return true;
}

std::vector<std::string> Reader::split(const std::string& line) const {
  std::vector<std::string> out;
  std::size_t i = 0;
  const std::size_t n = line.size();
  while (true) {
    while (i < n && (line[i] == ' ' || line[i] == '\t')) ++i;
    std::string cell;
    if (i < n && line[i] == '"') {  // quoted: "" is a quote; blanks may follow the closing quote
      ++i;
      bool closed = false;
      while (i < n) {
        if (line[i] == '"') {
          if (i + 1 < n && line[i + 1] == '"') {
            cell += '"';
            i += 2;
            continue;
          }
          ++i;
          closed = true;
          break;
        }
        cell += line[i++];
      }
      if (!closed) throw InputError(where() + "column " + std::to_string(out.size() + 1) + ": a quoted cell without its closing quote");
      while (i < n && (line[i] == ' ' || line[i] == '\t')) ++i;
      if (i < n && line[i] != ',') {
        throw InputError(where() + "column " + std::to_string(out.size() + 1) + ": text after a quoted cell");
      }
    } else {
      const std::size_t comma = line.find(',', i);
      const std::size_t end = comma == std::string::npos ? n : comma;
      cell = std::string(trim(std::string_view(line).substr(i, end - i)));
      i = end;
    }
    out.push_back(std::move(cell));
    if (i >= n) break;
    ++i;  // the comma
    if (i == n) {
      out.emplace_back();
      break;
    }
  }
  return out;
}

bool Reader::next() {
  while (read_line(buffer_)) {
    if (skipped(buffer_)) continue;
    if (++rows_ > limits_.max_rows) throw InputError(where() + "more than " + std::to_string(limits_.max_rows) + " data rows: refused (docs/bench-files.md)");
    cells_ = split(buffer_);
    if (cells_.size() != header_.size()) {
      throw InputError(where() + std::to_string(cells_.size()) + " cells, the header (line " + std::to_string(header_line_) + ") has " +
                       std::to_string(header_.size()));
    }
    return true;
  }
  if (in_.bad()) throw InputError(origin_ + ": read error");
  cells_.clear();
  return false;
}

int Reader::column(std::string_view name) const {
  for (std::size_t c = 0; c < header_.size(); ++c)
    if (header_[c] == name) return static_cast<int>(c);
  return -1;
}

std::size_t Reader::require(std::string_view name) const {
  const int c = column(name);
  if (c < 0) throw InputError(origin_ + ":" + std::to_string(header_line_) + ": column '" + std::string(name) + "' is missing");
  return static_cast<std::size_t>(c);
}

std::string Reader::where() const { return origin_ + ":" + std::to_string(line_) + ": "; }

std::string Reader::at(std::size_t c) const {
  return where() + "column '" + shown(header_[c]) + "' = '" + shown(c < cells_.size() ? cells_[c] : std::string()) + "': ";
}

double Reader::number(std::size_t c, double max_abs, std::string_view unit) const {
  const std::string& s = cells_[c];
  const char* b = s.data();
  const char* e = b + s.size();
  const bool plus = b != e && *b == '+';
  if (plus) ++b;
  double v = 0.0;
  const auto [p, ec] = std::from_chars(b, e, v, std::chars_format::general);
  const std::string in_unit = unit.empty() ? std::string() : " (" + std::string(unit) + ")";
  // from_chars reads "inf" and "nan"; a sign after '+' ("+-1") is not a number either.
  if (s.empty() || b == e || (plus && *b == '-') || ec != std::errc() || p != e || !std::isfinite(v)) {
    throw InputError(at(c) + "not a finite decimal number" + in_unit);
  }
  if (std::abs(v) > max_abs) throw InputError(at(c) + "outside +-" + format::shortest(max_abs) + in_unit);
  return v;
}

std::string read_bounded(const std::filesystem::path& path, std::uintmax_t max_bytes, std::string_view what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.generic_string() + ": cannot read the " + std::string(what));
  std::string text;
  char chunk[65536];
  while (in.read(chunk, sizeof chunk) || in.gcount() > 0) {
    const auto got = static_cast<std::size_t>(in.gcount());
    if (text.size() + got > max_bytes) {
      throw InputError(path.generic_string() + ": the " + std::string(what) + " is larger than " + std::to_string(max_bytes) +
                       " bytes: refused (docs/reliability.md)");
    }
    text.append(chunk, got);
  }
  if (in.bad()) throw InputError(path.generic_string() + ": read error in the " + std::string(what));
  return text;
}

}  // namespace fivebar::csv
