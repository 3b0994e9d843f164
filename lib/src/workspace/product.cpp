// The `workspace` product: for every station of the scene, the exact reachable region of each
// mechanism, the assembly- and LCI-restricted areas, the shared region, and the files under
// workspace/: a .vtp of the curves, a .vti of each mechanism's fields, the picture as SVG and PNG.

#include <string>
#include <vector>

#include "fivebar/workspace/station.hpp"
#include "fivebar/workspace/files.hpp"
#include "fivebar/workspace/io.hpp"
#include "fivebar/workspace/plot.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {

namespace {

constexpr const char* kDir = "workspace";

std::string plus_minus(double value, double error) { return md::fixed(value, 1) + " ± " + md::fixed(error, 2); }

std::string station_markdown(const StationWorkspace& ws, const WorkspaceFileNames& names) {
  std::string out = "### Station " + md::code(ws.station) + "\n\n";
  md::Table t({"region", "exact area (mm²)", "perimeter (mm)", "components", "holes", "assembly side (mm²)",
               "LCI ≥ min_lci (mm²)", "min_lci"},
              "lrrrrrrr");
  for (const MechanismWorkspace& w : ws.mechanisms) {
    t.row({w.mechanism.name, md::fixed(w.region.area_mm2(), 2), md::fixed(w.region.perimeter_mm(), 2),
           std::to_string(w.region.components()), std::to_string(w.region.holes()),
           plus_minus(w.assembly.area_mm2, w.assembly.error_mm2), plus_minus(w.lci.area_mm2, w.lci.error_mm2),
           md::fixed(w.mechanism.min_lci, 2)});
  }
  if (ws.shared) {
    t.row({"shared", md::fixed(ws.shared->area_mm2(), 2), md::fixed(ws.shared->perimeter_mm(), 2),
           std::to_string(ws.shared->components()), std::to_string(ws.shared->holes()), "—", "—", "—"});
  }
  out += t.str() + "\n";
  const std::string dir = std::string(kDir) + "/";
  out += "![Station " + ws.station + " workspace](" + dir + names.png + ")\n\n";
  out += "Files: [" + names.svg + "](" + dir + names.svg + ") (vector), [" + names.vtp + "](" + dir + names.vtp +
         ") (curves)";
  for (const auto& vti : names.vti) out += ", [" + vti + "](" + dir + vti + ")";
  out += " (fields; open the VTK files in ParaView).\n\n";
  return out;
}

constexpr const char* kPreamble =
    "The *exact area* is the region of tactor points reachable in the design's working mode within its "
    "joint limits, bounded by circular arcs (CGAL, exact arithmetic; area by Green's theorem over the "
    "arcs). The *assembly side* keeps the points where the tactor is on the design's side of the distal "
    "links (no crossing of the type II singularity), and *LCI ≥ min_lci* further keeps the points with "
    "conditioning at least the design's `min_lci`; neither is bounded by circles, so both are measured by "
    "marching squares on grid cells refined as a quadtree wherever they could hold or hide a boundary "
    "(so thin regions between grid nodes are found), every crossing bisected, ± an error estimate from "
    "undoing the deepest refinement (docs/coverage.md). The *shared* region is where both tactors reach.\n\n"
    "In the pictures the lower mechanism is red and the upper blue (as in the paper's Fig. 4), the shared "
    "region is hatched, dashed lines bound the assembly side, and each linkage is drawn in its pose at the "
    "target centre; the right panel is the LCI (the smaller of both mechanisms) where both reach.\n\n";

}  // namespace

Product workspace_product() {
  Product p;
  p.name = "workspace";
  p.title = "Reachable workspace";
  p.cost_s = 1.0;  // scheduler hint only (Product::cost_s)
  p.unavailable = without_mechanisms;
  p.build = [](Context& ctx) {
    Built b;
    Json stations = Json::array();
    std::string markdown = kPreamble;
    const WorkspaceOptions options;
    markdown += "Sample spacing " + md::fixed(options.spacing_mm, 2) + " mm.\n\n";
    std::size_t mechanisms = 0, empty = 0;
    for (const Station& s : ctx.design.stations) {
      if (s.mechanisms().empty()) continue;
      ctx.say("workspace: station " + s.name);
      const StationWorkspace ws = analyse_workspace(s, options);
      PlotOptions plot;
      plot.subtitle = "design " + ctx.design.name + ", sample spacing " + md::fixed(options.spacing_mm, 2) + " mm";
      const WorkspaceFileNames names = workspace_file_names(ws);
      Json files = Json::array();
      for (const OutputFile& f : workspace_files(ws, plot)) {
        ctx.write_file(std::string(kDir) + "/" + f.name, f.content);
        files.push_back(std::string(kDir) + "/" + f.name);
      }
      Json j = to_json(ws);
      j["files"] = files;
      stations.push_back(j);
      markdown += station_markdown(ws, names);
      for (const auto& w : ws.mechanisms) {
        ++mechanisms;
        if (w.region.empty()) ++empty;
      }
    }
    b.result = {{"spacing_mm", options.spacing_mm}, {"stations", stations}};
    b.markdown = markdown;
    b.check = std::to_string(mechanisms) + " mechanism regions";
    if (empty > 0) b.check += ", " + std::to_string(empty) + " empty";
    b.check += "; VTK files and pictures in workspace/";
    return b;
  };
  return p;
}

}  // namespace fivebar::products
