// Speed of the studio's answer to one drag (fivebar/studio.hpp, docs/studio.md "Speed"): the edits
// set in the design (as the server does for each request), then the live figures of the paper's
// index station (exact regions, coverage of `fivebar coverage`, poses, outlines and the priority
// rule), each iteration with another link length; the same request as first written (the edited
// file loaded, nothing cached); the sampled figures (collision map, LCI field) that follow when
// the drag stops; and each stage of a request alone. The page's own
// figure, from a drag event to the redrawn figures, is measured in the browser by
// test/studio_browser.py (p95 <= 50 ms).
//   ./build/fivebar_bench --benchmark_filter=studio
#include <benchmark/benchmark.h>

#include <filesystem>
#include <vector>

#include "fivebar/collision.hpp"
#include "fivebar/coverage/coverage.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/studio.hpp"
#include "fivebar/workspace/region.hpp"

namespace {

using namespace fivebar;

const Studio& studio() {
  static const Studio s(std::filesystem::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml");
  return s;
}

/// One request as the server answers it: the edits set in the design read once (live_design), the
/// figures through the server's cache; each iteration with another link length and base (a drag
/// of the lower mechanism: its figures are recomputed, the upper's come from the cache).
void studio_answer(benchmark::State& state, StudioFigures which) {
  StudioCache cache;
  int k = 0;
  for (auto _ : state) {
    const double l3 = 14.5 + 0.01 * double(k++ % 100);  // a drag of the distal link, 14.5 to 15.5 mm
    const Design d = studio().live_design({{"stations.index.mechanisms.lower.links[2]", l3},
                                           {"stations.index.mechanisms.lower.bases[1][0]", 12.5 + 0.2 * (l3 - 15.0)}});
    benchmark::DoNotOptimize(studio_figures(d, "index", {}, which, &cache));
  }
  state.SetLabel("one request: the edits set, then the figures");
}

/// The same request the way the first studio answered it (the edited file loaded, no cache).
void BM_studio_live_figures_loaded(benchmark::State& state) {
  int k = 0;
  for (auto _ : state) {
    const double l3 = 14.5 + 0.01 * double(k++ % 100);
    const Design d = studio().design({{"stations.index.mechanisms.lower.links[2]", l3},
                                      {"stations.index.mechanisms.lower.bases[1][0]", 12.5 + 0.2 * (l3 - 15.0)}});
    benchmark::DoNotOptimize(studio_figures(d, "index", {}, StudioFigures::live));
  }
  state.SetLabel("one request: load the edited file + figures, no cache");
}

void BM_studio_live_figures(benchmark::State& state) { studio_answer(state, StudioFigures::live); }
void BM_studio_full_figures(benchmark::State& state) { studio_answer(state, StudioFigures::full); }
/// The first part of a drag's answer as the page asks for it now (the live figures but the priority
/// rule, which follows in a second request: BM_studio_stage_priority).
void BM_studio_quick_figures(benchmark::State& state) { studio_answer(state, StudioFigures::quick); }
BENCHMARK(BM_studio_live_figures)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_studio_quick_figures)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_studio_live_figures_loaded)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_studio_full_figures)->Unit(benchmark::kMillisecond);

// The stages of one live request, each alone (the split quoted in docs/studio.md "Speed").
std::vector<FileEdit> drag_edits(int k) {
  const double l3 = 14.5 + 0.01 * double(k % 100);
  return {{"stations.index.mechanisms.lower.links[2]", l3}, {"stations.index.mechanisms.lower.bases[1][0]", 12.5 + 0.2 * (l3 - 15.0)}};
}

void BM_studio_stage_load(benchmark::State& state) {
  int k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(studio().design(drag_edits(k++)).stations.size());
}
BENCHMARK(BM_studio_stage_load)->Unit(benchmark::kMillisecond);

void BM_studio_stage_live_design(benchmark::State& state) {
  int k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(studio().live_design(drag_edits(k++)).stations.size());
}
BENCHMARK(BM_studio_stage_live_design)->Unit(benchmark::kMicrosecond);

void BM_studio_stage_regions(benchmark::State& state) {
  std::vector<Design> designs;
  for (int k = 0; k < 100; ++k) designs.push_back(studio().design(drag_edits(k)));
  int k = 0;
  for (auto _ : state) {
    const Station& s = *designs[std::size_t(k++ % 100)].station("index");
    benchmark::DoNotOptimize(reachable_region(*s.lower).intersection(reachable_region(*s.upper)).area_mm2());
  }
}
BENCHMARK(BM_studio_stage_regions)->Unit(benchmark::kMillisecond);

void BM_studio_stage_coverage(benchmark::State& state) {
  std::vector<Design> designs;
  for (int k = 0; k < 100; ++k) designs.push_back(studio().design(drag_edits(k)));
  int k = 0;
  for (auto _ : state) benchmark::DoNotOptimize(station_coverage(*designs[std::size_t(k++ % 100)].station("index")).covered());
}
BENCHMARK(BM_studio_stage_coverage)->Unit(benchmark::kMillisecond);

void BM_studio_stage_priority(benchmark::State& state) {
  std::vector<Design> designs;
  for (int k = 0; k < 100; ++k) designs.push_back(studio().design(drag_edits(k)));
  int k = 0;
  for (auto _ : state) {
    const Design& d = designs[std::size_t(k++ % 100)];
    const Station& s = *d.station("index");
    benchmark::DoNotOptimize(apply_priority(*s.upper, *s.lower, *d.get<Geometry>(), s.target.center, s.target.center).moved_mm);
  }
}
BENCHMARK(BM_studio_stage_priority)->Unit(benchmark::kMillisecond);

}  // namespace
