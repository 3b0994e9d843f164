#pragma once
/// Small helpers for the Markdown of summary.md: tables and fixed number formats, so that every
/// product's section looks the same.

#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

namespace fivebar::md {

/// A pipe table; cells are escaped for '|'.
class Table {
 public:
  Table(std::initializer_list<std::string> header, std::string_view align = "");
  explicit Table(std::vector<std::string> header, std::string_view align = "");
  Table& row(std::vector<std::string> cells);
  bool empty() const { return rows_.empty(); }
  /// The table text, ending in a newline.
  std::string str() const;

 private:
  std::vector<std::string> header_;
  std::string align_;  ///< one of 'l', 'r', 'c' per column; missing = 'l'
  std::vector<std::vector<std::string>> rows_;
};

/// Fixed-point with `digits` decimals, "-0.000" printed as "0.000".
std::string fixed(double value, int digits = 3);
/// Scientific with `digits` significant decimals, e.g. 1.2e-15.
std::string sci(double value, int digits = 1);
/// "(x, y)" with fixed decimals.
std::string pair(double x, double y, int digits = 3);
/// Inline code: `text`.
std::string code(std::string_view text);

}  // namespace fivebar::md
