// The file set of a station's workspace (fivebar/workspace/files.hpp).
#include "fivebar/workspace/files.hpp"

#include "fivebar/io.hpp"
#include "fivebar/workspace/io.hpp"

namespace fivebar {

std::vector<OutputFile> workspace_files(const StationWorkspace& ws, const PlotOptions& plot) {
  const WorkspaceFileNames names = workspace_file_names(ws);
  std::vector<OutputFile> out;
  out.push_back({names.vtp, regions_vtp(ws)});
  for (std::size_t k = 0; k < ws.mechanisms.size(); ++k) out.push_back({names.vti[k], field_vti(ws.mechanisms[k].field)});
  out.push_back({names.svg, station_svg(ws, plot)});
  out.push_back({names.png, station_png(ws, plot)});
  return out;
}

std::vector<std::filesystem::path> write_workspace_files(const std::filesystem::path& dir, const StationWorkspace& ws,
                                                         const PlotOptions& plot) {
  plot.validate();
  // Every document is produced before the first is written: a failure while drawing leaves no file.
  const std::vector<OutputFile> files = workspace_files(ws, plot);
  make_directories(dir);
  std::vector<std::filesystem::path> out;
  for (const OutputFile& f : files) {
    write_file_atomic(dir / f.name, f.content);
    out.push_back(dir / f.name);
  }
  return out;
}

}  // namespace fivebar
