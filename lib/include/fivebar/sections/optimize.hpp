#pragma once
/// The `optimize:` section of a design file: a multi-objective dimensional synthesis of the device
/// (fivebar/optimize.hpp runs it). One module of the design (docs/architecture.md "Design
/// sections"): the struct and its validate() here, its loader and writer hooks in
/// lib/src/sections/optimize.cpp. A Design holds it as `design.get<OptimizeSettings>()`.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"

namespace fivebar {

/// One design variable: every key path in `keys` takes the same value (tied), in file units.
struct OptimizeVariable {
  std::string name;               ///< the file's label for it (the map key)
  std::vector<std::string> keys;  ///< design key paths (design_number()), at least one
  double lo = 0.0, hi = 0.0;      ///< bounds, lo < hi
  double step = 0.0;              ///< > 0: values lo + k step only (a whole number: step 1)
  /// `x` clamped to [lo, hi] and, with a step, rounded to the nearest lo + k step <= hi.
  double snap(double x) const;
};

/// When a figure is computed (docs/optimize.md "Stages"): the cheap path for every candidate, the
/// loop and the simulation only for candidates that satisfy every cheap constraint.
enum class OptimizeStage : std::uint8_t { cheap = 1, loop = 2, simulation = 3 };

/// A per-design figure that objectives and constraints name.
struct OptimizeFigure {
  std::string_view name;
  std::string_view unit;
  bool maximise = true;  ///< its natural direction (an objective may say otherwise)
  OptimizeStage stage = OptimizeStage::cheap;
  std::string_view meaning;
};
/// Every figure, in a fixed order (Candidate::figures is indexed by it): margin, min_lci, force,
/// footprint, collision, robust, max_rho, kp_margin, tracking_error, saturation.
const std::vector<OptimizeFigure>& optimize_figures();
/// Index of figure `name` in optimize_figures(), or -1.
int optimize_figure_index(std::string_view name);

struct OptimizeObjective {
  std::string figure;
  bool maximise = true;
};

/// `FIGURE >= BOUND` or `FIGURE <= BOUND` (strict forms read as the same bound).
struct OptimizeConstraint {
  std::string figure;
  bool at_least = true;  ///< >= (else <=)
  double bound = 0.0;
  std::string text() const;  ///< "robust >= 0"
};

struct OptimizeSettings {
  static constexpr std::string_view kKey = "optimize";
  std::vector<OptimizeVariable> variables;
  std::vector<OptimizeObjective> objectives;
  std::vector<OptimizeConstraint> constraints;
  /// nsga2 | moead (two or more objectives); cmaes | sade (one); auto: nsga2 or cmaes.
  std::string algorithm = "auto";
  int population = 32;        ///< individuals per island (nsga2: a multiple of 4)
  int islands = 2;            ///< populations evolved side by side, migrating in a ring
  int generations_per_round = 5;  ///< generations between migrations and checkpoints
  std::uint64_t evaluations = 4000;  ///< budget: candidates evaluated in all (the polish's included)
  double seconds = 600.0;     ///< budget: wall time, checked between rounds
  std::uint64_t seed = 1;
  bool polish = true;         ///< NLopt polish of the chosen design (docs/optimize.md "Polish")
  std::uint64_t polish_evaluations = 200;
  /// `knee` (the front's point nearest the ideal point, objectives normalised over the front)
  /// or the name of an objective's figure (the front's best in it).
  std::string choose = "knee";
  /// Non-dimensional performance atlas (fivebar/atlas.hpp) of each optimised station's family,
  /// the station and the chosen design marked; `atlas_cells` points along the chart's base.
  bool atlas = false;
  int atlas_cells = 41;
  /// Grid spacing of the collision fraction (as sweep.collision_spacing_mm).
  double collision_spacing_mm = 2.0;
  /// Rules that need no design (names, ranges, counts); the design checks keys and data.
  void validate() const;
  /// The algorithm `auto` stands for.
  std::string resolved_algorithm() const;
};

/// The stations a run optimises and evaluates: those whose keys the variables name
/// ("stations.<name>. ..."), every station with a mechanism when a variable sets a key outside
/// `stations:` (a section's number moves every station). In file order.
std::vector<std::string> optimize_station_names(const Design& design, const OptimizeSettings& settings);

}  // namespace fivebar
