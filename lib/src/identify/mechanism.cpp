// `identify --rig mechanism` (fivebar/identify/mechanism.hpp): the closed chain's share of each
// joint's torque from the design's dynamics, then each joint by IDIM-LS.
#include "fivebar/identify/mechanism.hpp"

#include <Eigen/Dense>

#include "fivebar/dynamics.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/identify/filter.hpp"
#include "fivebar/identify/model.hpp"

namespace fivebar::identify {

void require_log_joints_in(const Design& design, const IdentifyLog& log) {
  for (const JointLog& j : log.joints) {
    if (j.station.empty()) continue;  // a bench motor
    const std::string at = log.path + ":" + std::to_string(log.header_line) + ": column " + std::to_string(j.column) + " '" +
                           j.prefix + "_...': ";
    const Station* s = design.station(j.station);
    if (s == nullptr) throw InputError(at + "the design has no station '" + j.station + "'");
    if (s->mechanism(j.mechanism) == nullptr) {
      throw InputError(at + "station '" + j.station + "' has no " + j.mechanism + " mechanism");
    }
  }
}

std::vector<JointIdentification> identify_mechanism(const Design& design, const IdentifyLog& log, const std::string& station,
                                                    const std::string& mechanism, const IdentifyOptions& options) {
  require_log_joints_in(design, log);
  const Station& st = design.require_station(station);
  const Mechanism* mech = st.mechanism(mechanism);
  if (mech == nullptr) throw InputError("--rig mechanism " + station + "/" + mechanism + ": the station has no such mechanism");
  std::array<const JointLog*, 2> joints{nullptr, nullptr};
  for (const JointLog& j : log.joints) {
    if (j.station == station && j.mechanism == mechanism && (j.joint == 1 || j.joint == 2)) joints[static_cast<std::size_t>(j.joint - 1)] = &j;
  }
  for (int j = 0; j < 2; ++j) {
    if (joints[static_cast<std::size_t>(j)] == nullptr) {
      throw InputError(log.path + ": no columns for joint " + station + "_" + mechanism + "_theta" + std::to_string(j + 1) +
                       " (--rig mechanism needs both motors' drive and reading)");
    }
    if (joints[static_cast<std::size_t>(j)]->linear) throw InputError(log.path + ": --rig mechanism takes rotary joints");
  }
  // The closed chain without its rotors: the rotors are each joint's own inertia, identified.
  const auto inertia = station_inertia(design, st, nullptr, {});
  MechanismModel model;
  model.mechanism = *mech;
  model.inertia = inertia.at(mechanism);
  std::array<JointPrior, 2> priors;
  std::array<std::vector<double>, 2> q, w, a;
  const double dt = (log.time.back() - log.time.front()) / static_cast<double>(log.time.size() - 1);
  const double fc = options.cutoff_hz > 0.0 ? options.cutoff_hz : 0.1 / dt;
  const auto sos = butterworth_lowpass(options.filter_order, fc, 1.0 / dt);
  for (int j = 0; j < 2; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    const JointLog& jl = *joints[uj];
    priors[uj] = joint_prior(design, station, mechanism, j + 1, 0.0, jl.drive != DriveKind::torque);
    model.motors[uj] = priors[uj].motor;
    model.motors[uj].rotor_inertia_g_cm2 = 0.0;
    q[uj] = filtfilt(sos, joint_angle(jl, priors[uj]));
    w[uj] = derivative(q[uj], dt);
    a[uj] = derivative(w[uj], dt);
  }
  // The branch of the first pose, kept along the log.
  const Pose first = fk(*mech, q[0].front(), q[1].front());
  if (first.status != Status::ok) {
    throw InputError(log.path + ": the first logged angles (" + format::shortest(q[0].front() * format::kDegPerRad) + ", " +
                     format::shortest(q[1].front() * format::kDegPerRad) + " deg) do not assemble the mechanism");
  }
  model.branch = first.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
  for (int j = 0; j < 2; ++j) priors[static_cast<std::size_t>(j)].known_torque.resize(log.time.size());
  for (std::size_t i = 0; i < log.time.size(); ++i) {
    const DynamicsTerms t = dynamics_terms(model, Eigen::Vector2d(q[0][i], q[1][i]), Eigen::Vector2d(w[0][i], w[1][i]));
    if (t.status != Status::ok) {
      throw InputError(log.path + ": at t = " + format::shortest(log.time[i]) + " s the logged angles are " +
                       std::string(to_string(t.status)) + " for " + station + "/" + mechanism + ": the closed chain's model does not hold");
    }
    const Eigen::Vector2d known = t.M * Eigen::Vector2d(a[0][i], a[1][i]) + t.h;
    priors[0].known_torque[i] = known[0];
    priors[1].known_torque[i] = known[1];
  }
  IdentifyOptions o = options;
  o.output_error = false;
  o.use_output_error = false;
  std::vector<JointIdentification> out;
  for (int j = 0; j < 2; ++j) {
    const auto uj = static_cast<std::size_t>(j);
    out.push_back(identify_joint(*joints[uj], log.time, priors[uj], nullptr, nullptr, o));
    out.back().output_error_status = "not run: one joint of a closed chain (--rig mechanism) is not simulated alone";
  }
  return out;
}

}  // namespace fivebar::identify
