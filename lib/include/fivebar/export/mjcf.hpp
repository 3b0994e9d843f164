#pragma once
/// MJCF (MuJoCo's XML) of a station: both five-bars with their loops closed, the motors as
/// actuators, the potentiometers as sensors (`fivebar export` writes `<design>_<station>.xml` beside
/// the URDF; `--format mjcf` alone; docs/mjcf.md). SI units; checked against `fivebar simulate` by
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
/// Left out: the skin's shear contact (fivebar simulate's stick/slip spring anchored where the
/// tactor touches needs the skin's normal preload and an anchor that MJCF's contacts do not
/// express: the file is the unloaded device, as `fivebar simulate --no-contact`), gravity (the
/// design does not give the device's orientation; `gravity="0 0 0"`, as fivebar simulate),
/// collisions (geoms are visuals: contype = conaffinity = 0) and the ADC and PID (the client's
/// controller: the gains are in the exported parameters file).

#include <string>

#include "fivebar/design.hpp"
#include "fivebar/export/urdf.hpp"

namespace fivebar {

/// The connect constraints' solref time constant (s): twice the file's timestep, the smallest
/// MuJoCo keeps (a smaller one is raised to 2 timesteps).
inline constexpr double kMjcfSolrefTimeconst_s = 2e-4;
/// The file's `option timestep` (s).
inline constexpr double kMjcfTimestep_s = 1e-4;

/// `<design>_<station>.xml`.
std::string mjcf_file_name(const Design& design, const Station& station);

/// The MJCF document of `station` (layout above); `options` as for the URDF (meshes named relative
/// to the file through the compiler's meshdir). InputError without `geometry:`, when a mechanism's
/// joints have no usable range or its target centre has no pose.
std::string render_mjcf(const Design& design, const Station& station, const UrdfOptions& options = {});

}  // namespace fivebar
