// URDF of a station with a ros2_control block (fivebar/export/urdf.hpp, where the tree, the frames and
// the mass properties are stated).

#include "fivebar/export/urdf.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>

#include "fivebar/dynamics.hpp"
#include "fivebar/error.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/format.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/parts.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/sections/print.hpp"
#include "fivebar/version.hpp"
#include "export/robot_bodies.hpp"

namespace fivebar {

namespace {

constexpr double kMmPerM = 1000.0;
constexpr double kMm2PerM2 = 1e6;

std::string num(double v) { return format::shortest(v); }
std::string m(double mm) { return num(mm / kMmPerM); }

/// Text for an XML comment (read literally, no entities): no "--" inside, no '-' at its end.
std::string comment_text(std::string text) {
  std::size_t at;
  while ((at = text.find("--")) != std::string::npos) text.replace(at, 2, "- -");
  if (!text.empty() && text.back() == '-') text += ' ';
  return text;
}

using detail::Body;

class Writer {
 public:
  std::ostringstream out;
  void line(int indent, const std::string& text) { out << std::string(static_cast<std::size_t>(2 * indent), ' ') << text << "\n"; }
  void comment(int indent, const std::string& text) { line(indent, "<!-- " + comment_text(text) + " -->"); }
  void link_element(const std::string& name, const Body* body, const std::string& visual_box) {
    if (body == nullptr && visual_box.empty()) {
      line(1, "<link name=\"" + format::xml_escape(name) + "\"/>");
      return;
    }
    line(1, "<link name=\"" + format::xml_escape(name) + "\">");
    if (body != nullptr) {
      const Eigen::Matrix3d& I = body->inertia_kg_mm2;
      line(2, "<inertial>");
      line(3, "<origin xyz=\"" + m(body->com_mm.x()) + " " + m(body->com_mm.y()) + " " + m(body->com_mm.z()) + "\" rpy=\"0 0 0\"/>");
      line(3, "<mass value=\"" + num(body->mass_kg) + "\"/>");
      const auto si = [](double v) { return num(v / kMm2PerM2); };
      line(3, "<inertia ixx=\"" + si(I(0, 0)) + "\" ixy=\"" + si(I(0, 1)) + "\" ixz=\"" + si(I(0, 2)) + "\" iyy=\"" +
                  si(I(1, 1)) + "\" iyz=\"" + si(I(1, 2)) + "\" izz=\"" + si(I(2, 2)) + "\"/>");
      line(2, "</inertial>");
    }
    if (body != nullptr && !body->mesh.empty()) {
      line(2, "<visual>");
      line(3, "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>");
      line(3, "<geometry><mesh filename=\"" + format::xml_escape(body->mesh) + "\" scale=\"0.001 0.001 0.001\"/></geometry>");
      line(2, "</visual>");
    } else if (!visual_box.empty()) {
      line(2, "<visual>");
      line(3, visual_box);
      line(2, "</visual>");
    }
    line(1, "</link>");
  }
};

std::string xyz(double x_mm, double y_mm, double z_mm) { return "xyz=\"" + m(x_mm) + " " + m(y_mm) + " " + m(z_mm) + "\""; }

struct MotorJoint {
  std::string name;
  UsableRange range;
  std::optional<MotorParams> motor;
};

void write_transmissions(Writer& w, const std::vector<MotorJoint>& motor_joints);
void write_ros2_control(Writer& w, const std::string& robot, const std::vector<MotorJoint>& motor_joints);

}  // namespace

std::string urdf_file_name(const Design& design, const Station& station) { return design.name + "_" + station.name + ".urdf"; }

std::vector<std::pair<std::string, double>> initial_pose(const Design& design, const Station& station) {
  std::vector<std::pair<std::string, double>> out;
  for (const Mechanism* mech : station.mechanisms()) {
    const std::array<UsableRange, 2> ranges = usable_ranges(design, station, *mech);
    for (const UsableRange& r : ranges) {
      if (!r.usable) throw InputError("joint " + r.joint + " has no usable range: " + r.problem);
    }
    const Pose pose = fk(*mech, ranges[0].reference, ranges[1].reference);
    const Vec2 r3 = pose.P - pose.A1, r4 = pose.P - pose.A2;
    const std::array<double, 2> phi{std::atan2(r3.y(), r3.x()), std::atan2(r4.y(), r4.x())};
    const std::string prefix = station.name + "_" + mech->name;
    for (int j = 0; j < 2; ++j) {
      const std::size_t i = static_cast<std::size_t>(j);
      // Elbow in (-pi, pi]: the same angle as the MJCF's ref.
      double elbow = phi[i] - ranges[i].reference;
      elbow = std::remainder(elbow, 2.0 * std::numbers::pi);
      if (elbow <= -std::numbers::pi) elbow += 2.0 * std::numbers::pi;
      out.emplace_back(ranges[i].joint, ranges[i].reference);
      out.emplace_back(prefix + "_elbow" + std::to_string(j + 1), elbow);
    }
  }
  return out;
}

double motor_velocity_limit(const Design& design, const Station& station, const Mechanism& mechanism, int joint) {
  return joint_speed_limit(design, station, mechanism, joint);  // the one joint speed (fivebar/device/joint_limits.hpp)
}

namespace {

/// One mechanism's links and joints (the tree of fivebar/export/urdf.hpp); its motor joints appended to
/// `motor_joints`, its cut frame P (for SDFormat) to `sdf_frames`.
void write_mechanism(Writer& w, const Design& design, const Station& station, const detail::StationBodies& bodies,
                     const detail::MechanismBodies& mb, std::vector<MotorJoint>& motor_joints,
                     std::vector<std::string>& sdf_frames) {
  const Geometry& g = *design.get<Geometry>();
  const MotorSettings* motors = design.get<MotorSettings>();
  const double t = g.link_thickness;
  const auto plane_z = [&](int layer) { return bodies.plane_z(layer); };
  const std::string base = station.name + "_base";
  const Mechanism* mech = mb.mechanism;
  const std::string prefix = station.name + "_" + mech->name;
  const MechanismInertia& in = mb.inertia;
  const std::array<UsableRange, 2> ranges = usable_ranges(design, station, *mech);
  for (const UsableRange& r : ranges) {
    if (!r.usable) throw InputError("joint " + r.joint + " has no usable range: " + r.problem);
  }
  w.comment(1, mech->name + " mechanism. Mass properties: " +
                   (mb.from_stl ? std::string("volume integrals over the printed parts' STL renders (every component of "
                                              "the inertia tensor), ") + in.note
                                : "fivebar/dynamics.hpp closed_form_inertia(), " + in.note +
                                      "; the components out of the link plane are those of a plate of the link's "
                                      "width and thickness. " +
                                      (bodies.parts_problem.empty()
                                           ? std::string("Build the parts product (fivebar run) for the STL values and meshes.")
                                           : "The parts report could not be used: " + bodies.parts_problem)) +
                   " The motors' rotor inertia is not in the links: see the transmissions.");
  const int carrier = in.carrier;   // 2: L3, 3: L4
  const int other = 5 - carrier;
  const auto box = [&](std::size_t i) {
    const double L = mech->L[i];
    return "<origin xyz=\"" + m(0.5 * L) + " 0 " + m(0.5 * t) + "\" rpy=\"0 0 0\"/><geometry><box size=\"" + m(L) +
           " " + m(g.link_width[i]) + " " + m(t) + "\"/></geometry>";
  };
  for (std::size_t i = 0; i < 4; ++i) w.link_element(prefix + "_L" + std::to_string(i + 1), &mb.links[i], box(i));
  w.link_element(prefix + "_tip", &mb.tip, "");
  w.link_element(prefix + "_P", nullptr, "");

  // Motor joints.
  for (int j = 1; j <= 2; ++j) {
    const std::size_t i = static_cast<std::size_t>(j - 1);
    const UsableRange& r = ranges[i];
    const Vec2 O = j == 1 ? mech->O1 : mech->O2;
    std::string limit = "<limit";
    if (r.limited) limit += " lower=\"" + num(r.lo) + "\" upper=\"" + num(r.hi) + "\"";
    double effort = 0.0;
    std::string dynamics;
    std::optional<MotorParams> motor;
    if (motors != nullptr) {
      const MotorParams p = motors->joint(station.name, mech->name, j);
      motor = p;
      effort = p.gearbox_efficiency * p.gear_ratio * p.torque_constant() *
               std::min(p.supply_voltage_V / p.resistance(), p.current_limit_A);
      dynamics = "<dynamics damping=\"" + num(p.viscous_friction()) + "\" friction=\"" + num(p.coulomb_friction()) + "\"/>";
    }
    const double velocity = motor_velocity_limit(design, station, *mech, j);
    limit += " effort=\"" + num(effort) + "\" velocity=\"" + num(velocity) + "\"/>";
    w.comment(1, r.joint + ": motor joint. Position limits: " + describe(r) +
                     (motors != nullptr ? "; effort: the stall torque at the output, eta N k_t min(V_supply / R, I_limit) "
                                          "(motor: section); damping and friction at the output shaft"
                                        : "; effort 0: the design has no motor: section") +
                     "; velocity: the smaller of controller.max_velocity_deg_s and the motor's steady speed at the "
                     "supply voltage less what friction takes (the same value as the controller files and the export gate).");
    w.line(1, "<joint name=\"" + format::xml_escape(r.joint) + "\" type=\"" + (r.limited ? "revolute" : "continuous") + "\">");
    w.line(2, "<parent link=\"" + format::xml_escape(base) + "\"/>");
    w.line(2, "<child link=\"" + format::xml_escape(prefix + "_L" + std::to_string(j)) + "\"/>");
    w.line(2, "<origin " + xyz(O.x(), O.y(), plane_z(g.layers[i])) + " rpy=\"0 0 0\"/>");
    w.line(2, "<axis xyz=\"0 0 1\"/>");
    w.line(2, limit);
    if (!dynamics.empty()) w.line(2, dynamics);
    w.line(1, "</joint>");
    motor_joints.push_back({r.joint, r, motor});
  }
  // Passive elbows.
  for (int j = 1; j <= 2; ++j) {
    const std::size_t i = static_cast<std::size_t>(j - 1);
    const std::string name = prefix + "_elbow" + std::to_string(j);
    w.line(1, "<joint name=\"" + format::xml_escape(name) + "\" type=\"continuous\">");
    w.comment(2, "passive: phi" + std::to_string(j + 2) + " - theta" + std::to_string(j) + " from FK");
    w.line(2, "<parent link=\"" + format::xml_escape(prefix + "_L" + std::to_string(j)) + "\"/>");
    w.line(2, "<child link=\"" + format::xml_escape(prefix + "_L" + std::to_string(j + 2)) + "\"/>");
    w.line(2, "<origin " + xyz(mech->L[i], 0.0, plane_z(g.layers[i + 2]) - plane_z(g.layers[i])) + " rpy=\"0 0 0\"/>");
    w.line(2, "<axis xyz=\"0 0 1\"/>");
    w.line(1, "</joint>");
  }
  // The tip on the carrier's post, and the cut: the frame P fixed on the other distal link.
  const std::size_t c = static_cast<std::size_t>(carrier), o = static_cast<std::size_t>(other);
  w.line(1, "<joint name=\"" + format::xml_escape(prefix + "_tip_mount") + "\" type=\"fixed\">");
  w.comment(2, "the tactor tip on the post of L" + std::to_string(carrier + 1) + ", the link carrying it");
  w.line(2, "<parent link=\"" + format::xml_escape(prefix + "_L" + std::to_string(carrier + 1)) + "\"/>");
  w.line(2, "<child link=\"" + format::xml_escape(prefix + "_tip") + "\"/>");
  w.line(2, "<origin " + xyz(mech->L[c], 0.0, t + mb.post_height_mm) + " rpy=\"0 0 0\"/>");
  w.line(1, "</joint>");
  w.line(1, "<joint name=\"" + format::xml_escape(prefix + "_P_mount") + "\" type=\"fixed\">");
  w.comment(2, "the loop's cut: P on L" + std::to_string(other + 1) + " (at the height of L" + std::to_string(carrier + 1) +
                   "'s plane). Closing constraint: this frame's origin and the tip mount's have the same x and y; "
                   "a fixed frame, so no massless link moves");
  w.line(2, "<parent link=\"" + format::xml_escape(prefix + "_L" + std::to_string(other + 1)) + "\"/>");
  w.line(2, "<child link=\"" + format::xml_escape(prefix + "_P") + "\"/>");
  w.line(2, "<origin " + xyz(mech->L[o], 0.0, plane_z(g.layers[c]) - plane_z(g.layers[o])) + " rpy=\"0 0 0\"/>");
  w.line(1, "</joint>");
  w.comment(1, "SDFormat merges a fixed joint's child into its parent unless told to keep it.");
  w.line(1, "<gazebo reference=\"" + format::xml_escape(prefix + "_tip_mount") +
                "\"><preserveFixedJoint>true</preserveFixedJoint></gazebo>");
  sdf_frames.push_back("<frame name=\"" + format::xml_escape(prefix + "_P") + "\" attached_to=\"" +
                       format::xml_escape(prefix + "_L" + std::to_string(other + 1)) + "\"><pose relative_to=\"" +
                       format::xml_escape(prefix + "_L" + std::to_string(other + 1)) + "\">" + m(mech->L[o]) + " 0 " +
                       m(plane_z(g.layers[c]) - plane_z(g.layers[o])) + " 0 0 0</pose></frame>");
}

}  // namespace

std::string render_urdf(const Design& design, const Station& station, const UrdfOptions& options) {
  const detail::StationBodies bodies = detail::station_bodies(design, station, options);
  const MotorSettings* motors = design.get<MotorSettings>();
  const std::string robot = design.name + "_" + station.name;
  const std::string base = station.name + "_base";

  Writer w;
  w.line(0, "<?xml version=\"1.0\"?>");
  w.comment(0, "Generated by fivebar " + std::string(version()) + " from design " + design.name + ", station " + station.name +
                   " (design hash " + design_hash(design, {station.name}) + "). SI units (REP 103). Do not edit: "
                   "change the design and run fivebar export again.");
  w.line(0, "<robot name=\"" + format::xml_escape(robot) + "\" xmlns:drake=\"http://drake.mit.edu\">");
  w.comment(1, "The five-bar linkages are closed loops, which URDF cannot express: each loop is cut at its tactor "
               "P. Only the four motor joints (theta1, theta2 of each mechanism, the angles of the station "
               "frame) are measured and commanded. The controller fills the passive elbows from forward kinematics "
               "of the measured motor angles (the design's assembly mode): elbow1 = phi3 - theta1 and elbow2 = phi4 - "
               "theta2, where phi3 and phi4 are the directions of A1->P and A2->P; the closing constraint is that the "
               "frame <mechanism>_P (fixed on the distal link without the tactor, at P) and <mechanism>_tip_mount's "
               "origin (on the carrier) coincide in x and y. The MJCF of the sibling MuJoCo bundle (<design>_<station>/) "
               "states it as an equality. See docs/urdf.md.");
  w.comment(1, "MuJoCo reads the compiler settings below: keep the meshes' paths relative to this file (MuJoCo strips "
               "them by default). It reads neither the transmissions nor the rotor inertia: simulate the MJCF, whose "
               "joints carry the reflected rotor inertia as armature.");
  w.line(1, "<mujoco>");
  w.line(2, "<compiler strippath=\"false\" discardvisual=\"false\" fusestatic=\"false\" angle=\"radian\"/>");
  w.line(1, "</mujoco>");

  // Base: the root (or the child of `world`), with the base plate's inertia: SDFormat drops a root
  // link without one, and every link under it.
  if (options.world_link) {
    w.comment(1, "The device fixed in the world (a bench device; fivebar/export/urdf.hpp UrdfOptions::world_link).");
    w.line(1, "<link name=\"world\"/>");
    w.line(1, "<joint name=\"" + format::xml_escape(base + "_to_world") + "\" type=\"fixed\">");
    w.line(2, "<parent link=\"world\"/>");
    w.line(2, "<child link=\"" + format::xml_escape(base) + "\"/>");
    w.line(2, "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>");
    w.line(1, "</joint>");
  }
  w.comment(1, base + ": the station frame, z = 0 the base plate's top face. Mass properties: " +
                   (bodies.base_from_stl ? std::string("the base's STL render")
                                         : "a plate " + num(bodies.base_plate_size_mm.x()) + " x " +
                                               num(bodies.base_plate_size_mm.y()) + " x " +
                                               num(bodies.base_plate_size_mm.z()) +
                                               " mm under the base joints (the base's outline without the finger "
                                               "rest and the mounting pads)") +
                   ", at the printing density; the motors' own mass is not in the design and is left out.");
  {
    const Eigen::Vector3d& c = bodies.base_plate_centre_mm;
    const Eigen::Vector3d& e = bodies.base_plate_size_mm;
    w.link_element(base, &bodies.base,
                   "<origin " + xyz(c.x(), c.y(), c.z()) + " rpy=\"0 0 0\"/><geometry><box size=\"" + m(e.x()) + " " +
                       m(e.y()) + " " + m(e.z()) + "\"/></geometry>");
  }

  std::vector<MotorJoint> motor_joints;
  std::vector<std::string> sdf_frames;  // the cut frames P, for SDFormat (below)
  for (const detail::MechanismBodies& mb : bodies.mechanisms) write_mechanism(w, design, station, bodies, mb, motor_joints, sdf_frames);
  if (!sdf_frames.empty()) {
    w.comment(1, "For SDFormat (Gazebo), which drops a massless link: the cut frames P as SDF frames. SDFormat keeps "
                 "no loop closure here (its joints would close a loop where the links stand at the zero pose, an open "
                 "pose of this linkage): in Gazebo the mechanisms are open trees; the MJCF is the closed model.");
    w.line(1, "<gazebo>");
    for (const std::string& f : sdf_frames) w.line(2, f);
    w.line(1, "</gazebo>");
  }
  {
    std::string pose;
    for (const auto& [joint, angle] : initial_pose(design, station)) pose += (pose.empty() ? "" : ", ") + joint + " " + num(angle);
    w.comment(1, "Initial pose (rad), the device at the target centre; the joints' zero is not a pose of the device "
                 "(a motor joint's zero may lie outside its limits): " + pose + ".");
  }

  if (motors != nullptr) write_transmissions(w, motor_joints);
  write_ros2_control(w, robot, motor_joints);
  w.line(0, "</robot>");
  return w.out.str();
}

namespace {

// Transmissions: the gearing and the rotor inertia, as ROS 1 / Gazebo (mechanicalReduction) and
// Drake (drake:gear_ratio, drake:rotor_inertia) read them. The interface is the one ros2_control
// commands (position: the device runs its own PID).
void write_transmissions(Writer& w, const std::vector<MotorJoint>& motor_joints) {
  w.comment(1, "Transmissions: each motor drives its joint through a gearbox of ratio N (motor turns per joint "
               "turn). The rotor inertia J_r (at the motor shaft) reaches the joint as N^2 J_r, which dominates the "
               "links' inertia: a simulator that reads neither the transmission nor drake:rotor_inertia must add N^2 "
               "J_r to the joint (MuJoCo: the joint's armature; the MJCF has it). See docs/urdf.md.");
  for (const MotorJoint& mj : motor_joints) {
    const MotorParams& p = *mj.motor;
    w.line(1, "<transmission name=\"" + format::xml_escape(mj.name + "_transmission") + "\">");
    w.comment(2, "reflected rotor inertia N^2 J_r = " + num(p.gear_ratio * p.gear_ratio * p.rotor_inertia()) + " kg m^2");
    w.line(2, "<type>transmission_interface/SimpleTransmission</type>");
    w.line(2, "<joint name=\"" + format::xml_escape(mj.name) + "\">");
    w.line(3, "<hardwareInterface>hardware_interface/PositionJointInterface</hardwareInterface>");
    w.line(2, "</joint>");
    w.line(2, "<actuator name=\"" + format::xml_escape(mj.name + "_motor") + "\">");
    w.line(3, "<hardwareInterface>hardware_interface/PositionJointInterface</hardwareInterface>");
    w.line(3, "<mechanicalReduction>" + num(p.gear_ratio) + "</mechanicalReduction>");
    w.line(3, "<drake:gear_ratio value=\"" + num(p.gear_ratio) + "\"/>");
    w.line(3, "<drake:rotor_inertia value=\"" + num(p.rotor_inertia()) + "\"/>");
    w.line(2, "</actuator>");
    w.line(1, "</transmission>");
  }
}

void write_ros2_control(Writer& w, const std::string& robot, const std::vector<MotorJoint>& motor_joints) {
  w.comment(1, "ros2_control: the four motor joints, position commands, position and velocity states. The hardware is "
               "ros2_control's mock_components/GenericSystem: replace it with the device's hardware interface "
               "(potentiometers through the ADC, PWM to the motor drivers; the gains and calibration are in the "
               "exported parameters file).");
  w.line(1, "<ros2_control name=\"" + format::xml_escape(robot) + "\" type=\"system\">");
  w.line(2, "<hardware>");
  w.line(3, "<plugin>mock_components/GenericSystem</plugin>");
  w.line(2, "</hardware>");
  for (const MotorJoint& mj : motor_joints) {
    w.line(2, "<joint name=\"" + format::xml_escape(mj.name) + "\">");
    w.line(3, "<command_interface name=\"position\">");
    if (mj.range.limited) {
      w.line(4, "<param name=\"min\">" + num(mj.range.lo) + "</param>");
      w.line(4, "<param name=\"max\">" + num(mj.range.hi) + "</param>");
    }
    w.line(3, "</command_interface>");
    w.line(3, "<state_interface name=\"position\">");
    w.line(4, "<param name=\"initial_value\">" + num(mj.range.reference) + "</param>");
    w.line(3, "</state_interface>");
    w.line(3, "<state_interface name=\"velocity\"/>");
    w.line(2, "</joint>");
  }
  for (const MotorJoint& mj : motor_joints) {
    if (!mj.motor) continue;
    const MotorParams& p = *mj.motor;
    w.line(2, "<transmission name=\"" + format::xml_escape(mj.name + "_transmission") + "\">");
    w.line(3, "<plugin>transmission_interface/SimpleTransmission</plugin>");
    w.line(3, "<joint name=\"" + format::xml_escape(mj.name) + "\" role=\"joint1\">");
    w.line(4, "<mechanical_reduction>" + num(p.gear_ratio) + "</mechanical_reduction>");
    w.line(3, "</joint>");
    w.line(3, "<actuator name=\"" + format::xml_escape(mj.name + "_motor") + "\" role=\"actuator1\"/>");
    w.line(3, "<param name=\"rotor_inertia\">" + num(p.rotor_inertia()) + "</param>");
    w.line(2, "</transmission>");
  }
  w.line(1, "</ros2_control>");
}

}  // namespace

}  // namespace fivebar
