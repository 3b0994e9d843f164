// What `fivebar workspace` spends per station of the paper's device (index, default spacing
// 0.2 mm): the analysis (exact regions, fields, restricted areas, shared region) and each output
// document. No speed goal is set for these; they show where the time goes:
//   ./build/fivebar_bench --benchmark_filter='Workspace'
#include <benchmark/benchmark.h>

#include <filesystem>

#include "fivebar/design.hpp"
#include "fivebar/workspace/station.hpp"
#include "fivebar/workspace/files.hpp"
#include "fivebar/workspace/io.hpp"
#include "fivebar/workspace/plot.hpp"

namespace {

const fivebar::Station& index_station() {
  static const fivebar::Design d =
      fivebar::load_design(std::filesystem::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml");
  return *d.station("index");
}

const fivebar::StationWorkspace& analysed() {
  static const fivebar::StationWorkspace ws = fivebar::analyse_workspace(index_station());
  return ws;
}

void BM_WorkspaceAnalyseStation(benchmark::State& state) {
  fivebar::WorkspaceOptions o;
  o.spacing_mm = double(state.range(0)) / 100.0;
  for (auto _ : state) benchmark::DoNotOptimize(fivebar::analyse_workspace(index_station(), o));
  state.SetLabel("spacing " + std::to_string(o.spacing_mm).substr(0, 4) + " mm, both mechanisms");
}
BENCHMARK(BM_WorkspaceAnalyseStation)->Arg(20)->Arg(50)->Unit(benchmark::kMillisecond);

void BM_WorkspaceRegionsVtp(benchmark::State& state) {
  const auto& ws = analysed();
  for (auto _ : state) benchmark::DoNotOptimize(fivebar::regions_vtp(ws));
}
BENCHMARK(BM_WorkspaceRegionsVtp)->Unit(benchmark::kMillisecond);

void BM_WorkspaceFieldVti(benchmark::State& state) {
  const auto& ws = analysed();
  for (auto _ : state) benchmark::DoNotOptimize(fivebar::field_vti(ws.mechanisms[0].field));
}
BENCHMARK(BM_WorkspaceFieldVti)->Unit(benchmark::kMillisecond);

void BM_WorkspacePicturePng(benchmark::State& state) {
  const auto& ws = analysed();
  for (auto _ : state) benchmark::DoNotOptimize(fivebar::station_png(ws));
}
BENCHMARK(BM_WorkspacePicturePng)->Unit(benchmark::kMillisecond);

void BM_WorkspacePictureSvg(benchmark::State& state) {
  const auto& ws = analysed();
  for (auto _ : state) benchmark::DoNotOptimize(fivebar::station_svg(ws));
}
BENCHMARK(BM_WorkspacePictureSvg)->Unit(benchmark::kMillisecond);

}  // namespace
