// The `replay` product: software in the loop with the exported file. Every pattern of every
// station with both tactors is simulated with fivebar::runtime configured from the `export`
// product's JSON exactly as written (its gains, calibration, outlines and limits), as
// `fivebar replay DESIGN --sil --config EXPORTED.json` does; the figures are simulate's. The log
// of each run (replay/<station>-<pattern>-sil.csv, the device's log format, fivebar/replay.hpp) is
// then replayed through a fresh runtime read from the same file: its duties must equal the logged
// ones bit for bit (the field check `fivebar replay LOG --config` makes on a device's log).

#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "fivebar/dynamics.hpp"
#include "fivebar/format.hpp"
#include "fivebar/io.hpp"
#include "fivebar/replay.hpp"
#include "fivebar/runtime/json_config.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {

namespace {

constexpr const char* kPreamble =
    "The exported controller file run as the device runs it, closed around the simulator (software in the loop): "
    "each station's patterns simulated with `fivebar::runtime` configured from the export's JSON exactly as written "
    "(docs/runtime.md), the links' closed-form masses, the motors, driver, ADC and skin of `simulate`. Each run's log "
    "(`replay/<station>-<pattern>-sil.csv`: ADC codes, reference points, duties per cycle) is replayed through a fresh "
    "runtime read from the same file; its duties must match the logged ones bit for bit.\n\n";

}  // namespace

Product replay_product() {
  Product p;
  p.name = "replay";
  p.title = "Software in the loop with the exported file";
  p.prerequisites = {"export"};
  p.unavailable = [](const Design& d) -> std::optional<std::string> {
    if (!d.get<MotorSettings>()) return "the design has no `motor:` section (the motors' data)";
    if (!d.get<ControllerSettings>()) return "the design has no `controller:` section (the exported controller)";
    return without_pairs(d, "the exported collision outlines");
  };
  p.build = [](Context& ctx) {
    const Design& d = ctx.design;
    Built b;
    std::string json_file;
    if (const Json* e = ctx.result_of("export"); e && e->contains("files")) {
      for (const Json& f : (*e)["files"]) {
        const std::string s = f.get<std::string>();
        if (s.size() > 16 && s.compare(s.size() - 16, 16, "_controller.json") == 0) json_file = s;
      }
    }
    if (json_file.empty()) {
      b.passed = false;
      b.check = "no exported JSON to run (the export was refused or not built)";
      b.markdown = std::string(kPreamble) + "**Not run**: " + b.check + ".\n";
      b.result = {{"config", nullptr}, {"runs", Json::array()}};
      return b;
    }
    const auto config = std::make_shared<const runtime::Config>(runtime::load_config_json((ctx.dir / json_file).string()));
    md::Table table({"station", "pattern", "status", "mechanism", "max error (mm)", "rms error (mm)", "peak duty",
                     "saturated (s)", "replayed rows", "max |duty difference|"},
                    "llllrrrrrr");
    Json runs = Json::array();
    std::size_t total = 0, failed = 0;
    std::string problems;
    for (const Station& s : d.stations) {
      if (!has_pair(s)) continue;
      SimulationRequest request;
      request.station = s.name;
      for (SimulationInput in : simulation_inputs(d, request, station_inertia(d, s, nullptr, {}))) {
        ++total;
        if (!in.unusable.empty()) {
          ++failed;
          runs.push_back({{"station", s.name}, {"reference", in.reference_name}, {"status", "not_simulated"},
                          {"reason", in.unusable}});
          problems += "- ✗ " + s.name + " " + in.reference_name + ": not simulated, " + in.unusable + "\n";
          continue;
        }
        ctx.say("software in the loop: " + s.name + " " + in.reference_name);
        in.runtime = config;
        in.override_runtime_joints = false;
        const std::filesystem::path rel = std::filesystem::path("replay") / (s.name + "-" + in.reference_name + "-sil.csv");
        AtomicFile file = ctx.open_file(rel);
        bool header = false;
        SimulationOptions so;
        so.controller_log = [&](double t, const std::vector<double>& readings, runtime::Reading kind,
                                const std::vector<double>& targets, const runtime::Controller& ctl) {
          if (!header) write_replay_header(file.stream(), ctl.config(), kind), header = true;
          write_replay_row(file.stream(), t, readings, targets, ctl.duties(), ctl.joint_count());
        };
        const SimulationResult r = simulate(in, so);
        file.commit();
        ctx.record(rel);
        // The log back through a fresh runtime of the same file.
        std::ifstream log_in(ctx.dir / rel);
        const ReplayLog log = read_replay_log(log_in, *config, (ctx.dir / rel).string());
        const ReplayResult rr = replay_log(*config, log, 0.0);
        Json j = to_json(in, r);
        j["log"] = rel.generic_string();
        j["replay"] = to_json(rr);
        runs.push_back(j);
        const bool ok = r.ok() && rr.passed();
        if (!ok) {
          ++failed;
          problems += "- ✗ " + s.name + " " + in.reference_name + ": " +
                      (r.ok() ? std::to_string(rr.mismatches) + " duties differ from the log's on replay"
                              : std::string(to_string(r.status)) + ", " + r.reason) +
                      "\n";
        }
        for (const MechanismSummary& m : r.summary) {
          table.row({s.name, in.reference_name, std::string(to_string(r.status)), m.name, md::fixed(m.max_error_mm, 3),
                     md::fixed(m.rms_error_mm, 3), md::fixed(m.peak_duty, 3), md::fixed(m.saturation_s, 3),
                     std::to_string(rr.rows), format::shortest(rr.max_difference)});
        }
      }
    }
    b.result = {{"config", json_file}, {"runs", runs}};
    b.markdown = std::string(kPreamble) + "Configuration: [" + md::code(json_file) + "](" + json_file + ").\n\n" +
                 table.str() + "\n" + problems;
    b.passed = failed == 0;
    b.check = b.passed ? std::to_string(total) + " runs through the exported file, every log replayed bit for bit"
                       : std::to_string(failed) + " of " + std::to_string(total) + " runs failed or did not replay";
    return b;
  };
  return p;
}

}  // namespace fivebar::products
