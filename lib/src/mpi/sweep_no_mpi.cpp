// Built when FIVEBAR_WITH_MPI is off: sweeps run serially or by --shard only.
#include <cstdlib>
#include <stdexcept>

#include "fivebar/sweep.hpp"

namespace fivebar {

bool built_with_mpi() { return false; }

SweepResult run_sweep_mpi(const Design&, const SweepOptions&) {
  throw std::runtime_error("this fivebar was built without MPI (configure with -DFIVEBAR_WITH_MPI=ON)");
}

}  // namespace fivebar
