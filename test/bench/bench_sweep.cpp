// Sweep throughput (issue target: >= 200,000 designs/s on this 2-core machine for L3 x L4 grids of
// the paper's index lower mechanism without joint limits; >= 20,000 designs/s with joint limits
// and the shared region). Items per second = designs per second, over all threads. Arg 2 adds the
// collision fraction (2 mm grid), which the design's geometry: section turns on by default; the
// targets above are for the coverage metrics, so Args 0 and 1 switch it off.
//   ./build/fivebar_bench --benchmark_filter=sweep
#include <benchmark/benchmark.h>
#include <omp.h>

#include <filesystem>
#include <numbers>

#include "fivebar/sections/sweep.hpp"
#include "fivebar/sweep.hpp"

namespace {

using namespace fivebar;

Design design(bool limits_and_shared, bool collision = false) {
  Design d = load_design(std::filesystem::path(FIVEBAR_SOURCE_DIR) / "designs/iros2022.yaml");
  SweepSettings s;
  s.station = "index";
  if (!limits_and_shared) s.mechanism = "lower";
  s.vary = {{"L3", 10, 20, 300}, {"L4", 10, 20, 300}};
  s.collision_spacing_mm = collision ? 2.0 : 0.0;
  if (limits_and_shared) {
    constexpr double r = std::numbers::pi / 180;
    for (Station& st : d.stations) {
      if (st.name != "index") continue;
      st.lower->joint_limits = std::array<JointRange, 2>{JointRange{40 * r, 200 * r}, JointRange{-20 * r, 140 * r}};
      st.upper->joint_limits = std::array<JointRange, 2>{JointRange{160 * r, 320 * r}, JointRange{-140 * r, 20 * r}};
    }
  }
  d.set<SweepSettings>(s);
  d.validate();
  return d;
}

/// The whole pipeline as `fivebar sweep` runs it: evaluation on every core, CSV streaming, Pareto.
void BM_sweep_grid(benchmark::State& state) {
  const Design d = design(state.range(0) != 0, state.range(0) == 2);
  const auto dir = std::filesystem::temp_directory_path() / "fivebar_bench_sweep";
  SweepOptions o;
  o.out_dir = dir;
  o.plots = false;
  std::uint64_t designs = 0;
  double covered = 0;
  for (auto _ : state) {
    const SweepResult r = run_sweep(d, o);
    designs += r.evaluated;
    covered = double(r.covered) / double(r.evaluated);
  }
  std::filesystem::remove_all(dir);
  state.SetItemsProcessed(std::int64_t(designs));
  state.counters["covered_fraction"] = covered;
  state.counters["threads"] = omp_get_max_threads();
  state.SetLabel(state.range(0) == 0   ? "index lower, no limits"
                 : state.range(0) == 1 ? "index, joint limits, both mechanisms + shared"
                                       : "index, joint limits, shared + collision fraction (2 mm grid)");
}
BENCHMARK(BM_sweep_grid)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

/// One design evaluated on one core (no I/O): the cost of a covered and of a rejected design.
void BM_sweep_evaluate_one(benchmark::State& state) {
  const Design d = design(false);
  // Index 45150 is L3 = L4 = 15.0 (the paper's design, covered); index 0 is L3 = L4 = 10 (rejected).
  const std::uint64_t index = state.range(0) ? 0 : 150 * 300 + 150;
  bool covered = false;
  for (auto _ : state) {
    const SweepRow r = evaluate_sweep_design(d, *d.get<SweepSettings>(), index);
    covered = r.covered;
    benchmark::DoNotOptimize(r.margin_lower_mm);
  }
  state.SetItemsProcessed(state.iterations());
  state.SetLabel(covered ? "covered design" : "rejected design (early exit)");
}
BENCHMARK(BM_sweep_evaluate_one)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
