#pragma once
/// Link-dimension sweeps (issue "sweeps"): designs enumerated by index (grid, random or Sobol, all
/// deterministic functions of the index and the seed), evaluated in parallel with early exit on
/// the first failed hard constraint, streamed to CSV in index order, with an online Pareto set
/// over the chosen objectives and the best design. Sharding splits the index range in
/// contiguous blocks, so concatenating the shards' rows gives the unsharded sweep row for row.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "fivebar/coverage/coverage.hpp"
#include "fivebar/design.hpp"
#include "fivebar/sections/sweep.hpp"

namespace fivebar {

/// Number of designs of a sweep (grid: product of the n; random / sobol: count).
std::uint64_t sweep_size(const SweepSettings& settings);

/// Values (file units) of the swept variables of design `index`.
std::vector<double> sweep_point(const SweepSettings& settings, std::uint64_t index);

/// The station of `design` named by the sweep with `values` applied; throws ValidationError
/// (key relative to the station) when the result is not a valid design.
Station apply_sweep(const Design& design, const SweepSettings& settings, const std::vector<double>& values);

/// One evaluated design. Metrics not evaluated (early exit, invalid design) are NaN.
struct SweepRow {
  std::uint64_t index = 0;
  std::vector<double> values;
  std::string status;  ///< "covered", "not covered: ...", "undecided: ...", "invalid: ..."
  bool covered = false;
  double margin_lower_mm, margin_upper_mm, margin_shared_mm;
  double min_lci, min_force_capability;
  double footprint_w_mm, footprint_h_mm, footprint_mm2;
  double collision_fraction;  ///< see collision_fraction(); NaN without geometry or one mechanism
  /// The smallest robust margin of the swept mechanisms (fivebar/tolerance.hpp robust_coverage(),
  /// first order, the design's tolerance: sources): the margin a robust_fraction of printed
  /// devices keeps. NaN unless the objectives ask for `robust`.
  double robust_margin_mm;
  SweepRow();
  /// Objective value oriented so that larger is better (footprint, collision negated); NaN if missing.
  double score(const std::string& objective) const;
};

/// The collision fraction's grid has at most this many steps across the ellipse's larger axis
/// (about 450 points, 200,000 pairs), so that no design of a sweep costs more than tens of ms.
inline constexpr double kSweepCollisionStepsAcross = 24.0;
/// Grid spacing of the collision fraction of a design whose target is `target`: the settings'
/// collision_spacing_mm, coarsened to kSweepCollisionStepsAcross steps across a larger ellipse.
double sweep_collision_spacing(const SweepSettings& settings, const Ellipse& target);

/// Coverage sampling used by sweeps (coarser than the default).
CoverageOptions sweep_coverage_options();
/// Evaluates design `index` (no I/O).
SweepRow evaluate_sweep_design(const Design& design, const SweepSettings& settings, std::uint64_t index,
                               const CoverageOptions& coverage = sweep_coverage_options());

/// What evaluate_station_figures() computes beyond coverage, conditioning and footprint.
struct StationFigureRequest {
  std::string mechanism;              ///< "lower", "upper" or empty: every mechanism and the shared region
  double collision_spacing_mm = 0.0;  ///< > 0: the collision fraction at this spacing (coarsened as sweeps do)
  bool robust = false;                ///< the robust margin (fivebar/tolerance.hpp robust_coverage())
  CoverageOptions coverage = sweep_coverage_options();
};
/// The per-design figures of one station as the sweep computes them, with early exit on the first
/// failed coverage rule (row.status says which; row.covered when every one holds). index and
/// values are left empty. The station must be valid (Station::validate()).
SweepRow evaluate_station_figures(const Design& design, const Station& station, const StationFigureRequest& request);

/// Non-dominated set of covered designs over the objectives (online; deterministic for rows
/// inserted in index order).
class ParetoArchive {
 public:
  explicit ParetoArchive(std::vector<std::string> objectives) : objectives_(std::move(objectives)) {}
  void insert(const SweepRow& row);
  const std::vector<SweepRow>& rows() const { return rows_; }
  /// a dominates b: no worse in every objective and better in one.
  bool dominates(const SweepRow& a, const SweepRow& b) const;

 private:
  std::vector<std::string> objectives_;
  std::vector<SweepRow> rows_;
};

/// CSV header and row (shortest round-trip numbers; empty fields for NaN).
std::string sweep_csv_header(const SweepSettings& settings);
std::string sweep_csv_row(const SweepRow& row);

struct SweepOptions {
  std::filesystem::path out_dir;      ///< files go here (created)
  std::uint64_t shard = 0;            ///< this shard, 0-based
  std::uint64_t shards = 1;           ///< number of shards
  bool resume = false;                ///< continue an interrupted CSV in out_dir
  bool plots = true;                  ///< SVG/PNG of the objectives
  std::uint64_t chunk = 16384;        ///< designs per parallel chunk (memory stays flat)
  int threads = 0;                    ///< 0: every core (OMP_NUM_THREADS); at most kMaxSweepThreads
  /// Run even when estimate_sweep() says it exceeds kSweepConfirmSeconds or kSweepConfirmBytes
  /// (`fivebar sweep --yes`); otherwise run_sweep() refuses such a sweep before writing anything.
  bool confirmed = false;
  const std::atomic<bool>* stop = nullptr;  ///< set (e.g. by SIGINT) to stop after the chunk
  std::function<void(std::uint64_t done, std::uint64_t total, double seconds)> progress;
  CoverageOptions coverage = sweep_coverage_options();
};

struct SweepResult {
  std::uint64_t total = 0;        ///< designs in this shard
  std::uint64_t first = 0;        ///< index of its first design
  std::uint64_t done = 0;         ///< rows in the CSV (including resumed ones)
  std::uint64_t evaluated = 0;    ///< evaluated by this run
  std::uint64_t covered = 0;      ///< covered designs among the rows evaluated by this run
  std::uint64_t invalid = 0;
  double seconds = 0.0;
  double designs_per_s = 0.0;
  bool interrupted = false;
  std::vector<SweepRow> pareto;
  std::optional<SweepRow> best;   ///< by the objectives in order (lexicographic)
  std::optional<Design> best_design;
  std::filesystem::path csv;
  std::vector<std::filesystem::path> files;  ///< every file written
};

/// What a sweep will cost, measured on a probe of its own designs before it starts.
struct SweepEstimate {
  std::uint64_t designs = 0;  ///< in this shard
  double seconds = 0.0;       ///< wall time on `threads` threads
  double csv_bytes = 0.0;     ///< size of its CSV
  int threads = 1;
  /// "1.0e+12 designs: about 3.2e+05 h on 2 threads and 1.5e+14 bytes of CSV".
  std::string text() const;
};
/// Beyond these a sweep runs only when confirmed (docs/reliability.md "Resource bounds").
inline constexpr double kSweepConfirmSeconds = 3600.0;  ///< one hour
inline constexpr double kSweepConfirmBytes = 1e9;       ///< one gigabyte of CSV
/// Evaluates `probe` designs spread over the shard (one thread) and extrapolates.
SweepEstimate estimate_sweep(const Design& design, const SweepOptions& options, std::uint64_t probe = 128);

/// Most worker threads a sweep runs (docs/reliability.md "Resource bounds"): far above any
/// machine's cores, low enough that thread creation cannot exhaust the process.
inline constexpr int kMaxSweepThreads = 256;

/// The worker threads a sweep with `requested` threads (0: the OpenMP default, OMP_NUM_THREADS)
/// runs; InputError naming `threads` (or OMP_NUM_THREADS) above kMaxSweepThreads or below 0.
int sweep_threads(int requested);

/// Runs (a shard of) the design's `sweep:` section, writing `sweep.csv` (or
/// `sweep.shard-K-of-N.csv`), `pareto.csv`, `best.yaml` and the plots into options.out_dir.
SweepResult run_sweep(const Design& design, const SweepOptions& options);

/// Runs the sweep across the ranks of an MPI job (`mpirun -n R fivebar sweep ...`): rank r runs
/// shard r/R, rank 0 merges the shards' rows in order into sweep.csv and their Pareto sets.
/// Returns the merged result on rank 0 (and this rank's on the others). Throws std::runtime_error
/// when fivebar was built without MPI (FIVEBAR_WITH_MPI=OFF).
SweepResult run_sweep_mpi(const Design& design, const SweepOptions& options);
/// True when this process was started by an MPI launcher with more than one rank.
bool launched_by_mpi();
/// True when this build has MPI support.
bool built_with_mpi();

/// Reads a sweep CSV back (for resuming and merging): calls `row` for every data row; throws
/// InputError naming the file and line when a row does not parse or the header differs.
void read_sweep_csv(const std::filesystem::path& csv, const SweepSettings& settings,
                    const std::function<void(const SweepRow&, const std::string& line)>& row);

/// Scatter of the first two objectives (Pareto set marked) and, for grid sweeps of two or more
/// variables, a heat map of the first objective over the first two variables; streamed from the
/// CSV. Returns the files written (SVG and PNG).
std::vector<std::filesystem::path> write_sweep_plots(const std::filesystem::path& csv, const SweepSettings& settings,
                                                     const std::vector<SweepRow>& pareto,
                                                     const std::filesystem::path& out_dir);


}  // namespace fivebar
