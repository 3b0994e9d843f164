// Workspace VTK files (fivebar/workspace/io.hpp); the documents themselves are built in lib/src/vtk/.
#include "fivebar/workspace/io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>

#include "fivebar/io.hpp"

namespace fivebar {

const char* to_string(CurveKind kind) {
  switch (kind) {
    case CurveKind::region: return "region";
    case CurveKind::shared: return "shared";
    case CurveKind::target: return "target";
    case CurveKind::assembly_contour: return "assembly_contour";
    case CurveKind::lci_contour: return "lci_contour";
  }
  return "unknown";
}

void write_regions_vtp(const std::filesystem::path& path, const StationWorkspace& workspace) {
  write_file_atomic(path, regions_vtp(workspace));
}

void write_field_vti(const std::filesystem::path& path, const WorkspaceField& field) {
  write_file_atomic(path, field_vti(field));
}

}  // namespace fivebar
