#pragma once
/// The stability of one mechanism's sampled loop over a set of poses (fivebar/control/loop.hpp
/// gives the loop): its map over the target, its field over the reachable region, and its picture.
///
/// Stability map: rho at every pose of a grid over the filled target ellipse (or over the whole
/// reachable region, as a field): the verdict is max rho < 1, the worst pose is the argmax. Gain
/// margins: the largest factor f on every joint's kp (others fixed) with max rho < 1 over the
/// poses, found by bracketing and bisection (likewise kd).

#include <cstdint>
#include <string>
#include <vector>

#include "fivebar/control/loop.hpp"
#include "fivebar/json.hpp"
#include "fivebar/rendered_plot.hpp"

namespace fivebar {

struct StabilityOptions {
  int grid = 41;            ///< per axis over the target ellipse's box (~1,300 points inside)
  bool margins = true;      ///< bisect the kp and kd margins
  double margin_cap = 1e3;  ///< factors searched up to this
  double margin_rel_tol = 1e-3;
};

/// The stability of one mechanism's loop over a set of poses.
struct StabilityMap {
  std::string station, mechanism;
  std::vector<PoseLoop> poses;     ///< in the order of the points given
  std::size_t not_ok = 0;          ///< poses unreachable or singular (no verdict there)
  std::size_t worst = 0;           ///< index of the largest rho among the ok poses
  double max_rho = 0.0;
  bool stable = false;             ///< max rho < 1 over every ok pose, and at least one ok pose
  double damping = 1.0;            ///< of the dominant pole at the worst pose
  double frequency_hz = 0.0;
  /// The least damped oscillatory pole over the poses (LoopPoles), and where.
  double oscillatory_damping = 1.0;
  double oscillatory_frequency_hz = 0.0;
  Vec2 oscillatory_P_mm{0.0, 0.0};
  /// Largest factor on both joints' kp (resp. kd) keeping max rho < 1 over the poses (the others
  /// at their values); 0 when the loop is unstable at factor 0 too; margin_cap when still stable there.
  double kp_margin = 0.0, kd_margin = 0.0;
  Vec2 worst_P_mm() const { return poses.empty() ? Vec2(0.0, 0.0) : poses[worst].P_mm; }
};

/// max rho over `poses` with `gains` (early exit once a pose reaches `stop_at`).
double max_spectral_radius(const std::vector<PoseLoop>& poses, const std::array<PidGains, 2>& gains, bool delay,
                           double stop_at = 1.0e300);

/// The map of `loop` at `points` (mm).
StabilityMap stability_map(const LoopModel& loop, const std::vector<Vec2>& points, const StabilityOptions& options = {});
/// The same from poses already linearised and discretised (pose_loop() of `loop`'s model at each
/// point, any gains): only the poles are recomputed with `loop.gains`, so the result equals
/// stability_map() at those points without linearising again.
StabilityMap stability_map(const LoopModel& loop, const std::vector<PoseLoop>& linearised,
                           const StabilityOptions& options = {});

/// rho over the reachable region: a grid over the mechanism's reach (the intersection of its
/// legs' outer circles, plus a cell), rho where the working-mode IK is ok and within the joint
/// limits, NaN elsewhere (status says why).
struct RhoField {
  Grid grid;
  std::vector<double> rho;           ///< row-major (j * nx + i)
  std::vector<std::uint8_t> status;  ///< Status of the pose (as std::uint8_t); 255 outside the joint limits
};
RhoField rho_field(const LoopModel& loop, int cells_per_axis);

/// JSON of a map (units at the edges; poses not listed).
Json to_json(const StabilityMap& map);

/// The `.vti` document (ParaView image data) of a field: point data `rho` and `status`.
std::string rho_field_vti(const RhoField& field);

/// The picture of a station's maps (one panel per mechanism, `fields[k]` for `maps[k]`): rho over
/// the reachable region on the viridis map (red where >= 1), the target ellipse dashed, the worst
/// pose on it marked, and the verdict, damping and margins below (house style, lib/src/plot/).
RenderedPlot stability_plot(const Station& station, const std::vector<StabilityMap>& maps,
                            const std::vector<RhoField>& fields, const std::string& subtitle);

}  // namespace fivebar
