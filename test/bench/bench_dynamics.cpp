// Speed of the dynamics (fivebar/dynamics.hpp) on the paper's device (designs/iros2022.yaml), rtol
// 1e-6, masses from the closed form: the eight patterns of the two stations (both mechanisms of a
// station together) with the averaged and with the switched PWM (CVODE BDF), and a 1 mm step per
// simulated second for CVODE BDF and ARKODE ERK as the motor inductance shrinks (stiffness ratio
// T_loop R / L = 1e2, 1e3, 1e4).
//   ./build/fivebar_bench --benchmark_filter='simulate'
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <vector>

#include "fivebar/dynamics.hpp"

namespace {

using namespace fivebar;

const Design& design() {
  static const Design d = load_design(std::filesystem::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml");
  return d;
}

std::vector<SimulationInput> inputs(bool step) {
  const Design& d = design();
  std::vector<SimulationInput> out;
  for (const Station& s : d.stations) {
    const auto inertia = station_inertia(d, s, nullptr, {});
    SimulationRequest request;
    request.station = s.name;
    request.step = step;
    for (SimulationInput& in : simulation_inputs(d, request, inertia)) out.push_back(std::move(in));
  }
  return out;
}

void BM_simulate_paper_patterns(benchmark::State& state) {
  const std::vector<SimulationInput> all = inputs(false);
  SimulationOptions o;
  o.record = false;
  std::size_t steps = 0;
  for (auto _ : state) {
    for (const SimulationInput& in : all) {
      const SimulationResult r = simulate(in, o);
      if (!r.ok()) state.SkipWithError(r.reason.c_str());
      steps += r.steps;
    }
  }
  state.counters["patterns"] = double(all.size());
  state.counters["steps"] = benchmark::Counter(double(steps), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_simulate_paper_patterns)->Unit(benchmark::kMillisecond);

/// The same eight patterns with the switched 1 kHz PWM (every edge a restart).
void BM_simulate_paper_patterns_switched(benchmark::State& state) {
  const std::vector<SimulationInput> all = inputs(false);
  SimulationOptions o;
  o.record = false;
  o.pwm = PwmModel::switched;
  std::size_t steps = 0;
  for (auto _ : state) {
    for (const SimulationInput& in : all) {
      const SimulationResult r = simulate(in, o);
      if (!r.ok()) state.SkipWithError(r.reason.c_str());
      steps += r.steps;
    }
  }
  state.counters["patterns"] = double(all.size());
  state.counters["steps"] = benchmark::Counter(double(steps), benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_simulate_paper_patterns_switched)->Unit(benchmark::kMillisecond);

/// A 1 mm step on the index station, 1 s simulated; the first argument divides the motors'
/// inductance (0.5 mH) by 10^arg: electrical time constant 100 us, 10 us, 1 us (stiffness ratio
/// T_loop R / L = 1e2, 1e3, 1e4); the second picks the integrator (0 CVODE BDF, 1 ARKODE ERK).
void BM_simulate_step_per_second(benchmark::State& state) {
  SimulationInput in = inputs(true).front();
  const double scale = std::pow(10.0, -double(state.range(0)));
  for (SimulatedMechanism& m : in.mechanisms)
    for (MotorParams& mp : m.model.motors) mp.inductance_mH *= scale;
  SimulationOptions o;
  o.record = false;
  o.duration_s = 1.0;
  o.integrator = state.range(1) == 0 ? Integrator::bdf : Integrator::erk;
  std::size_t steps = 0;
  for (auto _ : state) {
    const SimulationResult r = simulate(in, o);
    if (!r.ok()) state.SkipWithError(r.reason.c_str());
    steps += r.steps;
  }
  state.counters["steps"] = benchmark::Counter(double(steps), benchmark::Counter::kAvgIterations);
  state.counters["L_over_R_us"] = in.mechanisms[0].model.motors[0].inductance() / in.mechanisms[0].model.motors[0].resistance() * 1e6;
}
BENCHMARK(BM_simulate_step_per_second)
    ->ArgsProduct({{0, 1, 2}, {0, 1}})
    ->ArgNames({"L_div_log10", "erk"})
    ->Unit(benchmark::kMillisecond);

}  // namespace
