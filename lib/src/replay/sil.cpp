// Software in the loop (fivebar/replay/sil.hpp): the runtime closed around the simulator for a
// design's patterns, shared by `fivebar replay --sil` and the `replay` product.

#include "fivebar/replay/sil.hpp"

#include <algorithm>
#include <fstream>

#include "fivebar/error.hpp"

namespace fivebar {

namespace {

std::vector<const Station*> pair_stations(const Design& design, const std::vector<std::string>& names) {
  std::vector<const Station*> out;
  if (names.empty()) {
    for (const Station& s : design.stations)
      if (s.lower && s.upper) out.push_back(&s);
    return out;
  }
  for (const std::string& name : names) {
    const Station* found = design.station(name);
    if (found == nullptr) throw InputError("station '" + name + "' is not in design '" + design.name + "'");
    if (!found->lower || !found->upper) throw InputError("station '" + name + "' does not have both mechanisms");
    out.push_back(found);
  }
  return out;
}

}  // namespace

void check_sil_config(const Design& design, const SilRequest& request, const std::string& origin) {
  if (!request.config) return;
  for (const Station* s : pair_stations(design, request.stations)) {
    const runtime::Config& c = *request.config;
    const auto st = std::find_if(c.stations.begin(), c.stations.end(), [&](const auto& x) { return x.name == s->name; });
    if (st == c.stations.end()) {
      throw InputError(origin + ": the configuration (design '" + c.design + "') has no station '" + s->name +
                       "': export it from this design (fivebar export --format json)");
    }
    for (const char* m : {"lower", "upper"}) {
      if (std::none_of(st->mechanisms.begin(), st->mechanisms.end(), [&](const auto& x) { return x.name == m; })) {
        throw InputError(origin + ": station '" + s->name + "' of the configuration has no " + m + " mechanism");
      }
    }
  }
}

std::vector<SilRun> run_sil(const Design& design, const SilRequest& request) {
  if (!request.open_log) throw std::invalid_argument("run_sil: open_log is required");
  if (request.replay && !request.config) throw std::invalid_argument("run_sil: replay needs the configuration");
  check_sil_config(design, request, "the configuration");  // before the first log is opened
  std::vector<SilRun> runs;
  for (const Station* s : pair_stations(design, request.stations)) {
    SimulationRequest sim;
    sim.station = s->name;
    sim.pattern = request.pattern;
    for (SimulationInput in : simulation_inputs(design, sim, station_inertia(design, *s, nullptr, {}))) {
      SilRun run;
      run.station = s->name;
      run.reference = in.reference_name;
      if (!in.unusable.empty()) {
        run.unusable = in.unusable;
        runs.push_back(std::move(run));
        continue;
      }
      if (request.progress) request.progress(run.station, run.reference);
      if (request.config) {
        in.runtime = request.config;
        in.override_runtime_joints = false;
      }
      AtomicFile file = request.open_log(s->name + "-" + in.reference_name + "-sil.csv");
      bool header = false;
      SimulationOptions so;
      so.controller_log = [&](double t, const std::vector<double>& readings, runtime::Reading kind,
                              const std::vector<double>& targets, const runtime::Controller& ctl) {
        if (!header) write_replay_header(file.stream(), ctl.config(), kind), header = true;
        write_replay_row(file.stream(), t, readings, targets, ctl.duties(), ctl.joint_count());
      };
      run.result = simulate(in, so);
      file.commit();
      run.log = file.path();
      run.figures = to_json(in, run.result);
      if (request.replay) {
        // The log as written, back through a fresh runtime of the same configuration.
        std::ifstream log_in(run.log);
        const ReplayLog log = read_replay_log(log_in, *request.config, run.log.string());
        run.replay = replay_log(*request.config, log, 0.0);
      }
      runs.push_back(std::move(run));
    }
  }
  return runs;
}

Json to_json(const SilRun& run) {
  if (!run.simulated()) {
    return {{"station", run.station}, {"reference", run.reference}, {"status", "not_simulated"}, {"reason", run.unusable}};
  }
  Json j = run.figures;
  if (run.replay) j["replay"] = to_json(*run.replay);
  return j;
}

}  // namespace fivebar
