// Workspace and coverage speed on the paper's index lower mechanism (issue targets: exact region
// and area < 5 ms; coverage verdict with margin < 20 us without joint limits, < 200 us with).
//   ./build/fivebar_bench --benchmark_filter='region|coverage'
#include <benchmark/benchmark.h>

#include <numbers>

#include "fivebar/coverage/coverage.hpp"
#include "fivebar/workspace/region.hpp"
#include "paper.hpp"

namespace {

using namespace fivebar;

/// The paper's index lower mechanism, with joint limits if `limits`.
Mechanism index_lower(bool limits) {
  Mechanism m = testing::paper_mechanism("index", "lower");
  if (limits) {
    constexpr double d = std::numbers::pi / 180.0;
    m.joint_limits = std::array<JointRange, 2>{JointRange{60 * d, 200 * d}, JointRange{-20 * d, 120 * d}};
  }
  return m;
}

Ellipse index_target() {
  Ellipse e;
  e.center = {6.25, 15.5};
  e.axes = {15.0, 12.0};
  return e;
}

void BM_region_exact_area(benchmark::State& state) {
  const Mechanism m = index_lower(state.range(0) != 0);
  for (auto _ : state) {
    const Region r = reachable_region(m);
    benchmark::DoNotOptimize(r.area_mm2());
  }
  state.SetLabel(state.range(0) ? "joint limits" : "annuli");
}
BENCHMARK(BM_region_exact_area)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_coverage_verdict(benchmark::State& state) {
  const Mechanism m = index_lower(state.range(0) != 0);
  const Ellipse e = index_target();
  bool ok = true;
  for (auto _ : state) {
    const CoverageResult c = coverage(m, e);
    ok = ok && c.covered;
    benchmark::DoNotOptimize(c.margin_mm);
  }
  if (!ok) state.SkipWithError("target not covered: the benchmark would time another path");
  state.SetLabel(state.range(0) ? "joint limits" : "annuli");
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_coverage_verdict)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_coverage_margin_only(benchmark::State& state) {
  const Mechanism m = index_lower(false);
  const Ellipse e = index_target();
  for (auto _ : state) benchmark::DoNotOptimize(annuli_margin(m, e));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_coverage_margin_only)->Unit(benchmark::kMicrosecond);

/// The sweep's per-design verdict: containment with its certified margin bounds.
void BM_containment(benchmark::State& state) {
  const Mechanism m = index_lower(state.range(0) != 0);
  const Ellipse e = index_target();
  bool ok = true;
  for (auto _ : state) {
    const Containment c = containment(m, e);
    ok = ok && c.inside && c.decided;
    benchmark::DoNotOptimize(c.margin_mm);
  }
  if (!ok) state.SkipWithError("target not inside: the benchmark would time another path");
  state.SetLabel(state.range(0) ? "joint limits" : "annuli");
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_containment)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
