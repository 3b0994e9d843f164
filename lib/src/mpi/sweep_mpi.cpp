// MPI distribution of a sweep (built when FIVEBAR_WITH_MPI): rank r runs shard r/R of the index
// range into its own CSV; rank 0 then concatenates the shards in rank order (the same rows as a
// serial run, row for row), merges their Pareto sets and writes the best design. The ranks share
// the output directory (a shared file system on a cluster).
#include <mpi.h>

#include <cstdlib>
#include <fstream>

#include "fivebar/io.hpp"
#include "fivebar/sweep.hpp"
#include "mpi/mpi_session.hpp"

namespace fivebar {

bool built_with_mpi() { return true; }

SweepResult run_sweep_mpi(const Design& design, const SweepOptions& options) {
  const detail::MpiSession mpi;
  const int rank = mpi.rank(), size = mpi.size();

  SweepOptions mine = options;
  mine.shard = std::uint64_t(rank);
  mine.shards = std::uint64_t(size);
  mine.plots = false;
  mine.resume = false;
  if (rank != 0) mine.progress = nullptr;
  SweepResult local;
  bool failed = false;
  std::string error;
  try {
    local = run_sweep(design, mine);
  } catch (const std::exception& e) {
    failed = true;
    error = e.what();
  }
  mpi.all_succeeded(failed, error);
  unsigned long long counts[4] = {local.evaluated, local.covered, local.invalid, local.interrupted ? 1ull : 0ull};
  unsigned long long sums[4] = {0, 0, 0, 0};
  MPI_Reduce(counts, sums, 4, MPI_UNSIGNED_LONG_LONG, MPI_SUM, 0, MPI_COMM_WORLD);
  double seconds = local.seconds, max_seconds = 0.0;
  MPI_Reduce(&seconds, &max_seconds, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD);
  MPI_Barrier(MPI_COMM_WORLD);  // every shard file is complete
  if (rank != 0) {
    MPI_Barrier(MPI_COMM_WORLD);
    return local;
  }

  const SweepSettings& s = *design.get<SweepSettings>();
  SweepResult merged;
  merged.total = sweep_size(s);
  merged.evaluated = sums[0];
  merged.covered = sums[1];
  merged.invalid = sums[2];
  merged.interrupted = sums[3] > 0;
  merged.seconds = max_seconds;
  merged.designs_per_s = max_seconds > 0 ? double(merged.evaluated) / max_seconds : 0.0;
  merged.csv = options.out_dir / "sweep.csv";
  ParetoArchive archive(s.objectives);
  std::optional<SweepRow> best;
  {
    AtomicFile csv(merged.csv);
    csv.stream() << sweep_csv_header(s) << '\n';
    for (int r = 0; r < size; ++r) {
      const auto part = options.out_dir /
                        ("sweep.shard-" + std::to_string(r) + "-of-" + std::to_string(size) + ".csv");
      read_sweep_csv(part, s, [&](const SweepRow& row, const std::string& line) {
        csv.stream() << line << '\n';
        archive.insert(row);
        ++merged.done;
      });
      std::filesystem::remove(part);
      std::filesystem::remove(options.out_dir /
                              ("pareto.shard-" + std::to_string(r) + "-of-" + std::to_string(size) + ".csv"));
      std::filesystem::remove(options.out_dir /
                              ("best.shard-" + std::to_string(r) + "-of-" + std::to_string(size) + ".yaml"));
    }
    csv.commit();
  }
  merged.files.push_back(merged.csv);
  merged.pareto = archive.rows();
  // The best row is re-derived from the merged stream by a serial run's rule (lexicographic).
  for (const SweepRow& row : merged.pareto) {
    bool better = !best;
    if (best) {
      for (const std::string& o : s.objectives) {
        if (row.score(o) != best->score(o)) {
          better = row.score(o) > best->score(o);
          break;
        }
      }
    }
    if (better) best = row;
  }
  {
    std::string text = sweep_csv_header(s) + "\n";
    for (const SweepRow& r : merged.pareto) text += sweep_csv_row(r) + "\n";
    write_file_atomic(options.out_dir / "pareto.csv", text);
    merged.files.push_back(options.out_dir / "pareto.csv");
  }
  if (best) {
    merged.best = best;
    Design d = design;
    const Station st = apply_sweep(design, s, best->values);
    for (Station& x : d.stations) {
      if (x.name == st.name) x = st;
    }
    d.reset<SweepSettings>();
    d.products.reset();
    // Its own name, so that `fivebar run best.yaml` does not overwrite the swept design's outputs.
    d.name = design.name.substr(0, 59) + "-best";
    merged.best_design = d;
    write_file_atomic(options.out_dir / "best.yaml",
                      "# Best design of the sweep (MPI run, " + std::to_string(size) + " ranks), design #" +
                          std::to_string(best->index) + ".\n" + to_yaml(d));
    merged.files.push_back(options.out_dir / "best.yaml");
  }
  if (options.plots) {
    for (const auto& f : write_sweep_plots(merged.csv, s, merged.pareto, options.out_dir)) merged.files.push_back(f);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  return merged;
}

}  // namespace fivebar
