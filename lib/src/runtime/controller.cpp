// One control cycle of the device (fivebar/runtime/controller.hpp; docs/runtime.md). Every buffer
// is sized in the constructor; cycle() only writes into them.

#include "fivebar/runtime/controller.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <string>
#include <utility>

#include "geometry.hpp"

namespace fivebar::runtime {

using detail::Mech;
using detail::Part;
using detail::PartTemplate;
using detail::Pose;
using detail::PoseStatus;
using detail::V2;

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kTwoPi = 2.0 * kPi;

// The priority rule's second stage (docs/runtime.md "Priority rule"), when the rays' march finds no
// free point: rings from kPriorityRingFirstRel length scales about the target, each
// kPriorityRingGrowth times the last (at most kPriorityRings), up to kPrioritySearchRadiusRel length
// scales, kPriorityRays points each. Within that radius the rule does not stop the lower mechanism
// while a free point exists (test_runtime checks it against a dense brute-force search).
constexpr double kPrioritySearchRadiusRel = 1.0;
constexpr double kPriorityRingFirstRel = 0.005;
constexpr double kPriorityRingGrowth = 1.2;
constexpr int kPriorityRings = 32;
}  // namespace

// --- Config -------------------------------------------------------------------------------------

double MechanismConfig::length_scale() const {
  const double base = std::hypot(o2[0] - o1[0], o2[1] - o1[1]);
  return std::max({L[0], L[1], L[2], L[3], base});
}

std::size_t Config::mechanism_count() const {
  std::size_t n = 0;
  for (const StationConfig& s : stations) n += s.mechanisms.size();
  return n;
}

const char* to_string(Status s) noexcept {
  switch (s) {
    case Status::ok: return "ok";
    case Status::moved_by_priority: return "moved_by_priority";
    case Status::unreachable: return "unreachable";
    case Status::singular: return "singular";
    case Status::limit: return "limit";
    case Status::sensor_fault: return "sensor_fault";
  }
  return "ok";
}

double pid_update(const Gains& g, double T, PidState& s, double e) noexcept {
  s.sum += e * T;
  if (g.i > 0.0) {
    const double bound = g.i_clamp / g.i;
    s.sum = std::clamp(s.sum, -bound, bound);
  }
  const double d = s.first ? 0.0 : (e - s.previous) / T;
  s.first = false;
  s.previous = e;
  return std::clamp(g.p * e + g.i * s.sum + g.d * d, -1.0, 1.0);
}

double adc_code(double volts, int bits, const std::array<double, 2>& range, double vpc) noexcept {
  const double top = std::ldexp(1.0, bits) - 1.0;
  if (!std::isfinite(volts)) return 0.0;
  return std::clamp(std::round((volts - range[0]) / vpc), 0.0, top);
}

// --- Plan ---------------------------------------------------------------------------------------

namespace detail {

/// A commanded pose and its outline.
struct Command {
  bool valid = false;
  Pose pose;
  std::array<double, 2> theta{};
  std::size_t outline = 0;  ///< offset of its parts in Plan::parts
};

struct MechPlan {
  Mech mech;
  const MechanismConfig* config = nullptr;
  std::array<PidState, 2> pid{};
  Command held;       ///< the last valid command (held when a new one fails)
  Command candidate;  ///< this cycle's
  Pose measured;
  std::size_t measured_outline = 0;
  bool fresh = false;  ///< this cycle's reference gave the command
  /// The joint targets the PIDs follow (the slew limit): the held command approached at most
  /// max_velocity * period per cycle; from the measured angles after construction, reset() or zero duty.
  std::array<double, 2> follow{};
  bool follow_valid = false;
};

struct StationPlan {
  int lower = -1, upper = -1;  ///< mechanism indices
};

struct Plan {
  Config config;
  double period = 0.0;
  double top_code = 0.0;
  std::vector<MechPlan> mechs;
  std::vector<StationPlan> stations;
  std::vector<MechanismState> state;
  std::vector<StationState> station_state;
  std::vector<double> duties;
  std::vector<PartTemplate> tpl;
  /// Outline buffers: per mechanism held, candidate and measured, plus two probes.
  std::vector<Part> parts;
  std::size_t probe_a = 0, probe_b = 0;
  std::array<V2, kPriorityRays> rays{};
  /// The priority rule's closed-form part (closest_free()): the radius of the lower outline's
  /// disks centred on its tactor point P, per plane (0: none), and per search the upper shapes
  /// inflated by it (the forbidden capsules of P), its candidate directions and their exits.
  std::vector<double> p_disk;
  std::vector<detail::Capsule> forbid;
  std::vector<detail::RayCapsule> seen;
  std::vector<double> t_in, t_out;
  std::vector<V2> dirs;
  std::vector<double> exits;
  std::vector<int> steps;
  std::vector<double> at, before;
};

}  // namespace detail

using detail::Command;
using detail::MechPlan;
using detail::Plan;

namespace {

std::size_t n_parts(const Plan& p) { return p.tpl.size(); }
Part* outline_at(Plan& p, std::size_t offset) { return p.parts.data() + offset; }

/// `theta` on the joint's branch: within [min, min + 2 pi) with limits, else as given.
double on_branch(const JointConfig& j, double theta) {
  if (!j.has_position_limits) return theta;
  double t = theta - kTwoPi * std::floor((theta - j.min_position) / kTwoPi);
  if (t < j.min_position) t += kTwoPi;  // rounding of the floor
  return t;
}

/// The centre of the one turn a joint's reading may lie in: its range's centre with limits, else
/// the calibration's zero.
double turn_centre(const JointConfig& j) {
  return j.has_position_limits ? 0.5 * (j.min_position + j.max_position) : 0.0;
}

/// IK of `point` for mechanism `mp` into `c`; the status of the attempt.
Status make_command(const Plan& plan, const MechPlan& mp, V2 point, Command& c) {
  c.valid = false;
  if (!std::isfinite(point.x) || !std::isfinite(point.y)) return Status::unreachable;
  const Pose pose = detail::ik(mp.mech, point);
  if (pose.status == PoseStatus::unreachable) return Status::unreachable;
  if (pose.status == PoseStatus::singular) return Status::singular;
  if (mp.mech.assembly != Assembly::any && pose.assembly != static_cast<std::int8_t>(mp.mech.assembly)) {
    return Status::unreachable;
  }
  const double raw[2] = {pose.theta1, pose.theta2};
  for (std::size_t j = 0; j < 2; ++j) {
    const JointConfig& jc = mp.config->joints[j];
    c.theta[j] = on_branch(jc, raw[j]);
    if (jc.has_position_limits &&
        !(c.theta[j] >= jc.min_position + plan.config.joint_margin && c.theta[j] <= jc.max_position - plan.config.joint_margin)) {
      return Status::limit;
    }
  }
  c.pose = pose;
  c.valid = true;
  return Status::ok;
}

/// The lower mechanism at q against the upper outline: how far it may move before its outline can
/// touch (0 when free or unusable; see closest_free()). Free: a valid command clear of the outline.
struct Probe {
  bool usable = false, free = false;
  double advance = 0.0;
};
Probe probe(Plan& plan, const MechPlan& low, const Part* upper, V2 q) {
  Probe r;
  Command c;
  if (make_command(plan, low, q, c) != Status::ok) return r;
  r.usable = true;
  Part* mine = outline_at(plan, plan.probe_a);
  detail::outline(plan.tpl, c.pose, mine);
  const double need = plan.config.collision.min_clearance;
  const double clearance = detail::min_clearance_below(upper, n_parts(plan), mine, n_parts(plan), need);
  r.free = !(clearance < need);
  if (r.free) return r;
  // Every point of the outline moves at most k times as fast as the tactor point: A_i at
  // 1 / |sin| of the angle between L_i and L_{i+2} (the circle of A_i about O_i against the
  // circle about P), the links' points between their ends.
  const detail::Mech& m = low.mech;
  const Pose& p = c.pose;
  const double s1 = std::fabs(detail::cross(p.A1 - m.O1, p.P - p.A1)) / (m.L[0] * m.L[2]);
  const double s2 = std::fabs(detail::cross(p.A2 - m.O2, p.P - p.A2)) / (m.L[1] * m.L[3]);
  const double k = std::max(1.0, 1.0 / std::min(s1, s2));
  r.advance = (need - clearance) / k;
  return r;
}

/// Whether q lies inside one of the first `nf` forbidden capsules of the tactor point (closed form:
/// blocked without a probe).
bool forbidden(const Plan& plan, std::size_t nf, V2 q) {
  for (std::size_t k = 0; k < nf; ++k) {
    const detail::Capsule& c = plan.forbid[k];
    const V2 d = c.b - c.a;
    const double dd = dot(d, d);
    const double t = dd > 0.0 ? std::clamp(dot(q - c.a, d) / dd, 0.0, 1.0) : 0.0;
    const V2 w = q - (c.a + t * d);
    if (dot(w, w) < c.r * c.r) return true;
  }
  return false;
}

/// The rule's second stage, when the rays' march found no free point (links block every exit
/// within its steps): rings about `origin` at radii r_k = kPriorityRingFirstRel * scale *
/// kPriorityRingGrowth^(k-1) up to `radius` (the search radius), kPriorityRays fixed
/// directions each (a point inside a forbidden capsule of the tactor is blocked without a probe); on
/// the first ring with a free point every free ray is bisected kPriorityBisections times against the
/// ring before, and the closest result wins. A ring point that cannot be held is not free, and its
/// ray goes on (points beyond it can be). At most kPriorityRings * kPriorityRays probes plus the
/// bisections.
bool ring_search(Plan& plan, const MechPlan& low, const Part* upper, V2 origin, std::size_t nf, double radius, V2& found) {
  const double scale = low.mech.scale;
  std::array<bool, kPriorityRays> hit{};
  double r_prev = 0.0, r = kPriorityRingFirstRel * scale;
  for (int k = 0; k < kPriorityRings && r_prev < radius; ++k) {
    r = std::min(r, radius);
    bool any = false;
    for (std::size_t j = 0; j < kPriorityRays; ++j) {
      const V2 q = origin + r * plan.rays[j];
      hit[j] = !forbidden(plan, nf, q) && probe(plan, low, upper, q).free;
      any = any || hit[j];
    }
    if (any) {
      double best = std::numeric_limits<double>::infinity();
      std::size_t best_j = 0;
      for (std::size_t j = 0; j < kPriorityRays; ++j) {
        if (!hit[j]) continue;
        double lo = r_prev, hi = r;
        for (int b = 0; b < kPriorityBisections; ++b) {
          const double mid = 0.5 * (lo + hi);
          const V2 q = origin + mid * plan.rays[j];
          if (!forbidden(plan, nf, q) && probe(plan, low, upper, q).free) hi = mid;
          else lo = mid;
        }
        if (hi < best) best = hi, best_j = j;
      }
      found = origin + best * plan.rays[best_j];
      return true;
    }
    r_prev = r;
    r *= kPriorityRingGrowth;
  }
  return false;
}

/// The priority rule (controller.hpp, docs/runtime.md "Priority rule"): the closest point q to
/// `origin` where the lower mechanism is free, i.e. usable and clear of the upper outline.
///
/// Every disk of the lower outline centred on its tactor point (tactor, post, pin P, the ends and
/// bosses of L3 and L4) follows q one to one, so q is blocked wherever such a disk comes closer
/// than min_clearance to an upper shape of its plane: inside the capsule of that shape inflated by
/// the disk's radius plus min_clearance. Along any ray from `origin` the first point outside the
/// union of those capsules is a closed form (ray_exit), and no point of the ray before it is
/// free. Candidate directions: kPriorityRays fixed rays and, per forbidden capsule, the direction
/// of the origin's projection onto it (where the closest point of a single capsule's boundary
/// lies). Their exits are probed (IK, outline, clearance) best first; a free exit settles its ray
/// exactly. The outline's links can still block an exit: such a ray advances conservatively (see
/// below); one that leaves what the lower mechanism can hold (reach, singularities, limits) ends.
/// At most kPriorityMaxProbes pose evaluations; true with the point.
bool closest_free(Plan& plan, const MechPlan& low, const Part* upper, V2 origin, V2& found) {
  const std::size_t np = n_parts(plan);
  const double scale = low.mech.scale;
  // The forbidden capsules of P.
  std::size_t nf = 0;
  for (std::size_t i = 0; i < np; ++i) {
    const auto plane = static_cast<std::size_t>(upper[i].plane);
    const double r = plane < plan.p_disk.size() ? plan.p_disk[plane] : 0.0;
    if (!(r > 0.0)) continue;
    for (int k = 0; k < upper[i].count; ++k) {
      detail::Capsule c = upper[i].shapes[static_cast<std::size_t>(k)];
      c.r += r + plan.config.collision.min_clearance;
      plan.forbid[nf++] = c;
    }
  }
  // Candidate directions: the fixed rays, then the projections.
  std::size_t nd = 0;
  for (const V2 u : plan.rays) plan.dirs[nd++] = u;
  for (std::size_t k = 0; k < nf; ++k) {
    const detail::Capsule& c = plan.forbid[k];
    const V2 d = c.b - c.a;
    const double dd = dot(d, d);
    const double t = dd > 0.0 ? std::clamp(dot(origin - c.a, d) / dd, 0.0, 1.0) : 0.0;
    const V2 w = origin - (c.a + t * d);
    const double len = norm(w);
    const auto add = [&](V2 u) {  // once: shapes of several planes share their axes
      for (std::size_t i = kPriorityRays; i < nd; ++i)
        if (dot(u, plan.dirs[i]) > 1.0 - 1e-12) return;
      plan.dirs[nd++] = u;
    };
    if (len > 1e-9 * scale) {
      add((1.0 / len) * w);
    } else if (dd > 0.0) {  // on the axis: both normals
      const V2 n = (1.0 / std::sqrt(dd)) * V2{-d.y, d.x};
      add(n);
      add(-1.0 * n);
    }
  }
  // Exits (closed form), just outside the boundary against rounding.
  const double nudge = 1e-9 * scale;
  for (std::size_t k = 0; k < nf; ++k) plan.seen[k] = detail::ray_capsule(origin, plan.forbid[k]);
  for (std::size_t j = 0; j < nd; ++j) {
    plan.exits[j] = detail::ray_exit(plan.dirs[j], plan.seen.data(), nf, plan.t_in.data(), plan.t_out.data()) + nudge;
  }
  // Best first over the rays: each ray's `at` is a distance before which no point of it is free
  // (first its exit); the ray with the smallest is probed next, until it is no smaller than the
  // best free point found. A blocked point advances its ray conservatively by the clearance
  // missing over the fastest speed of the outline (no free point is skipped while that speed
  // holds), at least kPriorityMinStepRel length scales. The first free point of a ray is bisected
  // kPriorityBisections times against the blocked one before it (none when it is the exit: exact).
  const double h_min = kPriorityMinStepRel * scale;
  const double inf = std::numeric_limits<double>::infinity();
  for (std::size_t j = 0; j < nd; ++j) {
    plan.at[j] = plan.exits[j];
    plan.before[j] = -1.0;
    plan.steps[j] = 0;
  }
  double best = inf;
  std::size_t best_dir = 0;
  int probes = 0;
  // The rays that start outside every forbidden capsule share their first point, the origin.
  bool shared = false;
  for (std::size_t j = 0; j < nd; ++j) shared = shared || plan.exits[j] <= 2.0 * nudge;
  if (shared) {
    ++probes;
    const Probe pr = probe(plan, low, upper, origin);
    for (std::size_t j = 0; j < nd; ++j) {
      if (!(plan.exits[j] <= 2.0 * nudge)) continue;
      if (!pr.usable) {
        plan.steps[j] = kPriorityAdvances + 1;
      } else if (pr.free) {
        best = 0.0;  // not colliding after all (the caller checked the held command)
      } else {
        plan.before[j] = 0.0;
        plan.at[j] = std::max(pr.advance, h_min);
        plan.steps[j] = 1;
      }
    }
  }
  while (probes < kPriorityMaxProbes) {
    std::size_t j = 0;
    double t = inf;
    for (std::size_t i = 0; i < nd; ++i) {
      if (plan.steps[i] <= kPriorityAdvances && plan.at[i] < t) t = plan.at[i], j = i;
    }
    if (!(t < best)) break;
    const V2 u = plan.dirs[j];
    ++probes;
    const Probe pr = probe(plan, low, upper, origin + t * u);
    if (!pr.usable) {
      plan.steps[j] = kPriorityAdvances + 1;  // the ray leaves what the lower mechanism can hold
      continue;
    }
    if (!pr.free) {
      plan.before[j] = t;
      plan.at[j] = t + std::max(pr.advance, h_min);
      ++plan.steps[j];
      continue;
    }
    if (plan.before[j] >= 0.0) {
      double lo = plan.before[j], hi = t;
      for (int b = 0; b < kPriorityBisections && probes < kPriorityMaxProbes; ++b) {
        const double mid = 0.5 * (lo + hi);
        ++probes;
        if (probe(plan, low, upper, origin + mid * u).free) hi = mid;
        else lo = mid;
      }
      t = hi;
    }
    best = t;
    best_dir = j;
    plan.steps[j] = kPriorityAdvances + 1;  // done
  }
  const double radius = kPrioritySearchRadiusRel * low.mech.scale;
  if (!(best < inf)) return ring_search(plan, low, upper, origin, nf, radius, found);
  found = origin + best * plan.dirs[best_dir];
  return true;
}

void zero(MechPlan& mp, MechanismState& st, double* duty) {
  mp.pid = {PidState{}, PidState{}};
  mp.follow_valid = false;  // the motors were unpowered: the slew starts again where the joints are
  duty[0] = duty[1] = 0.0;
  st.duty = {0.0, 0.0};
}

/// The slew limit (docs/runtime.md "One cycle" 5): joint j's target `follow` moves toward the
/// held command by at most max_velocity * T per cycle where the joint has velocity limits (else it
/// is the command), the difference taken within half a turn; it reaches the command exactly.
double slew(const JointConfig& jc, double command, double& follow, double T) {
  double step = command - follow;
  if (std::fabs(step) > kPi) step -= kTwoPi * std::round(step / kTwoPi);
  const double max_step = jc.max_velocity * T;
  follow = !jc.has_velocity_limits || std::fabs(step) <= max_step ? command : follow + std::copysign(max_step, step);
  return follow;
}

}  // namespace

Controller::Controller(Config config) {
  config.validate();
  auto plan = std::make_unique<Plan>();
  Plan& p = *plan;
  p.config = std::move(config);
  p.period = 1.0 / p.config.loop_rate_hz;
  p.top_code = std::ldexp(1.0, p.config.adc_bits) - 1.0;
  if (p.config.collision.checked) p.tpl = detail::outline_template(p.config.collision);
  for (const StationConfig& s : p.config.stations) {
    detail::StationPlan sp;
    for (const MechanismConfig& m : s.mechanisms) {
      MechPlan mp;
      mp.config = &m;
      mp.mech.O1 = {m.o1[0], m.o1[1]};
      mp.mech.O2 = {m.o2[0], m.o2[1]};
      mp.mech.L = m.L;
      mp.mech.mode = m.working_mode;
      mp.mech.assembly = m.assembly;
      mp.mech.scale = m.length_scale();
      (m.name == "lower" ? sp.lower : sp.upper) = static_cast<int>(p.mechs.size());
      p.mechs.push_back(mp);
    }
    p.stations.push_back(sp);
  }
  const std::size_t n = p.mechs.size(), np = p.tpl.size();
  for (std::size_t k = 0; k < n; ++k) {
    p.mechs[k].held.outline = (3 * k) * np;
    p.mechs[k].candidate.outline = (3 * k + 1) * np;
    p.mechs[k].measured_outline = (3 * k + 2) * np;
  }
  p.probe_a = 3 * n * np;
  p.probe_b = p.probe_a + np;
  p.parts.assign(3 * n * np + 2 * np, Part{});
  p.state.assign(n, MechanismState{});
  p.station_state.assign(p.stations.size(), StationState{});
  p.duties.assign(2 * n, 0.0);
  for (std::size_t j = 0; j < kPriorityRays; ++j) {
    const double phi = kTwoPi * double(j) / kPriorityRays;
    p.rays[j] = {std::cos(phi), std::sin(phi)};
  }
  // The lower outline's disks on P per plane (the largest; geometry.cpp outline()), and the
  // buffers of the priority rule sized for every upper shape in those planes.
  for (const PartTemplate& t : p.tpl) {
    const bool on_p = (t.link < 0 && t.point == 4) || t.link == 2 || t.link == 3;
    if (!on_p) continue;
    const double r = t.link >= 0 && t.boss ? std::max(t.r, t.boss_r) : t.r;
    const auto plane = static_cast<std::size_t>(t.plane);
    if (p.p_disk.size() <= plane) p.p_disk.resize(plane + 1, 0.0);
    p.p_disk[plane] = std::max(p.p_disk[plane], r);
  }
  std::size_t nf = 0;
  for (const PartTemplate& t : p.tpl) {
    const auto plane = static_cast<std::size_t>(t.plane);
    if (plane < p.p_disk.size() && p.p_disk[plane] > 0.0) nf += t.link >= 0 && t.boss ? 3 : 1;
  }
  p.forbid.assign(nf, detail::Capsule{});
  p.seen.assign(nf, detail::RayCapsule{});
  p.t_in.assign(nf, 0.0);
  p.t_out.assign(nf, 0.0);
  const std::size_t nd = kPriorityRays + 2 * nf;
  p.dirs.assign(nd, V2{});
  p.exits.assign(nd, 0.0);
  p.steps.assign(nd, 0);
  p.at.assign(nd, 0.0);
  p.before.assign(nd, 0.0);
  plan_ = plan.release();
}

Controller::~Controller() { delete plan_; }
Controller::Controller(Controller&& o) noexcept : plan_(std::exchange(o.plan_, nullptr)) {}
Controller& Controller::operator=(Controller&& o) noexcept {
  std::swap(plan_, o.plan_);
  return *this;
}

const Config& Controller::config() const noexcept { return plan_->config; }
std::size_t Controller::mechanism_count() const noexcept { return plan_->mechs.size(); }
const double* Controller::duties() const noexcept { return plan_->duties.data(); }
const MechanismState& Controller::mechanism(std::size_t k) const noexcept { return plan_->state[k]; }
const StationState& Controller::station(std::size_t s) const noexcept { return plan_->station_state[s]; }

void Controller::reset() noexcept {
  for (MechPlan& mp : plan_->mechs) {
    mp.pid = {PidState{}, PidState{}};
    mp.held.valid = false;
    mp.candidate.valid = false;
    mp.follow_valid = false;
  }
  for (MechanismState& s : plan_->state) s = MechanismState{};
  for (double& d : plan_->duties) d = 0.0;
}

void Controller::cycle(const double* readings, Reading kind, const double* targets) noexcept {
  Plan& p = *plan_;
  const Config& c = p.config;
  const bool outlines = c.collision.checked;
  const std::size_t np = p.tpl.size();
  // 1-3: readings, FK of the measured joints, IK of the references.
  for (std::size_t k = 0; k < p.mechs.size(); ++k) {
    MechPlan& mp = p.mechs[k];
    MechanismState& st = p.state[k];
    st = MechanismState{};
    bool fault = readings == nullptr;
    for (std::size_t j = 0; j < 2 && !fault; ++j) {
      const double r = readings[2 * k + j];
      const JointConfig& jc = mp.config->joints[j];
      double volts = 0.0;
      const double centre = turn_centre(jc);
      if (!std::isfinite(r)) {
        fault = true;
      } else if (kind == Reading::radians) {
        // An angle (an encoder's, any representation) more than a turn from the joint's range.
        fault = !(std::fabs(r - centre) <= kTwoPi);
        st.theta_measured[j] = fault ? 0.0 : r;
        continue;
      } else if (kind == Reading::counts) {
        fault = !(r > 0.5 && r < p.top_code - 0.5);  // outside the ADC or within half a code of a rail
        volts = c.adc_range_v[0] + r * c.volts_per_count;
      } else {
        const double half = 0.5 * c.volts_per_count;
        fault = !(r > c.adc_range_v[0] + half && r < c.adc_range_v[0] + (p.top_code - 0.5) * c.volts_per_count);
        volts = r;
      }
      const double theta = jc.rad_per_volt * (volts - jc.volts_at_zero);
      // A potentiometer turns at most once: an angle more than half a turn from the joint's
      // range's centre is not one the calibration can read (the converter spans more).
      fault = fault || !(std::fabs(theta - centre) <= kPi);
      st.theta_measured[j] = fault ? 0.0 : theta;
    }
    if (!fault) {
      mp.measured = detail::fk(mp.mech, st.theta_measured[0], st.theta_measured[1]);
      // No closed loop through the measured angles: the readings contradict the geometry.
      fault = mp.measured.status == PoseStatus::unreachable;
      st.measured_pose = !fault;
      if (!fault) {
        st.point_measured = {mp.measured.P.x, mp.measured.P.y};
        if (outlines) detail::outline(p.tpl, mp.measured, outline_at(p, mp.measured_outline));
      }
    }
    if (fault) {
      st.theta_measured = {0.0, 0.0};
      st.status = Status::sensor_fault;
    }
    const V2 target = targets ? V2{targets[2 * k], targets[2 * k + 1]} : V2{std::nan(""), std::nan("")};
    st.target = {std::isfinite(target.x) ? target.x : 0.0, std::isfinite(target.y) ? target.y : 0.0};
    const Status s = make_command(p, mp, target, mp.candidate);
    mp.fresh = mp.candidate.valid;
    if (st.status == Status::ok) st.status = s;
    if (outlines && mp.candidate.valid) detail::outline(p.tpl, mp.candidate.pose, outline_at(p, mp.candidate.outline));
    if (mp.candidate.valid) {
      // The new command replaces the held one (buffers swap: no copy of the parts).
      std::swap(mp.held, mp.candidate);
    }
  }
  // 4: the priority rule per station (upper first: it keeps its command).
  for (std::size_t s = 0; s < p.stations.size(); ++s) {
    const detail::StationPlan& sp = p.stations[s];
    StationState& ss = p.station_state[s];
    ss = StationState{};
    if (!outlines || sp.lower < 0 || sp.upper < 0) continue;
    MechPlan& low = p.mechs[static_cast<std::size_t>(sp.lower)];
    MechPlan& up = p.mechs[static_cast<std::size_t>(sp.upper)];
    MechanismState& lst = p.state[static_cast<std::size_t>(sp.lower)];
    if (p.state[static_cast<std::size_t>(sp.upper)].measured_pose && lst.measured_pose) {
      ss.checked = true;
      ss.measured_clearance = detail::min_clearance(outline_at(p, up.measured_outline), np, outline_at(p, low.measured_outline), np);
      if (!std::isfinite(ss.measured_clearance)) ss.measured_clearance = 0.0, ss.checked = false;
      ss.measured_collision = ss.checked && ss.measured_clearance < c.collision.min_clearance;
    }
    if (!up.held.valid || !low.held.valid) continue;
    const Part* upper = outline_at(p, up.held.outline);
    if (!detail::collide(upper, np, outline_at(p, low.held.outline), np, c.collision.min_clearance)) continue;
    // Search from the reference point when it has a command this cycle, else from the held point.
    const V2 origin = low.fresh ? V2{lst.target[0], lst.target[1]} : low.held.pose.P;
    V2 found;
    Command moved;
    moved.outline = low.candidate.outline;
    if (closest_free(p, low, upper, origin, found) && make_command(p, low, found, moved) == Status::ok) {
      detail::outline(p.tpl, moved.pose, outline_at(p, moved.outline));
      std::swap(low.held, moved);
      low.candidate.outline = moved.outline;
      if (lst.status == Status::ok) lst.status = Status::moved_by_priority;  // a worse status stays
      lst.moved = norm(found - origin);
    } else {
      low.held.valid = false;  // nowhere free to go: the motors stop
      if (lst.status == Status::ok) lst.status = Status::unreachable;
    }
  }
  // 5: the PIDs.
  for (std::size_t k = 0; k < p.mechs.size(); ++k) {
    MechPlan& mp = p.mechs[k];
    MechanismState& st = p.state[k];
    double* duty = p.duties.data() + 2 * k;
    st.command = mp.held.valid;
    if (mp.held.valid) {
      st.point_command = {mp.held.pose.P.x, mp.held.pose.P.y};
      st.theta_command = mp.held.theta;
    }
    if (st.status == Status::sensor_fault || !mp.held.valid) {
      zero(mp, st, duty);
      continue;
    }
    if (!mp.follow_valid) {  // after construction, reset() or zero duty: from where the joints are
      mp.follow = st.theta_measured;
      mp.follow_valid = true;
    }
    for (std::size_t j = 0; j < 2; ++j) {
      const double target = slew(mp.config->joints[j], mp.held.theta[j], mp.follow[j], p.period);
      st.theta_follow[j] = target;
      st.slew_limited = st.slew_limited || target != mp.held.theta[j];
      double e = target - st.theta_measured[j];
      if (std::fabs(e) > kPi) e -= kTwoPi * std::round(e / kTwoPi);
      duty[j] = pid_update(mp.config->joints[j].gains, p.period, mp.pid[j], e);
      st.duty[j] = duty[j];
    }
  }
}

}  // namespace fivebar::runtime
