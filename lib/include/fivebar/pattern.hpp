#pragma once
/// Skin-deformation patterns for the two tactors of a station (paper Sec. IV-A, Fig. 6: stretching,
/// slipping, twisting) and pivoting (Sec. IV-B: the tactors track two points of the rotating
/// object), sampled at the controller rate and checked sample by sample: reachable in the working
/// mode, non-singular, on the design's assembly side, within the joint limits, LCI >= min_lci,
/// collision-free with the paper's priority rule applied, and motor speeds within the limit.
///
/// Paths (c = centre, s = separation_mm, a = amplitude_mm, T = duration_s, ramp
/// u(t) = (1 - cos(pi t / T)) / 2, which starts and ends at rest):
///   stretch: upper c + (0, s/2) + (a u, 0), lower c - (0, s/2) - (a u, 0): the tactors start one
///            above the other at the centre, as close as `s` says, and move apart horizontally;
///   slip:    upper c + (0, s/2 + a/2 - a u), lower c + (0, -s/2 + a/2 - a u): both start in the
///            upper region and move down together by a;
///   twist:   both on the circle of diameter s about c, upper on top and lower at the bottom,
///            turned counter-clockwise by the angle (a u) / (s/2) (a is the arc length);
///   pivot:   contact points p_up, p_low (relative to c; default (0, +-s/2)) of an object turning
///            about c by phi(t) = amplitude sin(2 pi f t).

#include <array>
#include <cstdint>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/collision.hpp"
#include "fivebar/design.hpp"
#include "fivebar/rendered_plot.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/json.hpp"
#include "fivebar/kinematics.hpp"

namespace fivebar {

/// Targets of both tactors over time, before any check.
struct PatternPath {
  PatternKind kind = PatternKind::stretch;
  Vec2 centre{0.0, 0.0};
  std::vector<double> time_s;
  std::vector<Vec2> upper;  ///< mm
  std::vector<Vec2> lower;
};

/// The path of `spec` (formulas above) at t = k / rate_hz, k = 0 ... spec.samples() - 1 (up to
/// duration_s inclusive when duration * rate is whole); `default_centre` is used when spec.centre
/// is not set (the station's target centre).
PatternPath pattern_path(const PatternSpec& spec, const Vec2& default_centre);

/// What a sample of one mechanism is, worst first when several apply.
enum class SampleStatus : std::uint8_t {
  ok = 0,
  unreachable,            ///< the point is outside the working-mode workspace
  singular,               ///< type I or type II singularity
  wrong_assembly,         ///< on the other side of the distal links than the design's assembly mode
  outside_joint_limits,
  no_collision_free_point,  ///< lower: collides and no free point exists
  collision_moved,        ///< lower: collided; the priority rule moved it (see moved_mm)
  low_lci,                ///< LCI below the mechanism's min_lci
  too_fast,               ///< a motor would exceed max_joint_speed since the previous sample
};
std::string_view to_string(SampleStatus status);

struct TactorSample {
  Vec2 target{0.0, 0.0};  ///< the pattern's point
  Vec2 point{0.0, 0.0};   ///< commanded point: the target, or where the priority rule moved it
  Pose pose;              ///< IK at `point` in the working mode
  SampleStatus status = SampleStatus::ok;
  std::array<double, 2> theta{0.0, 0.0};        ///< continuous (unwrapped) motor angles, rad
  std::array<double, 2> joint_speed{0.0, 0.0};  ///< |dtheta/dt| from the previous sample, rad/s
};

struct PatternSample {
  double time_s = 0.0;
  TactorSample upper, lower;
  /// Clearance of the requested targets (mm), when both poses exist; the commanded pair's after
  /// the priority rule in `commanded_clearance_mm`.
  std::optional<double> clearance_mm;
  std::optional<double> commanded_clearance_mm;
  std::string closest_pair;  ///< e.g. "upper.L3 vs lower.L3" at the requested targets
  double moved_mm = 0.0;     ///< how far the priority rule moved the lower target
};

/// The first sample that fails, if any.
struct PatternFailure {
  std::size_t index = 0;
  double time_s = 0.0;
  std::string mechanism;  ///< "upper" or "lower"
  SampleStatus status = SampleStatus::ok;
  std::string reason;     ///< one line
};

struct PatternResult {
  std::string station;
  PatternSpec spec;
  Vec2 centre{0.0, 0.0};
  double max_joint_speed = 0.0;  ///< rad/s, the limit checked against
  std::vector<PatternSample> samples;
  bool passed = false;
  std::optional<PatternFailure> first_failure;
  // Worst margins over every sample (of the commanded points).
  std::array<double, 2> min_lci{1.0, 1.0};           ///< {upper, lower}
  std::array<double, 2> min_type1_distance_mm{0.0, 0.0};
  double min_clearance_mm = 0.0;            ///< of the requested targets (before the rule)
  double min_commanded_clearance_mm = 0.0;  ///< after the rule
  double max_moved_mm = 0.0;
  std::size_t moved_samples = 0;
  double peak_joint_speed = 0.0;  ///< rad/s
  std::string peak_joint_motor;   ///< e.g. "upper theta1"
  double peak_joint_time_s = 0.0;
  /// Number of mechanism samples per status (index = SampleStatus).
  std::array<std::size_t, 9> status_counts{};
};

/// The pattern of `kind` a design gives `station`: its own entry under `patterns:` (the station's,
/// else the top-level one), else the defaults of PatternSpec at the section's rate (pivot: 2 s).
/// What `fivebar pattern` checks before its command-line overrides, and the studio plays.
PatternSpec pattern_spec(const Design& design, const Station& station, PatternKind kind);

/// Generates and checks `spec` on a station with both mechanisms (InputError otherwise).
/// `max_joint_speed` in rad/s.
PatternResult check_pattern(const Station& station, const Geometry& g, const PatternSpec& spec, double max_joint_speed,
                            const PriorityOptions& priority = {});

/// Header of the trajectory CSV.
extern const char* const kTrajectoryHeader;
/// Joint trajectories of the four motors: two rows per sample (upper, lower):
/// time_s,station,mechanism,theta1_deg,theta2_deg,x_mm,y_mm,status,target_x_mm,target_y_mm,lci.
/// Angles are continuous from a first value in (-180, 180]; x, y are the commanded tactor point
/// (FK of the angles); angles and lci are empty when the point is unreachable.
void write_trajectory_csv(std::ostream& out, const PatternResult& result);

/// Summary with units at the edges: spec, verdict, worst margins, first failure; with
/// `samples` also every sample.
Json to_json(const PatternResult& result, bool samples = false);

/// Paths of the patterns of one station over its workspace: one panel per result, with the
/// reachable regions, the target ellipse, both tactor paths, the links at the start and end, moved
/// and failing samples marked.
RenderedPlot plot_patterns(const Station& station, const Geometry& g, const std::vector<PatternResult>& results);

}  // namespace fivebar
