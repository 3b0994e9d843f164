#pragma once
// The comparison of docs/optimize.md "The hybrid algorithm": the default algorithm against pagmo's
// own NSGA-II (same population, islands, budget and seeds) on the 2-, 3- and 8-variable problems of
// the docs, the hypervolume of each run's front (every feasible candidate of the run) normalised by
// the ideal and nadir of the union of every front of the study (both algorithms, every seed),
// reference point 1.1 in each objective. Used by test/test_optimize.cpp (a small version) and
// test/bench/bench_optimize.cpp (8 seeds).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/optimize.hpp"
#include "fivebar/sections/optimize.hpp"

namespace fivebar::testing {

/// 2: L34 x L12 of both index mechanisms (tied), margin against footprint, population 16, 2
/// islands, 256 evaluations (a tenth of the 57 x 49 grid of docs/optimize.md "Measured").
/// 3: the same and the base spacing O2x of both mechanisms (tied, 8 ... 17 mm), margin, min_lci
/// and footprint, population 16, 2 islands, 800 evaluations.
/// 8: the showcase's eight variables without the robust constraint (min_lci >= 0.25), margin,
/// min_lci and footprint, population 32, 2 islands, 3,000 evaluations.
inline Design study_problem(int variables, const std::string& algorithm, std::uint64_t seed) {
  Design d = load_design(std::filesystem::path(FIVEBAR_SOURCE_DIR) / "designs/iros2022.yaml");
  OptimizeSettings s = *d.get<OptimizeSettings>();
  auto keys = [](const std::string& suffix) {
    std::vector<std::string> k;
    for (const char* m : {"lower", "upper"}) k.push_back(std::string("stations.index.mechanisms.") + m + "." + suffix);
    return k;
  };
  if (variables != 8) {
    OptimizeVariable l34{"L34", keys("links[2]"), 12, 19, 0}, l12{"L12", keys("links[0]"), 6, 12, 0};
    for (const auto& k : keys("links[3]")) l34.keys.push_back(k);
    for (const auto& k : keys("links[1]")) l12.keys.push_back(k);
    s.variables = {l34, l12};
    s.objectives = {{"margin", true}, {"footprint", false}};
    s.constraints.clear();
    s.population = 16;
    s.evaluations = 256;
    if (variables == 3) {
      s.variables.push_back({"O2x", keys("bases[1][0]"), 8, 17, 0});
      s.objectives = {{"margin", true}, {"min_lci", true}, {"footprint", false}};
      s.evaluations = 800;
    }
  } else {
    s.constraints = {{"min_lci", true, 0.25}};
    s.evaluations = 3000;
  }
  s.islands = 2;
  s.algorithm = algorithm;
  s.seed = seed;
  s.polish = false;
  s.atlas = false;
  d.set(s);
  d.validate();
  return d;
}

struct StudyRow {
  int variables = 0;
  std::vector<double> hybrid, nsga2;  ///< hypervolume per seed
  std::uint64_t evaluations_hybrid = 0, distinct_hybrid = 0, evaluations_nsga2 = 0, distinct_nsga2 = 0;
  static double mean(const std::vector<double>& v) {
    double s = 0.0;
    for (double x : v) s += x;
    return v.empty() ? 0.0 : s / double(v.size());
  }
  double ratio() const { return mean(hybrid) / mean(nsga2); }
};

/// Runs both algorithms on the problem of `variables` for seeds 1 ... `seeds`.
inline StudyRow algorithm_study(int variables, int seeds, const std::filesystem::path& scratch) {
  StudyRow row;
  row.variables = variables;
  std::vector<std::vector<OptimizeCandidate>> fronts[2];
  const char* names[2] = {"hybrid", "nsga2"};
  const OptimizeProblem p(study_problem(variables, "hybrid", 1));
  for (int a = 0; a < 2; ++a) {
    for (int seed = 1; seed <= seeds; ++seed) {
      OptimizeOptions o;
      o.plots = false;
      o.full_figures = false;
      o.out_dir = scratch / (std::string(names[a]) + std::to_string(variables) + "-" + std::to_string(seed));
      const OptimizeResult r = run_optimize(study_problem(variables, names[a], std::uint64_t(seed)), o);
      fronts[a].push_back(r.front);
      (a == 0 ? row.evaluations_hybrid : row.evaluations_nsga2) += r.evaluations;
      (a == 0 ? row.distinct_hybrid : row.distinct_nsga2) += r.distinct;
    }
  }
  std::vector<OptimizeCandidate> all;
  for (const auto& fa : fronts) {
    for (const auto& f : fa) all.insert(all.end(), f.begin(), f.end());
  }
  const auto union_front = optimize_front(p, all);
  const std::size_t m = p.settings().objectives.size();
  std::vector<double> ideal(m, 1e300), nadir(m, -1e300);
  for (const auto& c : union_front) {
    const auto f = p.fitness(c);
    for (std::size_t i = 0; i < m; ++i) ideal[i] = std::min(ideal[i], f[i]), nadir[i] = std::max(nadir[i], f[i]);
  }
  const std::vector<double> ref(m, 1.1);
  for (int a = 0; a < 2; ++a) {
    for (const auto& f : fronts[a]) (a == 0 ? row.hybrid : row.nsga2).push_back(hypervolume(normalised_objectives(p, f, ideal, nadir), ref));
  }
  return row;
}

inline void print_study_row(const StudyRow& r) {
  std::printf("%d variables, %zu seeds: hybrid %.4f, nsga2 %.4f (ratio %.3f); evaluations %llu / %llu distinct (hybrid), "
              "%llu / %llu distinct (nsga2)\n  per seed hybrid:",
              r.variables, r.hybrid.size(), StudyRow::mean(r.hybrid), StudyRow::mean(r.nsga2), r.ratio(),
              (unsigned long long)r.evaluations_hybrid, (unsigned long long)r.distinct_hybrid,
              (unsigned long long)r.evaluations_nsga2, (unsigned long long)r.distinct_nsga2);
  for (double h : r.hybrid) std::printf(" %.4f", h);
  std::printf("\n  per seed nsga2: ");
  for (double h : r.nsga2) std::printf(" %.4f", h);
  std::printf("\n");
}

}  // namespace fivebar::testing
