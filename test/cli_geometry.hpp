#pragma once
// The paper's device worked out by hand for the end-to-end tests of the subcommands
// (test/test_cli_<command>.cpp): Table 1's linkages, elbow positions, the areas and margins of the
// annuli. Written independently of the library, so that the binary's answers are checked against
// geometry rather than against itself.

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

namespace fivebar::testing::paper {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = std::numbers::pi / 180.0;

// Paper Table 1, index station: O1 (0,0), O2 (12.5,0), O3 (0,31), O4 (12.5,31), L1=L2=9, L3=L4=15.
struct Linkage {
  std::array<double, 2> O1, O2;
  std::array<double, 4> L;
};
constexpr Linkage kIndexLower{{0.0, 0.0}, {12.5, 0.0}, {9.0, 9.0, 15.0, 15.0}};
constexpr Linkage kIndexUpper{{0.0, 31.0}, {12.5, 31.0}, {9.0, 9.0, 15.0, 15.0}};

using P2 = std::array<double, 2>;
inline P2 elbow(const P2& O, double L, double theta_deg) {
  return {O[0] + L * std::cos(theta_deg * kDeg), O[1] + L * std::sin(theta_deg * kDeg)};
}
inline double dist(const P2& a, const P2& b) { return std::hypot(a[0] - b[0], a[1] - b[1]); }
/// cross(a - o, b - o).
inline double cross(const P2& o, const P2& a, const P2& b) {
  return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
}
/// A JSON point [x, y].
inline P2 xy(const nlohmann::json& j) { return {j.at(0).get<double>(), j.at(1).get<double>()}; }

/// Rows and cells of a CSV text (a trailing comma gives an empty last cell).
inline std::vector<std::vector<std::string>> parse_csv(const std::string& text) {
  std::vector<std::vector<std::string>> rows;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::string cell;
    std::istringstream ls(line);
    while (std::getline(ls, cell, ',')) cells.push_back(cell);
    if (!line.empty() && line.back() == ',') cells.emplace_back();
    rows.push_back(cells);
  }
  return rows;
}

inline const std::vector<std::string> kIndexLowerArgs{"--station", "index", "--mechanism", "lower"};

/// head, then target, then tail.
inline std::vector<std::string> args(std::initializer_list<std::string> head, const std::vector<std::string>& target,
                                     std::initializer_list<std::string> tail) {
  std::vector<std::string> out(head);
  out.insert(out.end(), target.begin(), target.end());
  out.insert(out.end(), tail);
  return out;
}

/// Area of the intersection of two disks of radii a and b whose centres are d apart.
inline double lens(double a, double b, double d) {
  if (d >= a + b) return 0.0;
  if (d <= std::fabs(a - b)) return kPi * std::min(a, b) * std::min(a, b);
  const double alpha = std::acos((d * d + a * a - b * b) / (2 * d * a));
  const double beta = std::acos((d * d + b * b - a * a) / (2 * d * b));
  return a * a * (alpha - std::sin(2 * alpha) / 2) + b * b * (beta - std::sin(2 * beta) / 2);
}
/// Two annuli r <= |P - O_i| <= R with centres d apart (inclusion-exclusion over the disks).
inline double annuli_area(double r, double R, double d) { return lens(R, R, d) - 2 * lens(R, r, d) + lens(r, r, d); }

/// Signed margin of a filled ellipse inside the two annuli about (ox1, oy) and (ox2, oy): the
/// smallest of R - max|p - O_i| and min|p - O_i| - r over the ellipse boundary (the centres are
/// outside the ellipse), by dense sampling of the boundary.
inline double annuli_margin(double r, double R, double ox1, double ox2, double oy, double cx, double cy, double a,
                            double b) {
  double margin = 1e9;
  const int n = 400000;
  for (int k = 0; k < n; ++k) {
    const double t = 2 * kPi * k / n;
    const double x = cx + a * std::cos(t), y = cy + b * std::sin(t);
    for (double ox : {ox1, ox2}) {
      const double d = std::hypot(x - ox, y - oy);
      margin = std::min({margin, R - d, d - r});
    }
  }
  return margin;
}

}  // namespace fivebar::testing::paper
