#pragma once
/// Workspace files for ParaView and friends (VTK XML, written with VTK behind lib/src/vtk/):
///   - `.vtp` poly data of a station's curves: every exact region boundary loop as a closed
///     polyline (arcs in steps of at most 1 degree), the shared region, the target ellipse and the
///     refined marching-squares contours of the assembly- and LCI-restricted regions; cell data
///     `kind` (CurveKind), `mechanism_id` (0 lower, 1 upper, -1 none), `loop_index`, `hole`;
///   - `.vti` image data of a WorkspaceField: origin and spacing in mm, point data arrays
///     reach, status, assembly_ok, lci, type1_distance_mm, type1_sin, type2_sin, transmission_deg,
///     force_capability (x fastest, as WorkspaceField's row-major order).
/// Every file is written atomically (fivebar/io.hpp). Coordinates in mm, z = 0.

#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "fivebar/workspace/station.hpp"
#include "fivebar/workspace/region.hpp"
#include "fivebar/workspace/polyline.hpp"

namespace fivebar {

/// What a curve of the `.vtp` is (cell data array `kind`; its names are in the field data array
/// `kind_names` in this order).
enum class CurveKind : std::int32_t {
  region = 0,            ///< boundary loop of a mechanism's exact region
  shared = 1,            ///< boundary loop of the shared region (mechanism_id -1)
  target = 2,            ///< the target ellipse (mechanism_id -1)
  assembly_contour = 3,  ///< refined boundary of the assembly-restricted region
  lci_contour = 4,       ///< refined boundary of the LCI-restricted region
};
const char* to_string(CurveKind kind);

/// The `.vtp` document (VTK XML, binary appended data) of a station's curves.
std::string regions_vtp(const StationWorkspace& workspace);
/// The `.vti` document of one field.
std::string field_vti(const WorkspaceField& field);

/// A scalar field of any study on a regular grid (x fastest, then y), for ParaView: VTK XML image
/// data with one double point array per entry of `arrays`, the first one active.
struct ImageField {
  double x0 = 0.0, y0 = 0.0;  ///< origin, mm
  double spacing = 1.0;       ///< mm
  int nx = 0, ny = 0;
  std::vector<std::pair<std::string, std::vector<double>>> arrays;  ///< name, nx * ny values
};
/// The `.vti` document of an ImageField (InputError when an array has not nx * ny values).
std::string image_vti(const ImageField& field);

/// Writes regions_vtp() / field_vti() to `path` atomically; IoError when it cannot.
void write_regions_vtp(const std::filesystem::path& path, const StationWorkspace& workspace);
void write_field_vti(const std::filesystem::path& path, const WorkspaceField& field);

}  // namespace fivebar
