// Speed of the loop's stability map (fivebar/control.hpp) on the paper's device
// (designs/iros2022.yaml, masses from the closed form): 1,000 poses of each mechanism's target
// (ik, linearised plant, ZOH by the matrix exponential, 12-state closed loop, its eigenvalues),
// without and with the kp/kd margin bisections. Goal: the map of 1,000 poses per mechanism in
// under 50 ms. And the tuning of the whole device as the `control` product runs it (controller.tune
// of the showcase: pole placement start, COBYLA, 60 evaluations per mechanism, 4 mechanisms, every
// pattern simulated per evaluation). Goal: under 30 s.
//   ./build/fivebar_bench --benchmark_filter='control'
#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "fivebar/control.hpp"

namespace {

using namespace fivebar;

const Design& design() {
  static const Design d = load_design(std::filesystem::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml");
  return d;
}

/// About 1,000 points of the index target (a 37 x 37 grid over its box).
std::vector<Vec2> points() { return ellipse_lattice(design().require_station("index").target, 37); }

void BM_control_stability_map_1000(benchmark::State& state) {
  const Design& d = design();
  const Station& s = d.require_station("index");
  const std::vector<LoopModel> loops = loop_models(d, s, station_inertia(d, s, nullptr, {}));
  const std::vector<Vec2> pts = points();
  StabilityOptions o;
  o.margins = state.range(0) != 0;
  double rho = 0.0;
  for (auto _ : state) {
    const StabilityMap m = stability_map(loops.front(), pts, o);
    rho = m.max_rho;
    benchmark::DoNotOptimize(rho);
  }
  state.counters["poses"] = double(pts.size());
}
BENCHMARK(BM_control_stability_map_1000)->Arg(0)->Arg(1)->ArgName("margins")->Unit(benchmark::kMillisecond);

void BM_control_tune_paper_device(benchmark::State& state) {
  const Design& d = design();
  std::vector<const Station*> stations;
  std::map<std::string, std::map<std::string, MechanismInertia>> inertia;
  for (const Station& s : d.stations) {
    stations.push_back(&s);
    inertia[s.name] = station_inertia(d, s, nullptr, {});
  }
  TuneOptions o = tune_options(*d.get<ControllerSettings>());
  o.max_seconds = 600.0;  // measure the work, not the bound
  int evaluations = 0;
  for (auto _ : state) {
    const TuneResult r = tune_controller(d, stations, inertia, o);
    evaluations = 0;
    for (const TunedMechanism& t : r.mechanisms) evaluations += t.evaluations;
    benchmark::DoNotOptimize(evaluations);
  }
  state.counters["evaluations"] = double(evaluations);
}
BENCHMARK(BM_control_tune_paper_device)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
