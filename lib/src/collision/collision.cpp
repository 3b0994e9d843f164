// Link outlines as capsules, exact capsule clearances, interference of the two mechanisms of a
// station, the paper's priority rule and the sampled collision map (fivebar/collision.hpp).

#include "fivebar/format.hpp"
#include "fivebar/collision.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "fivebar/error.hpp"

namespace fivebar {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTwoPi = 2.0 * std::numbers::pi;
/// Golden-section ratio (sqrt(5) - 1) / 2.
const double kGolden = 0.5 * (std::sqrt(5.0) - 1.0);
/// Width of the separation bins of the collision map, mm.
constexpr double kBinWidthMm = 0.5;

double orient(const Vec2& a, const Vec2& b, const Vec2& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

bool opposite(double u, double v) { return (u > 0.0 && v < 0.0) || (u < 0.0 && v > 0.0); }

/// Closest point of the segment [a, b] to p (clamped projection; a point for a == b).
Vec2 closest_on_segment(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 d = b - a;
  const double dd = d.squaredNorm();
  if (!(dd > 0.0)) return a;
  const double t = (p - a).dot(d) / dd;
  if (t <= 0.0) return a;
  if (t >= 1.0) return b;
  return a + t * d;
}

// Static part names: OutlinePart::name views them.
constexpr std::string_view kLinkNames[4] = {"L1", "L2", "L3", "L4"};
constexpr std::string_view kPinA1 = "pin A1";
constexpr std::string_view kPinA2 = "pin A2";
constexpr std::string_view kPinP = "pin P";
constexpr std::string_view kShaftNames[2] = {"shaft O1", "shaft O2"};
constexpr std::string_view kPost = "post P";
constexpr std::string_view kTactor = "tactor";

OutlinePart disk_part(std::string_view name, int plane, const Vec2& c, double radius) {
  OutlinePart part;
  part.name = name;
  part.plane = plane;
  part.shapes[0] = Capsule{c, c, radius};
  part.count = 1;
  return part;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Capsules

SegmentDistance segment_distance(const Vec2& p0, const Vec2& p1, const Vec2& q0, const Vec2& q1) {
  const double o1 = orient(p0, p1, q0);
  const double o2 = orient(p0, p1, q1);
  const double o3 = orient(q0, q1, p0);
  const double o4 = orient(q0, q1, p1);
  if (opposite(o1, o2) && opposite(o3, o4)) {
    // Proper crossing: the point where p crosses the line of q.
    const double t = o3 / (o3 - o4);
    const Vec2 x = p0 + t * (p1 - p0);
    return {0.0, x, x};
  }
  // Otherwise the minimum is attained at an endpoint of one of the segments.
  SegmentDistance best{kInf, p0, q0};
  const auto consider = [&](const Vec2& on_p, const Vec2& on_q) {
    const double d = (on_p - on_q).norm();
    if (d < best.distance) best = {d, on_p, on_q};
  };
  consider(p0, closest_on_segment(p0, q0, q1));
  consider(p1, closest_on_segment(p1, q0, q1));
  consider(closest_on_segment(q0, p0, p1), q0);
  consider(closest_on_segment(q1, p0, p1), q1);
  return best;
}

double capsule_clearance(const Capsule& a, const Capsule& b, Vec2* on_a, Vec2* on_b) {
  const SegmentDistance d = segment_distance(a.a, a.b, b.a, b.b);
  if (on_a) *on_a = d.on_first;
  if (on_b) *on_b = d.on_second;
  return d.distance - a.radius - b.radius;
}

// ---------------------------------------------------------------------------------------------
// Outlines

int tactor_plane(const Geometry& g) { return *std::max_element(g.layers.begin(), g.layers.end()) + 1; }

std::vector<OutlinePart> link_outline(const Mechanism& m, const Pose& pose, const Geometry& g) {
  if (pose.status == Status::unreachable) {
    throw InputError("mechanism " + m.name + ": an unreachable pose has no outline");
  }
  std::vector<OutlinePart> parts;
  parts.reserve(12);
  const double boss_r = 0.5 * g.boss_diameter;
  const double pin_r = 0.5 * g.pin_diameter;
  const std::array<std::array<Vec2, 2>, 4> ends{{{m.O1, pose.A1}, {m.O2, pose.A2}, {pose.A1, pose.P}, {pose.A2, pose.P}}};
  for (std::size_t i = 0; i < 4; ++i) {
    OutlinePart link;
    link.name = kLinkNames[i];
    link.plane = g.layers[i];
    const double r = 0.5 * g.link_width[i];
    link.shapes[0] = Capsule{ends[i][0], ends[i][1], r};
    link.count = 1;
    if (boss_r > r) {
      link.shapes[1] = Capsule{ends[i][0], ends[i][0], boss_r};
      link.shapes[2] = Capsule{ends[i][1], ends[i][1], boss_r};
      link.count = 3;
    }
    parts.push_back(link);
  }
  // Pins through the planes between the two links they join.
  const auto pin = [&](std::string_view name, const Vec2& at, int plane_a, int plane_b) {
    for (int p = std::min(plane_a, plane_b) + 1; p < std::max(plane_a, plane_b); ++p) {
      parts.push_back(disk_part(name, p, at, pin_r));
    }
  };
  pin(kPinA1, pose.A1, g.layers[0], g.layers[2]);
  pin(kPinA2, pose.A2, g.layers[1], g.layers[3]);
  pin(kPinP, pose.P, g.layers[2], g.layers[3]);
  // Motor shafts rise from below plane 0 to their proximal link.
  for (int p = 0; p < g.layers[0]; ++p) parts.push_back(disk_part(kShaftNames[0], p, m.O1, 0.5 * g.motor_shaft_diameter));
  for (int p = 0; p < g.layers[1]; ++p) parts.push_back(disk_part(kShaftNames[1], p, m.O2, 0.5 * g.motor_shaft_diameter));
  // The tactor post rises from the joint P through every link plane above it.
  const int top = tactor_plane(g);
  for (int p = std::max(g.layers[2], g.layers[3]) + 1; p < top; ++p) parts.push_back(disk_part(kPost, p, pose.P, pin_r));
  parts.push_back(disk_part(kTactor, top, pose.P, 0.5 * g.tactor_diameter));
  for (OutlinePart& part : parts) {
    part.box_lo = Vec2(kInf, kInf);
    part.box_hi = Vec2(-kInf, -kInf);
    for (int i = 0; i < part.count; ++i) {
      const Capsule& c = part.shapes[i];
      const Vec2 r(c.radius, c.radius);
      part.box_lo = part.box_lo.cwiseMin(c.a.cwiseMin(c.b) - r);
      part.box_hi = part.box_hi.cwiseMax(c.a.cwiseMax(c.b) + r);
    }
  }
  return parts;
}

// ---------------------------------------------------------------------------------------------
// Interference

std::string PairClearance::name() const {
  return "upper." + std::string(upper_part) + " vs lower." + std::string(lower_part);
}

namespace {

/// Clearance of two parts in the same plane and their closest points.
double part_clearance(const OutlinePart& a, const OutlinePart& b, Vec2* on_a, Vec2* on_b) {
  double best = kInf;
  for (int i = 0; i < a.count; ++i) {
    for (int j = 0; j < b.count; ++j) {
      Vec2 pa, pb;
      const double c = capsule_clearance(a.shapes[i], b.shapes[j], &pa, &pb);
      if (c < best) {
        best = c;
        if (on_a) *on_a = pa;
        if (on_b) *on_b = pb;
      }
    }
  }
  return best;
}

}  // namespace

double min_clearance(const std::vector<OutlinePart>& upper, const std::vector<OutlinePart>& lower, double stop_below) {
  double best = kInf;
  for (const OutlinePart& a : upper) {
    for (const OutlinePart& b : lower) {
      if (a.plane != b.plane) continue;
      best = std::min(best, part_clearance(a, b, nullptr, nullptr));
      if (best < stop_below) return best;
    }
  }
  return best;
}

namespace {

/// Are two parts closer than `threshold`? Same plane assumed. Parts whose bounding boxes are
/// disjoint and at least `threshold` apart are not compared (their clearance is at least that).
bool parts_collide(const OutlinePart& a, const OutlinePart& b, double threshold) {
  const double gx = std::max({0.0, a.box_lo.x() - b.box_hi.x(), b.box_lo.x() - a.box_hi.x()});
  const double gy = std::max({0.0, a.box_lo.y() - b.box_hi.y(), b.box_lo.y() - a.box_hi.y()});
  if (gx > 0.0 || gy > 0.0) {
    const double gap = std::hypot(gx, gy);
    if (gap >= threshold) return false;  // disjoint boxes: clearance >= gap
  }
  // part_clearance(a, b) < threshold: some capsule pair closer than it, each pair's box tested first.
  for (int i = 0; i < a.count; ++i) {
    const Capsule& ca = a.shapes[i];
    for (int j = 0; j < b.count; ++j) {
      const Capsule& cb = b.shapes[j];
      const double r = ca.radius + cb.radius;
      const double cx = std::max({0.0, std::min(ca.a.x(), ca.b.x()) - std::max(cb.a.x(), cb.b.x()) - r,
                                  std::min(cb.a.x(), cb.b.x()) - std::max(ca.a.x(), ca.b.x()) - r});
      const double cy = std::max({0.0, std::min(ca.a.y(), ca.b.y()) - std::max(cb.a.y(), cb.b.y()) - r,
                                  std::min(cb.a.y(), cb.b.y()) - std::max(ca.a.y(), ca.b.y()) - r});
      if ((cx > 0.0 || cy > 0.0) && std::hypot(cx, cy) >= threshold) continue;  // clearance >= that gap
      if (capsule_clearance(ca, cb, nullptr, nullptr) < threshold) return true;
    }
  }
  return false;
}

/// outlines_collide(), trying first the pair (upper index, lower index) in `hint` and leaving
/// there the pair found colliding: the verdict is whether any pair collides, so the order only
/// changes how soon a search over nearby poses (the priority rule's) finds it.
bool outlines_collide_from(const std::vector<OutlinePart>& upper, const std::vector<OutlinePart>& lower, double threshold,
                           std::pair<std::size_t, std::size_t>& hint) {
  if (hint.first < upper.size() && hint.second < lower.size() && upper[hint.first].plane == lower[hint.second].plane &&
      parts_collide(upper[hint.first], lower[hint.second], threshold)) {
    return true;
  }
  for (std::size_t i = 0; i < upper.size(); ++i) {
    for (std::size_t j = 0; j < lower.size(); ++j) {
      if (upper[i].plane != lower[j].plane || !parts_collide(upper[i], lower[j], threshold)) continue;
      hint = {i, j};
      return true;
    }
  }
  return false;
}

}  // namespace

bool outlines_collide(const std::vector<OutlinePart>& upper, const std::vector<OutlinePart>& lower, double threshold) {
  std::pair<std::size_t, std::size_t> hint{upper.size(), lower.size()};
  return outlines_collide_from(upper, lower, threshold, hint);
}

Interference interference(const Mechanism& upper, const Pose& upper_pose, const Mechanism& lower,
                          const Pose& lower_pose, const Geometry& g) {
  const auto up = link_outline(upper, upper_pose, g);
  const auto low = link_outline(lower, lower_pose, g);
  const int top = tactor_plane(g);
  Interference result;
  result.required_mm = g.min_clearance;
  result.min_clearance_mm = kInf;
  for (const OutlinePart& a : up) {
    for (const OutlinePart& b : low) {
      if (a.plane != b.plane) continue;
      PairClearance pair;
      pair.upper_part = a.name;
      pair.lower_part = b.name;
      pair.plane = a.plane;
      pair.clearance_mm = part_clearance(a, b, &pair.upper_point, &pair.lower_point);
      if (pair.clearance_mm < g.min_clearance) result.colliding.push_back(pair);
      if (pair.clearance_mm < result.min_clearance_mm) {
        result.min_clearance_mm = pair.clearance_mm;
        result.closest = pair;
      }
      auto it = std::find_if(result.planes.begin(), result.planes.end(),
                             [&](const PlaneClearance& p) { return p.plane == a.plane; });
      if (it == result.planes.end()) {
        result.planes.push_back({a.plane, a.plane == top, pair});
      } else if (pair.clearance_mm < it->closest.clearance_mm) {
        it->closest = pair;
      }
    }
  }
  std::stable_sort(result.colliding.begin(), result.colliding.end(),
                   [](const PairClearance& x, const PairClearance& y) { return x.clearance_mm < y.clearance_mm; });
  std::sort(result.planes.begin(), result.planes.end(),
            [](const PlaneClearance& x, const PlaneClearance& y) { return x.plane < y.plane; });
  result.collides = !result.colliding.empty();
  return result;
}

bool usable(const Mechanism& m, const Pose& pose) {
  if (pose.status != Status::ok || !pose.within_joint_limits) return false;
  if (m.assembly_mode == AssemblyMode::Any) return true;
  return pose.assembly == static_cast<std::int8_t>(m.assembly_mode);
}

// ---------------------------------------------------------------------------------------------
// Priority rule

std::string_view to_string(PriorityStatus status) {
  switch (status) {
    case PriorityStatus::clear: return "clear";
    case PriorityStatus::moved: return "moved";
    case PriorityStatus::upper_unusable: return "upper_unusable";
    case PriorityStatus::lower_unusable: return "lower_unusable";
    case PriorityStatus::no_free_point: return "no_free_point";
  }
  return "clear";
}

namespace {

std::string pose_problem(const Mechanism& m, const Pose& pose) {
  if (pose.status != Status::ok) return std::string(to_string(pose.status));
  if (!pose.within_joint_limits) return "outside the joint limits";
  return "on the wrong assembly side (" + to_string(m.assembly_mode) + " required)";
}

std::string fixed3(double v) { return format::fixed(v, 3); }

/// Is the lower tactor free (usable and clear of the fixed upper outline) at q?
class LowerProbe {
 public:
  LowerProbe(const Mechanism& lower, const Geometry& g, const std::vector<OutlinePart>& upper_outline)
      : lower_(lower), g_(g), upper_(upper_outline) {}
  bool free(const Vec2& q) const {
    const Pose pose = ik(lower_, q);
    if (!usable(lower_, pose)) return false;
    // The verdict of min_clearance(...) >= g.min_clearance, with part pairs whose boxes are
    // farther apart than the threshold skipped (as the collision map does) and the pair that
    // collided at the last point tried first.
    return !outlines_collide_from(upper_, link_outline(lower_, pose, g_), g_.min_clearance, hint_);
  }

 private:
  const Mechanism& lower_;
  const Geometry& g_;
  const std::vector<OutlinePart>& upper_;
  mutable std::pair<std::size_t, std::size_t> hint_{~std::size_t(0), ~std::size_t(0)};  ///< the last colliding pair
};

struct RayHit {
  double phi = 0.0;
  double t = kInf;  ///< free distance along the ray (free side of the bracket)
};

/// Bisects [lo, hi] along direction phi from `origin`: lo blocked, hi free. Returns the free end.
double bisect_ray(const LowerProbe& probe, const Vec2& origin, double phi, double lo, double hi, double tol) {
  const Vec2 u(std::cos(phi), std::sin(phi));
  while (hi - lo > tol) {
    const double mid = 0.5 * (lo + hi);
    if (probe.free(origin + mid * u)) {
      hi = mid;
    } else {
      lo = mid;
    }
  }
  return hi;
}

}  // namespace

PriorityResult apply_priority(const Mechanism& upper, const Mechanism& lower, const Geometry& g,
                              const Vec2& upper_target, const Vec2& lower_target, const PriorityOptions& options) {
  if (options.rays < 8 || !(options.step_rel > 0.0) || !(options.tolerance_rel > 0.0) ||
      options.refine_candidates < 1) {
    throw InputError("priority search: rays >= 8, step_rel > 0, tolerance_rel > 0 and refine_candidates >= 1 needed");
  }
  PriorityResult r;
  r.upper_target = upper_target;
  r.lower_target = lower_target;
  r.lower_point = lower_target;
  r.upper = ik(upper, upper_target);
  r.lower = ik(lower, lower_target);
  const bool upper_ok = usable(upper, r.upper);
  const bool lower_ok = usable(lower, r.lower);
  if (r.upper.status != Status::unreachable && r.lower.status != Status::unreachable) {
    r.before = interference(upper, r.upper, lower, r.lower, g);
    r.after = r.before;
  }
  if (!upper_ok) {
    r.status = PriorityStatus::upper_unusable;
    r.reason = "the upper target cannot be held: " + pose_problem(upper, r.upper);
    return r;
  }
  if (!lower_ok) {
    r.status = PriorityStatus::lower_unusable;
    r.reason = "the lower target cannot be held: " + pose_problem(lower, r.lower);
    return r;
  }
  if (!r.before->collides) {
    r.status = PriorityStatus::clear;
    r.reason = "no collision: clearance " + fixed3(r.before->min_clearance_mm) + " mm (" +
               r.before->closest.name() + ")";
    return r;
  }

  const auto upper_outline = link_outline(upper, r.upper, g);
  const LowerProbe probe(lower, g, upper_outline);
  const double scale = lower.length_scale();
  const double h = options.step_rel * scale;
  const double tol = options.tolerance_rel * scale;
  const int n = options.rays;
  const double dphi = kTwoPi / n;
  // Every point the lower mechanism reaches is within L1 + L3 of O1.
  const double reach = (lower_target - lower.O1).norm() + lower.L[0] + lower.L[2];
  const int rings = static_cast<int>(std::ceil(reach / h)) + 1;
  const auto ray_point = [&](int j, double t) {
    const double phi = j * dphi;
    return Vec2(lower_target.x() + t * std::cos(phi), lower_target.y() + t * std::sin(phi));
  };

  // Ring search: the first ring with a free point, and the next one.
  std::vector<std::uint8_t> free_k(n, 0), free_k1(n, 0);
  int first = -1;
  for (int k = 1; k <= rings && first < 0; ++k) {
    for (int j = 0; j < n; ++j) free_k[j] = probe.free(ray_point(j, k * h)) ? 1 : 0;
    if (std::any_of(free_k.begin(), free_k.end(), [](std::uint8_t f) { return f != 0; })) first = k;
  }
  if (first < 0) {
    r.status = PriorityStatus::no_free_point;
    r.reason = "collision (" + r.before->closest.name() + ") and no collision-free point within the lower " +
               "mechanism's reach";
    return r;
  }
  for (int j = 0; j < n; ++j) free_k1[j] = free_k[j] ? 0 : (probe.free(ray_point(j, (first + 1) * h)) ? 1 : 0);

  // Bisect every candidate ray between its last blocked and first free ring.
  std::vector<RayHit> hits;
  for (int j = 0; j < n; ++j) {
    if (free_k[j]) {
      hits.push_back({j * dphi, bisect_ray(probe, lower_target, j * dphi, (first - 1) * h, first * h, tol)});
    } else if (free_k1[j]) {
      hits.push_back({j * dphi, bisect_ray(probe, lower_target, j * dphi, first * h, (first + 1) * h, tol)});
    }
  }
  std::sort(hits.begin(), hits.end(), [](const RayHit& a, const RayHit& b) { return a.t < b.t; });
  RayHit best = hits.front();

  // Golden-section refinement of the angle around the best candidates.
  const auto boundary = [&](double phi, double t_guess) {
    const double lo = std::max(0.0, t_guess - h);
    const double hi = t_guess + h;
    const Vec2 u(std::cos(phi), std::sin(phi));
    if (lo > 0.0 && probe.free(lower_target + lo * u)) return kInf;  // not a bracket: leave it
    if (!probe.free(lower_target + hi * u)) return kInf;
    return bisect_ray(probe, lower_target, phi, lo, hi, tol);
  };
  const std::size_t refine = std::min<std::size_t>(hits.size(), static_cast<std::size_t>(options.refine_candidates));
  for (std::size_t c = 0; c < refine; ++c) {
    const RayHit start = hits[c];
    double a = start.phi - dphi, b = start.phi + dphi;
    double x1 = b - kGolden * (b - a), x2 = a + kGolden * (b - a);
    double f1 = boundary(x1, start.t), f2 = boundary(x2, start.t);
    const auto keep = [&](double phi, double t) {
      if (t < best.t) best = {phi, t};
    };
    keep(x1, f1);
    keep(x2, f2);
    while ((b - a) * (start.t + h) > tol) {
      if (f1 <= f2) {
        b = x2, x2 = x1, f2 = f1;
        x1 = b - kGolden * (b - a);
        f1 = boundary(x1, start.t);
        keep(x1, f1);
      } else {
        a = x1, x1 = x2, f1 = f2;
        x2 = a + kGolden * (b - a);
        f2 = boundary(x2, start.t);
        keep(x2, f2);
      }
    }
  }

  r.lower_point = lower_target + best.t * Vec2(std::cos(best.phi), std::sin(best.phi));
  r.lower = ik(lower, r.lower_point);
  r.moved_mm = (r.lower_point - lower_target).norm();
  r.after = interference(upper, r.upper, lower, r.lower, g);
  r.status = PriorityStatus::moved;
  r.reason = "collision (" + r.before->closest.name() + ", clearance " + fixed3(r.before->min_clearance_mm) +
             " mm): lower target moved by " + fixed3(r.moved_mm) + " mm";
  return r;
}

// ---------------------------------------------------------------------------------------------
// Collision map

namespace {

bool inside_ellipse(const Ellipse& e, const Vec2& p) {
  const Vec2 d = p - e.center;
  const double c = std::cos(e.angle), s = std::sin(e.angle);
  const double u = (c * d.x() + s * d.y()) / (0.5 * e.axes.x());
  const double v = (-s * d.x() + c * d.y()) / (0.5 * e.axes.y());
  return u * u + v * v <= 1.0;
}

}  // namespace

std::vector<Vec2> ellipse_grid(const Ellipse& e, double spacing_mm) {
  if (!(spacing_mm > 0.0) || !std::isfinite(spacing_mm)) {
    throw InputError("collision map spacing must be a positive number of mm");
  }
  const double half = 0.5 * std::max(e.axes.x(), e.axes.y());
  if (half / spacing_mm > 400.0) {
    throw InputError("collision map spacing " + fixed3(spacing_mm) +
                     " mm is too fine for this ellipse (more than 800 points across)");
  }
  std::vector<Vec2> points;
  const int n = static_cast<int>(std::floor(half / spacing_mm));
  for (int j = -n; j <= n; ++j) {
    for (int i = -n; i <= n; ++i) {
      const Vec2 p = e.center + spacing_mm * Vec2(i, j);
      if (inside_ellipse(e, p)) points.push_back(p);
    }
  }
  return points;
}

namespace {

void require_both(const Station& station) {
  if (!station.lower || !station.upper) {
    throw InputError("station " + station.name + ": the collision map needs both a lower and an upper mechanism");
  }
}

/// Outlines of the usable poses at `points` (empty where the pose is not usable).
void usable_outlines(const Mechanism& m, const Geometry& g, const std::vector<Vec2>& points,
                     std::vector<std::uint8_t>& ok, std::vector<std::vector<OutlinePart>>& outlines) {
  ok.assign(points.size(), 0);
  outlines.assign(points.size(), {});
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Pose pose = ik(m, points[i]);
    if (usable(m, pose)) ok[i] = 1, outlines[i] = link_outline(m, pose, g);
  }
}

}  // namespace

CollisionFraction collision_fraction(const Station& station, const Geometry& g, double spacing_mm) {
  require_both(station);
  const std::vector<Vec2> points = ellipse_grid(station.target, spacing_mm);
  std::vector<std::uint8_t> up_ok, low_ok;
  std::vector<std::vector<OutlinePart>> up_outline, low_outline;
  usable_outlines(*station.upper, g, points, up_ok, up_outline);
  usable_outlines(*station.lower, g, points, low_ok, low_outline);
  CollisionFraction f;
  f.points = points.size();
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!up_ok[i]) continue;
    for (std::size_t j = 0; j < points.size(); ++j) {
      if (!low_ok[j]) continue;
      ++f.pairs;
      if (outlines_collide(up_outline[i], low_outline[j], g.min_clearance)) ++f.colliding;
    }
  }
  f.fraction = f.pairs > 0 ? double(f.colliding) / double(f.pairs) : 0.0;
  return f;
}

CollisionMap collision_map(const Station& station, const Geometry& g, const CollisionMapOptions& options) {
  require_both(station);
  const Ellipse& e = station.target;
  const Mechanism& up = *station.upper;
  const Mechanism& low = *station.lower;

  CollisionMap map;
  map.station = station.name;
  map.target = e;
  map.spacing_mm = options.spacing_mm;
  map.points = ellipse_grid(e, options.spacing_mm);
  const std::size_t np = map.points.size();
  std::vector<std::vector<OutlinePart>> up_outline, low_outline;
  usable_outlines(up, g, map.points, map.upper_ok, up_outline);
  usable_outlines(low, g, map.points, map.lower_ok, low_outline);

  map.upper_fraction.assign(np, 0.0);
  map.lower_fraction.assign(np, 0.0);
  std::vector<std::size_t> lower_pairs(np, 0), lower_hits(np, 0);
  map.min_free_separation_mm = kInf;
  for (std::size_t i = 0; i < np; ++i) {
    if (options.progress && i % 16 == 0) options.progress(i, np);
    if (!map.upper_ok[i]) continue;
    std::size_t pairs = 0, hits = 0;
    for (std::size_t j = 0; j < np; ++j) {
      if (!map.lower_ok[j]) continue;
      const double sep = (map.points[i] - map.points[j]).norm();
      const bool collides = outlines_collide(up_outline[i], low_outline[j], g.min_clearance);
      ++pairs, ++lower_pairs[j];
      const std::size_t bin = static_cast<std::size_t>(sep / kBinWidthMm);
      if (map.bins.size() <= bin) {
        for (std::size_t b = map.bins.size(); b <= bin; ++b) {
          map.bins.push_back({double(b) * kBinWidthMm, double(b + 1) * kBinWidthMm, 0, 0});
        }
      }
      ++map.bins[bin].pairs;
      if (collides) {
        ++hits, ++lower_hits[j], ++map.bins[bin].colliding;
        if (!map.any_colliding || sep > map.max_colliding_separation_mm) {
          map.any_colliding = true;
          map.max_colliding_separation_mm = sep;
          map.max_colliding_pair = {map.points[i], map.points[j]};
        }
      } else if (sep < map.min_free_separation_mm) {
        map.any_free = true;
        map.min_free_separation_mm = sep;
        map.min_free_pair = {map.points[i], map.points[j]};
      }
    }
    map.pairs += pairs;
    map.colliding += hits;
    map.upper_fraction[i] = pairs > 0 ? double(hits) / double(pairs) : 0.0;
  }
  if (options.progress) options.progress(np, np);
  for (std::size_t j = 0; j < np; ++j) {
    map.lower_fraction[j] = lower_pairs[j] > 0 ? double(lower_hits[j]) / double(lower_pairs[j]) : 0.0;
  }
  if (!map.any_free) map.min_free_separation_mm = 0.0;
  map.colliding_fraction = map.pairs > 0 ? double(map.colliding) / double(map.pairs) : 0.0;

  // The lower positions blocked by the upper tactor at the centre.
  map.centre_collides.assign(np, 2);
  const Pose centre_up = ik(up, e.center);
  if (usable(up, centre_up)) {
    const auto centre_outline = link_outline(up, centre_up, g);
    for (std::size_t j = 0; j < np; ++j) {
      if (!map.lower_ok[j]) continue;
      map.centre_collides[j] = outlines_collide(centre_outline, low_outline[j], g.min_clearance) ? 1 : 0;
    }
  }
  map.centre_rule = apply_priority(up, low, g, e.center, e.center);
  return map;
}

// ---------------------------------------------------------------------------------------------
// JSON

namespace {
Json xy(const Vec2& p) { return Json::array({p.x(), p.y()}); }
/// Clearance for JSON: infinity (nothing shared) becomes null.
Json finite_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }
}  // namespace

Json to_json(const PairClearance& pair) {
  Json j;
  j["pair"] = pair.name();
  j["upper_part"] = std::string(pair.upper_part);
  j["lower_part"] = std::string(pair.lower_part);
  j["plane"] = pair.plane;
  j["clearance_mm"] = finite_or_null(pair.clearance_mm);
  j["upper_point_mm"] = xy(pair.upper_point);
  j["lower_point_mm"] = xy(pair.lower_point);
  return j;
}

Json to_json(const Interference& in) {
  Json j;
  j["collides"] = in.collides;
  j["min_clearance_mm"] = finite_or_null(in.min_clearance_mm);
  j["required_clearance_mm"] = in.required_mm;
  j["closest"] = std::isfinite(in.min_clearance_mm) ? to_json(in.closest) : Json(nullptr);
  Json colliding = Json::array();
  for (const auto& p : in.colliding) colliding.push_back(to_json(p));
  j["colliding"] = colliding;
  Json planes = Json::array();
  for (const auto& p : in.planes) {
    planes.push_back({{"plane", p.plane},
                      {"tactor_plane", p.tactor},
                      {"min_clearance_mm", finite_or_null(p.closest.clearance_mm)},
                      {"closest", p.closest.name()}});
  }
  j["planes"] = planes;
  return j;
}

Json to_json(const PriorityResult& r) {
  Json j;
  j["status"] = std::string(to_string(r.status));
  j["reason"] = r.reason;
  j["upper_target_mm"] = xy(r.upper_target);
  j["lower_target_mm"] = xy(r.lower_target);
  j["lower_point_mm"] = xy(r.lower_point);
  j["moved_mm"] = r.moved_mm;
  // Mechanisms as records, lower first, as every JSON document lists them (docs/conventions.md).
  Json lower = {{"mechanism", "lower"}}, upper = {{"mechanism", "upper"}};
  lower.update(to_json(r.lower));
  upper.update(to_json(r.upper));
  j["mechanisms"] = Json::array({lower, upper});
  j["before"] = r.before ? to_json(*r.before) : Json(nullptr);
  j["after"] = r.after ? to_json(*r.after) : Json(nullptr);
  return j;
}

Json to_json(const CollisionMap& map) {
  Json j;
  j["station"] = map.station;
  j["target"] = to_json(map.target);
  j["spacing_mm"] = map.spacing_mm;
  j["points"] = map.points.size();
  j["upper_usable_points"] = std::count(map.upper_ok.begin(), map.upper_ok.end(), 1);
  j["lower_usable_points"] = std::count(map.lower_ok.begin(), map.lower_ok.end(), 1);
  j["pairs"] = map.pairs;
  j["colliding_pairs"] = map.colliding;
  j["colliding_fraction"] = map.colliding_fraction;
  j["min_free_separation_mm"] = map.any_free ? Json(map.min_free_separation_mm) : Json(nullptr);
  j["min_free_pair_mm"] = map.any_free ? Json::array({xy(map.min_free_pair[0]), xy(map.min_free_pair[1])}) : Json(nullptr);
  j["max_colliding_separation_mm"] = map.any_colliding ? Json(map.max_colliding_separation_mm) : Json(nullptr);
  j["max_colliding_pair_mm"] =
      map.any_colliding ? Json::array({xy(map.max_colliding_pair[0]), xy(map.max_colliding_pair[1])}) : Json(nullptr);
  Json bins = Json::array();
  for (const auto& b : map.bins) {
    bins.push_back({{"separation_mm", Json::array({b.lo_mm, b.hi_mm})},
                    {"pairs", b.pairs},
                    {"colliding", b.colliding},
                    {"fraction", b.pairs > 0 ? double(b.colliding) / double(b.pairs) : 0.0}});
  }
  j["by_separation"] = bins;
  Json rule = {{"status", std::string(to_string(map.centre_rule.status))},
               {"reason", map.centre_rule.reason},
               {"target_mm", xy(map.target.center)},
               {"lower_point_mm", xy(map.centre_rule.lower_point)},
               {"moved_mm", map.centre_rule.moved_mm}};
  j["priority_at_centre"] = rule;
  return j;
}

}  // namespace fivebar
