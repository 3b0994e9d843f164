// fivebar sweep: link-dimension sweeps (grid / random / Sobol), parallel, resumable, shardable and
// distributable with MPI; CSV, Pareto set, best design, plots.

#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>

#include "common.hpp"
#include "fivebar/io.hpp"
#include "fivebar/sweep.hpp"

namespace fivebar::cli {

namespace {

struct SweepCliOptions {
  std::string design;
  std::string station;
  std::string mechanism;
  std::vector<std::string> vary;
  std::string sample;
  std::uint64_t count = 0;
  std::uint64_t seed = 0;
  bool seed_set = false;
  std::vector<std::string> objectives;
  std::optional<double> collision_spacing;
  std::string out;
  std::string shard;
  bool resume = false;
  bool yes = false;
  bool no_plots = false;
  int threads = 0;
  bool json = false;
};


/// NAME=LO:HI:N -> SweepVariable (N optional for random/Sobol sampling: 1).
SweepVariable parse_vary(const std::string& text) {
  const auto eq = text.find('=');
  auto bad = [&] {
    throw InputError("--vary '" + text + "': expected NAME=LO:HI:N (mm), e.g. L34=12:20:9");
  };
  if (eq == std::string::npos || eq == 0) bad();
  SweepVariable v;
  v.name = text.substr(0, eq);
  std::vector<std::string> parts;
  std::string rest = text.substr(eq + 1);
  std::size_t start = 0;
  while (true) {
    const auto c = rest.find(':', start);
    parts.push_back(rest.substr(start, c == std::string::npos ? std::string::npos : c - start));
    if (c == std::string::npos) break;
    start = c + 1;
  }
  if (parts.size() != 2 && parts.size() != 3) bad();
  const auto lo = parse_number(parts[0]), hi = parse_number(parts[1]);
  if (!lo || !hi) bad();
  v.lo = *lo;
  v.hi = *hi;
  v.n = 1;
  if (parts.size() == 3) {
    const auto n = parse_number(parts[2]);
    if (!n || *n != std::floor(*n) || *n < 1 || *n > 1e8) bad();
    v.n = int(*n);
  }
  return v;
}

/// The sweep settings: the design's `sweep:` section with the command line's values on top.
SweepSettings settings_of(const Design& design, const SweepCliOptions& o) {
  const SweepSettings* given = design.get<SweepSettings>();
  SweepSettings s = given ? *given : SweepSettings{};
  if (!o.station.empty()) s.station = o.station;
  if (s.station.empty() && design.stations.size() == 1) s.station = design.stations[0].name;
  if (!o.mechanism.empty()) s.mechanism = o.mechanism;
  if (!o.vary.empty()) {
    s.vary.clear();
    for (const auto& v : o.vary) s.vary.push_back(parse_vary(v));
  }
  if (!o.sample.empty()) s.sample = o.sample;
  if (o.count) s.count = o.count;
  if (o.seed_set) s.seed = o.seed;
  if (!o.objectives.empty()) s.objectives = o.objectives;
  if (o.collision_spacing) s.collision_spacing_mm = *o.collision_spacing;
  if (s.station.empty()) throw InputError("sweep: choose the station with --station (or a sweep: section)");
  if (s.vary.empty()) throw InputError("sweep: give at least one --vary NAME=LO:HI:N (or a sweep: section)");
  return s;
}

void progress_bar(std::uint64_t done, std::uint64_t total, double seconds) {
  const double frac = total ? double(done) / double(total) : 1.0;
  const double rate = seconds > 0 ? double(done) / seconds : 0.0;
  const double eta = rate > 0 ? double(total - done) / rate : 0.0;
  char bar[31];
  const int filled = int(frac * 30);
  for (int i = 0; i < 30; ++i) bar[i] = i < filled ? '#' : '.';
  bar[30] = '\0';
  std::fprintf(stderr, "\r[%s] %5.1f%%  %llu/%llu designs  %.0f/s  ETA %02d:%02d ", bar, 100 * frac,
               (unsigned long long)done, (unsigned long long)total, rate, int(eta) / 60, int(eta) % 60);
  if (done >= total) std::fputc('\n', stderr);
  std::fflush(stderr);
}

Json row_json(const SweepSettings& s, const SweepRow& r) {
  Json j;
  j["index"] = r.index;
  Json values = Json::object();
  for (std::size_t d = 0; d < s.vary.size(); ++d) values[s.vary[d].name + "_mm"] = r.values[d];
  j["values"] = values;
  j["status"] = r.status;
  j["covered"] = r.covered;
  auto opt = [](double v) { return std::isnan(v) ? Json(nullptr) : Json(v); };
  j["margin_lower_mm"] = opt(r.margin_lower_mm);
  j["margin_upper_mm"] = opt(r.margin_upper_mm);
  j["margin_shared_mm"] = opt(r.margin_shared_mm);
  j["min_lci"] = opt(r.min_lci);
  j["min_force_capability"] = opt(r.min_force_capability);
  j["footprint_mm"] = {opt(r.footprint_w_mm), opt(r.footprint_h_mm)};
  j["footprint_mm2"] = opt(r.footprint_mm2);
  j["collision_fraction"] = opt(r.collision_fraction);
  return j;
}

int run_sweep_cmd(const SweepCliOptions& o) {
  // An interrupt from here on stops the sweep cleanly (after its current chunk, CSV resumable);
  // one that comes before the sweep starts stops it before its first chunk.
  const StopOnInterrupt interrupt;  // SIGINT / SIGTERM: stop at the next checkpoint
  Design design = load(o.design);
  SweepSettings settings = settings_of(design, o);
  try {
    Design check = design;
    check.set<SweepSettings>(settings);
    check.validate();
  } catch (const ValidationError& e) {
    throw InputError(o.design + ": sweep (file and command line): " + e.what());
  }
  design.set<SweepSettings>(settings);
  SweepOptions options;
  options.out_dir = o.out.empty() ? std::filesystem::path("outputs") / design.name / "sweep" : std::filesystem::path(o.out);
  const WriteFence fence(options.out_dir);  // nothing of this command lands outside it (fivebar/io.hpp)
  if (!o.shard.empty()) std::tie(options.shard, options.shards) = parse_shard(o.shard);
  options.resume = o.resume;
  options.confirmed = o.yes;
  options.plots = !o.no_plots;
  if (o.threads < 0 || o.threads > kMaxSweepThreads) {
    throw InputError("--threads " + std::to_string(o.threads) + ": must be 1 ... " + std::to_string(kMaxSweepThreads) +
                     " (absent: every core)");
  }
  (void)sweep_threads(o.threads);  // OMP_NUM_THREADS too, before any file is written
  options.threads = o.threads;
  options.stop = interrupt.stop();
  const bool mpi = launched_by_mpi();
  if (mpi && !o.shard.empty()) throw InputError("--shard and an MPI launch both split the sweep: use one");
  if (mpi && o.resume) throw InputError("--resume is not supported in an MPI launch: rerun with the same ranks");
  if (::isatty(STDERR_FILENO)) options.progress = progress_bar;
  const SweepResult r = mpi ? run_sweep_mpi(design, options) : run_sweep(design, options);
  if (mpi) {
    int rank = 0;
    if (const char* v = std::getenv("OMPI_COMM_WORLD_RANK")) rank = std::atoi(v);
    if (const char* v = std::getenv("PMI_RANK")) rank = std::atoi(v);
    if (rank != 0) return kOk;
  }
  if (o.json) {
    Json doc;
    doc["command"] = "sweep";
    doc["design"] = design.name;
    doc["station"] = settings.station;
    doc["mechanism"] = settings.mechanism.empty() ? Json(nullptr) : Json(settings.mechanism);
    doc["sample"] = settings.sample;
    doc["seed"] = settings.seed;
    doc["objectives"] = settings.objectives;
    doc["designs"] = sweep_size(settings);
    doc["shard"] = {options.shard, options.shards};
    doc["first_index"] = r.first;
    doc["shard_designs"] = r.total;
    doc["rows"] = r.done;
    doc["evaluated"] = r.evaluated;
    doc["covered"] = r.covered;
    doc["invalid"] = r.invalid;
    doc["seconds"] = r.seconds;
    doc["designs_per_s"] = r.designs_per_s;
    doc["interrupted"] = r.interrupted;
    doc["mpi"] = mpi;
    doc["csv"] = r.csv.generic_string();
    Json pareto = Json::array();
    for (const auto& row : r.pareto) pareto.push_back(row_json(settings, row));
    doc["pareto"] = pareto;
    doc["best"] = r.best ? row_json(settings, *r.best) : Json(nullptr);
    Json files = Json::array();
    for (const auto& f : r.files) files.push_back(f.generic_string());
    doc["files"] = files;
    print_json(doc);
  } else {
    std::printf("sweep of %s, station %s%s: %s sampling, %llu designs%s\n", design.name.c_str(),
                settings.station.c_str(), settings.mechanism.empty() ? "" : (" / " + settings.mechanism).c_str(),
                settings.sample.c_str(), (unsigned long long)sweep_size(settings),
                options.shards > 1 ? (" (shard " + o.shard + ")").c_str() : "");
    std::printf("  evaluated %llu in %.2f s: %.0f designs/s; covered %llu, invalid %llu\n",
                (unsigned long long)r.evaluated, r.seconds, r.designs_per_s, (unsigned long long)r.covered,
                (unsigned long long)r.invalid);
    std::printf("  Pareto set over (");
    for (std::size_t i = 0; i < settings.objectives.size(); ++i) std::printf("%s%s", i ? ", " : "", settings.objectives[i].c_str());
    std::printf("): %zu designs\n", r.pareto.size());
    if (r.best) {
      std::printf("  best #%llu:", (unsigned long long)r.best->index);
      for (std::size_t d = 0; d < settings.vary.size(); ++d) {
        std::printf(" %s=%s", settings.vary[d].name.c_str(), exact(r.best->values[d]).c_str());
      }
      std::printf("  margin %s mm, min LCI %s, footprint %s mm^2", fixed(r.best->score("margin")).c_str(),
                  fixed(r.best->min_lci).c_str(), fixed(r.best->footprint_mm2, 1).c_str());
      if (!std::isnan(r.best->collision_fraction)) {
        std::printf(", %s %% of tactor pairs collide", fixed(100.0 * r.best->collision_fraction, 1).c_str());
      }
      std::printf("\n");
    } else {
      std::printf("  no design covers the target\n");
    }
    for (const auto& f : r.files) std::printf("  wrote %s\n", f.generic_string().c_str());
  }
  if (r.interrupted) {
    std::fprintf(stderr, "fivebar sweep: interrupted after %llu of %llu designs; %s holds them; continue with --resume\n",
                 (unsigned long long)r.done, (unsigned long long)r.total, r.csv.generic_string().c_str());
    return 130;
  }
  return r.best ? kOk : kCheckFailed;
}

}  // namespace

void setup_sweep(CLI::App& app) {
  auto [sub, opt] = add_command<SweepCliOptions>(
      app, "sweep", "Sweep link dimensions (grid, random, Sobol) in parallel: CSV per design, Pareto set, best design, plots",
      run_sweep_cmd);
  add_design_argument(*sub, opt->design);
  add_station_option(*sub, opt->station, "the sweep: section's, or the only one");
  sub->add_option("-m,--mechanism", opt->mechanism, "lower or upper only (default: every mechanism and the shared region)");
  sub->add_option("--vary", opt->vary,
                  "NAME=LO:HI:N (mm), repeatable; NAME in L1 L2 L3 L4 L12 L34 spacing upper_height ellipse_a "
                  "ellipse_b (L12 / L34: both links tied)")
      ->type_name("NAME=LO:HI:N");
  sub->add_option("--sample", opt->sample, "grid, random or sobol (default grid)")->check(CLI::IsMember({"grid", "random", "sobol"}));
  sub->add_option("--count", opt->count, "Designs for random / Sobol sampling");
  // An init-capture: clang 14 (the fuzz build) does not capture a structured binding.
  sub->add_option_function<std::uint64_t>("--seed", [o = opt](const std::uint64_t& v) {
    o->seed = v;
    o->seed_set = true;
  }, "Seed of random / Sobol sampling (recorded in the output)");
  sub->add_option("--collision-spacing", opt->collision_spacing,
                  "Grid spacing (mm) of the per-design collision fraction when the design has geometry: (0: off; default 2)")
      ->type_name("MM");
  sub->add_option("--objective", opt->objectives, "margin, min_lci, force, footprint, collision, robust (the margin robust_fraction of printed devices keep: tolerance:); repeatable, in priority order")
      ->delimiter(',');
  add_out_option(*sub, opt->out, "sweep.csv, pareto.csv, best.yaml and the plots", "sweep");
  sub->add_option("--shard", opt->shard, "Run shard K of N (0-based K/N): contiguous blocks of the designs")->type_name("K/N");
  sub->add_flag("--resume", opt->resume, "Continue an interrupted sweep.csv in the output directory");
  sub->add_flag("--yes", opt->yes, "Run a sweep estimated at over an hour or a gigabyte of CSV (refused otherwise)");
  sub->add_flag("--no-plots", opt->no_plots, "Skip the SVG/PNG plots");
  sub->add_option("--threads", opt->threads, "Worker threads (default: every core)");
  add_json_flag(*sub, opt->json);
  sub->footer(exit_status(
      {.ok = "a design covers the target", .failed = "no design covers the target", .writes = true, .resumable = true}));
}

}  // namespace fivebar::cli
