// MPI distribution of an optimisation (built when FIVEBAR_WITH_MPI): rank r runs shard r/R of the
// islands into its own shard file; rank 0 then merges the shards' candidates into one front
// (merge_optimize_shards). The ranks share the output directory (a shared file system on a cluster).
#include <mpi.h>

#include <stdexcept>

#include "fivebar/optimize.hpp"

namespace fivebar {

OptimizeResult run_optimize_mpi(const Design& design, const OptimizeOptions& options) {
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (!initialized) MPI_Init(nullptr, nullptr);
  struct Finalize {
    bool owned;
    ~Finalize() {
      int finalized = 0;
      MPI_Finalized(&finalized);
      if (owned && !finalized) MPI_Finalize();
    }
  } finalize{initialized == 0};
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  OptimizeOptions mine = options;
  mine.shard = std::uint64_t(rank);
  mine.shards = std::uint64_t(size);
  mine.resume = false;
  if (rank != 0) mine.progress = nullptr;
  OptimizeResult local;
  int failed = 0;
  std::string error;
  try {
    local = run_optimize(design, mine);
  } catch (const std::exception& e) {
    failed = 1;
    error = e.what();
  }
  int any_failed = 0;
  MPI_Allreduce(&failed, &any_failed, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  if (any_failed) {
    if (failed) throw std::runtime_error("rank " + std::to_string(rank) + ": " + error);
    throw std::runtime_error("another rank failed");
  }
  MPI_Barrier(MPI_COMM_WORLD);  // every shard file is complete
  if (rank != 0) return local;
  OptimizeOptions whole = options;
  whole.shard = 0;
  whole.shards = 1;
  return merge_optimize_shards(design, whole, std::uint64_t(size));
}

}  // namespace fivebar
