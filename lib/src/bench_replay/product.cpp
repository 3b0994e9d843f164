// The `bench_replay` product: the device's logs that `bench.replay_logs` names (the CSV of
// `fivebar replay LOG`, fivebar/replay.hpp), each fed through a fresh fivebar::runtime configured
// from the `export` product's JSON exactly as written, its duties compared with the logged ones
// within `bench.replay_tolerance`: per log, whether the device runs this configuration (the field
// check of `fivebar replay LOG --config EXPORTED.json`, the same functions). Writes
// bench_replay/bench_replay.csv (per log and joint) and bench_replay/<log>-duties.csv (per cycle).

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "csv.hpp"
#include "fivebar/csv_reader.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/replay.hpp"
#include "fivebar/runtime/json_config.hpp"
#include "fivebar/sections/bench.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {

namespace {

std::string key_of(std::size_t k) { return "bench.replay_logs[" + std::to_string(k) + "]"; }

}  // namespace

Product bench_replay_product() {
  Product p;
  p.name = "bench_replay";
  p.title = "The device's logs through the exported runtime";
  p.prerequisites = {"export"};
  p.cost_s = 0.05;
  p.unavailable = [](const Design& d) -> std::optional<std::string> {
    const BenchSettings* b = d.get<BenchSettings>();
    if (b == nullptr || b->replay_logs.empty()) return "the design names no device log (`bench.replay_logs`)";
    // A design copied away from its bench files still runs its other products.
    for (std::size_t k = 0; k < b->replay_logs.size(); ++k) {
      if (const auto file = BenchSettings::resolve(d, b->replay_logs[k]); !std::filesystem::exists(file)) {
        return "the device log `" + b->replay_logs[k] + "` (`" + key_of(k) + "`) is not there: " + file.generic_string();
      }
    }
    return std::nullopt;
  };
  p.check_inputs = [](const Design& d) {
    // The header of each log, through the bench's one reader (the rows need the export's configuration).
    const BenchSettings& bench = *d.get<BenchSettings>();
    for (std::size_t k = 0; k < bench.replay_logs.size(); ++k) {
      BenchSettings::require_inside(d, "replay_logs[" + std::to_string(k) + "]", bench.replay_logs[k]);
      const std::filesystem::path file = BenchSettings::resolve(d, bench.replay_logs[k]);
      std::ifstream in(file, std::ios::binary);
      if (!in) throw InputError(file.generic_string() + ": cannot be read (" + key_of(k) + ")");
      (void)csv::Reader(in, file.generic_string());
    }
  };
  p.build = [](Context& ctx) {
    const Design& d = ctx.design;
    const BenchSettings& bench = *d.get<BenchSettings>();
    const double tolerance = bench.replay_tolerance;
    const std::string preamble =
        "Each device log that `bench.replay_logs` names (the log of `fivebar replay LOG`, docs/runtime.md \"Replay\") fed "
        "through a fresh `fivebar::runtime` configured from the export's JSON exactly as written, its duties compared "
        "with the logged ones (tolerance " + format::shortest(tolerance) + ", `bench.replay_tolerance`): whether the "
        "device runs this configuration and this loop, as `fivebar replay LOG --config EXPORTED.json` reports it.\n\n";
    Built b;
    const std::string json_file = exported_controller_json(ctx.result_of("export"));
    if (json_file.empty()) {
      b.passed = false;
      b.check = "no exported JSON to replay the logs against (the export was refused or not built)";
      b.markdown = preamble + "**Not run**: " + b.check + ".\n";
      b.result = {{"config", nullptr}, {"tolerance", tolerance}, {"logs", Json::array()}};
      return b;
    }
    const runtime::Config config = runtime::load_config_json((ctx.dir / json_file).string());
    md::Table table({"log", "verdict", "cycles", "joint", "max |duty difference|", "beyond tolerance"}, "llrlrr");
    std::ostringstream csv;
    csv << "log,joint,rows,tolerance,max_duty_difference,mismatches,passed\n";
    Json logs = Json::array();
    std::string details;
    std::size_t failed = 0;
    for (std::size_t k = 0; k < bench.replay_logs.size(); ++k) {
      const std::string& name = bench.replay_logs[k];
      const std::filesystem::path file = BenchSettings::resolve(d, name);
      ctx.say("replaying " + name);
      std::ifstream in(file, std::ios::binary);
      if (!in) throw InputError(file.generic_string() + ": cannot be read (" + key_of(k) + ")");
      const ReplayLog log = read_replay_log(in, config, file.generic_string());
      ReplayTrace trace;
      const ReplayResult r = replay_log(config, log, tolerance, &trace);
      const std::string rows_file = "bench_replay/" + std::filesystem::path(name).stem().string() + "-duties.csv";
      std::ostringstream rows;
      write_replay_comparison_csv(rows, log, r, trace);
      ctx.write_file(rows_file, rows.str());

      const std::string verdict = r.passed() ? "✓ runs this configuration" : "✗ does not run this configuration";
      if (!r.passed()) ++failed;
      for (const ReplayJoint& j : r.joints) {
        table.row({md::code(name), verdict, std::to_string(r.rows), md::code(j.joint), format::shortest(j.max_difference),
                   std::to_string(j.mismatches)});
        csv << csv::field(name) << "," << j.joint << "," << r.rows << "," << format::shortest(tolerance) << ","
            << format::shortest(j.max_difference) << "," << j.mismatches << "," << (r.passed() ? "true" : "false") << "\n";
      }
      details += "- " + md::code(name) + " (stations: " + format::join(log.stations) + "): ";
      for (std::size_t m = 0; m < r.mechanisms.size(); ++m) {
        details += (m ? "; " : "") + r.mechanisms[m] + ":";
        for (std::size_t s = 0; s < r.status_counts[m].size(); ++s) {
          if (r.status_counts[m][s]) {
            details += " " + std::string(runtime::to_string(static_cast<runtime::Status>(s))) + " " +
                       std::to_string(r.status_counts[m][s]);
          }
        }
      }
      if (r.first_mismatch) {
        details += "; first mismatch at row " + std::to_string(r.first_row + 1) + " (t = " + format::shortest(r.first_time_s) +
                   " s), " + md::code(r.first_joint) + ": logged " + format::shortest(r.first_logged) + ", runtime " +
                   format::shortest(r.first_runtime);
      }
      details += "; per cycle: [" + md::code(rows_file) + "](" + rows_file + ").\n";
      Json j = to_json(r);
      j["log"] = name;
      j["stations"] = log.stations;
      j["duties_csv"] = rows_file;
      logs.push_back(j);
    }
    ctx.write_file("bench_replay/bench_replay.csv", csv.str());
    const std::size_t n = bench.replay_logs.size();
    b.result = {{"config", json_file}, {"tolerance", tolerance}, {"logs", logs}, {"csv", "bench_replay/bench_replay.csv"}};
    b.markdown = preamble + "Configuration: [" + md::code(json_file) + "](" + json_file + ").\n\n" + table.str() + "\n" +
                 details + "\nPer log and joint: [`bench_replay/bench_replay.csv`](bench_replay/bench_replay.csv).\n";
    b.passed = failed == 0;
    b.check = b.passed ? std::to_string(n) + " log(s) through the exported runtime, every duty within " + format::shortest(tolerance)
                       : std::to_string(failed) + " of " + std::to_string(n) +
                             " log(s) differ from the exported runtime's duties: the device does not run this configuration";
    return b;
  };
  return p;
}

}  // namespace fivebar::products
