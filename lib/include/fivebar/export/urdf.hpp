#pragma once
/// URDF of a station with a ros2_control block (`fivebar export` writes one per exported station,
/// `<design>_<station>.urdf`, beside the controller files; docs/urdf.md). SI units (REP 103).
///
/// Tree (URDF holds a tree; the five-bar is a closed loop, cut at the tactor joint P):
///
///   <station>_base                        station frame; z = 0 the base plate's top face
///    ├─ <station>_<mech>_theta1 (revolute, motor)  at O1 ─ <..>_L1
///    │     └─ <..>_elbow1 (continuous, passive) at A1 ─ <..>_L3
///    │            └─ (fixed) <..>_tip_mount at P ─ <..>_tip     when L3 carries the tactor post
///    └─ <station>_<mech>_theta2 (revolute, motor)  at O2 ─ <..>_L2
///          └─ <..>_elbow2 (continuous, passive) at A2 ─ <..>_L4
///                 └─ <..>_P_mount (fixed) at P ─ <..>_P     the loop's cut (a frame, no mass)
///
/// (the roles of L3 and L4 swap when L4 carries the post: geometry.layers[3] > layers[2], as in
/// fivebar/dynamics.hpp). Each link's frame is its part's frame (fivebar/parts.hpp): z along its
/// first joint's axis, x towards its second joint; a joint angle of theta turns the link's x axis
/// to theta in the parent's frame. So the motor joints' positions are the station-frame angles
/// theta1, theta2 of docs/conventions.md, and a controller fills the passive joints from FK of the
/// measured theta (fivebar/kinematics.hpp fk(), the design's assembly mode):
///   elbow1 = phi3 - theta1,  elbow2 = phi4 - theta2,
/// phi3, phi4 the directions of A1->P and A2->P; then the origin of the frame <..>_P (fixed on the
/// distal link without the post) has the x and y of the tip's mount on the carrier: the loop
/// closure URDF cannot state. (An earlier layout hung <..>_P on a `continuous` tactor joint; a
/// massless link on a moving joint is refused by MuJoCo's compiler, so the cut is a fixed frame.)
///
/// Heights: the proximal links' hubs (PartsHardware::hub_height) stand on the base plate; link
/// plane k's plate starts at hub_height + k (link_thickness + layer_gap); the tip sits on the post,
/// tactor_height above the carrier's plate top minus the tip.
///
/// Mass properties (fivebar/dynamics.hpp station_inertia()): from the parts' STL renders when a
/// parts report is given (then every component of the inertia tensor, and the centre of mass
/// height, from mass_properties() of the same files), else closed_form_inertia(): mass, centre of
/// mass in the plane and z inertia from it, the other components those of a plate of the link's
/// width and thickness (ixx = m (w^2 + t^2) / 12, iyy = izz - m w^2 / 12 + m t^2 / 12, centre at
/// mid-plate). The URDF says which in a comment. The base (the root, or the child of `world`) carries
/// the base plate's inertia (from its STL render, else the plate of robot_bodies.hpp): SDFormat drops
/// a root link without one, and every link under it.
///
/// SDFormat (Gazebo's reader, `ign sdf -p`): fixed joints are merged into their parent unless kept, so
/// each tip mount carries `<gazebo reference><preserveFixedJoint>`; a massless link is dropped, so the
/// cut frame <..>_P is repeated as an SDF `<frame>` attached to its distal link (a top-level `<gazebo>`
/// block, which other readers ignore). SDFormat keeps no loop closure: its joints close a loop where the
/// links stand at the zero pose, an open pose of this linkage; the MJCF is the closed model.
///
/// Initial pose: the joints' zero is not the device's pose (the motor joints' zero may lie outside their
/// limits, as the station-frame angle 0 does); the pose at the target centre is given as the
/// ros2_control state's initial_value and, for every joint, in a comment (initial_pose()).
///
/// Interfaces: the device runs its own PID at the loop rate (the exported gains), so ros2_control
/// commands positions; the transmissions declare the same (PositionJointInterface).
///
/// Limits: motor joints carry the usable range of fivebar/device/joint_limits.hpp (continuous when the
/// joint has none), velocity motor_velocity_limit() (controller.max_velocity, at most the motor's
/// steady speed at the supply voltage less friction), effort the stall torque at the output of the motor section,
/// eta N k_t min(supply / R, current limit) (0 without `motor:`: unknown).
///
/// Gearing and rotor inertia (with `motor:`): per motor joint a top-level `<transmission>`
/// (transmission_interface/SimpleTransmission; the actuator `<joint>_motor` with
/// `mechanicalReduction` N, and Drake's `drake:gear_ratio` and `drake:rotor_inertia` J_r at the motor
/// shaft), and the same transmission inside `<ros2_control>` in its layout (`mechanical_reduction`,
/// a `rotor_inertia` param). The links' inertials stay the printed parts': the reflected inertia
/// N^2 J_r is the transmission's. A `<mujoco><compiler strippath="false"/></mujoco>` element keeps
/// the mesh paths relative to the file for MuJoCo's URDF import.
///
/// ros2_control: one `<ros2_control type="system">` naming the four motor joints, each with a
/// position command interface (min/max = the usable range) and position and velocity state
/// interfaces (position's initial_value the joint's angle at the target centre); its hardware is
/// ros2_control's mock_components/GenericSystem, to replace with the device's interface.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/json.hpp"

namespace fivebar {

struct UrdfOptions {
  /// A parts report (to_json(PartsReport), fivebar/parts.hpp) with STL renders: masses from them and
  /// the meshes as visuals. nullptr: closed-form masses, no meshes.
  const Json* parts = nullptr;
  /// Where the report's "stl" paths are relative to (to read them).
  std::filesystem::path parts_dir;
  /// The same folder as the URDF should name it (relative to the URDF file, e.g. "../parts"; in a
  /// ROS package "package://<package>/meshes").
  std::string mesh_prefix = "../parts";
  /// Add a link `world` and a fixed joint `<station>_base_to_world` above the base: the device fixed
  /// in the world, as Gazebo and RViz users expect of a bench device (fivebar/export/ros2_package.hpp
  /// sets it). Without it the base is the root, a free body for Gazebo.
  bool world_link = false;
};

/// The velocity limit of motor joint `joint` (1 or 2) of `mechanism`, rad/s: joint_speed_limit()
/// of fivebar/device/joint_limits.hpp, the one joint speed of every exported file and of the gate.
double motor_velocity_limit(const Design& design, const Station& station, const Mechanism& mechanism, int joint);

/// Every joint's angle at the target centre (rad), motor joints and elbows, in the URDF's joint order:
/// the pose a client starts the device in (the ros2_control initial_value, the ROS package's display
/// launch). InputError as render_urdf().
std::vector<std::pair<std::string, double>> initial_pose(const Design& design, const Station& station);

/// `<design>_<station>.urdf`.
std::string urdf_file_name(const Design& design, const Station& station);

/// The URDF document of `station` (layout above). InputError without `geometry:` (the links'
/// outlines) or when a mechanism's joints have no usable range.
std::string render_urdf(const Design& design, const Station& station, const UrdfOptions& options = {});

}  // namespace fivebar
