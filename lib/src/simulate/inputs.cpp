// A station's simulation inputs from a design (references from the patterns or a step), and the
// outputs of a run: the time series CSV and the JSON summary (fivebar/dynamics.hpp).

#include <cmath>
#include <numbers>
#include <ostream>

#include "fivebar/dynamics.hpp"
#include "fivebar/format.hpp"
#include "fivebar/numerics.hpp"
#include "fivebar/pattern.hpp"
#include "fivebar/device/config.hpp"
#include "fivebar/device/joint_limits.hpp"

namespace fivebar {

namespace {

using format::kDegPerRad;

/// `a` moved by whole turns to within half a turn of `near`.
double unwrap(double a, double near) {
  const double turn = 2.0 * std::numbers::pi;
  return a - turn * std::round((a - near) / turn);
}

SimulatedMechanism base_mechanism(const Design& design, const Station& station, const Mechanism& m,
                                  const std::map<std::string, MechanismInertia>& inertia) {
  const MotorSettings& motor = *design.get<MotorSettings>();
  const ControllerSettings& controller = *design.get<ControllerSettings>();
  SimulatedMechanism sm;
  sm.name = m.name;
  sm.model.mechanism = m;
  const auto it = inertia.find(m.name);
  if (it == inertia.end()) throw InputError("simulate: no mass properties for the " + m.name + " mechanism");
  sm.model.inertia = it->second;
  for (int j = 0; j < 2; ++j) {
    sm.model.motors[static_cast<std::size_t>(j)] = motor.joint(station.name, m.name, j + 1);
    sm.control[static_cast<std::size_t>(j)] = controller.joint(station.name, m.name, j + 1);
  }
  return sm;
}

/// The station's device configuration (fivebar/device/config.hpp device_config()): the Config
/// `fivebar export` writes for this station, the one the device loads, checked as the runtime
/// checks what it reads.
std::shared_ptr<const runtime::Config> exported_config(const Design& design, const std::string& station) {
  runtime::Config config = device_config(design, {station});
  try {
    config.validate();
  } catch (const runtime::ConfigError& e) {
    throw InputError(std::string("simulate: the runtime refuses the station's configuration: ") + e.what());
  }
  return std::make_shared<const runtime::Config>(std::move(config));
}

/// The loop's step response runs without the runtime's slew limit (docs/runtime.md "One cycle"
/// 5): through it a 1 mm step becomes a ramp at the joint speed, which measures the limiter rather
/// than the loop (the tuner holds the overshoot against a loop's damping; the report compares
/// integrators on this input).
std::shared_ptr<const runtime::Config> without_slew_limit(const runtime::Config& exported) {
  auto unlimited = std::make_shared<runtime::Config>(exported);
  for (runtime::StationConfig& st : unlimited->stations)
    for (runtime::MechanismConfig& m : st.mechanisms)
      for (runtime::JointConfig& j : m.joints) j.has_velocity_limits = false;
  return unlimited;
}

}  // namespace

runtime::Config runtime_config(const SimulationInput& input) {
  runtime::Config c;
  const ControllerSettings& ctl = input.controller;
  c.loop_rate_hz = ctl.loop_rate_hz;
  c.adc_bits = ctl.adc_bits;
  c.adc_range_v = ctl.adc_range_v;
  c.volts_per_count = (ctl.adc_range_v[1] - ctl.adc_range_v[0]) / std::ldexp(1.0, ctl.adc_bits);
  c.joint_margin = 0.0;
  for (std::size_t k = 0; k < input.mechanisms.size(); ++k) {
    const SimulatedMechanism& sm = input.mechanisms[k];
    const Mechanism& m = sm.model.mechanism;
    runtime::StationConfig st;
    st.name = input.station + "_" + std::to_string(k);
    runtime::MechanismConfig mc;
    mc.name = "lower";
    mc.o1 = {m.O1.x() / 1000.0, m.O1.y() / 1000.0};
    mc.o2 = {m.O2.x() / 1000.0, m.O2.y() / 1000.0};
    for (std::size_t i = 0; i < 4; ++i) mc.L[i] = m.L[i] / 1000.0;
    mc.working_mode = {m.working_mode.sign1, m.working_mode.sign2};
    mc.assembly = m.assembly_mode == AssemblyMode::Plus    ? runtime::Assembly::plus
                  : m.assembly_mode == AssemblyMode::Minus ? runtime::Assembly::minus
                                                           : runtime::Assembly::any;
    for (std::size_t j = 0; j < 2; ++j) {
      runtime::JointConfig& jc = mc.joints[j];
      jc.name = st.name + "_lower_theta" + std::to_string(j + 1);
      const JointControl& ctlj = sm.control[j];
      jc.gains = {ctlj.pid.kp, ctlj.pid.ki, ctlj.pid.kd, ctlj.pid.i_clamp};
      jc.volts_at_zero = ctlj.potentiometer.volts_at_zero;
      jc.rad_per_volt = ctlj.potentiometer.rad_per_volt;
    }
    st.mechanisms.push_back(std::move(mc));
    c.stations.push_back(std::move(st));
  }
  return c;
}

std::vector<SimulationInput> simulation_inputs(const Design& design, const SimulationRequest& request,
                                               const std::map<std::string, MechanismInertia>& inertia) {
  const Station& station = design.require_station(request.station);
  // Missing sections name the design file (there is no line to name).
  const std::string where = design.source.empty() ? std::string("simulate: ") : design.source.string() + ": simulate: ";
  if (!station.lower || !station.upper) {
    throw InputError("simulate: station " + station.name + " needs both a lower and an upper mechanism");
  }
  if (!design.get<Geometry>()) throw InputError(where + "the design has no `geometry:` section (link outlines, masses)");
  if (!design.get<MotorSettings>()) {
    throw InputError(where + "the design has no `motor:` section (motor.terminal_resistance_ohm, ... : the motors' data)");
  }
  if (!design.get<ControllerSettings>()) {
    throw InputError(where + "the design has no `controller:` section (controller.pid, loop_rate_hz: the PID to simulate)");
  }
  const ControllerSettings& controller = *design.get<ControllerSettings>();
  const ContactSettings contact = design.get<ContactSettings>() ? *design.get<ContactSettings>() : ContactSettings{};
  const Geometry& g = *design.get<Geometry>();
  const double rate = controller.loop_rate_hz;

  const std::shared_ptr<const runtime::Config> runtime = exported_config(design, station.name);
  const auto make = [&](const std::string& name) {
    SimulationInput in;
    in.station = station.name;
    in.reference_name = name;
    in.controller = controller;
    in.contact = contact;
    in.runtime = runtime;
    in.mechanisms.push_back(base_mechanism(design, station, *station.lower, inertia));
    in.mechanisms.push_back(base_mechanism(design, station, *station.upper, inertia));
    return in;
  };

  std::vector<PatternSpec> specs;
  if (const PatternSettings* ps = design.get<PatternSettings>()) {
    specs = ps->for_station(station.name);
  } else {
    for (PatternKind kind : all_pattern_kinds()) {
      PatternSpec s;
      s.kind = kind;
      specs.push_back(s);
    }
  }
  std::vector<SimulationInput> out;
  if (request.chirp) {
    double separation = PatternSpec{}.separation_mm;
    for (const PatternSpec& s : specs)
      if (s.kind == PatternKind::stretch) separation = s.separation_mm;
    const double f0 = request.chirp_f0_hz;
    const double f1 = request.chirp_f1_hz > 0.0 ? request.chirp_f1_hz : 0.25 * rate;
    const double D = request.chirp_duration_s;
    if (!(f0 > 0.0) || !(f1 > f0) || !(f1 <= 0.5 * rate) || !(D > 0.0) || !(request.chirp_amplitude_mm > 0.0)) {
      throw InputError("simulate: the chirp needs 0 < f0 < f1 <= half the loop rate, a duration and an amplitude > 0");
    }
    SimulationInput in = make("chirp");
    const Vec2 c = station.target.center;
    const std::array<Vec2, 2> start{c - Vec2(0.0, 0.5 * separation), c + Vec2(0.0, 0.5 * separation)};
    const auto n = static_cast<std::size_t>(std::floor(D * rate + tol::kSamplePeriodsRel)) + 1;
    const double k = f1 / f0;
    for (std::size_t m = 0; m < 2; ++m) {
      SimulatedMechanism& sm = in.mechanisms[m];
      std::array<double, 2> previous{0.0, 0.0};
      for (std::size_t s = 0; s < n; ++s) {
        const double t = double(s) / rate;
        const double phase = 2.0 * std::numbers::pi * f0 * D * (std::pow(k, t / D) - 1.0) / std::log(k);
        const Vec2 p = start[m] + Vec2(request.chirp_amplitude_mm * std::sin(phase), 0.0);
        const AnglesResult a = ik_angles(sm.model.mechanism, p);
        if (a.status != Status::ok) {
          throw InputError("simulate: the chirp of the " + sm.name + " tactor reaches (" + format::fixed(p.x(), 3) + ", " +
                           format::fixed(p.y(), 3) + ") mm, which is " + std::string(to_string(a.status)));
        }
        std::array<double, 2> th{a.theta1, a.theta2};
        if (s > 0) th = {unwrap(th[0], previous[0]), unwrap(th[1], previous[1])};
        previous = th;
        sm.reference.push_back(th);
        sm.reference_point_mm.push_back(p);
      }
      sm.theta0 = sm.reference.front();
    }
    out.push_back(std::move(in));
    return out;
  }
  if (request.step) {
    double separation = PatternSpec{}.separation_mm;
    for (const PatternSpec& s : specs)
      if (s.kind == PatternKind::stretch) separation = s.separation_mm;
    SimulationInput in = make("step");
    in.runtime = without_slew_limit(*runtime);
    const Vec2 c = station.target.center;
    const std::array<Vec2, 2> start{c - Vec2(0.0, 0.5 * separation), c + Vec2(0.0, 0.5 * separation)};
    const auto n = static_cast<std::size_t>(std::floor(request.step_hold_s * rate + tol::kSamplePeriodsRel)) + 1;
    for (std::size_t k = 0; k < 2; ++k) {
      SimulatedMechanism& sm = in.mechanisms[k];
      std::array<double, 2> previous{0.0, 0.0};
      for (std::size_t s = 0; s < n; ++s) {
        const Vec2 p = start[k] + Vec2(s == 0 ? 0.0 : request.step_mm, 0.0);
        const AnglesResult a = ik_angles(sm.model.mechanism, p);
        if (a.status != Status::ok) {
          throw InputError("simulate: the step of the " + sm.name + " tactor to (" + format::fixed(p.x(), 3) + ", " +
                           format::fixed(p.y(), 3) + ") mm is " + std::string(to_string(a.status)));
        }
        std::array<double, 2> th{a.theta1, a.theta2};
        if (s > 0) th = {unwrap(th[0], previous[0]), unwrap(th[1], previous[1])};
        previous = th;
        sm.reference.push_back(th);
        sm.reference_point_mm.push_back(p);
      }
      sm.theta0 = sm.reference.front();
    }
    out.push_back(std::move(in));
    return out;
  }
  for (PatternSpec spec : specs) {
    if (request.pattern && spec.kind != *request.pattern) continue;
    spec.rate_hz = rate;  // the controller samples the pattern
    const PatternResult pr = check_pattern(station, g, spec, pattern_joint_speed_limit(design, station));
    SimulationInput in = make(std::string(to_string(spec.kind)));
    for (const PatternSample& s : pr.samples) {
      for (const TactorSample* ts : {&s.lower, &s.upper}) {
        const SampleStatus st = ts->status;
        if (in.unusable.empty() && (st == SampleStatus::unreachable || st == SampleStatus::singular ||
                                    st == SampleStatus::no_collision_free_point || st == SampleStatus::wrong_assembly)) {
          in.unusable = "at t = " + format::fixed(s.time_s, 3) + " s the " + (ts == &s.lower ? "lower" : "upper") +
                        " tactor's reference is " + std::string(to_string(st)) +
                        " (fivebar pattern shows where): no joint reference to follow";
        }
      }
      in.mechanisms[0].reference.push_back(s.lower.theta);
      in.mechanisms[0].reference_point_mm.push_back(s.lower.point);
      in.mechanisms[0].target_mm.push_back(s.lower.target);
      in.mechanisms[1].target_mm.push_back(s.upper.target);
      in.mechanisms[1].reference.push_back(s.upper.theta);
      in.mechanisms[1].reference_point_mm.push_back(s.upper.point);
    }
    if (!in.unusable.empty()) {
      in.mechanisms.clear();
      out.push_back(std::move(in));
      continue;
    }
    if (in.mechanisms[0].reference.empty()) continue;
    for (SimulatedMechanism& sm : in.mechanisms) sm.theta0 = sm.reference.front();
    out.push_back(std::move(in));
  }
  if (out.empty() && request.pattern) {
    throw InputError("simulate: station " + station.name + " has no " + std::string(to_string(*request.pattern)) +
                     " pattern");
  }
  return out;
}

void write_time_series_csv(std::ostream& out, const SimulationResult& result) {
  out << "t_s,mechanism,theta1_ref_deg,theta2_ref_deg,theta1_deg,theta2_deg,w1_deg_s,w2_deg_s,i1_A,i2_A,duty1,duty2,"
         "x_ref_mm,y_ref_mm,x_mm,y_mm,fx_N,fy_N,slipping\n";
  const auto num = [](double v) { return format::shortest(v); };
  for (const TimeSample& s : result.samples) {
    for (std::size_t k = 0; k < s.mechanisms.size(); ++k) {
      const MechanismSample& m = s.mechanisms[k];
      out << num(s.t) << "," << result.summary[k].name << "," << num(m.theta_ref[0] * kDegPerRad) << ","
          << num(m.theta_ref[1] * kDegPerRad) << "," << num(m.theta[0] * kDegPerRad) << "," << num(m.theta[1] * kDegPerRad)
          << "," << num(m.w[0] * kDegPerRad) << "," << num(m.w[1] * kDegPerRad) << "," << num(m.current[0]) << ","
          << num(m.current[1]) << "," << num(m.duty[0]) << "," << num(m.duty[1]) << "," << num(m.P_ref_mm.x()) << ","
          << num(m.P_ref_mm.y()) << "," << num(m.P_mm.x()) << "," << num(m.P_mm.y()) << "," << num(m.force_N.x()) << ","
          << num(m.force_N.y()) << "," << (m.slipping ? 1 : 0) << "\n";
    }
  }
}

Json to_json(const SimulationInput& input, const SimulationResult& result) {
  Json j;
  j["station"] = input.station;
  j["reference"] = input.reference_name;
  j["status"] = std::string(to_string(result.status));
  if (!result.reason.empty()) j["reason"] = result.reason;
  j["t_end_s"] = result.t_end;
  j["steps"] = result.steps;
  j["rhs_evaluations"] = result.rhs_evaluations;
  j["restarts"] = result.restarts;
  j["wall_s"] = result.wall_s;
  j["samples"] = result.samples.size();
  Json mechs = Json::array();
  for (std::size_t k = 0; k < result.summary.size(); ++k) {
    const MechanismSummary& s = result.summary[k];
    Json m;
    m["mechanism"] = s.name;
    if (k < input.mechanisms.size()) {
      const MechanismInertia& in = input.mechanisms[k].model.inertia;
      m["mass_source"] = std::string(to_string(in.source));
      double mass = in.tip_mass_kg;
      for (const LinkInertia& l : in.links) mass += l.mass_kg;
      m["moving_mass_g"] = mass * 1e3;
    }
    m["max_error_mm"] = s.max_error_mm;
    m["rms_error_mm"] = s.rms_error_mm;
    m["max_joint_error_deg"] = s.max_joint_error_deg;
    m["peak_current_A"] = s.peak_current_A;
    m["rms_current_A"] = s.rms_current_A;
    m["peak_duty"] = s.peak_duty;
    m["saturation_s"] = s.saturation_s;
    m["peak_shear_N"] = s.peak_shear_N;
    m["slipped"] = s.slipped;
    m["slips"] = s.slips;
    mechs.push_back(m);
  }
  j["mechanisms"] = mechs;
  return j;
}

}  // namespace fivebar
