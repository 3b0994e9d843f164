// Mesh checks and hole fits of printed parts (fivebar/parts.hpp) on a synthetic part of a link's
// size: a pin boss (5 mm) with its 2.3 mm polyhole, 2.5 mm thick, as a closed tube of n-gons
// (4n vertices, 8n triangles). The openscad renders themselves are timed by `fivebar parts`.
//   ./build/fivebar_bench --benchmark_filter='mesh|fit'
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>

#include "fivebar/parts.hpp"

namespace {

fivebar::TriangleMesh boss(int n) {
  fivebar::TriangleMesh m;
  const double c = std::cos(std::numbers::pi / n);
  const double r_out = 2.5, r_in = 1.15 / c;
  for (double z : {0.0, 2.5}) {
    for (double r : {r_out, r_in}) {
      for (int i = 0; i < n; ++i) {
        const double a = 2 * std::numbers::pi * i / n;
        m.vertices.emplace_back(r * std::cos(a), r * std::sin(a), z);
      }
    }
  }
  const auto v = [n](int ring, int i) { return static_cast<std::uint32_t>(ring * n + (i % n)); };
  // Rings: 0 bottom outer, 1 bottom inner, 2 top outer, 3 top inner.
  for (int i = 0; i < n; ++i) {
    const int j = i + 1;
    m.triangles.push_back({v(0, i), v(0, j), v(2, j)});  // outer wall, facing out
    m.triangles.push_back({v(0, i), v(2, j), v(2, i)});
    m.triangles.push_back({v(1, i), v(3, j), v(1, j)});  // inner wall, facing the axis
    m.triangles.push_back({v(1, i), v(3, i), v(3, j)});
    m.triangles.push_back({v(2, i), v(2, j), v(3, j)});  // top, facing +z
    m.triangles.push_back({v(2, i), v(3, j), v(3, i)});
    m.triangles.push_back({v(0, i), v(1, j), v(0, j)});  // bottom, facing -z
    m.triangles.push_back({v(0, i), v(1, i), v(1, j)});
  }
  return m;
}

void mesh_check(benchmark::State& state) {
  const auto mesh = boss(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    const auto c = fivebar::check_mesh(mesh);
    if (!c.passed()) state.SkipWithError("the synthetic boss fails its checks");
    benchmark::DoNotOptimize(c.volume_mm3);
  }
  state.counters["triangles"] = static_cast<double>(mesh.triangles.size());
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(mesh_check)->Arg(24)->Arg(96)->Unit(benchmark::kMillisecond);

void fit_hole(benchmark::State& state) {
  const auto mesh = boss(static_cast<int>(state.range(0)));
  const fivebar::HoleSpec hole{"pin", {0.0, 0.0}, 2.3};
  for (auto _ : state) {
    const auto f = fivebar::fit_circle_wall(mesh, hole);
    if (!f.found) state.SkipWithError("hole not found");
    benchmark::DoNotOptimize(f.center_mm);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(fit_hole)->Arg(24)->Arg(96)->Unit(benchmark::kMicrosecond);

}  // namespace
