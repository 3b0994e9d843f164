// Speed of the performance atlas (fivebar/atlas.hpp): designs (cells of the normalised design
// triangle) per second for the paper's index target shape, on one thread and on every core, and
// the figures of one design (the paper's index station). The goal: the default 41-cell grid of a
// station's atlas in a few seconds on this 2-core machine, so that it can be part of a scene.
#include <benchmark/benchmark.h>

#include <cstdint>

#include "fivebar/atlas.hpp"
#include "paper.hpp"

namespace {

/// Arg(0): cells along the chart's base; Arg(1): threads (0: every core).
void BM_atlas_grid(benchmark::State& state) {
  fivebar::AtlasOptions o;
  o.cells = static_cast<int>(state.range(0));
  o.threads = static_cast<int>(state.range(1));
  o.shape = {12.0 / 15.0, 0.0};  // the index target, 15 x 12 mm
  std::size_t designs = 0;
  for (auto _ : state) {
    const fivebar::Atlas a = fivebar::performance_atlas(o);
    designs = a.cells.size() - a.count(fivebar::AtlasStatus::outside);
    benchmark::DoNotOptimize(a.cells.data());
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(designs));
  state.counters["designs"] = static_cast<double>(designs);
}
// Wall time (UseRealTime): the threads' work counts, not the main thread's CPU time.
BENCHMARK(BM_atlas_grid)->Args({15, 1})->Args({41, 1})->Args({41, 0})->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_atlas_paper_station(benchmark::State& state) {
  const fivebar::Mechanism m = fivebar::testing::paper_mechanism("index", "lower");
  for (auto _ : state) {
    const fivebar::InscribedTarget t = fivebar::inscribed_target(m, {12.0 / 15.0, 0.0});
    benchmark::DoNotOptimize(t.scale);
  }
}
BENCHMARK(BM_atlas_paper_station)->Unit(benchmark::kMillisecond);

}  // namespace
