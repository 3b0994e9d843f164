// The motor-rig model (fivebar/identify/model.hpp).

#include "fivebar/identify/model.hpp"

#include <cmath>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/identify/identify.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/motor.hpp"

namespace fivebar::identify {

ReducedDrive reduced_drive(DriveKind kind, const MotorParams& m) {
  const double K = m.gearbox_efficiency * m.gear_ratio * m.torque_constant();  // N m per A at the output
  const double emf = m.back_emf_constant() * m.gear_ratio;                      // V per rad/s at the output
  switch (kind) {
    case DriveKind::torque: return {1.0, 0.0};
    case DriveKind::current: return {K, 0.0};
    case DriveKind::voltage: return {K / m.resistance(), K * emf / m.resistance()};
    case DriveKind::duty: return {K * m.supply_voltage_V / m.resistance(), K * emf / m.resistance()};
  }
  return {1.0, 0.0};
}

std::vector<double> joint_angle(const JointLog& joint, const JointPrior& prior) {
  std::vector<double> q(joint.reading_values.size());
  const double volts_per_count = (prior.adc_hi_v - prior.adc_lo_v) / std::ldexp(1.0, prior.adc_bits);
  for (std::size_t i = 0; i < q.size(); ++i) {
    const double r = joint.reading_values[i];
    switch (joint.reading) {
      case ReadingKind::angle: q[i] = r; break;
      case ReadingKind::volts: q[i] = prior.rad_per_volt * (r - prior.volts_at_zero); break;
      case ReadingKind::counts:
        q[i] = prior.rad_per_volt * (prior.adc_lo_v + r * volts_per_count - prior.volts_at_zero);
        break;
    }
  }
  return q;
}

std::vector<std::string> mechanical_names(bool per_direction, bool linear) {
  if (linear) {
    if (per_direction) return {"mass_kg", "viscous_pos_N_s_per_m", "viscous_neg_N_s_per_m", "coulomb_N", "offset_N"};
    return {"mass_kg", "viscous_N_s_per_m", "coulomb_N", "offset_N"};
  }
  if (per_direction) {
    return {"inertia_kg_m2", "viscous_pos_Nm_s_per_rad", "viscous_neg_Nm_s_per_rad", "coulomb_Nm", "offset_Nm"};
  }
  return {"inertia_kg_m2", "viscous_Nm_s_per_rad", "coulomb_Nm", "offset_Nm"};
}

std::unique_ptr<LoopController> design_pid(const Design& design, const JointLog& j, double sample_time, const std::string& file) {
  const std::string who = j.prefix.empty() ? "motor" : j.prefix;
  if (j.reference.empty()) {
    throw InputError(file + ": a closed-loop fit: joint '" + who + "' has no reference column (" + (j.prefix.empty() ? "" : j.prefix + "_") +
                     (j.linear ? "position_ref_m" : "theta_ref_rad") + ")");
  }
  if (j.drive != DriveKind::duty && j.drive != DriveKind::voltage) {
    throw InputError(file + ": a closed-loop fit: joint '" + who + "' is driven by '" + j.drive_column +
                     "'; the device's PID commands a duty (a duty or voltage_V column)");
  }
  const auto* controller = design.get<ControllerSettings>();
  if (controller == nullptr) throw InputError(design.name + ": a closed-loop fit needs the design's controller: section (the PID the log ran)");
  const PidGains pid = j.prefix.empty() ? controller->pid : controller->joint(j.station, j.mechanism, j.joint).pid;
  double scale = 1.0;
  if (j.drive == DriveKind::voltage) {
    const auto* motor = design.get<MotorSettings>();
    if (motor == nullptr) throw InputError(design.name + ": a closed-loop fit of a voltage_V drive needs the motor: section's supply_voltage_V");
    scale = j.prefix.empty() ? motor->defaults.supply_voltage_V : motor->joint(j.station, j.mechanism, j.joint).supply_voltage_V;
  }
  return device_pid(j.reference, runtime::Gains{pid.kp, pid.ki, pid.kd, pid.i_clamp}, sample_time, scale);
}

std::vector<JointIdentification> identify_motor_rig(const Design& design, const MotorRig& rig, const IdentifyOptions& o) {
  const std::vector<IdentifyLog>& logs = *rig.logs;
  std::vector<JointIdentification> results;
  for (const JointLog& j : logs.front().joints) {
    if (!rig.joint.empty() && j.prefix != rig.joint && !(rig.joint == "motor" && j.prefix.empty())) continue;
    const std::string who = j.prefix.empty() ? "motor" : j.prefix;
    const bool need_motor = !j.linear && j.drive != DriveKind::torque;
    const JointPrior prior = joint_prior(design, j.station, j.mechanism, j.joint, rig.load_inertia, need_motor);
    std::vector<std::unique_ptr<LoopController>> loops;
    auto segment = [&](const IdentifyLog& l, const std::string& file) {
      const JointLog* x = nullptr;
      for (const JointLog& c : l.joints) {
        if (c.prefix == j.prefix) x = &c;
      }
      if (x == nullptr) throw InputError(file + ": no columns for joint '" + who + "'");
      if (x->drive != j.drive || x->linear != j.linear) {
        throw InputError(file + ": joint '" + who + "' is driven by '" + x->drive_column + "', the first log by '" + j.drive_column + "'");
      }
      LogSegment g{x, &l.time, nullptr};
      if (rig.closed_loop) {
        loops.push_back(design_pid(design, *x, l.sample_time(), file));
        g.controller = loops.back().get();
      }
      return g;
    };
    std::vector<LogSegment> segs, vsegs;
    for (std::size_t i = 0; i < logs.size(); ++i) segs.push_back(segment(logs[i], i < rig.names.size() ? rig.names[i] : "log"));
    if (rig.validation != nullptr) vsegs.push_back(segment(*rig.validation, rig.validation_name));
    results.push_back(identify_joint(segs, prior, vsegs, o));
  }
  return results;
}

std::vector<std::string> refused_fits(const std::vector<JointIdentification>& results, const IdentifyOptions& o, const std::string& option) {
  std::vector<std::string> refused;
  for (const std::string& key : o.require) {
    bool known = false;
    for (const JointIdentification& r : results) {
      for (const Parameter& p : r.parameters) {
        if (p.key != key) continue;
        known = true;
        if (!p.identified) refused.push_back(key + " (" + r.joint + "): " + p.note);
      }
    }
    if (!known) {
      std::vector<std::string> keys;
      for (const Parameter& p : results.front().parameters) keys.push_back(p.key);
      throw InputError(option + " " + key + ": not a parameter of this rig (parameters: " + format::join(keys) + ")");
    }
  }
  return refused;
}

}  // namespace fivebar::identify
