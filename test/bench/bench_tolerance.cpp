// Speed of the tolerance studies (fivebar/tolerance.hpp), with the goals of the tolerance work
// (docs/architecture.md lists the benchmarks): first-order figures at 10,000 poses of one
// mechanism under 20 ms, and the Monte Carlo reference of 100,000 printed devices at 1,000 poses
// under 10 s on this 2-core machine.
#include <benchmark/benchmark.h>

#include <vector>

#include "fivebar/tolerance.hpp"
#include "paper.hpp"

namespace {

using fivebar::Vec2;

/// n x n poses over the index target's bounding box (15 x 12 mm about (6.25, 15.5)).
std::vector<Vec2> target_grid(int n) {
  std::vector<Vec2> out;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) out.emplace_back(-1.25 + 15.0 * i / (n - 1), 9.5 + 12.0 * j / (n - 1));
  return out;
}

fivebar::ParameterSigmas showcase_sigmas() {
  fivebar::ParameterSigmas s{};
  for (int j = 0; j < 4; ++j) s[static_cast<std::size_t>(j)] = 0.0612;
  for (int j = 4; j < 8; ++j) s[static_cast<std::size_t>(j)] = 0.1;
  s[8] = s[9] = 0.0115;
  return s;
}

void BM_tolerance_first_order_10k_poses(benchmark::State& state) {
  const fivebar::Mechanism m = fivebar::testing::paper_mechanism("index", "lower");
  const auto points = target_grid(100);
  const auto sigma = showcase_sigmas();
  for (auto _ : state) {
    double sum = 0.0;
    for (const Vec2& p : points) sum += fivebar::tolerance_first_order(m, p, sigma, 3.2e-4).worst_case_mm;
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(points.size()));
}
BENCHMARK(BM_tolerance_first_order_10k_poses)->Unit(benchmark::kMillisecond);

void BM_tolerance_play_10k_poses(benchmark::State& state) {
  const fivebar::Mechanism m = fivebar::testing::paper_mechanism("index", "lower");
  const auto points = target_grid(100);
  for (auto _ : state) {
    double sum = 0.0;
    for (const Vec2& p : points) sum += fivebar::tolerance_play(m, p, {0.25, 0.4}).extent_mm;
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(points.size()));
}
BENCHMARK(BM_tolerance_play_10k_poses)->Unit(benchmark::kMillisecond);

/// devices x poses FK evaluations of printed devices; Arg(0) = devices, Arg(1) = poses per side.
void BM_tolerance_monte_carlo(benchmark::State& state) {
  const fivebar::Mechanism m = fivebar::testing::paper_mechanism("index", "lower");
  const auto points = target_grid(static_cast<int>(state.range(1)));
  const auto sigma = showcase_sigmas();
  const auto devices = static_cast<std::size_t>(state.range(0));
  for (auto _ : state) {
    const auto r = fivebar::tolerance_monte_carlo(m, points, sigma, devices, 1);
    benchmark::DoNotOptimize(r.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(points.size() * devices));
}
BENCHMARK(BM_tolerance_monte_carlo)->Args({1000, 10})->Unit(benchmark::kMillisecond);
// The goal's size (100,000 devices at 1,000 poses: 32 x 32 = 1,024); left out of the smoke run.
BENCHMARK(BM_tolerance_monte_carlo)->Name("BM_tolerance_monte_carlo_full")->Args({100000, 32})->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
