// URDF of a station with a ros2_control block (fivebar/export/urdf.hpp, where the tree, the frames and
// the mass properties are stated).

#include "fivebar/export/urdf.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <sstream>

#include "fivebar/dynamics.hpp"
#include "fivebar/error.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/format.hpp"
#include "fivebar/export/joint_limits.hpp"
#include "fivebar/parts.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/sections/print.hpp"
#include "fivebar/version.hpp"

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

/// Full mass properties of one body in its link frame (mm, kg, kg mm^2).
struct Body {
  double mass_kg = 0.0;
  Eigen::Vector3d com_mm = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia_kg_mm2 = Eigen::Matrix3d::Zero();  ///< about the centre of mass
  std::string mesh;  ///< relative to the URDF, empty without a render
};

/// The plate approximation of the out-of-plane components (header).
Body plate(const LinkInertia& l, double width, double thickness) {
  Body b;
  b.mass_kg = l.mass_kg;
  b.com_mm = Eigen::Vector3d(l.com_mm.x(), l.com_mm.y(), 0.5 * thickness);
  const double ixx = l.mass_kg * (width * width + thickness * thickness) / 12.0;
  const double iyy = l.izz_kg_mm2 - l.mass_kg * width * width / 12.0 + l.mass_kg * thickness * thickness / 12.0;
  b.inertia_kg_mm2.diagonal() << ixx, iyy, l.izz_kg_mm2;
  return b;
}

Body from_mesh(const std::filesystem::path& file, double density) {
  const MassProperties p = mass_properties(read_stl(file), density);
  Body b;
  b.mass_kg = p.mass_kg;
  b.com_mm = p.com_mm;
  b.inertia_kg_mm2 = p.inertia_kg_mm2;
  return b;
}

/// The STL of every piece of `mechanism` ("L1" ... "tactor") and of "base", from a parts report.
std::map<std::string, std::string> stl_by_use(const Json& parts, const Station& station, const std::string& mechanism) {
  std::map<std::string, std::string> out;
  const Json& list = parts.contains("parts") ? parts["parts"] : parts;
  for (const Json& p : list) {
    if (!p.is_object() || p.value("station", "") != station.name || !p.contains("uses") || !p.contains("stl") ||
        !p["stl"].is_string()) {
      continue;
    }
    for (const Json& use : p["uses"]) {
      const std::string u = use.get<std::string>();
      const std::string prefix = mechanism + "/";
      if (u.rfind(prefix, 0) == 0) out[u.substr(prefix.size())] = p["stl"].get<std::string>();
      if (u == "base") out["base"] = p["stl"].get<std::string>();
    }
  }
  return out;
}

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

}  // namespace

std::string urdf_file_name(const Design& design, const Station& station) { return design.name + "_" + station.name + ".urdf"; }

std::string render_urdf(const Design& design, const Station& station, const UrdfOptions& options) {
  const Geometry* gp = design.get<Geometry>();
  if (gp == nullptr) throw InputError("the URDF needs the design's `geometry:` section (the links' outlines and masses)");
  const Geometry& g = *gp;
  const PrintSettings print = design.get<PrintSettings>() ? *design.get<PrintSettings>() : PrintSettings{};
  const PartsHardware hw;
  const ControllerSettings* controller = design.get<ControllerSettings>();
  const MotorSettings* motors = design.get<MotorSettings>();
  // The renders when the report has every piece of the station; the closed form otherwise (say why).
  const Json* parts = options.parts;
  std::string parts_problem;
  std::map<std::string, MechanismInertia> inertia;
  try {
    inertia = station_inertia(design, station, parts, options.parts_dir);
  } catch (const InputError& e) {
    if (parts == nullptr) throw;
    parts_problem = e.what();
    parts = nullptr;
    inertia = station_inertia(design, station, nullptr, options.parts_dir);
  }
  const double t = g.link_thickness;
  const auto plane_z = [&](int layer) { return hw.hub_height + layer * (t + g.layer_gap); };
  const std::string robot = design.name + "_" + station.name;
  const std::string base = station.name + "_base";

  Writer w;
  w.line(0, "<?xml version=\"1.0\"?>");
  w.comment(0, "Generated by fivebar " + std::string(version()) + " from design " + design.name + ", station " + station.name +
                   " (design hash " + design_hash(design, {station.name}) + "). SI units (REP 103). Do not edit: "
                   "change the design and run fivebar export again.");
  w.line(0, "<robot name=\"" + format::xml_escape(robot) + "\">");
  w.comment(1, "The five-bar linkages are closed loops, which URDF cannot express: each loop is cut at its tactor "
               "joint P. Only the four motor joints (theta1, theta2 of each mechanism, the angles of the station "
               "frame) are measured and commanded. The controller fills the passive joints from forward kinematics "
               "of the measured motor angles (the design's assembly mode): elbow1 = phi3 - theta1, elbow2 = phi4 - "
               "theta2 and tactor = phi_carrier - phi_other, where phi3 and phi4 are the directions of A1->P and "
               "A2->P; the frame <mechanism>_P then coincides with the carrier link's frame moved to P, which closes "
               "the loop. See docs/urdf.md.");

  // Base: the root, no inertia (it is fixed to the gripper).
  std::string base_mesh;
  for (const Mechanism* mech : station.mechanisms()) {
    if (parts != nullptr) {
      const auto stl = stl_by_use(*parts, station, mech->name);
      if (auto it = stl.find("base"); it != stl.end()) base_mesh = options.mesh_prefix + "/" + it->second;
    }
  }
  if (!base_mesh.empty()) {
    Body b;
    b.mesh = base_mesh;
    w.line(1, "<link name=\"" + format::xml_escape(base) + "\">");
    w.line(2, "<visual>");
    w.line(3, "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>");
    w.line(3, "<geometry><mesh filename=\"" + format::xml_escape(base_mesh) + "\" scale=\"0.001 0.001 0.001\"/></geometry>");
    w.line(2, "</visual>");
    w.line(1, "</link>");
  } else {
    w.link_element(base, nullptr, "");
  }

  struct MotorJoint {
    std::string name;
    UsableRange range;
  };
  std::vector<MotorJoint> motor_joints;
  for (const Mechanism* mech : station.mechanisms()) {
    const std::string prefix = station.name + "_" + mech->name;
    const MechanismInertia& in = inertia.at(mech->name);
    const std::array<UsableRange, 2> ranges = usable_ranges(design, station, *mech);
    for (const UsableRange& r : ranges) {
      if (!r.usable) throw InputError("joint " + r.joint + " has no usable range: " + r.problem);
    }
    std::map<std::string, std::string> stl;
    if (parts != nullptr) stl = stl_by_use(*parts, station, mech->name);
    const bool from_stl = in.source == MassSource::stl;
    w.comment(1, mech->name + " mechanism. Mass properties: " +
                     (from_stl ? std::string("volume integrals over the printed parts' STL renders (every component of "
                                             "the inertia tensor), ") + in.note
                               : "fivebar/dynamics.hpp closed_form_inertia(), " + in.note +
                                     "; the components out of the link plane are those of a plate of the link's "
                                     "width and thickness. " +
                                     (parts_problem.empty() ? std::string("Build the parts product (fivebar run) for "
                                                                          "the STL values and meshes.")
                                                            : "The parts report could not be used: " + parts_problem)));
    const int carrier = in.carrier;   // 2: L3, 3: L4
    const int other = 5 - carrier;
    std::array<Body, 4> bodies;
    for (std::size_t i = 0; i < 4; ++i) {
      const std::string use = "L" + std::to_string(i + 1);
      if (from_stl && stl.count(use) != 0) {
        bodies[i] = from_mesh(options.parts_dir / stl.at(use), print.density_g_cm3);
        bodies[i].mesh = options.mesh_prefix + "/" + stl.at(use);
      } else {
        bodies[i] = plate(in.links[i], g.link_width[i], t);
      }
    }
    Body tip;
    const double tip_height = hw.tip_flange_height + hw.tip_dome_height;
    const double post_height = std::max(0.0, g.tactor_height - tip_height);
    if (from_stl && stl.count("tactor") != 0) {
      tip = from_mesh(options.parts_dir / stl.at("tactor"), print.density_g_cm3);
      tip.mesh = options.mesh_prefix + "/" + stl.at("tactor");
    } else {
      // A disc of the tactor's diameter (closed_form_inertia(): flange, half the dome, the peg).
      const double r = 0.5 * g.tactor_diameter;
      const double h = hw.tip_flange_height + hw.tip_dome_height;
      tip.mass_kg = in.tip_mass_kg;
      tip.com_mm = Eigen::Vector3d(0.0, 0.0, 0.25 * h);
      const double side = in.tip_mass_kg * (3.0 * r * r + h * h) / 12.0;
      tip.inertia_kg_mm2.diagonal() << side, side, in.tip_izz_kg_mm2;
    }
    const auto box = [&](std::size_t i) {
      const double L = mech->L[i];
      return "<origin xyz=\"" + m(0.5 * L) + " 0 " + m(0.5 * t) + "\" rpy=\"0 0 0\"/><geometry><box size=\"" + m(L) +
             " " + m(g.link_width[i]) + " " + m(t) + "\"/></geometry>";
    };
    for (std::size_t i = 0; i < 4; ++i) w.link_element(prefix + "_L" + std::to_string(i + 1), &bodies[i], box(i));
    w.link_element(prefix + "_tip", &tip, "");
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
      if (motors != nullptr) {
        const MotorParams p = motors->joint(station.name, mech->name, j);
        effort = p.gearbox_efficiency * p.gear_ratio * p.torque_constant() *
                 std::min(p.supply_voltage_V / p.resistance(), p.current_limit_A);
        dynamics = "<dynamics damping=\"" + num(p.viscous_friction()) + "\" friction=\"" + num(p.coulomb_friction()) + "\"/>";
      }
      const double velocity = controller != nullptr ? controller->max_velocity : 0.0;
      limit += " effort=\"" + num(effort) + "\" velocity=\"" + num(velocity) + "\"/>";
      w.comment(1, r.joint + ": motor joint. Position limits: " + describe(r) +
                       (motors != nullptr ? "; effort: the stall torque at the output, eta N k_t min(V_supply / R, I_limit) "
                                            "(motor: section); damping and friction at the output shaft"
                                          : "; effort 0: the design has no motor: section") +
                       "; velocity: controller.max_velocity_deg_s.");
      w.line(1, "<joint name=\"" + format::xml_escape(r.joint) + "\" type=\"" + (r.limited ? "revolute" : "continuous") + "\">");
      w.line(2, "<parent link=\"" + format::xml_escape(base) + "\"/>");
      w.line(2, "<child link=\"" + format::xml_escape(prefix + "_L" + std::to_string(j)) + "\"/>");
      w.line(2, "<origin " + xyz(O.x(), O.y(), plane_z(g.layers[i])) + " rpy=\"0 0 0\"/>");
      w.line(2, "<axis xyz=\"0 0 1\"/>");
      w.line(2, limit);
      if (!dynamics.empty()) w.line(2, dynamics);
      w.line(1, "</joint>");
      motor_joints.push_back({r.joint, r});
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
    // The tip on the carrier's post, and the cut tactor joint on the other distal link.
    const std::size_t c = static_cast<std::size_t>(carrier), o = static_cast<std::size_t>(other);
    w.line(1, "<joint name=\"" + format::xml_escape(prefix + "_tip_mount") + "\" type=\"fixed\">");
    w.comment(2, "the tactor tip on the post of L" + std::to_string(carrier + 1) + ", the link carrying it");
    w.line(2, "<parent link=\"" + format::xml_escape(prefix + "_L" + std::to_string(carrier + 1)) + "\"/>");
    w.line(2, "<child link=\"" + format::xml_escape(prefix + "_tip") + "\"/>");
    w.line(2, "<origin " + xyz(mech->L[c], 0.0, t + post_height) + " rpy=\"0 0 0\"/>");
    w.line(1, "</joint>");
    w.line(1, "<joint name=\"" + format::xml_escape(prefix + "_tactor") + "\" type=\"continuous\">");
    w.comment(2, "passive tactor joint P where the loop is cut: phi" + std::to_string(carrier + 1) + " - phi" +
                     std::to_string(other + 1) + " from FK; its child frame is L" + std::to_string(carrier + 1) +
                     "'s frame moved to P");
    w.line(2, "<parent link=\"" + format::xml_escape(prefix + "_L" + std::to_string(other + 1)) + "\"/>");
    w.line(2, "<child link=\"" + format::xml_escape(prefix + "_P") + "\"/>");
    w.line(2, "<origin " + xyz(mech->L[o], 0.0, plane_z(g.layers[c]) - plane_z(g.layers[o])) + " rpy=\"0 0 0\"/>");
    w.line(2, "<axis xyz=\"0 0 1\"/>");
    w.line(1, "</joint>");
  }

  // ros2_control: the motor joints.
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
  w.line(1, "</ros2_control>");
  w.line(0, "</robot>");
  return w.out.str();
}

}  // namespace fivebar
