// Wall time of the showcase scene, `fivebar run designs/iros2022.yaml`, as the library runs it
// (run_scene(): every product of the showcase, independent products side by side on the cores;
// docs/architecture.md). Goal: under 10 s of wall time on a 2-core machine. Arg: the workers (0: one per core,
// 1: one after another). Each product's own time is in the scene's summary.json (built[].wall_s),
// reported here as counters.
//   ./build/fivebar_bench --benchmark_filter=scene
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>
#include <unistd.h>

#include "fivebar/design.hpp"
#include "fivebar/scene.hpp"

namespace {

using namespace fivebar;

void BM_scene_showcase(benchmark::State& state) {
  const Design d = load_design(std::filesystem::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml");
  const std::filesystem::path root =
      std::filesystem::temp_directory_path() / ("fivebar-bench-scene-" + std::to_string(::getpid()));
  SceneOptions o;
  o.out_root = root;
  o.jobs = static_cast<unsigned>(state.range(0));
  SceneReport report;
  for (auto _ : state) report = run_scene(d, o);
  for (const ProductOutcome& p : report.products)
    if (p.state == ProductOutcome::State::built) state.counters[p.name + "_s"] = p.wall_s;
  state.counters["ok"] = report.ok() ? 1.0 : 0.0;
  std::filesystem::remove_all(root);
}
BENCHMARK(BM_scene_showcase)->Arg(0)->Arg(1)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace
