// Built when FIVEBAR_WITH_MPI is off: optimisations run on one machine or by --shard / --merge.
#include <stdexcept>

#include "fivebar/optimize.hpp"

namespace fivebar {

OptimizeResult run_optimize_mpi(const Design&, const OptimizeOptions&) {
  throw std::runtime_error("this fivebar was built without MPI (configure with -DFIVEBAR_WITH_MPI=ON)");
}

}  // namespace fivebar
