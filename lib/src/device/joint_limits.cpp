// Joint limits from the hardware (fivebar/device/joint_limits.hpp, where the model is stated): the
// potentiometer window, the base hard stops of the proximal links, the usable range per joint and
// the margin check over the target and the patterns.

#include "fivebar/device/joint_limits.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "fivebar/collision.hpp"
#include "fivebar/design/angles.hpp"
#include "fivebar/device/config.hpp"
#include "fivebar/format.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/pattern.hpp"
#include "fivebar/sections/patterns.hpp"

namespace fivebar {

namespace {

using angles::kPi;
using angles::kTwoPi;
constexpr double kInf = std::numeric_limits<double>::infinity();
using format::fixed;
using format::kDegPerRad;

std::string deg(double rad, int digits = 2) { return fixed(rad * kDegPerRad, digits); }

}  // namespace

std::optional<JointRange> potentiometer_window(const Potentiometer& pot) {
  if (!pot.travel) return std::nullopt;
  const double k = pot.rad_per_volt;
  const double T = *pot.travel;
  const double end0 = -k * pot.volts_at_zero;              // theta at 0 V
  const double end1 = std::copysign(T, k) - k * pot.volts_at_zero;  // theta at T / |k| volts
  const double lo = std::min(end0, end1);
  return JointRange{lo, lo + T};
}

double hard_stop_half_angle(double d, double L, double r_link, double r_end, double r_obstacle) {
  const double re = r_end + r_obstacle;
  const double rs = r_link + r_obstacle;
  if (!(d > re)) return kPi;  // the obstacle overlaps the link's own end at its axis
  double alpha = 0.0;
  // End disk: |A - O_k|^2 = d^2 + L^2 - 2 d L cos(alpha) < re^2.
  const double c = (d * d + L * L - re * re) / (2.0 * d * L);
  if (c < -1.0) return kPi;
  if (c < 1.0) alpha = std::acos(c);  // acos is fine here: no tangency is decided from it
  // Segment: the foot of the perpendicular from O_k on the line is on the segment at the critical
  // angle (d cos alpha_s = sqrt(d^2 - rs^2) <= L); then d sin|alpha| < rs there.
  if (d > rs && std::sqrt((d - rs) * (d + rs)) <= L) alpha = std::max(alpha, std::asin(rs / d));
  return alpha;
}

std::vector<HardStop> hard_stops(const Station& station, const Mechanism& m, int joint, const Geometry& g) {
  const std::size_t i = static_cast<std::size_t>(joint - 1);
  const Vec2 O = joint == 1 ? m.O1 : m.O2;
  const double r_link = 0.5 * g.link_width[i];
  const double r_end = 0.5 * std::max(g.link_width[i], g.boss_diameter);
  std::vector<HardStop> out;
  for (const Mechanism* other : station.mechanisms()) {
    for (int k = 1; k <= 2; ++k) {
      if (other->name == m.name && k == joint) continue;
      const std::size_t ki = static_cast<std::size_t>(k - 1);
      if (g.layers[ki] != g.layers[i]) continue;  // the other proximal link runs in another plane
      const Vec2 Ok = k == 1 ? other->O1 : other->O2;
      const Vec2 delta = Ok - O;
      const double d = delta.norm();
      HardStop s;
      s.obstacle = other->name + " O" + std::to_string(k);
      s.direction = std::atan2(delta.y(), delta.x());
      s.half_angle = hard_stop_half_angle(d, m.L[i], r_link, r_end, 0.5 * std::max(g.link_width[ki], g.boss_diameter));
      out.push_back(s);
    }
  }
  return out;
}

std::array<UsableRange, 2> usable_ranges(const Design& design, const Station& station, const Mechanism& m) {
  std::array<UsableRange, 2> out;
  const Pose centre = ik(m, station.target.center);
  const ControllerSettings* controller = design.get<ControllerSettings>();
  const Geometry* geometry = design.get<Geometry>();
  for (int j = 1; j <= 2; ++j) {
    UsableRange& r = out[static_cast<std::size_t>(j - 1)];
    r.joint = joint_name(station.name, m.name, j);
    if (centre.status == Status::unreachable) {
      r.usable = false;
      r.problem = "the target centre is unreachable: no reference angle";
      continue;
    }
    r.reference = angles::wrap_pi(j == 1 ? centre.theta1 : centre.theta2);
    // Distances from the reference to the nearest end, clockwise (down) and counter-clockwise (up).
    double down = kInf, up = kInf;
    const auto allowed_arc = [&](const JointRange& arc, const std::string& by) {
      r.limited = true;
      const double span = arc.span();
      const double offset = angles::wrap_two_pi(r.reference - arc.lo);
      if (offset > span) {
        r.usable = false;
        r.problem = "the target centre's angle " + deg(r.reference) + " deg is outside the " + by;
        return;
      }
      if (offset < down) down = offset, r.lo_by = by;
      if (span - offset < up) up = span - offset, r.hi_by = by;
    };
    const auto blocked_arc = [&](double direction, double half, const std::string& by) {
      if (!(half > 0.0)) return;
      r.limited = true;
      if (half >= kPi) {
        r.usable = false;
        r.problem = "the " + by + " blocks every angle";
        return;
      }
      const double start = direction - half;  // blocked (start, start + 2 half)
      const double offset = angles::wrap_two_pi(r.reference - start);
      if (offset < 2.0 * half) {
        r.usable = false;
        r.problem = "the target centre's angle " + deg(r.reference) + " deg is inside the " + by + " (" +
                    deg(direction - half) + " ... " + deg(direction + half) + " deg)";
        return;
      }
      // Going up from the reference we meet `start`; going down, start + 2 half.
      const double to_start = angles::wrap_two_pi(start - r.reference);
      const double to_end = offset - 2.0 * half;
      if (to_start < up) up = to_start, r.hi_by = by;
      if (to_end < down) down = to_end, r.lo_by = by;
    };
    if (m.joint_limits) allowed_arc((*m.joint_limits)[static_cast<std::size_t>(j - 1)], "joint_limits");
    if (controller != nullptr) {
      if (const auto window = potentiometer_window(controller->joint(station.name, m.name, j).potentiometer)) {
        allowed_arc(*window, "potentiometer travel");
      }
    }
    if (geometry != nullptr) {
      for (const HardStop& s : hard_stops(station, m, j, *geometry)) blocked_arc(s.direction, s.half_angle, "hard stop at " + s.obstacle);
    }
    if (!r.usable || !r.limited) continue;
    // Only allowed arcs set an end at infinity when none of them; blocked arcs always set both.
    if (down == kInf) down = 0.0, r.lo_by.clear();
    if (up == kInf) up = 0.0, r.hi_by.clear();
    if (down + up > kTwoPi) up = kTwoPi - down;
    r.lo = r.reference - down;
    r.hi = r.reference + up;
  }
  return out;
}

Station with_usable_limits(const Design& design, const Station& station) {
  Station out = station;
  for (std::optional<Mechanism>* slot : {&out.lower, &out.upper}) {
    if (!slot->has_value()) continue;
    Mechanism& m = **slot;
    const std::array<UsableRange, 2> r = usable_ranges(design, station, m);
    if (!r[0].usable || !r[1].usable || (!r[0].limited && !r[1].limited)) continue;
    std::array<JointRange, 2> limits;
    for (std::size_t j = 0; j < 2; ++j) {
      // JointRange{a, a} is the full turn (span 2 pi).
      limits[j] = r[j].limited ? JointRange{r[j].lo, r[j].hi} : JointRange{r[j].reference - kPi, r[j].reference - kPi};
    }
    m.joint_limits = limits;
  }
  return out;
}

double range_margin(const UsableRange& range, double theta) {
  if (!range.limited) return kInf;
  const double span = range.span();
  const double offset = angles::wrap_two_pi(theta - range.lo);
  if (offset <= span) return std::min(offset, span - offset);
  return -std::min(offset - span, kTwoPi - offset);
}

namespace {

/// Smallest clearance between a proximal link and the other leg's links in its plane (mm).
double other_leg_clearance(const Mechanism& m, const Pose& pose, const Geometry& g) {
  const std::vector<OutlinePart> parts = link_outline(m, pose, g);
  const auto find = [&](std::string_view name) -> const OutlinePart* {
    for (const OutlinePart& p : parts) {
      if (p.name == name) return &p;
    }
    return nullptr;
  };
  const auto clearance = [&](const OutlinePart* a, const OutlinePart* b) {
    if (a == nullptr || b == nullptr || a->plane != b->plane) return kInf;
    double best = kInf;
    for (int i = 0; i < a->count; ++i) {
      for (int k = 0; k < b->count; ++k) best = std::min(best, capsule_clearance(a->shapes[static_cast<std::size_t>(i)], b->shapes[static_cast<std::size_t>(k)]));
    }
    return best;
  };
  const OutlinePart *l1 = find("L1"), *l2 = find("L2"), *l3 = find("L3"), *l4 = find("L4");
  return std::min({clearance(l1, l2), clearance(l1, l4), clearance(l2, l3)});
}

/// Running worst of one check.
struct Worst {
  double margin = kInf;
  std::string joint;
  double theta = 0.0;
  Vec2 point{0.0, 0.0};
  double clearance = kInf;
  Vec2 clearance_point{0.0, 0.0};
  std::size_t samples = 0;
  bool any_limited = false;
};

void visit(const Mechanism& m, const std::array<UsableRange, 2>& ranges, const Geometry* g, const Vec2& p, Worst& w) {
  const Pose pose = ik(m, p);
  if (pose.status == Status::unreachable) return;
  ++w.samples;
  const std::array<double, 2> theta{pose.theta1, pose.theta2};
  for (std::size_t j = 0; j < 2; ++j) {
    if (!ranges[j].limited || !ranges[j].usable) continue;
    w.any_limited = true;
    const double margin = range_margin(ranges[j], theta[j]);
    if (margin < w.margin) {
      w.margin = margin, w.joint = ranges[j].joint, w.point = p;
      // On the range's branch, for the message.
      w.theta = ranges[j].lo + angles::wrap_two_pi(theta[j] - ranges[j].lo);
      if (w.theta > ranges[j].hi + kPi) w.theta -= kTwoPi;
    }
  }
  if (g != nullptr) {
    const double c = other_leg_clearance(m, pose, *g);
    if (c < w.clearance) w.clearance = c, w.clearance_point = p;
  }
}

JointMarginCheck verdict(std::string subject, const Worst& w, double margin, const Geometry* g) {
  JointMarginCheck c;
  c.subject = std::move(subject);
  c.samples = w.samples;
  c.worst_margin = w.margin;
  c.worst_joint = w.joint;
  c.min_link_clearance_mm = w.clearance;
  const bool margin_ok = !w.any_limited || w.margin >= margin;
  const bool clearance_ok = g == nullptr || !(w.clearance < g->min_clearance);
  c.passed = margin_ok && clearance_ok;
  const auto point = [](const Vec2& p) { return "(" + fixed(p.x(), 3) + ", " + fixed(p.y(), 3) + ") mm"; };
  std::string d;
  if (!w.any_limited) {
    d = "no joint limits (nothing to keep inside)";
  } else {
    d = "closest to a limit: " + w.joint + " " + deg(w.margin) + " deg inside at " + point(w.point) +
        (margin_ok ? " >= " : ", below ") + "the margin " + deg(margin) + " deg";
  }
  if (g != nullptr) {
    d += std::string("; proximal links vs the other leg's links ") +
         (std::isfinite(w.clearance) ? fixed(w.clearance, 3) + " mm at " + point(w.clearance_point) : std::string("share no plane")) +
         (std::isfinite(w.clearance) ? (clearance_ok ? " >= " : ", below ") + fixed(g->min_clearance, 3) + " mm" : std::string());
  }
  c.detail = d + " (" + std::to_string(w.samples) + " samples)";
  return c;
}

}  // namespace

std::vector<JointMarginCheck> check_joint_margins(const Design& design, const Station& station,
                                                  const JointMarginOptions& options) {
  const ControllerSettings* controller = design.get<ControllerSettings>();
  const Geometry* g = design.get<Geometry>();
  const double margin = controller != nullptr ? controller->joint_margin : 0.0;
  std::vector<JointMarginCheck> out;
  std::array<std::array<UsableRange, 2>, 2> ranges;  // lower, upper
  const Ellipse& e = station.target;
  for (const Mechanism* m : station.mechanisms()) {
    const auto& r = ranges[m->name == "lower" ? 0 : 1] = usable_ranges(design, station, *m);
    Worst w;
    visit(*m, r, g, e.center, w);
    const int n = std::max(8, options.boundary_samples);
    for (int k = 0; k < n; ++k) visit(*m, r, g, e.boundary_point(kTwoPi * k / n), w);
    const int rings = std::max(1, options.rings);
    const int angles = std::max(8, options.angles);
    for (int i = 1; i < rings; ++i) {
      const double s = double(i) / rings;
      for (int k = 0; k < angles; ++k) visit(*m, r, g, e.center + s * (e.boundary_point(kTwoPi * k / angles) - e.center), w);
    }
    out.push_back(verdict(station.name + "/" + m->name, w, margin, g));
  }
  const PatternSettings* patterns = design.get<PatternSettings>();
  if (patterns == nullptr || !(station.lower && station.upper)) return out;
  for (const PatternSpec& spec : patterns->for_station(station.name)) {
    const PatternPath path = pattern_path(spec, e.center);
    Worst w;
    for (std::size_t k = 0; k < path.time_s.size(); ++k) {
      visit(*station.lower, ranges[0], g, path.lower[k], w);
      visit(*station.upper, ranges[1], g, path.upper[k], w);
    }
    out.push_back(verdict(station.name + " " + std::string(to_string(spec.kind)), w, margin, g));
  }
  return out;
}

std::string describe(const UsableRange& r) {
  if (!r.usable) return r.problem;
  if (!r.limited) return "every angle";
  const auto end = [](const std::string& by) { return by.empty() ? std::string("-") : by; };
  return "[" + deg(r.lo) + ", " + deg(r.hi) + "] deg (" + end(r.lo_by) + " ... " + end(r.hi_by) + ")";
}

}  // namespace fivebar

namespace fivebar {

double motor_free_speed(const MotorParams& p) {
  const double gain = p.gearbox_efficiency * p.gear_ratio * p.torque_constant();  // output torque per ampere
  const double ke = p.back_emf_constant() * p.gear_ratio;                         // back-emf per output rad/s
  const double tau_c = p.coulomb_friction(), b = p.viscous_friction();
  double w = (gain * p.supply_voltage_V / p.resistance() - tau_c) / (gain * ke / p.resistance() + b);
  if ((p.supply_voltage_V - ke * w) / p.resistance() > p.current_limit_A && b > 0.0) {
    w = (gain * p.current_limit_A - tau_c) / b;  // the driver's limit binds before the speed settles
  }
  return std::max(w, 0.0);
}

double joint_speed_limit(const Design& design, const Station& station, const Mechanism& mechanism, int joint) {
  const ControllerSettings* controller = design.get<ControllerSettings>();
  const MotorSettings* motors = design.get<MotorSettings>();
  double v = controller != nullptr ? controller->max_velocity : 0.0;
  if (motors != nullptr) {
    const double motor = motor_free_speed(motors->joint(station.name, mechanism.name, joint));
    v = controller != nullptr ? std::min(v, motor) : motor;
  }
  return v;
}

double station_joint_speed_limit(const Design& design, const Station& station) {
  double v = std::numeric_limits<double>::infinity();
  for (const Mechanism* m : station.mechanisms()) {
    for (int j = 1; j <= 2; ++j) v = std::min(v, joint_speed_limit(design, station, *m, j));
  }
  return std::isfinite(v) ? v : 0.0;
}

double pattern_joint_speed_limit(const Design& design, const Station& station) {
  const double v = station_joint_speed_limit(design, station);
  if (v > 0.0) return v;
  const PatternSettings* patterns = design.get<PatternSettings>();
  return patterns != nullptr ? patterns->max_joint_speed : PatternSettings{}.max_joint_speed;
}

}  // namespace fivebar
