#pragma once
/// The files of a station's workspace, as `fivebar workspace` and the workspace product write them:
/// the VTK documents (fivebar/workspace/io.hpp) and the picture (fivebar/workspace/plot.hpp),
/// named by workspace_file_names().

#include <filesystem>
#include <string>
#include <vector>

#include "fivebar/workspace/station.hpp"
#include "fivebar/workspace/plot.hpp"

namespace fivebar {

/// Every output of a station, named by workspace_file_names(): the `.vtp`, one `.vti` per
/// mechanism, the picture as SVG and PNG.
struct OutputFile {
  std::string name;  ///< relative to the output directory
  std::string content;
};
std::vector<OutputFile> workspace_files(const StationWorkspace& workspace, const PlotOptions& plot = {});
/// Writes workspace_files() into `dir` (created when missing), each atomically; returns the paths.
std::vector<std::filesystem::path> write_workspace_files(const std::filesystem::path& dir,
                                                         const StationWorkspace& workspace,
                                                         const PlotOptions& plot = {});

}  // namespace fivebar
