#pragma once
// The MPI frame shared by the sweep's and the optimiser's distributed runs (private to lib/src/mpi/):
// MPI initialised for the call unless the caller did it, finalised on every path (mpirun reports a
// rank that exits without MPI_Finalize as a failure), and one collective verdict on the ranks' work.
#include <mpi.h>

#include <stdexcept>
#include <string>

namespace fivebar::detail {

class MpiSession {
 public:
  MpiSession() {
    int initialized = 0;
    MPI_Initialized(&initialized);
    owned_ = initialized == 0;
    if (owned_) MPI_Init(nullptr, nullptr);
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  ~MpiSession() {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (owned_ && !finalized) MPI_Finalize();
  }
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  int rank() const { return rank_; }
  int size() const { return size_; }

  /// Collective: every rank says whether its part failed; when any did, every rank throws (the
  /// failed ones with their own message), so that no rank waits for a merge that will not come.
  void all_succeeded(bool failed, const std::string& error) const {
    int mine = failed ? 1 : 0, any = 0;
    MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    if (!any) return;
    if (failed) throw std::runtime_error("rank " + std::to_string(rank_) + ": " + error);
    throw std::runtime_error("another rank failed");
  }

 private:
  bool owned_ = false;
  int rank_ = 0, size_ = 1;
};

}  // namespace fivebar::detail
