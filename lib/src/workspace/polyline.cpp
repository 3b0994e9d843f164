// Polylines of workspace curves (fivebar/workspace/polyline.hpp).
#include "fivebar/workspace/polyline.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>

namespace fivebar {

std::vector<Vec2> discretise(const CurvePiece& piece, double max_step_rad) {
  if (!(max_step_rad > 0.0)) throw std::invalid_argument("discretise: max_step_rad must be > 0");
  if (!piece.is_arc) return {piece.source, piece.target};
  const double sweep = piece.sweep();
  const int n = std::max(1, int(std::ceil(std::fabs(sweep) / max_step_rad)));
  const Vec2 a = piece.source - piece.center;
  const double a0 = std::atan2(a.y(), a.x());
  std::vector<Vec2> out;
  out.reserve(std::size_t(n) + 1);
  out.push_back(piece.source);
  for (int k = 1; k < n; ++k) {
    const double t = a0 + sweep * double(k) / double(n);
    out.push_back(piece.center + piece.radius * Vec2(std::cos(t), std::sin(t)));
  }
  out.push_back(piece.target);
  return out;
}

std::vector<Vec2> discretise(const BoundaryLoop& loop, double max_step_rad) {
  std::vector<Vec2> out;
  for (const CurvePiece& p : loop.pieces) {
    const std::vector<Vec2> pts = discretise(p, max_step_rad);
    out.insert(out.end(), pts.begin(), pts.end() - 1);  // the next piece starts at this one's target
  }
  return out;
}

std::vector<Polyline> chain_segments(const std::vector<std::vector<Vec2>>& pieces, double tol_mm) {
  std::vector<Polyline> out;
  if (pieces.empty()) return out;
  const double q = tol_mm > 0.0 ? tol_mm : 1e-300;
  auto cell = [q](const Vec2& p) { return std::pair<std::int64_t, std::int64_t>{std::int64_t(std::floor(p.x() / q)), std::int64_t(std::floor(p.y() / q))}; };
  auto key = [](std::int64_t i, std::int64_t j) { return std::uint64_t(i) * 0x9E3779B97F4A7C15ull ^ std::uint64_t(j); };
  // Endpoint index: (piece, end) under the quantised cell of the point.
  std::unordered_map<std::uint64_t, std::vector<std::pair<std::size_t, int>>> ends;
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    if (pieces[k].size() < 2) continue;
    for (int e = 0; e < 2; ++e) {
      const auto [i, j] = cell(e == 0 ? pieces[k].front() : pieces[k].back());
      ends[key(i, j)].push_back({k, e});
    }
  }
  std::vector<bool> used(pieces.size(), false);
  // An unused piece with an end within tol of p: returns (piece, end) or piece = npos.
  auto find = [&](const Vec2& p) -> std::pair<std::size_t, int> {
    const auto [ci, cj] = cell(p);
    for (std::int64_t di = -1; di <= 1; ++di) {
      for (std::int64_t dj = -1; dj <= 1; ++dj) {
        const auto it = ends.find(key(ci + di, cj + dj));
        if (it == ends.end()) continue;
        for (const auto& [k, e] : it->second) {
          if (used[k]) continue;
          const Vec2& x = e == 0 ? pieces[k].front() : pieces[k].back();
          if ((x - p).norm() <= tol_mm) return {k, e};
        }
      }
    }
    return {std::size_t(-1), 0};
  };
  for (std::size_t start = 0; start < pieces.size(); ++start) {
    if (used[start] || pieces[start].size() < 2) continue;
    used[start] = true;
    std::vector<Vec2> chain(pieces[start].begin(), pieces[start].end());
    for (int direction = 0; direction < 2; ++direction) {
      while (true) {
        const auto [k, e] = find(chain.back());
        if (k == std::size_t(-1)) break;
        used[k] = true;
        const auto& p = pieces[k];
        // Append p from the matching end, skipping the shared point.
        if (e == 0) {
          chain.insert(chain.end(), p.begin() + 1, p.end());
        } else {
          chain.insert(chain.end(), p.rbegin() + 1, p.rend());
        }
      }
      std::reverse(chain.begin(), chain.end());  // then grow the other end
    }
    Polyline line;
    line.closed = chain.size() > 3 && (chain.front() - chain.back()).norm() <= tol_mm;
    if (line.closed) chain.pop_back();
    line.points = std::move(chain);
    out.push_back(std::move(line));
  }
  return out;
}

std::vector<Vec2> ellipse_polyline(const Ellipse& e, int segments) {
  std::vector<Vec2> out;
  segments = std::max(segments, 3);
  out.reserve(std::size_t(segments));
  for (int k = 0; k < segments; ++k) out.push_back(e.boundary_point(2.0 * std::numbers::pi * k / segments));
  return out;
}

}  // namespace fivebar
