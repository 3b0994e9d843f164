// fivebar optimize (issue "optimize"): throughput of the cheap evaluation path (goal >= 200,000
// designs/s on this 2-core machine, as the sweep's), and the showcase's eight-variable search of
// the index station against a Sobol sweep of the same budget (hypervolume of both fronts,
// normalised by the union's ideal and nadir, reference 1.1; goal: a stated margin in < 60 s).
//   ./build/fivebar_bench --benchmark_filter=optimize
#include <benchmark/benchmark.h>
#include <omp.h>

#include <chrono>
#include <filesystem>
#include <random>

#include "fivebar/optimize.hpp"
#include "fivebar/sections/optimize.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/sections/sweep.hpp"
#include "fivebar/sweep.hpp"
#include "optimize_study.hpp"

namespace {

using namespace fivebar;
namespace fs = std::filesystem;

Design showcase() { return load_design(fs::path(FIVEBAR_SOURCE_DIR) / "designs/iros2022.yaml"); }

/// Arg 0: the sweep benchmark's problem (L3 and L4 of the index lower mechanism, margin and
/// min_lci); 1: L34 x L12 of both index mechanisms (margin, min_lci, footprint); 2: the showcase's
/// eight variables without the robust constraint; 3: with it (about 1 ms a covering design).
Design problem(int which) {
  Design d = showcase();
  OptimizeSettings s = *d.get<OptimizeSettings>();
  s.atlas = false;  // the search alone (the atlas is its own benchmark, bench_atlas.cpp)
  if (which == 0) {
    OptimizeVariable l3{"L3", {"stations.index.mechanisms.lower.links[2]"}, 10, 20, 0};
    OptimizeVariable l4{"L4", {"stations.index.mechanisms.lower.links[3]"}, 10, 20, 0};
    s.variables = {l3, l4};
    s.objectives = {{"margin", true}, {"min_lci", true}};
    s.constraints.clear();
    // Only the lower mechanism: a station of one mechanism, as the sweep's lower-only problem.
    d.stations[0].upper.reset();
    d.reset<PatternSettings>();
    d.reset<ControllerSettings>();  // its tuned scopes name the upper mechanism
    d.reset<MotorSettings>();
  } else if (which == 1) {
    OptimizeVariable l34{"L34", {}, 12, 19, 0}, l12{"L12", {}, 6, 12, 0};
    for (const char* m : {"lower", "upper"}) {
      for (int i : {2, 3}) l34.keys.push_back(std::string("stations.index.mechanisms.") + m + ".links[" + std::to_string(i) + "]");
      for (int i : {0, 1}) l12.keys.push_back(std::string("stations.index.mechanisms.") + m + ".links[" + std::to_string(i) + "]");
    }
    s.variables = {l34, l12};
    s.objectives = {{"margin", true}, {"min_lci", true}, {"footprint", false}};
    s.constraints.clear();
  } else if (which == 2) {
    s.constraints = {{"min_lci", true, 0.25}};
  }
  d.set(s);
  d.validate();
  return d;
}

void BM_optimize_evaluate(benchmark::State& state) {
  const Design d = problem(int(state.range(0)));
  const OptimizeProblem p(d);
  const std::size_t n = p.dimension();
  constexpr int kBatch = 20000;
  std::vector<double> points(std::size_t(kBatch) * n);
  std::mt19937_64 rng(1);
  for (int k = 0; k < kBatch; ++k) {
    for (std::size_t i = 0; i < n; ++i) {
      points[std::size_t(k) * n + i] = std::uniform_real_distribution<double>(p.lower()[i], p.upper()[i])(rng);
    }
  }
  std::int64_t designs = 0, feasible = 0;
  for (auto _ : state) {
    std::int64_t ok = 0;
#pragma omp parallel for schedule(dynamic, 64) reduction(+ : ok)
    for (int k = 0; k < kBatch; ++k) {
      std::vector<double> x(points.begin() + std::ptrdiff_t(k) * std::ptrdiff_t(n),
                            points.begin() + std::ptrdiff_t(k + 1) * std::ptrdiff_t(n));
      ok += p.evaluate(x).feasible();
    }
    designs += kBatch;
    feasible += ok;
  }
  state.SetItemsProcessed(designs);
  state.counters["feasible_fraction"] = double(feasible) / double(designs);
  state.counters["threads"] = omp_get_max_threads();
}
BENCHMARK(BM_optimize_evaluate)->Arg(0)->Arg(1)->Arg(2)->Arg(3)->Unit(benchmark::kMillisecond)->UseRealTime();

/// The eight-variable search (Arg: 0 without, 1 with the robust constraint) and a Sobol sweep of
/// the same number of candidates.
void BM_optimize_eight_variables_vs_sobol(benchmark::State& state) {
  Design d = problem(state.range(0) ? 3 : 2);
  OptimizeSettings s = *d.get<OptimizeSettings>();
  s.evaluations = std::uint64_t(state.range(1));
  s.seconds = 60;
  d.set(s);
  const OptimizeProblem p(d);
  const fs::path dir = fs::temp_directory_path() / ("fivebar_bench_optimize_" + std::to_string(::getpid()));
  double hv_opt = 0, hv_sobol = 0, seconds = 0;
  std::uint64_t evaluations = 0;
  for (auto _ : state) {
    OptimizeOptions o;
    o.out_dir = dir;
    o.plots = false;
    const auto t0 = std::chrono::steady_clock::now();
    const OptimizeResult r = run_optimize(d, o);
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    evaluations = r.evaluations;
    // The Sobol sweep: the sweep's own sequence (shifted by the seed) over the same box.
    SweepSettings sw;
    sw.sample = "sobol";
    sw.count = r.evaluations;
    sw.seed = 1;
    for (const auto& v : s.variables) sw.vary.push_back({"L1", v.lo, v.hi, 1});
    std::vector<OptimizeCandidate> sobol(r.evaluations);
#pragma omp parallel for schedule(dynamic, 16)
    for (std::int64_t k = 0; k < std::int64_t(r.evaluations); ++k) sobol[std::size_t(k)] = p.evaluate(sweep_point(sw, std::uint64_t(k)));
    const auto sobol_front = optimize_front(p, sobol);
    std::vector<OptimizeCandidate> both = r.front;
    both.insert(both.end(), sobol_front.begin(), sobol_front.end());
    std::vector<double> ideal(s.objectives.size(), 1e300), nadir(s.objectives.size(), -1e300);
    for (const auto& c : both) {
      const auto f = p.fitness(c);
      for (std::size_t i = 0; i < f.size(); ++i) ideal[i] = std::min(ideal[i], f[i]), nadir[i] = std::max(nadir[i], f[i]);
    }
    const std::vector<double> ref(s.objectives.size(), 1.1);
    hv_opt = hypervolume(normalised_objectives(p, r.front, ideal, nadir), ref);
    hv_sobol = hypervolume(normalised_objectives(p, sobol_front, ideal, nadir), ref);
  }
  std::error_code ec;
  fs::remove_all(dir, ec);
  state.counters["evaluations"] = double(evaluations);
  state.counters["search_s"] = seconds;
  state.counters["hv_optimize"] = hv_opt;
  state.counters["hv_sobol"] = hv_sobol;
  state.counters["hv_ratio"] = hv_sobol > 0 ? hv_opt / hv_sobol : 0.0;
}
BENCHMARK(BM_optimize_eight_variables_vs_sobol)
    ->Args({0, 3000})
    ->Args({0, 20000})
    ->Args({1, 3000})
    ->Unit(benchmark::kSecond)
    ->UseRealTime()
    ->Iterations(1);

/// docs/optimize.md "The hybrid algorithm": the default algorithm against pagmo's own NSGA-II, same
/// population, islands, budget and seeds 1 ... 8, on the 2-, 3- and 8-variable problems
/// (test/optimize_study.hpp); mean hypervolume of each run's front, normalised by the union of
/// every front of the study. Goal: hybrid / nsga2 >= 1.05 on each. Prints the per-seed table.
void BM_optimize_hybrid_vs_nsga2(benchmark::State& state) {
  const fs::path dir = fs::temp_directory_path() / ("fivebar_bench_optimize_study_" + std::to_string(::getpid()));
  fivebar::testing::StudyRow r;
  for (auto _ : state) r = fivebar::testing::algorithm_study(int(state.range(0)), 8, dir);
  std::error_code ec;
  fs::remove_all(dir, ec);
  fivebar::testing::print_study_row(r);
  state.counters["hv_hybrid"] = fivebar::testing::StudyRow::mean(r.hybrid);
  state.counters["hv_nsga2"] = fivebar::testing::StudyRow::mean(r.nsga2);
  state.counters["ratio"] = r.ratio();
  state.counters["distinct_fraction_nsga2"] = double(r.distinct_nsga2) / double(r.evaluations_nsga2);
  state.counters["distinct_fraction_hybrid"] = double(r.distinct_hybrid) / double(r.evaluations_hybrid);
}
BENCHMARK(BM_optimize_hybrid_vs_nsga2)->Arg(2)->Arg(3)->Arg(8)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

/// docs/reliability.md: loading a design whose optimize: section ties 13 numbers of each of
/// Arg stations in one variable (1,300 keys for 100). Every key is resolved in one reading of
/// the design (fivebar/design/edit.hpp), so the time grows linearly with the keys (it was
/// quadratic: 29 s for 1,200 keys). Goal: well under a second for 1,300 keys.
void BM_LoadDesignWithManyOptimizeKeys(benchmark::State& state) {
  const int stations = int(state.range(0));
  std::string text = "name: many\nstations:\n", keys;
  for (int s = 0; s < stations; ++s) {
    const std::string n = "s" + std::to_string(s), p = "stations." + n + ".";
    text += "  " + n + ":\n    target: {center: [6.25, 15.5], axes: [15, 12], angle: 0}\n    mechanisms:\n"
            "      lower: {bases: [[0, 0], [12.5, 0]], links: [15, 15, 15, 15], working_mode: \"-+\", assembly_mode: \"+\"}\n";
    const auto q = [](const std::string& k) { return "\"" + k + "\", "; };  // quoted: [ ] are flow indicators
    for (int i = 0; i < 4; ++i) keys += q(p + "mechanisms.lower.links[" + std::to_string(i) + "]");
    for (int i = 0; i < 4; ++i) keys += q(p + "mechanisms.lower.bases[" + std::to_string(i / 2) + "][" + std::to_string(i % 2) + "]");
    for (int i = 0; i < 2; ++i) keys += q(p + "target.center[" + std::to_string(i) + "]") + q(p + "target.axes[" + std::to_string(i) + "]");
    keys += q(p + "target.angle");
  }
  keys.resize(keys.size() - 2);
  text += "optimize:\n  variables:\n    all: {keys: [" + keys + "], range: [12, 18]}\n  objectives: [margin]\n";
  for (auto _ : state) benchmark::DoNotOptimize(load_design_from_string(text, "many.yaml"));
  state.counters["keys"] = 13.0 * stations;
  state.SetComplexityN(stations);
}
BENCHMARK(BM_LoadDesignWithManyOptimizeKeys)->Arg(25)->Arg(50)->Arg(100)->Unit(benchmark::kMillisecond)->Complexity();

}  // namespace
