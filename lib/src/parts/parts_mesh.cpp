// Meshes of printed parts without CGAL: reading binary STL and measuring hole walls (circle fits).
// The CGAL checks are in cgal/mesh_checks.cpp.

#include <Eigen/Dense>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <numbers>
#include <optional>
#include <set>
#include <unordered_map>

#include "fivebar/csv_reader.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "fivebar/parts.hpp"
#include "fivebar/numerics.hpp"

namespace fivebar {
namespace fs = std::filesystem;

namespace {
/// Widest polygon a hole of $fn >= 8 can be: vertices at r / cos(180 / 8).
const double kWidestPolygon = 1.0 / std::cos(std::numbers::pi / 8.0);
}  // namespace

Eigen::Vector3d TriangleMesh::bbox_min() const {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  for (const auto& v : vertices) lo = lo.cwiseMin(v);
  return lo;
}

Eigen::Vector3d TriangleMesh::bbox_max() const {
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  for (const auto& v : vertices) hi = hi.cwiseMax(v);
  return hi;
}

TriangleMesh read_stl(const fs::path& path) {
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw IoError("cannot read '" + path.string() + "': " + std::strerror(errno));
  }
  // A part's STL is megabytes; bounded as every read (docs/reliability.md).
  const std::string data = csv::read_bounded(path, kMaxStlBytes, "STL mesh");
  if (data.size() < 84) throw InputError(path.string() + ": not a binary STL (" + std::to_string(data.size()) + " bytes)");
  std::uint32_t count = 0;
  std::memcpy(&count, data.data() + 80, 4);
  const std::size_t expected = 84 + 50 * static_cast<std::size_t>(count);
  if (data.size() != expected) {
    const bool ascii = data.rfind("solid", 0) == 0;
    throw InputError(path.string() + ": " +
                     (ascii ? std::string("an ASCII STL; binary STL expected")
                            : "binary STL of " + std::to_string(count) + " triangles should be " +
                                  std::to_string(expected) + " bytes, is " + std::to_string(data.size())));
  }
  TriangleMesh mesh;
  mesh.triangles.reserve(count);
  struct Key {
    std::array<std::uint32_t, 3> bits;
    bool operator==(const Key&) const = default;
  };
  struct KeyHash {
    std::size_t operator()(const Key& k) const {
      return (static_cast<std::size_t>(k.bits[0]) * 73856093u) ^ (static_cast<std::size_t>(k.bits[1]) * 19349663u) ^
             (static_cast<std::size_t>(k.bits[2]) * 83492791u);
    }
  };
  std::unordered_map<Key, std::uint32_t, KeyHash> index;
  for (std::uint32_t t = 0; t < count; ++t) {
    const char* record = data.data() + 84 + 50 * static_cast<std::size_t>(t);
    std::array<std::uint32_t, 3> tri{};
    for (int v = 0; v < 3; ++v) {
      Key key{};
      std::memcpy(key.bits.data(), record + 12 + 12 * v, 12);
      const auto [it, inserted] = index.emplace(key, static_cast<std::uint32_t>(mesh.vertices.size()));
      if (inserted) {
        float xyz[3];
        std::memcpy(xyz, key.bits.data(), 12);
        if (!std::isfinite(xyz[0]) || !std::isfinite(xyz[1]) || !std::isfinite(xyz[2])) {
          throw InputError(path.string() + ": triangle " + std::to_string(t) + " has a non-finite vertex");
        }
        mesh.vertices.emplace_back(xyz[0], xyz[1], xyz[2]);
      }
      tri[static_cast<std::size_t>(v)] = it->second;
    }
    mesh.triangles.push_back(tri);
  }
  return mesh;
}

namespace {

struct Fit {
  Vec2 c{0, 0};
  double r = 0;
};

/// Algebraic circle fit (Kasa): minimises sum (|p|^2 + D x + E y + F)^2; exact for points on a
/// circle. Points are relative to a nearby origin for conditioning.
std::optional<Fit> kasa(const std::vector<Vec2>& pts) {
  if (pts.size() < 3) return std::nullopt;
  Eigen::MatrixXd A(pts.size(), 3);
  Eigen::VectorXd b(pts.size());
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    A(row, 0) = pts[i].x();
    A(row, 1) = pts[i].y();
    A(row, 2) = 1.0;
    b(row) = -pts[i].squaredNorm();
  }
  const Eigen::Vector3d x = A.colPivHouseholderQr().solve(b);
  Fit f;
  f.c = Vec2(-0.5 * x(0), -0.5 * x(1));
  const double r2 = f.c.squaredNorm() - x(2);
  if (!(r2 > 0.0) || !std::isfinite(r2)) return std::nullopt;
  f.r = std::sqrt(r2);
  return f;
}

}  // namespace

CircleFit fit_circle_wall(const TriangleMesh& mesh, const HoleSpec& hole) {
  CircleFit out;
  const double r = 0.5 * hole.diameter_mm;
  const double lo = 0.9 * r;
  const double hi = 1.1 * r * kWidestPolygon;
  // Distinct (x, y) of wall vertices, relative to the nominal axis.
  std::set<std::pair<double, double>> seen;
  std::vector<Vec2> pts;
  for (const auto& v : mesh.vertices) {
    if (v.z() < hole.z_min_mm || v.z() > hole.z_max_mm) continue;
    const Vec2 p = Vec2(v.x(), v.y()) - hole.center_mm;
    const double dist = p.norm();
    if (dist < lo || dist > hi) continue;
    if (seen.emplace(p.x(), p.y()).second) pts.push_back(p);
  }
  constexpr std::size_t kMinPoints = 6;
  std::optional<Fit> fit;
  while (pts.size() >= kMinPoints) {
    fit = kasa(pts);
    if (!fit) break;
    std::size_t worst = 0;
    double worst_res = -1.0;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      const double res = std::abs((pts[i] - fit->c).norm() - fit->r);
      if (res > worst_res) {
        worst_res = res;
        worst = i;
      }
    }
    if (worst_res <= tol::kCircleFitRejectRel * fit->r) break;
    pts.erase(pts.begin() + static_cast<std::ptrdiff_t>(worst));
    fit.reset();
  }
  if (!fit) return out;
  out.found = true;
  out.points = pts.size();
  out.center_mm = hole.center_mm + fit->c;
  out.vertex_radius_mm = fit->r;
  double sq = 0.0;
  for (const Vec2& p : pts) sq += std::pow((p - fit->c).norm() - fit->r, 2);
  out.rms_mm = std::sqrt(sq / static_cast<double>(pts.size()));
  if (hole.peg) {
    out.diameter_mm = 2.0 * fit->r;
    return out;
  }
  // Narrowest width: distance from the axis to the nearest facet, i.e. to the chord between
  // angularly neighbouring vertices (gaps much wider than the typical one are not facets: the
  // flat of a D-bore).
  std::vector<std::pair<double, Vec2>> around;
  for (const Vec2& p : pts) {
    const Vec2 q = p - fit->c;
    around.emplace_back(std::atan2(q.y(), q.x()), q);
  }
  std::sort(around.begin(), around.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<double> gaps;
  for (std::size_t i = 0; i < around.size(); ++i) {
    const auto& a = around[i];
    const auto& b = around[(i + 1) % around.size()];
    double gap = b.first - a.first;
    if (gap <= 0.0) gap += 2.0 * std::numbers::pi;
    gaps.push_back(gap);
  }
  std::vector<double> sorted = gaps;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
  const double typical = sorted[sorted.size() / 2];
  double nearest = fit->r;
  for (std::size_t i = 0; i < around.size(); ++i) {
    if (gaps[i] > 1.5 * typical) continue;
    const Vec2& a = around[i].second;
    const Vec2& b = around[(i + 1) % around.size()].second;
    const double chord = (b - a).norm();
    if (chord <= 0.0) continue;
    nearest = std::min(nearest, std::abs(a.x() * b.y() - a.y() * b.x()) / chord);
  }
  out.diameter_mm = 2.0 * nearest;
  return out;
}

}  // namespace fivebar
