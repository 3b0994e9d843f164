// The `replay` product: software in the loop with the exported file. Every pattern of every
// station with both tactors is simulated with fivebar::runtime configured from the `export`
// product's JSON exactly as written (its gains, calibration, outlines and limits), as
// `fivebar replay DESIGN --sil --config EXPORTED.json` does; the figures are simulate's. The log
// of each run (replay/<station>-<pattern>-sil.csv, the device's log format, fivebar/replay.hpp) is
// then replayed through a fresh runtime read from the same file: its duties must equal the logged
// ones bit for bit (the field check `fivebar replay LOG --config` makes on a device's log).

#include <filesystem>
#include <memory>
#include <string>

#include "fivebar/dynamics.hpp"
#include "fivebar/format.hpp"
#include "fivebar/io.hpp"
#include "fivebar/replay.hpp"
#include "fivebar/replay/sil.hpp"
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
    const std::string json_file = exported_controller_json(ctx.result_of("export"));
    if (json_file.empty()) {
      b.passed = false;
      b.check = "no exported JSON to run (the export was refused or not built)";
      b.markdown = std::string(kPreamble) + "**Not run**: " + b.check + ".\n";
      b.result = {{"config", nullptr}, {"runs", Json::array()}};
      return b;
    }
    SilRequest request;
    request.config = std::make_shared<const runtime::Config>(runtime::load_config_json((ctx.dir / json_file).string()));
    request.replay = true;
    request.open_log = [&ctx](const std::string& name) { return ctx.open_file(std::filesystem::path("replay") / name); };
    request.progress = [&ctx](const std::string& station, const std::string& reference) {
      ctx.say("software in the loop: " + station + " " + reference);
    };
    md::Table table({"station", "pattern", "status", "mechanism", "max error (mm)", "rms error (mm)", "peak duty",
                     "saturated (s)", "replayed rows", "max |duty difference|"},
                    "llllrrrrrr");
    Json runs = Json::array();
    std::size_t total = 0, failed = 0;
    std::string problems;
    for (const SilRun& run : run_sil(d, request)) {
      ++total;
      Json j = to_json(run);
      if (!run.simulated()) {
        ++failed;
        runs.push_back(j);
        problems += "- ✗ " + run.station + " " + run.reference + ": not simulated, " + run.unusable + "\n";
        continue;
      }
      const SimulationResult& r = run.result;
      const ReplayResult& rr = *run.replay;
      const std::filesystem::path rel = std::filesystem::path("replay") / run.log.filename();
      ctx.record(rel);
      j["log"] = rel.generic_string();
      runs.push_back(j);
      if (!run.ok()) {
        ++failed;
        problems += "- ✗ " + run.station + " " + run.reference + ": " +
                    (r.ok() ? std::to_string(rr.mismatches) + " duties differ from the log's on replay"
                            : std::string(to_string(r.status)) + ", " + r.reason) +
                    "\n";
      }
      for (const MechanismSummary& m : r.summary) {
        table.row({run.station, run.reference, std::string(to_string(r.status)), m.name, md::fixed(m.max_error_mm, 3),
                   md::fixed(m.rms_error_mm, 3), md::fixed(m.peak_duty, 3), md::fixed(m.saturation_s, 3),
                   std::to_string(rr.rows), format::shortest(rr.max_difference)});
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
