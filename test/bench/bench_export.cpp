// Controller export: the gate on the paper's device (coverage, LCI, joint ranges, calibration and the
// eight patterns), rendering the three documents, and re-reading one for --check.

#include <benchmark/benchmark.h>

#include <filesystem>

#include "fivebar/export/export.hpp"

namespace {

const fivebar::Design& paper() {
  static const fivebar::Design d =
      fivebar::load_design(std::filesystem::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml");
  return d;
}

void BM_export_gate(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(fivebar::export_gate(paper()));
}
BENCHMARK(BM_export_gate)->Unit(benchmark::kMillisecond);

void BM_export_render_all_formats(benchmark::State& state) {
  for (auto _ : state) {
    const fivebar::Json tree = fivebar::controller_parameters(paper(), {});
    for (fivebar::ExportFormat f : fivebar::all_export_formats()) benchmark::DoNotOptimize(fivebar::render(f, tree));
  }
}
BENCHMARK(BM_export_render_all_formats)->Unit(benchmark::kMicrosecond);

void BM_export_check(benchmark::State& state) {
  const auto format = static_cast<fivebar::ExportFormat>(state.range(0));
  const std::string text = fivebar::render(format, fivebar::controller_parameters(paper(), {}));
  for (auto _ : state) benchmark::DoNotOptimize(fivebar::check_export(text, format, paper(), "bench"));
  state.SetLabel(std::string(fivebar::to_string(format)));
}
BENCHMARK(BM_export_check)->DenseRange(0, 2)->Unit(benchmark::kMicrosecond);

}  // namespace
