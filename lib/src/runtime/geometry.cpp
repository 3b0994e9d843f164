// The runtime's kinematics and outlines (lib/src/runtime/geometry.hpp). The formulas and their
// order of operations are those of lib/src/kinematics/kinematics.cpp, lib/src/kinematics/kinematics_common.hpp and
// lib/src/collision/collision.cpp; test/test_runtime.cpp checks them against those.

#include "geometry.hpp"

#include <cstring>
#include <limits>

namespace fivebar::runtime::detail {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double from_bits(std::uint64_t u) {
  double d;
  std::memcpy(&d, &u, sizeof d);
  return d;
}

/// Exact power-of-4 scaling of a squared length (lib/src/kinematics/kinematics_common.hpp Pow4Scale).
void pow4(double x, double& s, double& u) {
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  const int e = std::clamp(int((bits >> 52) & 0x7ff), 1, 2046) - 1023;
  const int m = e >> 1;
  s = from_bits(std::uint64_t(1023 - 2 * m) << 52);
  u = from_bits(std::uint64_t(1022 + m) << 52);
}

std::int8_t sign_if(double v, bool defined) {
  return !defined ? std::int8_t{0} : v > 0.0 ? std::int8_t{1} : v < 0.0 ? std::int8_t{-1} : std::int8_t{0};
}

/// Status and realised signs from the positions (lib/src/kinematics/kinematics.cpp analyse()).
void analyse(const Mech& m, Pose& p) {
  const V2 e1 = p.A1 - m.O1, f1 = p.P - p.A1, e2 = p.A2 - m.O2, f2 = p.P - p.A2;
  const double c1 = cross(e1, f1), c2 = cross(e2, f2), cb = cross(f1, f2);
  const double s1 = std::min(1.0, std::fabs(c1) / (m.L[0] * m.L[2]));
  const double s2 = std::min(1.0, std::fabs(c2) / (m.L[1] * m.L[3]));
  const double sb = std::min(1.0, std::fabs(cb) / (m.L[2] * m.L[3]));
  p.mode = {sign_if(c1, s1 >= kSingularSin), sign_if(c2, s2 >= kSingularSin)};
  p.assembly = sign_if(cb, sb >= kSingularSin);
  p.status = std::min(s1, s2) < kSingularSin || sb < kSingularSin ? PoseStatus::singular : PoseStatus::ok;
}

}  // namespace

Circle intersect(V2 c1, double r1, V2 c2, double r2, int side) {
  Circle out;
  const V2 dv = c2 - c1;
  const double d2 = dv.x * dv.x + dv.y * dv.y;
  const double d = std::sqrt(d2);
  const double scale = std::max({r1, r2, d});
  if (d <= kCoincidentRel * scale || !(d2 >= DBL_MIN)) {
    if (std::fabs(r1 - r2) <= kReachRel * scale) {
      out.meet = true;
      out.offset = {0.0, side >= 0 ? r1 : -r1};
      out.point = c1 + out.offset;
    }
    return out;
  }
  const double inv_d2 = 1.0 / d2;
  const double k = 0.5 * ((r1 - r2) * (r1 + r2));
  const double dm = (r1 - r2) * (r1 - r2), dp = (r1 + r2) * (r1 + r2);
  double ns, nu;
  pow4(dp, ns, nu);
  const double t = 0.5 + k * inv_d2;
  const double g_in = std::max(0.0, d2 - dm);
  const double g_out = std::max(0.0, dp - d2);
  const double hd = std::sqrt(g_in * (g_out * ns)) * (nu * inv_d2);
  if (!((d2 >= dm * (1.0 - kReachRel)) & (d2 <= dp * (1.0 + kReachRel)))) return out;
  const double s = side >= 0 ? 1.0 : -1.0;
  const double hs = s * hd;
  out.meet = true;
  out.offset = {t * dv.x - hs * dv.y, t * dv.y + hs * dv.x};
  out.point = c1 + out.offset;
  return out;
}

Pose ik(const Mech& m, V2 P) {
  Pose p;
  p.O1 = m.O1;
  p.O2 = m.O2;
  p.P = P;
  if (!std::isfinite(P.x) || !std::isfinite(P.y)) return p;
  const Circle x1 = intersect(m.O1, m.L[0], P, m.L[2], -m.mode[0]);
  const Circle x2 = intersect(m.O2, m.L[1], P, m.L[3], -m.mode[1]);
  if (!x1.meet || !x2.meet) return p;
  p.A1 = x1.point;
  p.A2 = x2.point;
  p.theta1 = std::atan2(x1.offset.y, x1.offset.x);
  p.theta2 = std::atan2(x2.offset.y, x2.offset.x);
  analyse(m, p);
  const V2 a1 = m.O1 + m.L[0] * V2{std::cos(p.theta1), std::sin(p.theta1)};
  const V2 a2 = m.O2 + m.L[1] * V2{std::cos(p.theta2), std::sin(p.theta2)};
  const double closure = std::max(std::fabs(norm(P - a1) - m.L[2]), std::fabs(norm(P - a2) - m.L[3]));
  if (!(closure <= kClosureRel * m.scale)) p.status = PoseStatus::singular;
  return p;
}

namespace {
Pose fk_side(const Mech& m, double t1, double t2, int side) {
  Pose p;
  p.O1 = m.O1;
  p.O2 = m.O2;
  p.theta1 = t1;
  p.theta2 = t2;
  p.A1 = m.O1 + m.L[0] * V2{std::cos(t1), std::sin(t1)};
  p.A2 = m.O2 + m.L[1] * V2{std::cos(t2), std::sin(t2)};
  const Circle x = intersect(p.A1, m.L[2], p.A2, m.L[3], side);
  if (!x.meet) {
    p.status = PoseStatus::unreachable;
    return p;
  }
  p.P = x.point;
  analyse(m, p);
  return p;
}
}  // namespace

Pose fk(const Mech& m, double t1, double t2) {
  if (!std::isfinite(t1) || !std::isfinite(t2)) return Pose{};
  if (m.assembly == Assembly::plus) return fk_side(m, t1, t2, +1);
  if (m.assembly == Assembly::minus) return fk_side(m, t1, t2, -1);
  Pose plus = fk_side(m, t1, t2, +1);
  if (plus.status == PoseStatus::unreachable || plus.mode == m.mode) return plus;
  Pose minus = fk_side(m, t1, t2, -1);
  return minus.mode == m.mode ? minus : plus;
}

// --- Outlines -------------------------------------------------------------------------------------

std::vector<PartTemplate> outline_template(const CollisionConfig& c) {
  std::vector<PartTemplate> t;
  const double boss_r = 0.5 * c.boss_diameter, pin_r = 0.5 * c.pin_diameter;
  for (int i = 0; i < 4; ++i) {
    PartTemplate p;
    p.plane = c.layers[static_cast<std::size_t>(i)];
    p.link = i;
    p.r = 0.5 * c.link_widths[static_cast<std::size_t>(i)];
    p.boss = boss_r > p.r;
    p.boss_r = boss_r;
    t.push_back(p);
  }
  const auto disks = [&](int point, int from, int to, double r) {
    for (int plane = from; plane < to; ++plane) {
      PartTemplate p;
      p.plane = plane;
      p.point = point;
      p.r = r;
      t.push_back(p);
    }
  };
  const auto& L = c.layers;
  disks(2, std::min(L[0], L[2]) + 1, std::max(L[0], L[2]), pin_r);  // pin A1
  disks(3, std::min(L[1], L[3]) + 1, std::max(L[1], L[3]), pin_r);  // pin A2
  disks(4, std::min(L[2], L[3]) + 1, std::max(L[2], L[3]), pin_r);  // pin P
  disks(0, 0, L[0], 0.5 * c.motor_shaft_diameter);                  // shaft O1
  disks(1, 0, L[1], 0.5 * c.motor_shaft_diameter);                  // shaft O2
  const int top = *std::max_element(L.begin(), L.end()) + 1;
  disks(4, std::max(L[2], L[3]) + 1, top, pin_r);  // tactor post
  disks(4, top, top + 1, 0.5 * c.tactor_diameter);  // tactor
  return t;
}

void outline(const std::vector<PartTemplate>& tpl, const Pose& pose, Part* out) {
  const V2 pts[5] = {pose.O1, pose.O2, pose.A1, pose.A2, pose.P};
  static constexpr int kEnds[4][2] = {{0, 2}, {1, 3}, {2, 4}, {3, 4}};
  for (std::size_t k = 0; k < tpl.size(); ++k) {
    const PartTemplate& t = tpl[k];
    Part& p = out[k];
    p.plane = t.plane;
    if (t.link >= 0) {
      const V2 a = pts[kEnds[t.link][0]], b = pts[kEnds[t.link][1]];
      p.shapes[0] = {a, b, t.r};
      p.count = 1;
      if (t.boss) {
        p.shapes[1] = {a, a, t.boss_r};
        p.shapes[2] = {b, b, t.boss_r};
        p.count = 3;
      }
    } else {
      const V2 c = pts[t.point];
      p.shapes[0] = {c, c, t.r};
      p.count = 1;
    }
    p.lo = {kInf, kInf};
    p.hi = {-kInf, -kInf};
    for (int i = 0; i < p.count; ++i) {
      const Capsule& s = p.shapes[static_cast<std::size_t>(i)];
      p.lo = {std::min(p.lo.x, std::min(s.a.x, s.b.x) - s.r), std::min(p.lo.y, std::min(s.a.y, s.b.y) - s.r)};
      p.hi = {std::max(p.hi.x, std::max(s.a.x, s.b.x) + s.r), std::max(p.hi.y, std::max(s.a.y, s.b.y) + s.r)};
    }
  }
}

namespace {

double orient(V2 a, V2 b, V2 c) { return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x); }
bool opposite(double u, double v) { return (u > 0.0 && v < 0.0) || (u < 0.0 && v > 0.0); }

V2 closest_on_segment(V2 p, V2 a, V2 b) {
  const V2 d = b - a;
  const double dd = dot(d, d);
  if (!(dd > 0.0)) return a;
  const double t = dot(p - a, d) / dd;
  if (t <= 0.0) return a;
  if (t >= 1.0) return b;
  return a + t * d;
}

/// Distance between two closed segments (lib/src/collision/collision.cpp segment_distance()).
double segment_distance(V2 p0, V2 p1, V2 q0, V2 q1) {
  const double o1 = orient(p0, p1, q0), o2 = orient(p0, p1, q1);
  const double o3 = orient(q0, q1, p0), o4 = orient(q0, q1, p1);
  if (opposite(o1, o2) && opposite(o3, o4)) return 0.0;
  double best = kInf;
  best = std::min(best, norm(p0 - closest_on_segment(p0, q0, q1)));
  best = std::min(best, norm(p1 - closest_on_segment(p1, q0, q1)));
  best = std::min(best, norm(closest_on_segment(q0, p0, p1) - q0));
  best = std::min(best, norm(closest_on_segment(q1, p0, p1) - q1));
  return best;
}

/// Whether a pair whose bounding boxes are `gap` apart (>= 0) can be skipped when only clearances
/// below `best` matter: the pair's clearance is at least the gap, which must be positive, as boxes
/// that touch can hold overlapping shapes (a negative clearance) whatever `best` is.
bool skip(double gap, double best) { return gap > 0.0 && gap >= best; }

/// The gap between the bounding boxes of two capsules along one axis (0 when they overlap): a
/// lower bound on their clearance.
double box_gap(double a0, double a1, double ra, double b0, double b1, double rb) {
  const double alo = std::min(a0, a1) - ra, ahi = std::max(a0, a1) + ra;
  const double blo = std::min(b0, b1) - rb, bhi = std::max(b0, b1) + rb;
  return std::max({0.0, alo - bhi, blo - ahi});
}

/// The clearance of two parts (the least over their pairs of shapes) where it is below `cap`, else
/// some value >= cap: a pair of shapes whose bounding boxes are `cap` or more apart is skipped (its
/// clearance is at least that gap).
double part_clearance_below(const Part& a, const Part& b, double cap) {
  double best = cap;
  for (int i = 0; i < a.count; ++i) {
    for (int j = 0; j < b.count; ++j) {
      const Capsule& x = a.shapes[static_cast<std::size_t>(i)];
      const Capsule& y = b.shapes[static_cast<std::size_t>(j)];
      if (skip(box_gap(x.a.x, x.b.x, x.r, y.a.x, y.b.x, y.r), best) || skip(box_gap(x.a.y, x.b.y, x.r, y.a.y, y.b.y, y.r), best)) {
        continue;
      }
      best = std::min(best, segment_distance(x.a, x.b, y.a, y.b) - x.r - y.r);
    }
  }
  return best;
}

}  // namespace

double min_clearance(const Part* a, std::size_t na, const Part* b, std::size_t nb) {
  // Every pair whose boxes are no closer than the best clearance so far cannot lower it.
  return min_clearance_below(a, na, b, nb, kInf);
}

double min_clearance_below(const Part* a, std::size_t na, const Part* b, std::size_t nb, double cap) {
  double best = cap;
  for (std::size_t i = 0; i < na; ++i) {
    for (std::size_t j = 0; j < nb; ++j) {
      if (a[i].plane != b[j].plane) continue;
      const double gx = std::max({0.0, a[i].lo.x - b[j].hi.x, b[j].lo.x - a[i].hi.x});
      const double gy = std::max({0.0, a[i].lo.y - b[j].hi.y, b[j].lo.y - a[i].hi.y});
      if (skip(gx, best) || skip(gy, best)) continue;  // the boxes' gap bounds the pair's clearance
      best = std::min(best, part_clearance_below(a[i], b[j], best));
    }
  }
  return best;
}

bool collide(const Part* a, std::size_t na, const Part* b, std::size_t nb, double threshold) {
  for (std::size_t i = 0; i < na; ++i) {
    for (std::size_t j = 0; j < nb; ++j) {
      if (a[i].plane != b[j].plane) continue;
      const double gx = std::max({0.0, a[i].lo.x - b[j].hi.x, b[j].lo.x - a[i].hi.x});
      const double gy = std::max({0.0, a[i].lo.y - b[j].hi.y, b[j].lo.y - a[i].hi.y});
      const double gap = std::hypot(gx, gy);
      if (gap > 0.0 && gap >= threshold) continue;
      if (part_clearance_below(a[i], b[j], threshold) < threshold) return true;
    }
  }
  return false;
}

RayCapsule ray_capsule(V2 o, const Capsule& c) {
  RayCapsule r;
  r.wa = o - c.a;
  r.wb = o - c.b;
  r.ca = dot(r.wa, r.wa) - c.r * c.r;
  r.cb = dot(r.wb, r.wb) - c.r * c.r;
  r.r = c.r;
  const V2 d = c.b - c.a;
  r.len = norm(d);
  if (r.len > 0.0) {
    r.e = (1.0 / r.len) * d;
    r.n = {-r.e.y, r.e.x};
    r.along = dot(r.wa, r.e);
    r.across = dot(r.wa, r.n);
  }
  // The bounding disk, widened by a relative 1e-9 so that rounding never skips a capsule the ray
  // enters.
  const double R = (0.5 * r.len + c.r) * (1.0 + 1e-9);
  r.wm = o - 0.5 * (c.a + c.b);
  r.cm = dot(r.wm, r.wm) - R * R;
  return r;
}

bool ray_interval(const RayCapsule& c, V2 u, double& t_in, double& t_out) {
  double lo = kInf, hi = -kInf;
  // End disks: |w + t u|^2 = r^2.
  const auto disk = [&](V2 w, double cw) {
    const double b = dot(w, u), disc = b * b - cw;
    if (disc > 0.0) {
      const double s = std::sqrt(disc);
      lo = std::min(lo, -b - s);
      hi = std::max(hi, -b + s);
    }
  };
  disk(c.wa, c.ca);
  disk(c.wb, c.cb);
  // The rectangle: 0 < along < len and |across| < r, each a slab between two parallel lines.
  if (c.len > 0.0) {
    double r_lo = -kInf, r_hi = kInf;
    const auto slab = [&](double start, double rate, double from, double to) {
      if (rate == 0.0) {
        if (!(start > from && start < to)) r_lo = kInf, r_hi = -kInf;
        return;
      }
      const double t0 = (from - start) / rate, t1 = (to - start) / rate;
      r_lo = std::max(r_lo, std::min(t0, t1));
      r_hi = std::min(r_hi, std::max(t0, t1));
    };
    slab(c.along, dot(u, c.e), 0.0, c.len);
    slab(c.across, dot(u, c.n), -c.r, c.r);
    if (r_lo < r_hi) {
      lo = std::min(lo, r_lo);
      hi = std::max(hi, r_hi);
    }
  }
  t_in = lo;
  t_out = hi;
  return lo < hi;
}

double ray_exit(V2 u, const RayCapsule* caps, std::size_t n, double* t_in, double* t_out) {
  for (std::size_t k = 0; k < n; ++k) {
    // The ray o + t u (t >= 0) misses the bounding disk |w_m + t u| < R when the line misses it or
    // when o is outside and the ray leads away from its centre.
    const double b = dot(caps[k].wm, u);
    const bool misses = b * b - caps[k].cm <= 0.0 || (caps[k].cm > 0.0 && b >= 0.0);
    if (misses || !ray_interval(caps[k], u, t_in[k], t_out[k])) t_in[k] = kInf, t_out[k] = -kInf;
  }
  double t = 0.0;
  for (std::size_t pass = 0; pass <= n; ++pass) {
    bool moved = false;
    for (std::size_t k = 0; k < n; ++k) {
      if (t_in[k] <= t && t < t_out[k]) {
        t = t_out[k];
        moved = true;
      }
    }
    if (!moved) break;
  }
  return t;
}

}  // namespace fivebar::runtime::detail
