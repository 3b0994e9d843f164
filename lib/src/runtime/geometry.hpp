#pragma once
// The runtime's kinematics and link outlines (private to lib/src/runtime/): the closed forms of
// fivebar/kinematics.hpp (stable circle-circle intersection, docs/conventions.md "Numerics") and
// the capsule model of fivebar/collision.hpp, restated in plain C++17 over a two-double vector so
// that the runtime builds alone. No allocation, no exception, no loop without a fixed bound.

#include <algorithm>
#include <array>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <vector>

#include "fivebar/runtime/config.hpp"

namespace fivebar::runtime::detail {

struct V2 {
  double x = 0.0, y = 0.0;
};
inline V2 operator+(V2 a, V2 b) { return {a.x + b.x, a.y + b.y}; }
inline V2 operator-(V2 a, V2 b) { return {a.x - b.x, a.y - b.y}; }
inline V2 operator*(double s, V2 a) { return {s * a.x, s * a.y}; }
inline double dot(V2 a, V2 b) { return a.x * b.x + a.y * b.y; }
inline double cross(V2 a, V2 b) { return a.x * b.y - a.y * b.x; }
inline double norm(V2 a) { return std::sqrt(a.x * a.x + a.y * a.y); }

// Tolerances as in fivebar/numerics.hpp (relative to a length scale).
inline constexpr double kEps = DBL_EPSILON;
inline constexpr double kReachRel = 16.0 * kEps;
inline constexpr double kSingularSin = 1e-7;
inline constexpr double kClosureRel = 256.0 * kEps;
inline constexpr double kCoincidentRel = 4.0 * kEps;

enum class PoseStatus : std::uint8_t { ok, unreachable, singular };

struct Pose {
  PoseStatus status = PoseStatus::unreachable;
  double theta1 = 0.0, theta2 = 0.0;
  V2 O1, O2, A1, A2, P;
  std::int8_t assembly = 0;  ///< realised sign of cross(A2 - A1, P - A1), 0 on type II
  std::array<std::int8_t, 2> mode{};
};

/// Prepared mechanism: the config's numbers as vectors.
struct Mech {
  V2 O1, O2;
  std::array<double, 4> L{};
  std::array<std::int8_t, 2> mode{};
  Assembly assembly = Assembly::any;
  double scale = 0.0;
};

struct Circle {
  bool meet = false;
  V2 point, offset;
};

/// Circles (c1, r1), (c2, r2); side +1: the point left of c1 -> c2.
Circle intersect(V2 c1, double r1, V2 c2, double r2, int side);
/// IK in the mechanism's working mode; singular also when the loop does not close (kClosureRel).
Pose ik(const Mech& m, V2 P);
/// FK in the mechanism's assembly mode (any: the branch whose working mode is the design's).
Pose fk(const Mech& m, double theta1, double theta2);

// --- Outlines (fivebar/collision.hpp) ------------------------------------------------------------

struct Capsule {
  V2 a, b;
  double r = 0.0;
};

/// One part of an outline: up to three capsules in one plane, with a bounding box.
struct Part {
  int plane = 0;
  int count = 0;
  std::array<Capsule, 3> shapes{};
  V2 lo, hi;
};

/// Where each part of an outline sits, independent of the pose (from the geometry alone).
struct PartTemplate {
  int plane = 0;
  int link = -1;   ///< 0..3: link L1..L4; -1: a disk
  int point = 0;   ///< disk centre: 0 O1, 1 O2, 2 A1, 3 A2, 4 P
  double r = 0.0;  ///< capsule or disk radius
  bool boss = false;
  double boss_r = 0.0;
};

/// The outline's parts for a geometry (allocates: at initialisation).
std::vector<PartTemplate> outline_template(const CollisionConfig& c);
/// Fills `out` (sized as the template) for a pose that exists.
void outline(const std::vector<PartTemplate>& tpl, const Pose& pose, Part* out);
/// Smallest clearance between two outlines over shared planes (+inf when none is shared).
double min_clearance(const Part* a, std::size_t na, const Part* b, std::size_t nb);
/// Some pair of parts in a shared plane closer than `threshold` (bounding boxes skip far pairs).
bool collide(const Part* a, std::size_t na, const Part* b, std::size_t nb, double threshold);
/// min_clearance() where it is below `cap`, else some value >= cap (pairs whose bounding boxes
/// are apart, by `cap` or more, are skipped; boxes that touch never are).
double min_clearance_below(const Part* a, std::size_t na, const Part* b, std::size_t nb, double cap);

/// A capsule seen from a fixed origin o, for rays o + t u (u a unit vector): the points inside it
/// (distance to [a, b] < r) form one open interval of t (the capsule is convex), in closed form from
/// the slab of the segment (two pairs of parallel lines) and the two end disks.
struct RayCapsule {
  V2 wa, wb;                  ///< o - a, o - b
  double ca = 0.0, cb = 0.0;  ///< |o - a|^2 - r^2, |o - b|^2 - r^2
  V2 e, n;                    ///< unit along and across the segment (len 0: a disk)
  double along = 0.0, across = 0.0, len = 0.0, r = 0.0;  ///< o's coordinates, |b - a|, radius
  V2 wm;              ///< o - the segment's midpoint
  double cm = 0.0;    ///< |o - midpoint|^2 - R^2 for the bounding disk's radius R (len / 2 + r, widened)
};
RayCapsule ray_capsule(V2 o, const Capsule& c);
/// The interval of the ray in the capsule: false when the line misses it.
bool ray_interval(const RayCapsule& c, V2 u, double& t_in, double& t_out);
/// The first t >= 0 at which o + t u is inside none of the `n` capsules (the exit of the ray from
/// their union): each capsule is left at most once along a ray, so at most n + 1 passes over the
/// intervals (kept in `t_in`, `t_out`, n entries each, caller's buffers). A capsule whose bounding
/// disk the ray (t >= 0) misses is skipped: it cannot hold a point of the ray.
double ray_exit(V2 u, const RayCapsule* caps, std::size_t n, double* t_in, double* t_out);

}  // namespace fivebar::runtime::detail
