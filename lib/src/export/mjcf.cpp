// MJCF of a station and its MuJoCo bundle (fivebar/export/mjcf.hpp, where the bodies, the loop closure,
// the contacts and the actuators are stated). The bundle's scene, README and preview are in
// mujoco_bundle.cpp.

#include "fivebar/export/mjcf.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>

#include "fivebar/error.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/format.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/version.hpp"
#include "export/mjcf_detail.hpp"
#include "export/robot_bodies.hpp"

namespace fivebar {

namespace detail {

std::string mj_num(double v) { return format::shortest(v); }
std::string mj_m(double mm) { return mj_num(mm / 1000.0); }
std::string mj_q(const std::string& s) { return "\"" + format::xml_escape(s) + "\""; }
std::string mj_vec(double x_mm, double y_mm, double z_mm) {
  return "\"" + mj_m(x_mm) + " " + mj_m(y_mm) + " " + mj_m(z_mm) + "\"";
}

std::string mj_comment_text(std::string text) {
  std::size_t at;
  while ((at = text.find("--")) != std::string::npos) text.replace(at, 2, "- -");
  if (!text.empty() && text.back() == '-') text += ' ';
  return text;
}

}  // namespace detail

namespace {

using detail::mj_m;
using detail::mj_num;
using detail::mj_q;
using detail::mj_vec;
using detail::MjWriter;

constexpr double kMm2PerM2 = 1e6;
constexpr double kTurn = 2.0 * std::numbers::pi;

std::string num(double v) { return mj_num(v); }
std::string m(double mm) { return mj_m(mm); }
std::string q(const std::string& s) { return mj_q(s); }
std::string vec(double x, double y, double z) { return mj_vec(x, y, z); }

/// `a` wrapped to (-pi, pi].
double wrap(double a) {
  a -= kTurn * std::floor(a / kTurn);
  return a > std::numbers::pi ? a - kTurn : a;
}

/// An asset name for a mesh file ("index/link.stl" -> "mesh_index_link").
std::string mesh_name(const std::string& rel) {
  std::string stem = rel.substr(0, rel.rfind('.') == std::string::npos ? rel.size() : rel.rfind('.'));
  for (char& c : stem) {
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  }
  return "mesh_" + stem;
}

void inertial(MjWriter& w, int indent, const detail::Body& b) {
  const Eigen::Matrix3d& I = b.inertia_kg_mm2;
  const auto si = [](double v) { return num(v / kMm2PerM2); };
  w.line(indent, "<inertial pos=" + vec(b.com_mm.x(), b.com_mm.y(), b.com_mm.z()) + " mass=\"" + num(b.mass_kg) +
                     "\" fullinertia=\"" + si(I(0, 0)) + " " + si(I(1, 1)) + " " + si(I(2, 2)) + " " + si(I(0, 1)) + " " +
                     si(I(0, 2)) + " " + si(I(1, 2)) + "\"/>");
}

/// Everything the writers need about one mechanism.
struct MjMechanism {
  const detail::MechanismBodies* mb = nullptr;
  std::string prefix;
  std::array<UsableRange, 2> ranges;
  std::array<StopRange, 2> stops;
  std::array<double, 2> theta{0.0, 0.0};  ///< refs: the pose at the target centre
  std::array<double, 2> elbow{0.0, 0.0};
  std::array<std::optional<MotorParams>, 2> motor;
  std::array<PidGains, 2> pid;
  int carrier = 2;  ///< 2: L3, 3: L4
};

/// The duty actuator's gain G and bias B and the current limit (fivebar/export/mjcf.hpp).
struct MotorLine {
  double gain = 0.0, bias = 0.0, fmax = 0.0;
};
MotorLine motor_line(const MotorParams& p) {
  const double kt = p.gearbox_efficiency * p.gear_ratio * p.torque_constant();
  return {kt * p.supply_voltage_V / p.resistance(), -kt * p.back_emf_constant() * p.gear_ratio / p.resistance(),
          kt * p.current_limit_A};
}

std::vector<MjMechanism> mechanism_models(const Design& design, const Station& station, const detail::StationBodies& bodies) {
  const MotorSettings* motors = design.get<MotorSettings>();
  const ControllerSettings* controller = design.get<ControllerSettings>();
  std::vector<MjMechanism> out;
  for (const detail::MechanismBodies& mb : bodies.mechanisms) {
    const Mechanism& mech = *mb.mechanism;
    MjMechanism mm;
    mm.mb = &mb;
    mm.prefix = station.name + "_" + mech.name;
    mm.ranges = usable_ranges(design, station, mech);
    for (const UsableRange& r : mm.ranges) {
      if (!r.usable) throw InputError("joint " + r.joint + " has no usable range: " + r.problem);
    }
    const Pose pose = fk(mech, mm.ranges[0].reference, mm.ranges[1].reference);
    if (pose.status != Status::ok && pose.status != Status::singular_type1) {
      throw InputError("the MJCF: the " + mech.name + " mechanism of station " + station.name +
                       " has no pose at its target centre (" + std::string(to_string(pose.status)) + ")");
    }
    mm.theta = {mm.ranges[0].reference, mm.ranges[1].reference};
    const Vec2 r3 = pose.P - pose.A1, r4 = pose.P - pose.A2;
    mm.elbow = {wrap(std::atan2(r3.y(), r3.x()) - mm.theta[0]), wrap(std::atan2(r4.y(), r4.x()) - mm.theta[1])};
    for (int j = 1; j <= 2; ++j) {
      const std::size_t i = static_cast<std::size_t>(j - 1);
      mm.stops[i] = stop_range(design, station, mech, j, mm.theta[i]);
      if (motors != nullptr) mm.motor[i] = motors->joint(station.name, mech.name, j);
      if (controller != nullptr) mm.pid[i] = controller->joint(station.name, mech.name, j).pid;
    }
    mm.carrier = mb.inertia.carrier;
    out.push_back(mm);
  }
  return out;
}

/// The collision outline of link `i` (fivebar/collision.hpp, extruded over its plate).
void link_collision(MjWriter& w, int indent, const Geometry& g, double L, std::size_t i) {
  const double t = g.link_thickness;
  const double r_end = 0.5 * std::max(g.link_width[i], g.boss_diameter);
  w.line(indent, "<geom class=\"collision\" type=\"box\" pos=" + vec(0.5 * L, 0.0, 0.5 * t) + " size=" +
                     vec(0.5 * L, 0.5 * g.link_width[i], 0.5 * t) + "/>");
  for (double x : {0.0, L}) {
    w.line(indent, "<geom class=\"collision\" type=\"cylinder\" pos=" + vec(x, 0.0, 0.5 * t) + " size=\"" + m(r_end) + " " +
                       m(0.5 * t) + "\"/>");
  }
}

void link_visual(MjWriter& w, int indent, const detail::Body& b, const std::map<std::string, std::string>& meshes,
                 const Geometry& g, double L, std::size_t i) {
  if (!b.mesh_rel.empty()) {
    w.line(indent, "<geom class=\"visual\" type=\"mesh\" mesh=" + q(meshes.at(b.mesh_rel)) + "/>");
  } else {
    w.line(indent, "<geom class=\"visual\" type=\"box\" pos=" + vec(0.5 * L, 0.0, 0.5 * g.link_thickness) + " size=" +
                       vec(0.5 * L, 0.5 * g.link_width[i], 0.5 * g.link_thickness) + "/>");
  }
}

std::string joint_element(const MjMechanism& mm, std::size_t i) {
  const UsableRange& r = mm.ranges[i];
  const StopRange& s = mm.stops[i];
  std::string joint = "<joint name=" + q(r.joint) + " type=\"hinge\" axis=\"0 0 1\" ref=\"" + num(mm.theta[i]) + "\"";
  joint += s.limited ? " limited=\"true\" range=\"" + num(s.lo) + " " + num(s.hi) + "\" solreflimit=\"" +
                           num(kMjcfSolrefTimeconst_s) + " 1\" solimplimit=\"0.99 0.9999 0.001 0.5 2\""
                     : " limited=\"false\"";
  if (mm.motor[i]) {
    const MotorParams& p = *mm.motor[i];
    joint += " armature=\"" + num(p.gear_ratio * p.gear_ratio * p.rotor_inertia()) + "\" damping=\"" +
             num(p.viscous_friction()) + "\" frictionloss=\"" + num(p.coulomb_friction()) + "\"";
  }
  return joint + "/>";
}

/// One mechanism's bodies under the base.
void write_mechanism(MjWriter& w, const MjMechanism& mm, const detail::StationBodies& bodies, const Geometry& g,
                     const std::map<std::string, std::string>& meshes, std::vector<std::string>& sites) {
  const detail::MechanismBodies& mb = *mm.mb;
  const Mechanism& mech = *mb.mechanism;
  const double t = g.link_thickness;
  w.comment(3, mech.name + " mechanism, placed at its pose at the target centre (qpos0: every joint's ref). Mass "
                           "properties: " +
                   (mb.from_stl ? std::string("the printed parts' STL renders, ") + mb.inertia.note
                                : "fivebar/dynamics.hpp closed_form_inertia(), " + mb.inertia.note +
                                      "; the out-of-plane components those of a plate of the link's width and thickness") +
                   ". Joint ranges: the hard stops (mechanical); the usable ranges (sensor) are the custom numerics "
                   "<joint>_usable_range.");
  for (int j = 1; j <= 2; ++j) {
    const std::size_t i = static_cast<std::size_t>(j - 1);
    const Vec2 O = j == 1 ? mech.O1 : mech.O2;
    w.line(3, "<body name=" + q(mm.prefix + "_L" + std::to_string(j)) + " pos=" +
                  vec(O.x(), O.y(), bodies.plane_z(g.layers[i])) + " axisangle=\"0 0 1 " + num(mm.theta[i]) + "\">");
    w.line(4, joint_element(mm, i));
    inertial(w, 4, mb.links[i]);
    link_visual(w, 4, mb.links[i], meshes, g, mech.L[i], i);
    link_collision(w, 4, g, mech.L[i], i);
    w.line(4, "<body name=" + q(mm.prefix + "_L" + std::to_string(j + 2)) + " pos=" +
                  vec(mech.L[i], 0.0, bodies.plane_z(g.layers[i + 2]) - bodies.plane_z(g.layers[i])) + " axisangle=\"0 0 1 " +
                  num(mm.elbow[i]) + "\">");
    w.line(5, "<joint name=" + q(mm.prefix + "_elbow" + std::to_string(j)) + " type=\"hinge\" axis=\"0 0 1\" ref=\"" +
                  num(mm.elbow[i]) + "\" limited=\"false\"/>");
    inertial(w, 5, mb.links[i + 2]);
    link_visual(w, 5, mb.links[i + 2], meshes, g, mech.L[i + 2], i + 2);
    link_collision(w, 5, g, mech.L[i + 2], i + 2);
    if (static_cast<int>(i + 2) == mm.carrier) {
      const double Lc = mech.L[i + 2];
      const double post = mb.post_height_mm;
      if (post > 0.0) {
        w.line(5, "<geom class=\"collision\" type=\"cylinder\" pos=" + vec(Lc, 0.0, t + 0.5 * post) + " size=\"" +
                      m(0.5 * g.pin_diameter) + " " + m(0.5 * post) + "\"/>");
      }
      w.line(5, "<site name=" + q(mm.prefix + "_tactor") + " pos=" + vec(Lc, 0.0, t + post) + " size=\"0.0005\"/>");
      sites.push_back(mm.prefix + "_tactor");
      w.line(5, "<body name=" + q(mm.prefix + "_tip") + " pos=" + vec(Lc, 0.0, t + post) + ">");
      inertial(w, 6, mb.tip);
      const double h = mb.tip_height_mm;
      if (!mb.tip.mesh_rel.empty()) {
        w.line(6, "<geom class=\"visual\" type=\"mesh\" mesh=" + q(meshes.at(mb.tip.mesh_rel)) + "/>");
      } else {
        w.line(6, "<geom class=\"visual\" type=\"cylinder\" pos=" + vec(0.0, 0.0, 0.5 * h) + " size=\"" +
                      m(0.5 * g.tactor_diameter) + " " + m(0.5 * h) + "\"/>");
      }
      w.line(6, "<geom class=\"collision\" type=\"cylinder\" pos=" + vec(0.0, 0.0, 0.5 * h) + " size=\"" +
                    m(0.5 * g.tactor_diameter) + " " + m(0.5 * h) + "\"/>");
      w.line(5, "</body>");
    }
    w.line(4, "</body>");
    w.line(3, "</body>");
  }
}

void write_head(MjWriter& w, const Design& design, const Station& station, const UrdfOptions& options,
                const std::map<std::string, std::string>& meshes, const std::vector<MjMechanism>& models) {
  w.line(0, "<?xml version=\"1.0\"?>");
  w.comment(0, "Generated by fivebar " + std::string(version()) + " from design " + design.name + ", station " + station.name +
                   " (design hash " + design_hash(design, {station.name}) + "). MJCF for MuJoCo (written for 2.2.2), SI "
                   "units. Do not edit: change the design and run fivebar export again. See docs/mjcf.md.");
  w.line(0, "<mujoco model=" + q(design.name + "_" + station.name) + ">");
  w.line(1, "<compiler angle=\"radian\" inertiafromgeom=\"false\"" +
                (meshes.empty() ? std::string() : " meshdir=" + q(options.mesh_prefix) + " strippath=\"false\"") + "/>");
  w.comment(1, "timestep 0.1 ms: the loop closures below are made stiff with a solref time constant of two timesteps "
               "(0.2 ms), and the 100 Hz controller's 10 ms period is 100 steps; at MuJoCo's default 2 ms the tactor "
               "is off by tens of micrometres on a 1 mm step (docs/mjcf.md). integrator Euler: MuJoCo's "
               "semi-implicit Euler, first order, implicit in the joints' damping; the figures of docs/mjcf.md were "
               "measured with it. No gravity: the design does not give the device's orientation (as fivebar "
               "simulate).");
  w.line(1, "<option timestep=\"" + num(kMjcfTimestep_s) + "\" integrator=\"Euler\" gravity=\"0 0 0\"/>");
  w.comment(1, "Classes as MuJoCo Menagerie's: visual geoms (group 2) do not collide; collision geoms (group 3) are "
               "the outlines of the collision study (fivebar/collision.hpp), stiff (solref two timesteps). Friction: "
               "MuJoCo's default, not measured.");
  w.line(1, "<default>");
  w.line(2, "<default class=\"visual\">");
  w.line(3, "<geom contype=\"0\" conaffinity=\"0\" group=\"2\" rgba=\"0.8 0.8 0.8 1\"/>");
  w.line(2, "</default>");
  w.line(2, "<default class=\"collision\">");
  w.line(3, "<geom contype=\"1\" conaffinity=\"1\" group=\"3\" rgba=\"0.9 0.4 0.2 0.5\" solref=\"" +
                num(kMjcfSolrefTimeconst_s) + " 1\" solimp=\"0.99 0.9999 0.001 0.5 2\"/>");
  w.line(2, "</default>");
  w.line(1, "</default>");
  if (!meshes.empty()) {
    w.line(1, "<asset>");
    for (const auto& [rel, name] : meshes) {
      w.line(2, "<mesh name=" + q(name) + " file=" + q(rel) + " scale=\"0.001 0.001 0.001\"/>");
    }
    w.line(1, "</asset>");
  }
  w.comment(1, "The usable range of each motor joint (rad, lo hi): its potentiometer's travel, the hard stops and the "
               "declared joint_limits (docs/urdf.md). A sensor range where an end is the potentiometer's: the joint "
               "turns on to its hard stop (the joint's range) but its reading saturates.");
  std::vector<std::string> numerics;
  for (const MjMechanism& mm : models) {
    for (const UsableRange& r : mm.ranges) {
      if (r.limited) numerics.push_back("<numeric name=" + q(r.joint + "_usable_range") + " data=\"" + num(r.lo) + " " + num(r.hi) + "\"/>");
    }
  }
  if (!numerics.empty()) {
    w.line(1, "<custom>");
    for (const std::string& n : numerics) w.line(2, n);
    w.line(1, "</custom>");
  }
}

void write_actuators(MjWriter& w, const std::vector<MjMechanism>& models, MjcfActuators actuators) {
  bool any = false;
  for (const MjMechanism& mm : models) any = any || mm.motor[0] || mm.motor[1];
  if (!any) {
    w.comment(1, "No actuators: the design has no motor: section (the motors' data).");
    return;
  }
  if (actuators == MjcfActuators::duty) {
    w.comment(1, "One DC gearmotor per motor joint, ctrl = the PWM duty in [-1, 1]: torque = gainprm[0] ctrl + "
                 "biasprm[2] qvel, the motor's torque-speed line at the driver's supply voltage (gain eta N k_t "
                 "V_supply / R, bias -eta N^2 k_t k_e / R), clamped to the driver's current limit (forcerange +-eta N "
                 "k_t I_limit); the winding's inductance is neglected. The joints carry the reflected rotor inertia "
                 "N^2 J_r as armature, the output shaft's viscous (damping) and Coulomb (frictionloss) friction.");
  } else {
    w.comment(1, "Position servos: the exported PID's proportional and derivative terms in continuous time through the "
                 "motor line, torque = G (kp (ctrl - q) - kd qdot) + B qdot, G and B the duty actuator's gain and "
                 "back-EMF bias (kp, kd in duty per rad and per rad/s, controller: section); ctrl = the commanded joint "
                 "angle (rad) within the usable range. Left out: the integral term, the 10 ms sampling, the ADC and "
                 "the duty's saturation at +-1 (docs/mjcf.md).");
  }
  w.line(1, "<actuator>");
  for (const MjMechanism& mm : models) {
    for (std::size_t i = 0; i < 2; ++i) {
      if (!mm.motor[i]) continue;
      const MotorLine line = motor_line(*mm.motor[i]);
      const UsableRange& r = mm.ranges[i];
      std::string a = "<general name=" + q(r.joint) + " joint=" + q(r.joint);
      if (actuators == MjcfActuators::duty) {
        a += " ctrllimited=\"true\" ctrlrange=\"-1 1\" gaintype=\"fixed\" gainprm=\"" + num(line.gain) +
             "\" biastype=\"affine\" biasprm=\"0 0 " + num(line.bias) + "\"";
      } else {
        const PidGains& pid = mm.pid[i];
        a += r.limited ? " ctrllimited=\"true\" ctrlrange=\"" + num(r.lo) + " " + num(r.hi) + "\"" : " ctrllimited=\"false\"";
        a += " gaintype=\"fixed\" gainprm=\"" + num(line.gain * pid.kp) + "\" biastype=\"affine\" biasprm=\"0 " +
             num(-line.gain * pid.kp) + " " + num(line.bias - line.gain * pid.kd) + "\"";
      }
      a += " forcelimited=\"true\" forcerange=\"" + num(-line.fmax) + " " + num(line.fmax) + "\"/>";
      w.line(2, a);
    }
  }
  w.line(1, "</actuator>");
}

void write_keyframe(MjWriter& w, const Design& design, const Station& station, const std::vector<MjMechanism>& models,
                    MjcfActuators actuators) {
  const MjcfHome home = mjcf_home(design, station);
  std::string qpos, ctrl, where;
  for (std::size_t k = 0; k < models.size(); ++k) {
    const MjcfHome::Mechanism& h = home.mechanisms[k];
    for (std::size_t i = 0; i < 2; ++i) {
      // The body order of the file: L1 (theta1), L3 (elbow1), L2 (theta2), L4 (elbow2).
      qpos += (qpos.empty() ? "" : " ") + num(h.theta[i]) + " " + num(h.elbow[i]);
      if (models[k].motor[i]) {
        ctrl += (ctrl.empty() ? "" : " ") + num(actuators == MjcfActuators::position ? h.theta[i] : 0.0);
      }
    }
    where += (where.empty() ? "" : ", ") + h.name + " tactor at (" + format::fixed(h.P_mm.x(), 3) + ", " +
             format::fixed(h.P_mm.y(), 3) + ") mm";
  }
  const bool apart = home.separation_mm > 0.0 || home.mechanisms.size() < 2;
  w.comment(1, "home: the tactors about the target centre (" + where +
                   (home.separation_mm > 0.0 ? "; " + format::fixed(home.separation_mm, 3) + " mm apart, " + home.separation_from
                                             : home.separation_from.empty() ? std::string() : "; " + home.separation_from) +
                   ")" + (apart ? ", every contact clear" : ", the tactors overlapping") + "; ctrl " +
                   (actuators == MjcfActuators::position ? "the home angles." : "0 (duty)."));
  w.line(1, "<keyframe>");
  w.line(2, "<key name=\"home\" qpos=\"" + qpos + "\"" + (ctrl.empty() ? std::string() : " ctrl=\"" + ctrl + "\"") + "/>");
  w.line(1, "</keyframe>");
}

/// The nearest blocked arc from `reference`, counter-clockwise (+1) or clockwise (-1): its distance and name.
std::pair<double, std::string> nearest_stop(const std::vector<HardStop>& stops, double reference, int direction) {
  double best = kTurn;
  std::string by;
  for (const HardStop& s : stops) {
    if (s.half_angle <= 0.0) continue;
    const double edge = direction > 0 ? s.direction - s.half_angle : s.direction + s.half_angle;
    double d = direction * (edge - reference);
    d -= kTurn * std::floor(d / kTurn);
    if (d < best) {
      best = d;
      by = "hard stop at " + s.obstacle;
    }
  }
  return {best, by};
}

}  // namespace

StopRange stop_range(const Design& design, const Station& station, const Mechanism& m, int joint, double reference) {
  const Geometry* g = design.get<Geometry>();
  if (g == nullptr) throw InputError("the hard stops need the design's `geometry:` section");
  const std::vector<HardStop> stops = hard_stops(station, m, joint, *g);
  const auto [up, up_by] = nearest_stop(stops, reference, +1);
  const auto [down, down_by] = nearest_stop(stops, reference, -1);
  StopRange r;
  if (up_by.empty() && down_by.empty()) return r;
  r.limited = true;
  r.lo = reference - down;
  r.hi = reference + up;
  r.lo_by = down_by;
  r.hi_by = up_by;
  return r;
}

namespace {

/// One mechanism's home at the tactor point centre + (0, dy), on the branches of its pose at the
/// centre; std::nullopt when it cannot reach the point or a joint leaves its usable range there.
std::optional<MjcfHome::Mechanism> home_of(const Design& design, const Station& station, const Mechanism& mech, double dy) {
  const std::array<UsableRange, 2> ranges = usable_ranges(design, station, mech);
  const Pose centre = fk(mech, ranges[0].reference, ranges[1].reference);
  MjcfHome::Mechanism h;
  h.name = mech.name;
  h.P_mm = station.target.center + Vec2(0.0, dy);
  const Pose pose = ik(mech, h.P_mm);
  if (pose.status == Status::unreachable) return std::nullopt;
  const Vec2 r3 = pose.P - pose.A1, r4 = pose.P - pose.A2;
  const std::array<double, 2> phi{std::atan2(r3.y(), r3.x()), std::atan2(r4.y(), r4.x())};
  const std::array<double, 2> theta_c{ranges[0].reference, ranges[1].reference};
  const Vec2 c3 = centre.P - centre.A1, c4 = centre.P - centre.A2;
  const std::array<double, 2> elbow_c{wrap(std::atan2(c3.y(), c3.x()) - theta_c[0]), wrap(std::atan2(c4.y(), c4.x()) - theta_c[1])};
  const std::array<double, 2> theta{pose.theta1, pose.theta2};
  for (std::size_t i = 0; i < 2; ++i) {
    h.theta[i] = theta_c[i] + wrap(theta[i] - theta_c[i]);
    h.elbow[i] = elbow_c[i] + wrap(phi[i] - h.theta[i] - elbow_c[i]);
    if (range_margin(ranges[i], h.theta[i]) < 0.0) return std::nullopt;
  }
  return h;
}

}  // namespace

MjcfHome mjcf_home(const Design& design, const Station& station) {
  const Geometry* g = design.get<Geometry>();
  if (g == nullptr) throw InputError("the MJCF needs the design's `geometry:` section");
  const std::vector<const Mechanism*> mechs = station.mechanisms();
  // Separations to try, in order: the stretch pattern's start, the tactors' disks and the bosses at P
  // clear of each other by min_clearance, and none (every tactor at the centre: the target's own pose,
  // always within the usable ranges).
  std::vector<std::pair<double, std::string>> candidates;
  if (mechs.size() == 2) {
    if (const PatternSettings* p = design.get<PatternSettings>()) {
      for (const PatternSpec& spec : p->for_station(station.name)) {
        if (spec.kind == PatternKind::stretch) candidates.emplace_back(spec.separation_mm, "the stretch pattern's separation_mm");
      }
    }
    candidates.emplace_back(std::max(g->tactor_diameter, g->boss_diameter) + g->min_clearance,
                            "max(tactor_diameter, boss_diameter) + min_clearance");
  }
  candidates.emplace_back(0.0, mechs.size() == 2 ? "none reachable apart: both at the target centre" : "");
  for (const auto& [separation, from] : candidates) {
    MjcfHome home;
    home.separation_mm = separation;
    home.separation_from = from;
    for (const Mechanism* mech : mechs) {
      // The upper mechanism's tactor above the lower one's (y from the lower base line toward the upper).
      const double dy = (mech->name == "upper" ? 0.5 : -0.5) * separation;
      if (const auto h = home_of(design, station, *mech, dy)) home.mechanisms.push_back(*h);
    }
    if (home.mechanisms.size() == mechs.size()) return home;
  }
  throw InputError("the MJCF's home keyframe: a mechanism of station " + station.name + " has no pose at its target centre");
}

std::string mjcf_file_name(const Design& design, const Station& station, MjcfActuators actuators) {
  return design.name + "_" + station.name + (actuators == MjcfActuators::position ? "_position" : "") + ".xml";
}

std::string render_mjcf(const Design& design, const Station& station, const UrdfOptions& options, MjcfActuators actuators) {
  const detail::StationBodies bodies = detail::station_bodies(design, station, options);
  const Geometry& g = *design.get<Geometry>();
  const std::vector<MjMechanism> models = mechanism_models(design, station, bodies);

  // Mesh assets, one per file.
  std::map<std::string, std::string> meshes;  // rel -> name
  const auto add_mesh = [&](const detail::Body& b) {
    if (!b.mesh_rel.empty()) meshes.emplace(b.mesh_rel, mesh_name(b.mesh_rel));
  };
  add_mesh(bodies.base);
  for (const detail::MechanismBodies& mb : bodies.mechanisms) {
    for (const detail::Body& b : mb.links) add_mesh(b);
    add_mesh(mb.tip);
  }

  MjWriter w;
  write_head(w, design, station, options, meshes, models);
  std::vector<std::string> sites;
  w.line(1, "<worldbody>");
  w.line(2, "<body name=" + q(station.name + "_base") + ">");
  if (!bodies.base.mesh_rel.empty()) {
    w.line(3, "<geom class=\"visual\" type=\"mesh\" mesh=" + q(meshes.at(bodies.base.mesh_rel)) + "/>");
  }
  for (const MjMechanism& mm : models) write_mechanism(w, mm, bodies, g, meshes, sites);
  w.line(2, "</body>");
  w.line(1, "</worldbody>");

  w.comment(1, "Bodies joined by a loop (the two distal links at P, the tip and the distal link without it) do not "
               "collide; MuJoCo already skips a body and its parent.");
  w.line(1, "<contact>");
  for (const MjMechanism& mm : models) {
    const std::string carrier = mm.prefix + "_L" + std::to_string(mm.carrier + 1);
    const std::string other = mm.prefix + "_L" + std::to_string(5 - mm.carrier + 1);
    w.line(2, "<exclude body1=" + q(carrier) + " body2=" + q(other) + "/>");
    w.line(2, "<exclude body1=" + q(mm.prefix + "_tip") + " body2=" + q(other) + "/>");
  }
  w.line(1, "</contact>");

  w.comment(1, "The loops, closed at the tactor P: the anchor is P in the carrier's frame; MuJoCo computes the other "
               "body's anchor from qpos0, a closed pose here. Stiff: solref time constant " +
               num(kMjcfSolrefTimeconst_s) + " s (twice the timestep), impedance 0.9999.");
  w.line(1, "<equality>");
  for (const MjMechanism& mm : models) {
    const std::size_t c = static_cast<std::size_t>(mm.carrier);
    w.line(2, "<connect name=" + q(mm.prefix + "_loop") + " body1=" + q(mm.prefix + "_L" + std::to_string(mm.carrier + 1)) +
                  " body2=" + q(mm.prefix + "_L" + std::to_string(5 - mm.carrier + 1)) + " anchor=\"" +
                  m(mm.mb->mechanism->L[c]) + " 0 0\" solref=\"" + num(kMjcfSolrefTimeconst_s) +
                  " 1\" solimp=\"0.9999 0.9999 0.001 0.5 2\"/>");
  }
  w.line(1, "</equality>");

  write_actuators(w, models, actuators);
  w.comment(1, "Sensors: the potentiometers (each motor joint's angle, named as the joint) and the tactors' positions.");
  w.line(1, "<sensor>");
  for (const MjMechanism& mm : models) {
    for (const UsableRange& r : mm.ranges) w.line(2, "<jointpos name=" + q(r.joint) + " joint=" + q(r.joint) + "/>");
  }
  for (const std::string& s : sites) w.line(2, "<framepos name=" + q(s) + " objtype=\"site\" objname=" + q(s) + "/>");
  w.line(1, "</sensor>");
  write_keyframe(w, design, station, models, actuators);
  w.line(0, "</mujoco>");
  return w.out.str();
}

}  // namespace fivebar
