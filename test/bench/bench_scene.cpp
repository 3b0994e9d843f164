// Wall time of the showcase scene, `fivebar run designs/iros2022.yaml`, as the library runs it
// (run_scene(): every product of the showcase, independent products side by side on the cores;
// docs/architecture.md). Goal: under 10 s of wall time on a 2-core machine. Arg: the workers (0: one per core,
// 1: one after another). Each product's own time is in the scene's summary.json (built[].wall_s),
// reported here as counters, with the CPU time of the whole process and its children (openscad):
// process_cpu_s. On 2 cores 10 s of wall needs at most about 18 s of CPU.
//   ./build/fivebar_bench --benchmark_filter=scene
#include <benchmark/benchmark.h>

#include <filesystem>
#include <string>
#include <sys/resource.h>
#include <unistd.h>

#include "fivebar/design.hpp"
#include "fivebar/scene.hpp"

namespace {

using namespace fivebar;

/// CPU seconds (user + system) of this process and of its waited-for children so far.
double process_cpu_s() {
  const auto seconds = [](const timeval& t) { return double(t.tv_sec) + 1e-6 * double(t.tv_usec); };
  rusage self{}, children{};
  getrusage(RUSAGE_SELF, &self);
  getrusage(RUSAGE_CHILDREN, &children);
  return seconds(self.ru_utime) + seconds(self.ru_stime) + seconds(children.ru_utime) + seconds(children.ru_stime);
}

void BM_scene_showcase(benchmark::State& state) {
  const Design d = load_design(std::filesystem::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml");
  const std::filesystem::path root =
      std::filesystem::temp_directory_path() / ("fivebar-bench-scene-" + std::to_string(::getpid()));
  SceneOptions o;
  o.out_root = root;
  o.jobs = static_cast<unsigned>(state.range(0));
  SceneReport report;
  const double cpu0 = process_cpu_s();
  for (auto _ : state) report = run_scene(d, o);
  state.counters["process_cpu_s"] = (process_cpu_s() - cpu0) / double(state.iterations());
  for (const ProductOutcome& p : report.products)
    if (p.state == ProductOutcome::State::built) state.counters[p.name + "_s"] = p.wall_s;
  state.counters["ok"] = report.ok() ? 1.0 : 0.0;
  std::filesystem::remove_all(root);
}
BENCHMARK(BM_scene_showcase)->Arg(0)->Arg(1)->Unit(benchmark::kSecond)->UseRealTime()->Iterations(1);

}  // namespace
