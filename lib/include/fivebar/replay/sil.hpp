#pragma once
/// Software in the loop (docs/runtime.md "Replay"): fivebar::runtime closed around the simulator
/// for a design's patterns, each run's log written in the device's format (fivebar/replay.hpp) and,
/// when asked, replayed through a fresh runtime of the same configuration. The one implementation
/// behind `fivebar replay DESIGN --sil` and the `replay` product of `fivebar run`.

#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fivebar/dynamics.hpp"
#include "fivebar/io.hpp"
#include "fivebar/json.hpp"
#include "fivebar/replay.hpp"
#include "fivebar/runtime/config.hpp"

namespace fivebar {

struct SilRequest {
  /// The stations to run, each with both mechanisms (InputError otherwise); empty: every station
  /// of the design with both mechanisms, in the design's order.
  std::vector<std::string> stations;
  std::optional<PatternKind> pattern;  ///< nullopt: every pattern of each station
  /// The runtime's configuration as given, its gains and calibration too (an exported file, as
  /// `--config` reads it); null: the design's export, in memory.
  std::shared_ptr<const runtime::Config> config;
  /// Opens the log of one run, named `<station>-<pattern>-sil.csv` (an AtomicFile wherever the
  /// caller puts it); the run writes it row by row and commits it.
  std::function<AtomicFile(const std::string& file_name)> open_log;
  /// Replays each committed log, read back from its file, through a fresh runtime of `config`
  /// (which must then be given): SilRun::replay, tolerance 0.
  bool replay = false;
  /// Called before each simulation (may be empty).
  std::function<void(const std::string& station, const std::string& reference)> progress;
};

/// One pattern of one station.
struct SilRun {
  std::string station, reference;
  /// Not empty: the reference cannot be followed, and why; the run was not simulated (nothing
  /// below is set).
  std::string unusable;
  SimulationResult result;
  Json figures;                        ///< simulate's figures: to_json(input, result)
  std::filesystem::path log;           ///< the log's path, as the AtomicFile of open_log named it
  std::optional<ReplayResult> replay;  ///< SilRequest::replay
  bool simulated() const { return unusable.empty(); }
  /// Simulated, finished, and (when replayed) every duty of the log reproduced.
  bool ok() const { return simulated() && result.ok() && (!replay || replay->passed()); }
};

/// InputError naming `origin` when request.config lacks a requested station or one of its two
/// mechanisms (checked by run_sil() before it writes anything; a caller that creates an output
/// folder calls it first).
void check_sil_config(const Design& design, const SilRequest& request, const std::string& origin);

/// Runs the request (the links' closed-form masses: no parts render). Throws InputError for a
/// station that is not the design's or lacks a mechanism, or a design without `geometry:`,
/// `motor:` or `controller:`; an unusable reference is a SilRun with `unusable`, not an error.
std::vector<SilRun> run_sil(const Design& design, const SilRequest& request);

/// One run as `fivebar replay --sil --json` and the `replay` product report it: simulate's figures
/// plus `replay` (to_json(ReplayResult)) when replayed; for a run not simulated {station,
/// reference, status: "not_simulated", reason}. The caller adds `log` in its own form.
Json to_json(const SilRun& run);

}  // namespace fivebar
