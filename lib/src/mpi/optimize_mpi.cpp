// MPI distribution of an optimisation (built when FIVEBAR_WITH_MPI): rank r runs shard r/R of the
// islands into its own shard file; rank 0 then merges the shards' candidates into one front
// (merge_optimize_shards). The ranks share the output directory (a shared file system on a cluster).
#include <mpi.h>

#include <stdexcept>

#include "fivebar/optimize.hpp"
#include "mpi/mpi_session.hpp"

namespace fivebar {

OptimizeResult run_optimize_mpi(const Design& design, const OptimizeOptions& options) {
  const detail::MpiSession mpi;
  const int rank = mpi.rank(), size = mpi.size();
  OptimizeOptions mine = options;
  mine.shard = std::uint64_t(rank);
  mine.shards = std::uint64_t(size);
  mine.resume = false;
  if (rank != 0) mine.progress = nullptr;
  OptimizeResult local;
  bool failed = false;
  std::string error;
  try {
    local = run_optimize(design, mine);
  } catch (const std::exception& e) {
    failed = true;
    error = e.what();
  }
  mpi.all_succeeded(failed, error);
  MPI_Barrier(MPI_COMM_WORLD);  // every shard file is complete
  if (rank != 0) return local;
  OptimizeOptions whole = options;
  whole.shard = 0;
  whole.shards = 1;
  return merge_optimize_shards(design, whole, std::uint64_t(size));
}

}  // namespace fivebar
