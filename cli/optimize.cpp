// fivebar optimize: multi-objective dimensional synthesis of the device (the design's optimize:
// section): pagmo2 islands, NLopt polish, Pareto front, chosen design re-checked by the exact
// products, resumable, shardable and distributable with MPI.

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <memory>

#include "common.hpp"
#include "fivebar/io.hpp"
#include "fivebar/optimize.hpp"
#include "fivebar/scene.hpp"
#include "fivebar/sweep.hpp"

namespace fivebar::cli {

namespace {

struct OptimizeCliOptions {
  std::string design;
  std::string out;
  std::uint64_t evaluations = 0;
  double seconds = 0.0;
  std::optional<std::uint64_t> seed;
  int threads = 0;
  std::string shard;
  std::uint64_t merge = 0;
  bool resume = false;
  bool no_plots = false;
  bool no_check = false;
  bool no_polish = false;
  bool no_atlas = false;
  bool json = false;
};


void progress_line(std::uint64_t done, std::uint64_t budget, double seconds, std::size_t front) {
  std::fprintf(stderr, "\r  %llu / %llu candidates  %.1f s  front %zu   ", (unsigned long long)done,
               (unsigned long long)budget, seconds, front);
  if (done >= budget) std::fputc('\n', stderr);
  std::fflush(stderr);
}

int run_optimize_cmd(const OptimizeCliOptions& o) {
  const StopOnInterrupt interrupt;  // SIGINT / SIGTERM: stop at the next checkpoint
  Design design = load(o.design);
  if (!design.get<OptimizeSettings>()) {
    throw InputError(o.design + ": the design has no optimize: section (docs/optimize.md shows one)");
  }
  if (o.seed || o.no_polish || o.no_atlas) {
    OptimizeSettings s = *design.get<OptimizeSettings>();
    if (o.seed) s.seed = *o.seed;
    if (o.no_polish) s.polish = false;
    if (o.no_atlas) s.atlas = false;
    design.set(s);
  }
  if (o.evaluations > std::uint64_t(1e9)) throw InputError("--evaluations: must be 1 ... 1e9");
  if (!(o.seconds >= 0.0 && o.seconds <= 1e7)) throw InputError("--seconds: must be > 0 and <= 1e7");
  OptimizeOptions options;
  options.out_dir = o.out.empty() ? std::filesystem::path("outputs") / design.name / "optimize" : std::filesystem::path(o.out);
  const WriteFence fence(options.out_dir);
  if (!o.shard.empty()) std::tie(options.shard, options.shards) = parse_shard(o.shard);
  if (o.merge && !o.shard.empty()) throw InputError("--merge N merges the shards' fronts: do not give --shard with it");
  if (o.merge && o.resume) throw InputError("--merge and --resume: merge after every shard has finished");
  options.resume = o.resume;
  options.plots = !o.no_plots;
  options.full_figures = !o.no_check;
  options.evaluations = o.evaluations;
  options.seconds = o.seconds;
  if (o.threads < 0 || o.threads > kMaxSweepThreads) {
    throw InputError("--threads " + std::to_string(o.threads) + ": must be 1 ... " + std::to_string(kMaxSweepThreads) +
                     " (absent: every core)");
  }
  (void)sweep_threads(o.threads);
  options.threads = o.threads;
  options.stop = interrupt.stop();
  const bool mpi = launched_by_mpi();
  if (mpi && (!o.shard.empty() || o.merge)) throw InputError("--shard / --merge and an MPI launch both split the islands: use one");
  if (mpi && o.resume) throw InputError("--resume is not supported in an MPI launch: rerun with the same ranks");
  if (::isatty(STDERR_FILENO)) options.progress = progress_line;
  const OptimizeProblem problem(design);
  OptimizeResult r = o.merge ? merge_optimize_shards(design, options, o.merge)
                     : mpi   ? run_optimize_mpi(design, options)
                             : run_optimize(design, options);
  if (mpi) {
    int rank = 0;
    if (const char* v = std::getenv("OMPI_COMM_WORLD_RANK")) rank = std::atoi(v);
    if (const char* v = std::getenv("PMI_RANK")) rank = std::atoi(v);
    if (rank != 0) return kOk;
  }
  const bool whole = options.shards == 1;
  std::optional<SceneReport> check;
  if (whole && r.chosen_design && !o.no_check) {
    check = check_design(*r.chosen_design, options.out_dir);
    for (const auto& p : check->products) {
      for (const auto& f : p.files) r.files.push_back(check->out_dir / f);
    }
    r.files.push_back(check->summary_md);
    r.files.push_back(check->summary_json);
    r.files.push_back(check->index_html);
  }
  const auto rows = optimize_comparison(problem, r);
  if (o.json) {
    Json doc = r.to_json(problem);
    doc["command"] = "optimize";
    doc["design"] = design.name;
    doc["shard"] = {options.shard, options.shards};
    doc["mpi"] = mpi;
    Json cmp = Json::array();
    for (const auto& row : rows) cmp.push_back(Json{{"figure", row[0]}, {"given", row[1]}, {"chosen", row[2]}});
    doc["comparison"] = cmp;
    if (check) {
      Json c = Json::array();
      for (const auto& p : check->products) {
        if (p.state != ProductOutcome::State::built) continue;
        c.push_back(Json{{"product", p.name}, {"passed", p.passed}, {"check", p.check}});
      }
      doc["recheck"] = c;
    } else {
      doc["recheck"] = nullptr;
    }
    Json files = Json::array();
    for (const auto& f : r.files) files.push_back(f.generic_string());
    doc["files"] = files;
    print_json(doc);
  } else {
    const auto& s = problem.settings();
    std::printf("optimize %s: %s, %d islands of %d, %zu variables, %zu objectives, %zu constraints%s\n", design.name.c_str(),
                r.algorithm.c_str(), s.islands, s.population, s.variables.size(), s.objectives.size(),
                s.constraints.size(), whole ? "" : (" (shard " + o.shard + ")").c_str());
    std::printf("  %llu candidates in %.2f s (%llu rounds)%s: %llu invalid, %llu not covered, %llu cheap constraint, "
                "%llu loop, %llu simulation, %llu feasible\n",
                (unsigned long long)r.evaluations, r.seconds, (unsigned long long)r.rounds,
                r.budget_time ? ", stopped by the time budget" : "", (unsigned long long)r.stages.invalid,
                (unsigned long long)r.stages.not_covered, (unsigned long long)r.stages.cheap,
                (unsigned long long)r.stages.loop, (unsigned long long)r.stages.simulation,
                (unsigned long long)r.stages.feasible);
    std::printf("  %llu evaluations, %llu distinct (the cache answered %llu requests without evaluating)\n",
                (unsigned long long)r.evaluations, (unsigned long long)r.distinct, (unsigned long long)r.cache_hits);
    std::printf("  front: %zu designs; hypervolume %s (normalised)\n", r.front.size(),
                r.hypervolume.empty() ? "-" : fixed(r.hypervolume.back().second).c_str());
    if (whole) {
      if (r.chosen) {
        std::printf("  chosen (%s%s):\n", s.choose.c_str(), r.polished ? ", polished" : "");
        std::printf("    %-28s %14s %14s\n", "", "given", "chosen");
        for (const auto& row : rows) std::printf("    %-28s %14s %14s\n", row[0].c_str(), row[1].c_str(), row[2].c_str());
      } else {
        std::printf("  no feasible design: every candidate was rejected (see candidates.csv)\n");
      }
      for (const Json& a : r.atlases) {
        std::printf("  atlas of station %s: see atlas-%s.svg\n", a["station"].get<std::string>().c_str(),
                    a["station"].get<std::string>().c_str());
      }
      if (check) {
        for (const auto& p : check->products) {
          if (p.state != ProductOutcome::State::built) continue;
          std::printf("  re-check %-10s %s: %s\n", p.name.c_str(), p.passed ? "passed" : "FAILED", p.check.c_str());
        }
      }
    }
    for (const auto& f : r.files) std::printf("  wrote %s\n", f.generic_string().c_str());
  }
  if (r.interrupted) {
    std::fprintf(stderr, "fivebar optimize: interrupted after %llu candidates; continue with --resume\n",
                 (unsigned long long)r.evaluations);
    return 130;
  }
  if (!whole) return kOk;
  if (!r.chosen) return kCheckFailed;
  if (check) {
    for (const auto& p : check->products) {
      if (p.state == ProductOutcome::State::built && !p.passed) return kCheckFailed;
    }
  }
  return kOk;
}

}  // namespace

void setup_optimize(CLI::App& app) {
  auto [sub, opt] = add_command<OptimizeCliOptions>(
      app, "optimize",
      "Optimise the design's numbers (optimize: section) with pagmo2 islands and an NLopt polish: Pareto front, chosen "
      "design re-checked, plots",
      run_optimize_cmd);
  add_design_argument(*sub, opt->design);
  add_out_option(*sub, opt->out, "the front, the chosen design, its re-check and the plots", "optimize");
  sub->add_option("--evaluations", opt->evaluations, "Budget of candidates (default: optimize.evaluations)");
  sub->add_option("--seconds", opt->seconds, "Wall-time budget, checked between rounds (default: optimize.seconds)")->type_name("S");
  sub->add_option("--seed", opt->seed, "Seed (default: optimize.seed)");
  sub->add_option("--threads", opt->threads, "Worker threads (default: every core; the result does not depend on it)");
  sub->add_option("--shard", opt->shard, "Run shard K of N (0-based K/N): islands K, K+N, ...; merge with --merge N")->type_name("K/N");
  sub->add_option("--merge", opt->merge, "Merge the fronts of N finished shards in the output directory")->type_name("N");
  sub->add_flag("--resume", opt->resume, "Continue from the output directory's checkpoint");
  sub->add_flag("--no-plots", opt->no_plots, "Skip the SVG/PNG plots");
  sub->add_flag("--no-polish", opt->no_polish, "Skip the NLopt polish of the chosen design (optimize.polish: false)");
  sub->add_flag("--no-atlas", opt->no_atlas, "Skip the performance atlas of each optimised station (optimize.atlas: false)");
  sub->add_flag("--no-check", opt->no_check, "Skip the re-check of the chosen design (the coverage, collision and pattern products, and its loop and simulated figures beside the given design's)");
  add_json_flag(*sub, opt->json);
  sub->footer(exit_status({.ok = "a design chosen and its re-check passed (or a shard finished)",
                           .failed = "no design chosen or its re-check failed",
                           .writes = true,
                           .resumable = true}));
}

}  // namespace fivebar::cli
