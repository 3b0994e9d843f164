#pragma once
/// Controller validation and tuning, one header per job (docs/architecture.md):
///   fivebar/control/loop.hpp         the sampled-data loop of one mechanism: linearised plant, exact
///                                    ZOH discretisation, closed loop with the exported PID, poles
///   fivebar/control/stability.hpp    spectral radius over the target (map), the reachable region
///                                    (field), gain margins, and the picture
///   fivebar/control/performance.hpp  bandwidth, resolution, force and Z-width over the target
///   fivebar/control/study.hpp        a station's study (the `control` subcommand and product)
///   fivebar/control/tune.hpp         tuning of the gains under damping, margin and step floors

#include "fivebar/control/loop.hpp"
#include "fivebar/control/performance.hpp"
#include "fivebar/control/stability.hpp"
#include "fivebar/control/study.hpp"
#include "fivebar/control/tune.hpp"
