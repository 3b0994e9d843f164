#include "fivebar/format.hpp"
#include "products/markdown.hpp"

#include <cstdio>

namespace fivebar::md {

namespace {
std::string escape(const std::string& cell) {
  std::string out;
  out.reserve(cell.size());
  for (char c : cell) {
    if (c == '|') out += '\\';
    if (c == '\n') {
      out += ' ';
      continue;
    }
    out += c;
  }
  return out;
}
}  // namespace

Table::Table(std::initializer_list<std::string> header, std::string_view align)
    : Table(std::vector<std::string>(header), align) {}

Table::Table(std::vector<std::string> header, std::string_view align)
    : header_(std::move(header)), align_(align) {}

Table& Table::row(std::vector<std::string> cells) {
  cells.resize(header_.size());
  rows_.push_back(std::move(cells));
  return *this;
}

std::string Table::str() const {
  std::string out = "|";
  for (const auto& h : header_) out += " " + escape(h) + " |";
  out += "\n|";
  for (std::size_t i = 0; i < header_.size(); ++i) {
    const char a = i < align_.size() ? align_[i] : 'l';
    out += a == 'r' ? "---:|" : (a == 'c' ? ":---:|" : "---|");
  }
  out += "\n";
  for (const auto& r : rows_) {
    out += "|";
    for (const auto& c : r) out += " " + escape(c) + " |";
    out += "\n";
  }
  return out;
}

std::string fixed(double value, int digits) { return format::fixed(value, digits); }

std::string sci(double value, int digits) { return format::sci(value, digits); }

std::string pair(double x, double y, int digits) { return "(" + fixed(x, digits) + ", " + fixed(y, digits) + ")"; }

std::string code(std::string_view text) { return "`" + std::string(text) + "`"; }

}  // namespace fivebar::md
