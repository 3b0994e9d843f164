#pragma once
/// A ROS 2 description package of the exported stations (`fivebar export DESIGN --ros2-package DIR`;
/// docs/ros2-package.md), laid out as `ros2 pkg create --build-type ament_cmake` lays one out:
///
///   package.xml                  format 3, ament_cmake, the run dependencies of the launch file
///   CMakeLists.txt               installs urdf/, meshes/ (when there are meshes), config/, launch/
///   urdf/<design>_<station>.urdf per station: render_urdf() with a fixed `world` link and the meshes
///                                named package://<package>/meshes/<part>.stl
///   meshes/                      the parts' STL renders (when the export has a parts report)
///   config/<design>_controller.yaml  the exported parameters file (fivebar/export/export.hpp)
///   config/ros2_controllers.yaml     controller_manager at the loop rate: joint_state_broadcaster and,
///                                per station, a position_controllers/JointGroupPositionController on its
///                                motor joints (the `<ros2_control>` block commands positions)
///   launch/display.launch.py     robot_state_publisher, joint_state_publisher_gui starting at the
///                                initial pose (fivebar/export/urdf.hpp initial_pose()) and rviz2;
///                                `station:=<name>` picks the URDF
///   README.md                    what is where, and what to fill in (maintainer, licence)
///
/// The package's name: the design's name in lower case, other characters than [a-z0-9_] as '_', a
/// leading digit prefixed with "fivebar_", then "_description" (ROS's naming rule, REP 144).

#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/export/mjcf.hpp"
#include "fivebar/export/urdf.hpp"
#include "fivebar/json.hpp"

namespace fivebar {

/// `<design>_description` as above.
std::string ros2_package_name(const Design& design);

/// Every file of the package, paths inside the package's folder. `parameters` is the exported tree
/// (controller_parameters()); `parts` as for the URDF (meshes copied from parts.parts_dir).
/// InputError as render_urdf().
std::vector<BundleFile> ros2_package(const Design& design, const std::vector<std::string>& stations, const Json& parameters,
                                     const UrdfOptions& parts = {});

}  // namespace fivebar
