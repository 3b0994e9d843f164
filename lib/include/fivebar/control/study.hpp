#pragma once
/// A station's controller study: the `control` subcommand and product (stability maps, fields and
/// performance of every mechanism).

#include <string>
#include <vector>

#include "fivebar/control/performance.hpp"
#include "fivebar/control/stability.hpp"
#include "fivebar/json.hpp"

namespace fivebar {

// --- A station's study (the `control` subcommand and product) ----------------------------------

struct ControlOptions {
  StabilityOptions stability;
  int field_cells = 81;  ///< per axis over each mechanism's reach, for the field
  int performance_grid = 15;  ///< per axis over the target, for the bandwidth, resolution, force, Z-width
};

/// Every mechanism of a station: its map over the target and its field over the reachable region.
struct StationControl {
  std::string station;
  std::vector<StabilityMap> maps;  ///< lower first
  std::vector<RhoField> fields;    ///< as maps
  std::vector<PerformanceMap> performance;  ///< as maps
  bool stable() const;             ///< every map stable
};

StationControl station_control(const Design& design, const Station& station,
                               const std::map<std::string, MechanismInertia>& inertia,
                               const ControlOptions& options = {});

/// The files of a station's study, as (name, bytes): `<station>-stability.svg` and `.png` (the
/// picture), `<station>-<mechanism>-rho.vti` (the field, ParaView), `<station>-stability.csv`
/// (every target pose: station,mechanism,x_mm,y_mm,status,rho,damping,frequency_hz) and
/// `<station>-performance.csv` (every pose of the performance grid: station,mechanism,x_mm,y_mm,
/// status,bandwidth_hz,resolution_um_per_count,force_every_direction_N,tactor_damping_N_s_per_mm,
/// zwidth_N_per_mm,coulomb_friction_N,position_quantum_um,zwidth_quantisation_N_per_mm,
/// zwidth_abbott_okamura_N_per_mm,loop_rate_for_target_hz; the last empty where the quantisation
/// forbids the target stiffness).
std::vector<std::pair<std::string, std::string>> control_files(const StationControl& study, const Station& station,
                                                               const std::string& subtitle);

/// {"station", "stable", "mechanisms": [to_json(map) ...], "performance": [to_json(performance) ...]}.
Json to_json(const StationControl& study);

/// One summary line per mechanism: "index lower: stable over the target, max rho 0.8731 at
/// (6.25, 18.10) mm (1313 poses); dominant pole damping 0.412 at 5.21 Hz; margins kp x2.31, kd x4.50",
/// then one performance_line() per mechanism.
std::vector<std::string> summary_lines(const StationControl& study);

}  // namespace fivebar
