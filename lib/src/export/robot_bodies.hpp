#pragma once
// Private to lib: the rigid bodies of a station as the URDF (fivebar/export/urdf.hpp) and the MJCF
// (fivebar/export/mjcf.hpp) write them: per mechanism the four links and the tactor tip with their full
// mass properties in their part frames, from the parts' STL renders or the closed form
// (fivebar/dynamics.hpp station_inertia()), and the geometry both files place them with.

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/export/urdf.hpp"

namespace fivebar::detail {

/// Full mass properties of one body in its link frame (mm, kg, kg mm^2).
struct Body {
  double mass_kg = 0.0;
  Eigen::Vector3d com_mm = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia_kg_mm2 = Eigen::Matrix3d::Zero();  ///< about the centre of mass
  std::string mesh;      ///< as the file should name it (options.mesh_prefix + "/" + the report's path); empty without a render
  std::string mesh_rel;  ///< the report's path alone (relative to the parts folder); empty without a render
};

struct MechanismBodies {
  const Mechanism* mechanism = nullptr;
  MechanismInertia inertia;
  std::array<Body, 4> links;  ///< L1 .. L4
  Body tip;                   ///< on the carrier's post (inertia.carrier: 2 = L3, 3 = L4)
  bool from_stl = false;
  double post_height_mm = 0.0;  ///< tactor_height less the tip
  double tip_height_mm = 0.0;   ///< the tip: flange and dome (PartsHardware)
};

struct StationBodies {
  std::vector<MechanismBodies> mechanisms;  ///< station.mechanisms() order
  /// The base plate: from its STL render with one, else a plate of PartsHardware::base_plate_thickness
  /// under z = 0 over the base joints' bounding box grown by the motor's radius and the base margin
  /// (the base's outline in fivebar/parts.hpp, without the finger rest and the mounting pads).
  Body base;
  bool base_from_stl = false;
  Eigen::Vector3d base_plate_size_mm = Eigen::Vector3d::Zero();  ///< the plate's x, y, z extent
  Eigen::Vector3d base_plate_centre_mm = Eigen::Vector3d::Zero();
  std::string base_mesh;                    ///< as the file should name it; empty without a render
  std::string base_mesh_rel;
  std::string parts_problem;                ///< why a given parts report could not be used
  double hub_height_mm = 0.0;
  double link_thickness_mm = 0.0;
  double layer_gap_mm = 0.0;
  /// z of link plane `layer`'s plate bottom in the station frame (mm).
  double plane_z(int layer) const { return hub_height_mm + layer * (link_thickness_mm + layer_gap_mm); }
};

/// InputError without `geometry:`.
StationBodies station_bodies(const Design& design, const Station& station, const UrdfOptions& options);
/// Appends to `meshes` each mesh (relative to the parts folder) a station's bodies name and `meshes`
/// does not hold yet: the files a bundle or a package copies beside its model.
void add_station_meshes(const StationBodies& bodies, std::vector<std::string>& meshes);

}  // namespace fivebar::detail
