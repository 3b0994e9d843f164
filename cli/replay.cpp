// fivebar replay: a device log through fivebar::runtime, its duties against the logged ones
// (fivebar/replay.hpp); --sil: the runtime closed around the simulator for a pattern, reporting
// simulate's figures and writing the log of the run in the same format.

#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>

#include "common.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "fivebar/replay.hpp"
#include "fivebar/replay/sil.hpp"
#include "fivebar/runtime/json_config.hpp"
#include "tactors.hpp"

namespace fivebar::cli {

namespace {

struct ReplayOptions {
  std::string input;  // the log, or with --sil the design
  std::string config;
  bool sil = false;
  std::string station;
  std::string pattern;
  double tolerance = 1e-9;
  std::string out;
  bool json = false;
};

runtime::Config read_config(const std::string& path) {
  try {
    return runtime::load_config_json(path);
  } catch (const runtime::ConfigError& e) {
    throw InputError(std::string("--config: ") + e.what());
  }
}

int run_log(const ReplayOptions& opt) {
  if (opt.config.empty()) throw InputError("--config EXPORTED.json is needed to replay a log (the configuration the device ran)");
  if (!(opt.tolerance >= 0.0) || !(opt.tolerance <= 2.0)) throw InputError("--tolerance must be within [0, 2]");
  const runtime::Config config = read_config(opt.config);
  std::ifstream in(opt.input, std::ios::binary);
  if (!in) throw InputError(opt.input + ": cannot be read");
  const ReplayLog log = read_replay_log(in, config, opt.input);
  const ReplayResult r = replay_log(config, log, opt.tolerance);
  if (opt.json) {
    // command and design lead, as in every --json document (docs/conventions.md).
    Json j = {{"command", "replay"}, {"design", config.design}, {"mode", "log"}, {"log", opt.input}, {"config", opt.config}};
    const Json body = to_json(r);  // named: items() of a temporary would dangle
    for (const auto& [key, value] : body.items()) j[key] = value;
    print_json(j);
  } else {
    std::cout << opt.input << ": " << r.rows << " cycles through the runtime of " << opt.config << " (design "
              << config.design << ")\n";
    for (const ReplayJoint& j : r.joints) {
      std::cout << "  " << j.joint << ": max |duty difference| " << exact(j.max_difference) << ", " << j.mismatches
                << " beyond " << exact(r.tolerance) << "\n";
    }
    for (std::size_t k = 0; k < r.mechanisms.size(); ++k) {
      std::cout << "  " << r.mechanisms[k] << ":";
      for (std::size_t s = 0; s < 6; ++s) {
        if (r.status_counts[k][s]) std::cout << " " << runtime::to_string(static_cast<runtime::Status>(s)) << " " << r.status_counts[k][s];
      }
      std::cout << "\n";
    }
    if (r.failed_readings) {
      std::cout << "  failed readings (empty cells): " << r.failed_readings << ", " << r.failed_not_faulted
                << " without the runtime's sensor_fault and zero duty\n";
    }
    if (r.first_status_mismatch) {
      std::cout << "  statuses: " << r.status_mismatches << " differ from the logged ones; first: row " << r.first_status_row + 1
                << ", " << r.first_status_mechanism << ": logged " << runtime::to_string(r.first_status_logged) << ", runtime "
                << runtime::to_string(r.first_status_runtime) << "\n";
    }
    if (r.first_mismatch) {
      std::cout << "  first mismatch: row " << r.first_row + 1 << " (t = " << exact(r.first_time_s) << " s), " << r.first_joint
                << ": logged " << exact(r.first_logged) << ", runtime " << exact(r.first_runtime) << "\n";
    }
  }
  if (r.failed_not_faulted) {
    std::cerr << "fivebar replay: " << r.failed_not_faulted << " failed readings did not give the runtime's sensor_fault and zero duty\n";
  }
  if (r.status_mismatches) {
    std::cerr << "fivebar replay: " << r.status_mismatches << " logged statuses differ from the runtime's\n";
  }
  if (r.mismatches) {
    std::cerr << "fivebar replay: the runtime's duties differ from the logged ones in " << r.mismatches
              << " values: the device does not run this configuration (or this loop)\n";
  }
  if (!r.passed()) return kCheckFailed;
  return kOk;
}

int run_sil(const ReplayOptions& opt) {
  std::optional<PatternKind> kind;
  if (!opt.pattern.empty()) {
    kind = parse_pattern_kind(opt.pattern);
    if (!kind) throw InputError("--pattern '" + opt.pattern + "': expected stretch, slip, twist or pivot");
  }
  const Design design = load(opt.input);
  std::vector<const Station*> stations;
  if (!opt.station.empty()) {
    stations.push_back(&select_pair_station(design, opt.station));
  } else {
    for (const Station& s : design.stations)
      if (s.lower && s.upper) stations.push_back(&s);
    if (stations.empty()) throw InputError("design '" + design.name + "' has no station with both mechanisms");
  }
  require_geometry(design);
  SilRequest request;
  for (const Station* s : stations) request.stations.push_back(s->name);
  request.pattern = kind;
  if (!opt.config.empty()) request.config = std::make_shared<const runtime::Config>(read_config(opt.config));
  check_sil_config(design, request, "--config " + opt.config);  // before the output folder exists
  const std::filesystem::path dir = output_dir(design, opt.out, "replay");
  const WriteFence fence(dir);
  request.open_log = [&dir](const std::string& name) { return AtomicFile(dir / name); };
  Json runs = Json::array();
  std::vector<std::string> files;
  bool all_ok = true;
  for (const SilRun& run : run_sil(design, request)) {
    all_ok = all_ok && run.ok();
    Json j = to_json(run);
    if (!run.simulated()) {
      runs.push_back(j);
      if (!opt.json) std::cout << run.station << "  " << run.reference << ": not simulated, " << run.unusable << "\n";
      continue;
    }
    const SimulationResult& r = run.result;
    const std::string csv = run.log.generic_string();
    files.push_back(csv);
    j["log"] = csv;
    j["config"] = request.config ? opt.config : std::string("the design's export, in memory");
    runs.push_back(j);
    if (!opt.json) {
      std::cout << run.station << "  " << run.reference << ": " << to_string(r.status) << ", " << fixed(r.t_end, 3)
                << " s through the runtime (software in the loop)\n";
      if (!r.ok()) std::cout << "  " << r.reason << "\n";
      for (const MechanismSummary& m : r.summary) {
        std::cout << "  " << m.name << ": tracking error max " << fixed(m.max_error_mm, 3) << " mm, rms "
                  << fixed(m.rms_error_mm, 3) << " mm; current peak " << fixed(m.peak_current_A, 3) << " A; peak duty "
                  << fixed(m.peak_duty, 3) << ", saturated " << fixed(m.saturation_s, 3) << " s\n";
      }
      std::cout << "  log: " << csv << " (fivebar replay LOG --config EXPORTED.json replays it)\n";
    }
  }
  if (opt.json) {
    print_json({{"command", "replay"}, {"mode", "sil"}, {"design", design.name}, {"runs", runs}, {"files", files}});
  }
  if (!all_ok) {
    std::cerr << "fivebar replay --sil: a simulation did not finish or could not start (its status and reason are above)\n";
    return kCheckFailed;
  }
  return kOk;
}

}  // namespace

void setup_replay(CLI::App& app) {
  auto [sub, opt] = add_command<ReplayOptions>(
      app, "replay",
      "A device log (measured joints, reference points, duties) through the runtime of an exported configuration: "
      "its duties against the logged ones; --sil: the runtime closed around the simulator",
      [](const ReplayOptions& o) { return o.sil ? run_sil(o) : run_log(o); });
  sub->add_option("input", opt->input, "The log (CSV), or with --sil the design file (YAML)")->required()->type_name("LOG|DESIGN");
  sub->add_option("-c,--config", opt->config, "The exported controller configuration (fivebar export --format json)")
      ->type_name("FILE");
  sub->add_flag("--sil", opt->sil, "Software in the loop: simulate the design's patterns with the runtime as the controller");
  add_station_option(*sub, opt->station, "every station with both tactors (--sil only)");
  sub->add_option("--pattern", opt->pattern, "--sil: only this pattern (stretch, slip, twist, pivot)")->type_name("KIND");
  sub->add_option("--tolerance", opt->tolerance, "Largest |duty difference| accepted per value (default 1e-9)")
      ->type_name("D");
  add_out_option(*sub, opt->out, "the logs of --sil", "replay");
  add_json_flag(*sub, opt->json);
  sub->footer(
      "Log columns: time_s; per joint <station>_<mechanism>_theta<1|2>_counts (or _volts, _theta_rad) and _duty;\n"
      "per mechanism <station>_<mechanism>_x_ref_mm and _y_ref_mm (docs/runtime.md \"Replay\").\n"
      "--sil uses the links' closed-form masses (no parts render).\n" +
      exit_status({.ok = "every duty matched (or every simulation finished)",
                   .failed = "a mismatch (or a simulation failed)",
                   .writes = true}));
}

}  // namespace fivebar::cli
