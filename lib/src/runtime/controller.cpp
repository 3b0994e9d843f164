// One control cycle of the device (fivebar/runtime/controller.hpp; docs/runtime.md). Every buffer
// is sized in the constructor; cycle() only writes into them.

#include "fivebar/runtime/controller.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
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

namespace {
void require(bool ok, const std::string& key, const std::string& what) {
  if (!ok) throw ConfigError(key + ": " + what);
}
bool finite_all(std::initializer_list<double> v) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}
}  // namespace

void Config::validate() const {
  require(std::isfinite(loop_rate_hz) && loop_rate_hz > 0.0, "loop_rate_hz", "must be a finite number > 0");
  require(adc_bits >= 1 && adc_bits <= 31, "adc.bits", "must be in [1, 31]");
  require(finite_all({adc_range_v[0], adc_range_v[1]}) && adc_range_v[1] > adc_range_v[0], "adc.range_v",
          "must be two finite volts, low < high");
  const double expected = (adc_range_v[1] - adc_range_v[0]) / std::ldexp(1.0, adc_bits);
  require(std::isfinite(volts_per_count) && volts_per_count > 0.0 &&
              std::fabs(volts_per_count - expected) <= 1e-9 * expected,
          "adc.volts_per_count", "must be (range_v[1] - range_v[0]) / 2^bits");
  require(std::isfinite(joint_margin) && joint_margin >= 0.0, "joint_margin_rad", "must be a finite number >= 0");
  if (collision.checked) {
    const CollisionConfig& c = collision;
    require(std::isfinite(c.min_clearance) && c.min_clearance >= 0.0, "collision.min_clearance_m", "must be >= 0");
    for (std::size_t i = 0; i < 4; ++i) {
      require(std::isfinite(c.link_widths[i]) && c.link_widths[i] > 0.0, "collision.link_widths_m[" + std::to_string(i) + "]",
              "must be > 0");
      require(c.layers[i] >= 0 && c.layers[i] <= 32, "collision.layers[" + std::to_string(i) + "]", "must be in [0, 32]");
    }
    require(finite_all({c.pin_diameter, c.boss_diameter, c.tactor_diameter, c.motor_shaft_diameter}) && c.pin_diameter > 0.0 &&
                c.boss_diameter >= 0.0 && c.tactor_diameter > 0.0 && c.motor_shaft_diameter >= 0.0,
            "collision", "pin, boss, tactor and motor shaft diameters must be finite, pin and tactor > 0");
  }
  require(!stations.empty(), "station_names", "no station");
  for (const StationConfig& s : stations) {
    const std::string sp = "stations." + s.name;
    require(!s.mechanisms.empty() && s.mechanisms.size() <= 2, sp + ".mechanisms", "one or two mechanisms");
    if (s.mechanisms.size() == 2) {
      require(s.mechanisms[0].name != s.mechanisms[1].name, sp + ".mechanisms", "a lower and an upper mechanism");
    }
    for (const MechanismConfig& m : s.mechanisms) {
      const std::string mp = sp + "." + m.name;
      require(m.name == "lower" || m.name == "upper", mp, "a mechanism is \"lower\" or \"upper\"");
      require(finite_all({m.o1[0], m.o1[1], m.o2[0], m.o2[1]}), mp + ".o1_m", "base joints must be finite");
      for (std::size_t i = 0; i < 4; ++i) {
        require(std::isfinite(m.L[i]) && m.L[i] > 0.0, mp + ".link_lengths_m[" + std::to_string(i) + "]", "must be > 0");
      }
      for (std::size_t j = 0; j < 2; ++j) {
        require(m.working_mode[j] == 1 || m.working_mode[j] == -1, mp + ".working_mode", "two signs");
        const JointConfig& jc = m.joints[j];
        const std::string g = "gains." + jc.name;
        require(finite_all({jc.gains.p, jc.gains.i, jc.gains.d, jc.gains.i_clamp}), g, "gains must be finite");
        require(jc.gains.i_clamp >= 0.0, g + ".i_clamp", "must be >= 0");
        const std::string pp = "potentiometers." + jc.name;
        require(std::isfinite(jc.volts_at_zero), pp + ".volts_at_zero", "must be finite");
        require(std::isfinite(jc.rad_per_volt) && jc.rad_per_volt != 0.0, pp + ".rad_per_volt", "must be finite and not 0");
        if (jc.has_position_limits) {
          const std::string lp = "joint_limits." + jc.name;
          require(finite_all({jc.min_position, jc.max_position}) && jc.max_position > jc.min_position &&
                      jc.max_position - jc.min_position <= kTwoPi + 1e-12,
                  lp, "min_position < max_position, at most one turn apart");
          require(jc.max_position - jc.min_position > 2.0 * joint_margin, lp,
                  "the range must be wider than twice joint_margin_rad");
        }
      }
    }
  }
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
  std::array<unsigned char, kPriorityRays> free_k{}, free_k1{};
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

/// Is the lower mechanism free at q (a valid command clear of the upper outline)?
bool probe_free(Plan& plan, const MechPlan& low, const Part* upper, V2 q) {
  Command c;
  if (make_command(plan, low, q, c) != Status::ok) return false;
  Part* mine = outline_at(plan, plan.probe_a);
  detail::outline(plan.tpl, c.pose, mine);
  return !detail::collide(upper, n_parts(plan), mine, n_parts(plan), plan.config.collision.min_clearance);
}

/// The priority search (controller.hpp): at most kPriorityMaxProbes probes. True with the point.
bool closest_free(Plan& plan, const MechPlan& low, const Part* upper, V2 origin, V2& found) {
  const double h = kPriorityRingRel * low.mech.scale;
  int first = -1;
  for (int k = 1; k <= kPriorityRings && first < 0; ++k) {
    bool any = false;
    for (int j = 0; j < kPriorityRays; ++j) {
      const auto uj = static_cast<std::size_t>(j);
      plan.free_k[uj] = probe_free(plan, low, upper, origin + (k * h) * plan.rays[uj]) ? 1 : 0;
      any = any || plan.free_k[uj];
    }
    if (any) first = k;
  }
  if (first < 0) return false;
  for (std::size_t j = 0; j < kPriorityRays; ++j) {
    plan.free_k1[j] = plan.free_k[j] ? 0 : (probe_free(plan, low, upper, origin + ((first + 1) * h) * plan.rays[j]) ? 1 : 0);
  }
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t j = 0; j < kPriorityRays; ++j) {
    if (!plan.free_k[j] && !plan.free_k1[j]) continue;
    double lo = plan.free_k[j] ? (first - 1) * h : first * h;
    double hi = lo + h;
    for (int b = 0; b < kPriorityBisections; ++b) {
      const double mid = 0.5 * (lo + hi);
      if (probe_free(plan, low, upper, origin + mid * plan.rays[j])) hi = mid;
      else lo = mid;
    }
    if (hi < best) {
      best = hi;
      found = origin + hi * plan.rays[j];
    }
  }
  return true;
}

void zero(MechPlan& mp, MechanismState& st, double* duty) {
  mp.pid = {PidState{}, PidState{}};
  duty[0] = duty[1] = 0.0;
  st.duty = {0.0, 0.0};
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
      if (!std::isfinite(r)) {
        fault = true;
      } else if (kind == Reading::radians) {
        st.theta_measured[j] = r;
        continue;
      } else if (kind == Reading::counts) {
        fault = !(r > 0.0 && r < p.top_code);  // outside the ADC or at a rail
        volts = c.adc_range_v[0] + r * c.volts_per_count;
      } else {
        const double half = 0.5 * c.volts_per_count;
        fault = !(r > c.adc_range_v[0] + half && r < c.adc_range_v[0] + (p.top_code - 0.5) * c.volts_per_count);
        volts = r;
      }
      st.theta_measured[j] = fault ? 0.0 : jc.rad_per_volt * (volts - jc.volts_at_zero);
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
    for (std::size_t j = 0; j < 2; ++j) {
      double e = mp.held.theta[j] - st.theta_measured[j];
      if (std::fabs(e) > kPi) e -= kTwoPi * std::round(e / kTwoPi);
      duty[j] = pid_update(mp.config->joints[j].gains, p.period, mp.pid[j], e);
      st.duty[j] = duty[j];
    }
  }
}

}  // namespace fivebar::runtime
