#pragma once
/// MJCF (MuJoCo's XML) of a station: both five-bars with their loops closed, the motors as
/// actuators, the potentiometers as sensors (`fivebar export` writes the station's MuJoCo bundle, a
/// folder `<design>_<station>/` with `<design>_<station>.xml` in it, beside the URDF; `--format mjcf`
/// alone; docs/mjcf.md). SI units; checked against `fivebar simulate` by
/// test/test_mujoco.cpp, which loads the files with MuJoCo 2.2.2 (Debian libmujoco-dev).
///
/// Bodies (the URDF's tree, fivebar/export/urdf.hpp, same frames and mass properties):
///   <station>_base (static)
///     <s>_<m>_L1 (hinge <s>_<m>_theta1 at O1) ─ <s>_<m>_L3 (hinge <s>_<m>_elbow1 at A1)
///     <s>_<m>_L2 (hinge <s>_<m>_theta2 at O2) ─ <s>_<m>_L4 (hinge <s>_<m>_elbow2 at A2)
///     <s>_<m>_tip on the carrying distal link's post (no joint)
/// Each body is placed at the mechanism's pose at the target centre (the IK of its centre, the
/// design's working and assembly modes) and each hinge's `ref` is its angle there, so qpos = the
/// station-frame angles theta1, theta2 (docs/conventions.md) and the elbows' phi - theta, as in the
/// URDF, and MuJoCo's default configuration qpos0 is a closed loop.
///
/// Loop closure: `<equality><connect body1=carrier body2=other anchor=P in the carrier's frame>`.
/// MuJoCo 2.2.2 computes the anchor on body2 from qpos0; with qpos0 closed (above) it is P in the
/// other distal link's frame. (With the bodies unrotated and no ref, qpos0 is the open tree's
/// straight pose and the anchor lands elsewhere: on the showcase's index station 0.0025 m along L4
/// instead of its 0.015 m length; a tree built another way lands elsewhere again.) Made stiff by
/// solref (time constant kMjcfSolrefTimeconst_s, critically damped) and solimp (impedance 0.9999):
/// the loop opens by nanometres under the PID's accelerations (test/test_mujoco.cpp).
///
/// Motors (with `motor:`): joint `armature` = N^2 J_r (the reflected rotor inertia), `damping` = b
/// and `frictionloss` = tau_c at the output shaft; one `general` actuator per motor joint,
/// ctrl = the PWM duty in [-1, 1], reproducing the DC motor's torque-speed line at the driver's
/// voltage V_supply with the inductance neglected (L / R = 0.1 ms with the assumed motor, against
/// the 10 ms control period):
///   torque = gainprm[0] ctrl + biasprm[2] qvel,  gainprm[0] = eta N k_t V_supply / R,
///                                                biasprm[2] = -eta N^2 k_t k_e / R,
/// clamped to forcerange +-eta N k_t I_limit (the driver's current limit; what fivebar simulate's
/// voltage clamp gives once the current has settled). Sensors: `jointpos` of each motor joint
/// (named as the joint) and `framepos` of the tactor site `<s>_<m>_tactor` at P.
///
/// Collisions (docs/mjcf.md "Contacts"): two default classes as MuJoCo Menagerie models have them,
/// `visual` (group 2, no contacts) and `collision` (group 3). Each link's collision geoms are the outline
/// of the collision study (fivebar/collision.hpp) extruded over its plate: a box of the link's length and
/// width with a cylinder of max(width, boss)/2 at each joint end, so links in one plane touch and links
/// in different planes do not; the tactor tip a cylinder of tactor_diameter, its post one of
/// pin_diameter. `<contact><exclude>` keeps the bodies joined by the loop (the two distal links, the tip
/// and the distal link without it) from touching; MuJoCo already skips parent and child.
///
/// Joint ranges: the motor joints' `range` is their mechanical range, the arc between the hard stops
/// (stop_range(): the base obstacles of fivebar/device/joint_limits.hpp; unlimited without one), made
/// stiff (solreflimit the connect constraints' time constant). The usable range (the potentiometer's
/// travel, the stops, the declared joint_limits) is a sensor range, not a stop: it is the position
/// servo's ctrlrange and a `<custom><numeric name="<joint>_usable_range">` (lo, hi) in the file.
///
/// Actuators (MjcfActuators): `duty` as above; `position`, the exported PID as MuJoCo can state it
/// without a plugin: the proportional and derivative terms in continuous time through the motor line,
///   torque = G (kp (ctrl - q) - kd qdot) + B qdot,   G = gainprm[0] of the duty actuator, B its biasprm[2],
/// i.e. gainprm[0] = G kp, biasprm = [0, -G kp, B - G kd], ctrl = the joint angle commanded (rad,
/// ctrlrange the usable range), forcerange the current limit. Left out: the integral term, the 10 ms
/// sampling, the ADC and the duty's saturation at +-1 (an approximation of the device's loop; test with
/// the duty variant and your own controller for the device's figures).
///
/// Keyframe `home` (mjcf_home()): the tactors about the target centre, the upper one above the
/// lower, separation apart in y (the stretch pattern's start, else clear of each other, else at the
/// centre when neither is reachable); ctrl 0 (duty) or the home angles (position).
///
/// Left out: the skin's shear contact (fivebar simulate's stick/slip spring anchored where the
/// tactor touches needs the skin's normal preload and an anchor that MJCF's contacts do not
/// express: the file is the unloaded device, as `fivebar simulate --no-contact`; the scene's finger is
/// a visual), gravity (the design does not give the device's orientation; `gravity="0 0 0"`, as
/// fivebar simulate), the pins and motor shafts as collision geoms, and the ADC and PID of the duty
/// variant (the client's controller: the gains are in the exported parameters file).
///
/// Bundle (mujoco_bundle(), docs/mjcf.md "The bundle"): a folder per station laid out as MuJoCo
/// Menagerie's models, `<design>_<station>/`: the model `<design>_<station>.xml` (duty actuators) and
/// `<design>_<station>_position.xml`, `scene.xml` and `scene_position.xml` (floor, light, the finger
/// as a capsule over the target), `assets/` (the parts' STL renders, when the scene built them),
/// `README.md`, `LICENSE` and `preview.svg`; it loads copied anywhere on its own.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/export/urdf.hpp"

namespace fivebar {

/// The connect constraints' solref time constant (s): twice the file's timestep, the smallest
/// MuJoCo keeps (a smaller one is raised to 2 timesteps).
inline constexpr double kMjcfSolrefTimeconst_s = 2e-4;
/// The file's `option timestep` (s).
inline constexpr double kMjcfTimestep_s = 1e-4;

/// The actuators of an MJCF (above).
enum class MjcfActuators : std::uint8_t { duty, position };

/// The mechanical range of motor joint `joint` (1, 2) of `m` around `reference` (rad): from the
/// reference, the nearest blocked arc of hard_stops() each way.
struct StopRange {
  bool limited = false;      ///< false: no base obstacle blocks the joint
  double lo = 0.0, hi = 0.0; ///< rad, on the reference's branch
  std::string lo_by, hi_by;  ///< "hard stop at lower O2", ...
};
/// InputError without `geometry:`.
StopRange stop_range(const Design& design, const Station& station, const Mechanism& m, int joint, double reference);

/// The keyframe `home` of a station (above).
struct MjcfHome {
  double separation_mm = 0.0;  ///< 0 with one mechanism
  std::string separation_from; ///< "patterns.stretch.separation_mm" or the clearance rule
  struct Mechanism {
    std::string name;
    Vec2 P_mm{0.0, 0.0};
    std::array<double, 2> theta{0.0, 0.0};  ///< rad, on the usable range's branch
    std::array<double, 2> elbow{0.0, 0.0};  ///< rad, on the turn of the MJCF's ref
  };
  std::vector<Mechanism> mechanisms;  ///< station.mechanisms() order
};
/// The first separation both mechanisms reach within their usable ranges: the stretch pattern's, the
/// clearance rule, else none (both tactors at the centre, overlapping; separation_from says so).
/// InputError when a mechanism has no pose at its target centre.
MjcfHome mjcf_home(const Design& design, const Station& station);

/// `<design>_<station>.xml` (duty), `<design>_<station>_position.xml` (position).
std::string mjcf_file_name(const Design& design, const Station& station, MjcfActuators actuators = MjcfActuators::duty);

/// The MJCF document of `station` (layout above); `options` as for the URDF (meshes named relative
/// to the file through the compiler's meshdir, options.mesh_prefix). InputError without `geometry:`,
/// when a mechanism's joints have no usable range or its target centre has no pose.
std::string render_mjcf(const Design& design, const Station& station, const UrdfOptions& options = {},
                        MjcfActuators actuators = MjcfActuators::duty);

/// One file of a model folder: its path inside the folder and its bytes.
struct BundleFile {
  std::filesystem::path path;
  std::string bytes;
};

/// `<design>_<station>`: the bundle's folder.
std::string mujoco_bundle_name(const Design& design, const Station& station);

/// Every file of the station's MuJoCo bundle (above), in memory. `parts` as for the URDF; the meshes
/// are read from options.parts_dir and copied into `assets/`. InputError as render_mjcf().
std::vector<BundleFile> mujoco_bundle(const Design& design, const Station& station, const UrdfOptions& parts = {});

}  // namespace fivebar
