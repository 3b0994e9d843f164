// Speed of the studio's answer to one drag (fivebar/studio.hpp, docs/studio.md "Speed"): the edited
// file text loaded with every rule (as the server does for each request), then the live figures of
// the paper's index station (exact regions, coverage of `fivebar coverage`, poses, outlines and the
// priority rule), each iteration with another link length so that nothing is reused; and the
// sampled figures (collision map, LCI field) that follow when the drag stops. The page's own
// figure, from a drag event to the redrawn figures, is measured in the browser by
// test/studio_browser.py (p95 <= 50 ms).
//   ./build/fivebar_bench --benchmark_filter=studio
#include <benchmark/benchmark.h>

#include <filesystem>

#include "fivebar/studio.hpp"

namespace {

using namespace fivebar;

const Studio& studio() {
  static const Studio s(std::filesystem::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml");
  return s;
}

void studio_answer(benchmark::State& state, StudioFigures which) {
  int k = 0;
  for (auto _ : state) {
    const double l3 = 14.5 + 0.01 * double(k++ % 100);  // a drag of the distal link, 14.5 to 15.5 mm
    const Design d = studio().design({{"stations.index.mechanisms.lower.links[2]", l3},
                                      {"stations.index.mechanisms.lower.bases[1][0]", 12.5 + 0.2 * (l3 - 15.0)}});
    benchmark::DoNotOptimize(studio_figures(d, "index", {}, which));
  }
  state.SetLabel("one request: load the edited file + figures");
}

void BM_studio_live_figures(benchmark::State& state) { studio_answer(state, StudioFigures::live); }
void BM_studio_full_figures(benchmark::State& state) { studio_answer(state, StudioFigures::full); }
BENCHMARK(BM_studio_live_figures)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_studio_full_figures)->Unit(benchmark::kMillisecond);

}  // namespace
