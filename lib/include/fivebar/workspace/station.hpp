#pragma once
/// The workspace of one finger station, analysed once and then written (VTK files, pictures) and
/// reported (tables, JSON): every mechanism's exact region, its sampled fields on one common grid,
/// the assembly- and LCI-restricted regions with their error estimates, the pose at the target
/// centre, and the shared region of the two mechanisms. Behind `fivebar workspace` and the
/// `workspace` product of `fivebar run`.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/json.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/workspace/region.hpp"

namespace fivebar {

struct WorkspaceOptions {
  /// Sample spacing of the fields and of the marching-squares areas (mm), > 0. 0.2 mm puts the
  /// restricted-area error of the paper's stations well under 0.1 % (see SampledArea::error_mm2).
  double spacing_mm = 0.2;
  /// Only this mechanism ("lower" or "upper"); empty: every mechanism of the station.
  std::string mechanism;
  /// Throws InputError naming `spacing_mm` or `mechanism` when broken.
  void validate() const;
};

/// One mechanism's share of a StationWorkspace.
struct MechanismWorkspace {
  Mechanism mechanism;
  Region region;           ///< exact, working mode and joint limits
  WorkspaceField field;    ///< on StationWorkspace::grid
  SampledArea assembly;    ///< Restriction::assembly
  SampledArea lci;         ///< Restriction::lci (LCI >= min_lci on the assembly side)
  Pose centre;             ///< IK at the target centre (for drawing the linkage)
};

struct StationWorkspace {
  std::string station;
  Ellipse target;
  /// Common grid of every field: covers the union of the regions' bounds (or the target when they
  /// are empty) with two samples of margin on each side, so that every contour closes.
  Grid grid;
  std::vector<MechanismWorkspace> mechanisms;  ///< lower first
  /// Exact intersection of the two regions, when both mechanisms were analysed.
  std::optional<Region> shared;

  const MechanismWorkspace* find(std::string_view mechanism) const;
};

/// Analyses `station` (every mechanism, or options.mechanism only). InputError when
/// options.mechanism names a mechanism the station does not have, or the spacing is not > 0.
/// `progress`, when set, receives one line per stage (e.g. for stderr).
StationWorkspace analyse_workspace(const Station& station, const WorkspaceOptions& options = {},
                                   const std::function<void(std::string_view)>& progress = {});

/// Results with units at the edges: station, target, spacing_mm, grid {origin_mm, spacing_mm,
/// nx, ny}, mechanisms {<name>: {area_mm2, perimeter_mm, components, holes, bounds_mm,
/// assembly_area_mm2, assembly_error_mm2, lci_area_mm2, lci_error_mm2, min_lci,
/// max_lci_sampled}}, shared ({area_mm2, perimeter_mm, components, holes} or null).
Json to_json(const StationWorkspace& workspace);

/// File names of a station's outputs, relative to the output directory.
struct WorkspaceFileNames {
  std::string vtp;                  ///< "<station>-regions.vtp"
  std::vector<std::string> vti;     ///< "<station>-<mechanism>-field.vti", one per mechanism
  std::string svg;                  ///< "<station>-workspace.svg"
  std::string png;                  ///< "<station>-workspace.png"
  std::vector<std::string> all() const;
};
WorkspaceFileNames workspace_file_names(const StationWorkspace& workspace);

}  // namespace fivebar
