#pragma once
/// Dimensional synthesis of the whole device (issue "optimize"; docs/optimize.md): the design's
/// `optimize:` section names design numbers by key path (fivebar/sections/optimize.hpp), the
/// figures to maximise or minimise and the constraints; islands of the hybrid algorithm (the
/// default for several objectives: NSGA-II's selection, a surrogate's pre-screening, no repeated
/// design), pagmo2's NSGA-II / MOEA/D, or CMA-ES / SADE (one objective) search the box of the
/// variables, migrating in a ring between rounds; one evaluation cache per process evaluates each
/// distinct design once; NLopt's COBYLA polishes the chosen design under the same constraints.
///
/// Evaluation is staged (docs/optimize.md "Stages"): every candidate goes through the sweep's
/// cheap per-design path (certified containment, conditioning, footprint, collision fraction,
/// robust margin: fivebar/sweep.hpp evaluate_station_figures()); only a candidate that covers its
/// targets and meets every cheap constraint is handed to the loop analysis (fivebar/control.hpp)
/// and the simulation of its patterns (fivebar/dynamics.hpp), and only when an objective or a
/// constraint asks for them.
///
/// Constraints (Deb's feasibility rules, as a penalty every algorithm sees the same way): a
/// feasible candidate's fitness is its objectives (to minimise: maximised figures negated); an
/// infeasible one's is, in every objective, kInfeasible(stage) + its violation, so that any
/// feasible candidate beats any infeasible one, a candidate rejected later (at a costlier stage)
/// beats one rejected earlier, and among those rejected at one stage the smaller violation wins.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <array>
#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/json.hpp"
#include "fivebar/sections/optimize.hpp"

namespace fivebar {

/// Where a candidate was rejected, in the order of the stages.
enum class OptimizeVerdict : std::uint8_t {
  invalid,            ///< the values break a rule of the design file (e.g. a link below the boss)
  not_covered,        ///< a target is not covered (margin, assembly side, LCI threshold)
  cheap_constraint,   ///< a constraint on a cheap figure
  loop_constraint,    ///< a constraint on a loop figure
  simulation_constraint,
  feasible,
};
const char* to_string(OptimizeVerdict verdict);

/// One evaluated candidate.
struct OptimizeCandidate {
  std::vector<double> x;        ///< variable values after OptimizeVariable::snap(), file units
  std::vector<double> figures;  ///< by optimize_figures() index; NaN where not computed
  OptimizeVerdict verdict = OptimizeVerdict::invalid;
  std::string status;           ///< "feasible", or why not ("not covered: lower margin -0.3 mm")
  double violation = 0.0;       ///< >= 0; 0 when feasible
  std::uint64_t evaluation = 0; ///< 1-based order of evaluation within its island (0: outside a run)
  int island = -1;              ///< -1: outside a run (the reference design, the polish)
  std::uint32_t round = 0;      ///< the round that evaluated it (0: the initial populations)
  bool feasible() const { return verdict == OptimizeVerdict::feasible; }
};

/// Fitness offsets of infeasible candidates (see the header comment): far above any objective.
double optimize_infeasible_offset(OptimizeVerdict verdict);

/// The problem of a design's `optimize:` section; evaluate() is thread-safe.
class OptimizeProblem {
 public:
  /// InputError when the design has no `optimize:` section.
  explicit OptimizeProblem(const Design& design);
  OptimizeProblem(const Design& design, const OptimizeSettings& settings);
  ~OptimizeProblem();
  OptimizeProblem(const OptimizeProblem&) = delete;
  OptimizeProblem& operator=(const OptimizeProblem&) = delete;

  const OptimizeSettings& settings() const;
  const Design& design() const;               ///< the design without its optimize: and sweep: sections
  const std::vector<std::string>& stations() const;
  std::size_t dimension() const;
  std::vector<double> lower() const;
  std::vector<double> upper() const;
  /// The design's own values at the variables' keys (the first key of a tied variable).
  std::vector<double> reference_values() const;
  /// True when every key is a station number the fast path sets directly (no YAML round trip).
  bool fast_path() const;
  /// Which stages any objective or constraint needs: [cheap, loop, simulation].
  bool needs(OptimizeStage stage) const;

  /// `x` with every variable snapped (OptimizeVariable::snap()): the canonical design of `x`, the
  /// key of the evaluation cache (tied keys take one value, and no number is set by two variables).
  std::vector<double> snap(const std::vector<double>& x) const;
  /// The complete design with `x` applied (snapped); InputError / ValidationError when invalid.
  Design design_at(const std::vector<double>& x) const;
  /// Evaluates the candidate `x` (snapped first) through the stages.
  OptimizeCandidate evaluate(const std::vector<double>& x) const;
  /// The vector pagmo minimises (size: number of objectives).
  std::vector<double> fitness(const OptimizeCandidate& c) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Calls of OptimizeProblem::evaluate() in this process so far (every problem, every thread): the
/// work done, against which a test checks that the search's cache evaluates no design twice.
std::uint64_t optimize_evaluate_calls();

/// Settings of `design` asking for every figure the design has the data for (each as a constraint
/// that always holds), for a complete report of one design.
OptimizeSettings every_figure_settings(const Design& design, const OptimizeSettings& settings);

/// Pareto dominance of two feasible candidates over the problem's objectives.
bool optimize_dominates(const OptimizeProblem& problem, const OptimizeCandidate& a, const OptimizeCandidate& b);
/// The non-dominated feasible candidates of `candidates` (stable: earlier first among equals,
/// duplicates of a point kept once).
std::vector<OptimizeCandidate> optimize_front(const OptimizeProblem& problem, const std::vector<OptimizeCandidate>& candidates);

/// Hypervolume (pagmo2's exact algorithms) dominated by `points` (each a vector to minimise)
/// and bounded by `reference`; points not strictly better than the reference in every
/// coordinate are left out. 0 for an empty set.
double hypervolume(const std::vector<std::vector<double>>& points, const std::vector<double>& reference);
/// The objective vectors (to minimise) of feasible candidates, normalised as
/// (f - ideal) / (nadir - ideal) with the given ideal and nadir (each to minimise).
std::vector<std::vector<double>> normalised_objectives(const OptimizeProblem& problem,
                                                       const std::vector<OptimizeCandidate>& candidates,
                                                       const std::vector<double>& ideal, const std::vector<double>& nadir);

struct OptimizeOptions {
  std::filesystem::path out_dir;  ///< files go here (created)
  int threads = 0;                ///< 0: every core; the result does not depend on it
  std::uint64_t shard = 0;        ///< this shard runs islands shard, shard + shards, ...
  std::uint64_t shards = 1;
  bool resume = false;            ///< continue from out_dir's checkpoint
  bool plots = true;
  /// Every figure the design has the data for (the loop and the simulations: seconds) of the
  /// design as given and of the chosen one, for the comparison (OptimizeResult::reference_full).
  bool full_figures = true;
  /// Overrides of the section's budget (0: the section's).
  std::uint64_t evaluations = 0;
  double seconds = 0.0;
  const std::atomic<bool>* stop = nullptr;  ///< set (e.g. by SIGINT): stop after the round, checkpointed
  std::function<void(std::uint64_t evaluations, std::uint64_t budget, double seconds, std::size_t front)> progress;
};

/// Counts of candidates by the stage that rejected them.
struct OptimizeStageCounts {
  std::uint64_t evaluated = 0, invalid = 0, not_covered = 0, cheap = 0, loop = 0, simulation = 0, feasible = 0;
  void add(const OptimizeCandidate& c);
  Json to_json() const;
};

struct OptimizeResult {
  std::string algorithm;
  std::uint64_t evaluations = 0;   ///< in the search (the polish's apart)
  /// Distinct designs (snapped values) among the search's evaluations: the others were answered by
  /// the evaluation cache, shared by the islands of a process (docs/optimize.md "Evaluation cache").
  std::uint64_t distinct = 0;
  /// Cache hits of this process (search and polish): requests answered without evaluating.
  std::uint64_t cache_hits = 0;
  std::uint64_t rounds = 0;
  double seconds = 0.0;
  bool interrupted = false;        ///< stopped by OptimizeOptions::stop (resumable)
  bool budget_time = false;        ///< stopped by the wall-time budget
  OptimizeStageCounts stages;
  std::vector<OptimizeCandidate> front;
  /// Hypervolume of the front after each round, normalised objectives (see optimize.md).
  std::vector<std::pair<std::uint64_t, double>> hypervolume;
  std::vector<double> ideal, nadir;  ///< of the normalisation (objectives to minimise)
  std::optional<OptimizeCandidate> chosen;    ///< by settings.choose, before the polish
  std::optional<OptimizeCandidate> polished;  ///< the polish's result when it improved on chosen
  std::uint64_t polish_evaluations = 0;
  OptimizeCandidate reference;                ///< the design as given
  /// The design as given and the chosen (or polished) one with every figure the design has the data
  /// for (the loop and the simulation included), for the comparison table.
  OptimizeCandidate reference_full, chosen_full;
  std::optional<Design> chosen_design;        ///< polished (or chosen) applied to the design
  /// With settings.atlas: per optimised station {station, atlas} (fivebar/atlas.hpp to_json()).
  Json atlases = Json::array();
  std::vector<std::filesystem::path> files;   ///< every file written
  Json to_json(const OptimizeProblem& problem) const;
};

/// Runs the design's `optimize:` section (or this shard's islands of it): writes
/// `optimize/front.csv` (every front point, its values and figures), `front.json`,
/// `candidates.csv` (every candidate evaluated, in island and evaluation order),
/// `chosen.yaml` (the chosen design, a complete design file without its optimize: section),
/// `hypervolume.svg/.png`, `front.svg/.png` (parallel coordinates) and `checkpoint.json`
/// into options.out_dir; a shard writes `front.shard-K-of-N.json` and its own checkpoint.
OptimizeResult run_optimize(const Design& design, const OptimizeOptions& options);

/// Merges the shard fronts `front.shard-K-of-N.json` (K = 0 ... N-1) of out_dir into one front
/// and writes the files of a whole run (chosen design, plots); the polish runs on the merged
/// choice. InputError naming a missing or foreign shard file.
OptimizeResult merge_optimize_shards(const Design& design, const OptimizeOptions& options, std::uint64_t shards);

/// Every rank of an MPI job runs shard rank/size; rank 0 merges (merge_optimize_shards).
/// Throws std::runtime_error when fivebar was built without MPI.
OptimizeResult run_optimize_mpi(const Design& design, const OptimizeOptions& options);

/// Summary table rows comparing the chosen design with the design as given: one row per
/// variable and per figure (every figure the design has the data for), {name, given, chosen}.
std::vector<std::array<std::string, 3>> optimize_comparison(const OptimizeProblem& problem, const OptimizeResult& result);

}  // namespace fivebar
