#pragma once
/// Interference of the two mechanisms of a station (paper Sec. II-D: "the collision is detected
/// by mesh overlapping; the upper mechanisms are given higher priority").
///
/// Physical model (design file `geometry:`). Every part is a union of capsules (a segment and a
/// radius; a zero-length segment is a disk) in one plane; parts of the two mechanisms interfere
/// only when they share a plane:
///   - link L_i, in plane layers[i]: the capsule of its centre line, radius link_width[i]/2,
///     plus disks of radius boss_diameter/2 at both joint ends when the boss is the wider;
///   - the pin of an elbow (A1: L1-L3, A2: L2-L4) or of the tactor joint P (L3-L4): a disk of
///     pin_diameter in every plane strictly between the planes of the two links it joins;
///   - the motor shaft at a base joint O_i: a disk of motor_shaft_diameter in every plane below
///     the plane of L1 / L2 (the motors sit under plane 0);
///   - the tactor post: a disk of pin_diameter in every link plane above the joint P (the P pin
///     rises through them to carry the tactor);
///   - the tactor: a disk of tactor_diameter in the tactor plane, one above the top link plane
///     (tactor_plane()): the tactors stand tactor_height above the links, so a tactor meets only
///     the other tactor there.
/// Clearances are exact Euclidean distances between capsules (segment-segment distance minus
/// both radii; no sampling); a pair of parts collides when its clearance is below
/// geometry.min_clearance.

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/rendered_plot.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/json.hpp"
#include "fivebar/kinematics.hpp"

namespace fivebar {

// --- Capsules -----------------------------------------------------------------------------------

/// Points within `radius` (mm) of the segment [a, b]; a == b gives a disk.
struct Capsule {
  Vec2 a{0.0, 0.0};
  Vec2 b{0.0, 0.0};
  double radius = 0.0;
};

/// Distance between two closed segments and a pair of closest points.
struct SegmentDistance {
  double distance = 0.0;
  Vec2 on_first{0.0, 0.0};
  Vec2 on_second{0.0, 0.0};
};

/// Euclidean distance between the closed segments [p0, p1] and [q0, q1] (either may be a point).
/// Crossing segments (opposite orientation signs on both sides) are at distance 0; otherwise the
/// minimum is attained at an endpoint, so it is the smallest of the four clamped endpoint-to-segment
/// distances. Parallel, collinear and touching segments need no special case. Symmetric in its
/// arguments up to rounding of a few ulps of the coordinates.
SegmentDistance segment_distance(const Vec2& p0, const Vec2& p1, const Vec2& q0, const Vec2& q1);

/// Clearance between two capsules (mm): segment distance minus both radii; negative = overlap depth.
/// `on_a`, `on_b` receive the closest points of the two centre segments.
double capsule_clearance(const Capsule& a, const Capsule& b, Vec2* on_a = nullptr, Vec2* on_b = nullptr);

// --- Outlines -----------------------------------------------------------------------------------

/// One part of a mechanism in one plane: a union of up to three capsules.
struct OutlinePart {
  std::string_view name;  ///< "L1" ... "L4", "pin A1", "pin A2", "pin P", "shaft O1", "shaft O2", "post P", "tactor"
  int plane = 0;          ///< link plane (geometry.layers), or tactor_plane() for the tactor disk
  std::array<Capsule, 3> shapes{};
  int count = 0;  ///< shapes used
  Vec2 box_lo{0.0, 0.0};  ///< bounding box of the shapes (radii included), set by link_outline
  Vec2 box_hi{0.0, 0.0};
};

/// Plane of the tactor disks: one above the highest link plane.
int tactor_plane(const Geometry& g);

/// Outline of `m` in `pose` (mm). Throws InputError for an unreachable pose (it has no configuration).
std::vector<OutlinePart> link_outline(const Mechanism& m, const Pose& pose, const Geometry& g);

// --- Interference -------------------------------------------------------------------------------

/// Clearance between a part of the upper and a part of the lower mechanism in one plane.
struct PairClearance {
  std::string_view upper_part;  ///< e.g. "L3"
  std::string_view lower_part;  ///< e.g. "L4"
  int plane = 0;
  double clearance_mm = 0.0;  ///< negative: overlap depth
  Vec2 upper_point{0.0, 0.0};  ///< closest points of the two parts' centre lines
  Vec2 lower_point{0.0, 0.0};
  /// "upper.L3 vs lower.L4"
  std::string name() const;
};

/// The closest pair of one plane that both mechanisms occupy.
struct PlaneClearance {
  int plane = 0;
  bool tactor = false;  ///< the tactor plane
  PairClearance closest;
};

struct Interference {
  bool collides = false;          ///< some pair is closer than geometry.min_clearance
  double min_clearance_mm = 0.0;  ///< over every shared plane
  PairClearance closest;          ///< the pair realising it
  std::vector<PairClearance> colliding;  ///< every part pair below min_clearance, worst first
  std::vector<PlaneClearance> planes;    ///< each plane both occupy, in plane order
  double required_mm = 0.0;              ///< geometry.min_clearance
};

/// Exact interference of the upper mechanism in `upper_pose` with the lower one in `lower_pose`.
/// Both poses must exist (status other than unreachable; InputError otherwise).
Interference interference(const Mechanism& upper, const Pose& upper_pose, const Mechanism& lower,
                          const Pose& lower_pose, const Geometry& g);

/// Smallest clearance between two outlines over shared planes (mm); +infinity when none is shared.
/// Stops early, returning a value below `stop_below`, as soon as one pair is closer than it.
double min_clearance(const std::vector<OutlinePart>& upper, const std::vector<OutlinePart>& lower,
                     double stop_below = -1e300);

/// True when some pair of parts in a shared plane is closer than `threshold` (mm); the same verdict
/// as min_clearance(upper, lower) < threshold, faster: part pairs whose bounding boxes are disjoint
/// and at least `threshold` apart are skipped (their clearance is at least the boxes' distance).
bool outlines_collide(const std::vector<OutlinePart>& upper, const std::vector<OutlinePart>& lower, double threshold);

/// A pose the device can hold: it exists, is not singular, is within the joint limits and on the
/// design's assembly side.
bool usable(const Mechanism& m, const Pose& pose);

// --- Priority rule ------------------------------------------------------------------------------

/// Search settings of apply_priority(). Lengths relative to the lower mechanism's length scale.
struct PriorityOptions {
  int rays = 256;               ///< directions of the ring search
  double step_rel = 0.01;       ///< ring spacing / length scale
  double tolerance_rel = 2e-5;  ///< accuracy of the moved distance / length scale
  int refine_candidates = 8;    ///< rays refined in angle after the ring search
};

enum class PriorityStatus : std::uint8_t {
  clear,           ///< the targets do not collide: both kept
  moved,           ///< collision: the lower target moved to the closest collision-free point
  upper_unusable,  ///< the upper target cannot be held (unreachable, singular, outside limits)
  lower_unusable,  ///< the lower target cannot be held; nothing to move
  no_free_point,   ///< collision and no collision-free point within the lower's reach
};
std::string_view to_string(PriorityStatus status);

struct PriorityResult {
  PriorityStatus status = PriorityStatus::clear;
  Vec2 upper_target{0.0, 0.0};
  Vec2 lower_target{0.0, 0.0};
  Pose upper;               ///< IK at upper_target: always the upper mechanism's solution
  Vec2 lower_point{0.0, 0.0};  ///< commanded lower tactor point (lower_target unless moved)
  Pose lower;               ///< IK at lower_point
  double moved_mm = 0.0;    ///< |lower_point - lower_target|
  std::optional<Interference> before;  ///< at the requested targets, when both poses exist
  std::optional<Interference> after;   ///< at the commanded pair, when both poses exist
  std::string reason;       ///< one line: what happened
};

/// The paper's priority rule: the upper mechanism keeps its IK solution; when the lower collides
/// with it, the lower target is replaced by the closest point the lower mechanism can hold without
/// collision ("the closest location in the border of the upper mechanism").
///
/// Search: rings of radius k*h (h = step_rel * scale) around the lower target, `rays` points per
/// ring, until a ring holds a collision-free usable point; every ray found free on that ring or the
/// next is bisected between its last blocked and first free ring, and the best `refine_candidates`
/// are refined by golden-section search over the ray angle (each evaluation bisected to
/// tolerance_rel * scale). The returned point is always on the free side of its bracket, so
/// after->collides is false; its distance exceeds the true minimum by at most the tolerance unless
/// a free pocket is thinner than the ring and ray spacing.
PriorityResult apply_priority(const Mechanism& upper, const Mechanism& lower, const Geometry& g,
                              const Vec2& upper_target, const Vec2& lower_target,
                              const PriorityOptions& options = {});

// --- Collision map ------------------------------------------------------------------------------

struct CollisionMapOptions {
  double spacing_mm = 0.75;  ///< grid spacing of the tactor positions in the target ellipse
  /// Called now and then with (upper positions done, total), e.g. for a progress line; may be empty.
  std::function<void(std::size_t, std::size_t)> progress;
};

/// Fraction of pairs that collide among pairs whose separation falls in [lo, hi).
struct SeparationBin {
  double lo_mm = 0.0, hi_mm = 0.0;
  std::size_t pairs = 0, colliding = 0;
};

/// Every pair (upper position, lower position) of grid points inside the target ellipse.
struct CollisionMap {
  std::string station;
  Ellipse target;
  double spacing_mm = 0.0;
  std::vector<Vec2> points;            ///< grid points inside the filled ellipse
  std::vector<std::uint8_t> upper_ok;  ///< usable by the upper mechanism
  std::vector<std::uint8_t> lower_ok;
  std::size_t pairs = 0;      ///< pairs with both positions usable
  std::size_t colliding = 0;
  double colliding_fraction = 0.0;
  bool any_free = false;
  double min_free_separation_mm = 0.0;   ///< closest tactors of a collision-free pair
  std::array<Vec2, 2> min_free_pair{};   ///< {upper, lower}
  bool any_colliding = false;
  double max_colliding_separation_mm = 0.0;  ///< every pair farther apart than this is free
  std::array<Vec2, 2> max_colliding_pair{};
  std::vector<double> upper_fraction;  ///< per point: fraction of usable lower points colliding with it
  std::vector<double> lower_fraction;  ///< per point: fraction of usable upper points colliding with it
  std::vector<std::uint8_t> centre_collides;  ///< per point: lower there collides with the upper at the centre (2 = unusable)
  std::vector<SeparationBin> bins;     ///< by tactor separation, 0.5 mm wide
  /// The priority rule with both targets at the ellipse centre (the paper's worst case).
  PriorityResult centre_rule;
};

/// Samples the collision map of a station with both mechanisms (InputError otherwise).
CollisionMap collision_map(const Station& station, const Geometry& g, const CollisionMapOptions& options = {});

/// Grid points of spacing `spacing_mm` inside the filled target ellipse, on a square grid centred
/// on the ellipse centre (the centre is a sample); row by row from the bottom. InputError for a
/// spacing that is not positive or finer than 1/800 of the larger axis.
std::vector<Vec2> ellipse_grid(const Ellipse& e, double spacing_mm);

/// The colliding fraction of a collision map alone (no per-point arrays, bins or priority rule):
/// what a sweep records per design. Same grid, same usable-pose rule, same verdict per pair.
struct CollisionFraction {
  std::size_t points = 0;        ///< grid points in the ellipse
  std::size_t pairs = 0;         ///< pairs with both positions usable
  std::size_t colliding = 0;
  double fraction = 0.0;         ///< colliding / pairs (0 when there are no pairs)
};
CollisionFraction collision_fraction(const Station& station, const Geometry& g, double spacing_mm);

// --- Output -------------------------------------------------------------------------------------

/// Three panels: the fraction of lower positions colliding per upper position, the lower positions
/// blocked by the upper tactor at the centre (with its links), and the colliding fraction against
/// the tactor separation.
RenderedPlot plot_collision_map(const Station& station, const Geometry& g, const CollisionMap& map);

/// JSON with units at the edges (clearances in mm, points [x, y] in mm).
Json to_json(const PairClearance& pair);
Json to_json(const Interference& interference);
Json to_json(const PriorityResult& result);
/// Summary of a collision map (numbers and bins; not the per-point arrays).
Json to_json(const CollisionMap& map);

}  // namespace fivebar
