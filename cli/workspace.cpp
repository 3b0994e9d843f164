// fivebar workspace: exact reachable regions, restricted areas and the shared region of each
// station, written as VTK files and a picture (SVG + PNG).

#include <cstdio>
#include <iostream>
#include <memory>

#include "common.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "fivebar/workspace/station.hpp"
#include "fivebar/workspace/files.hpp"
#include "fivebar/workspace/io.hpp"
#include "fivebar/workspace/plot.hpp"

namespace fivebar::cli {

namespace {

struct WorkspaceCliOptions {
  std::string design;
  std::string station;
  std::string mechanism;
  double spacing_mm = WorkspaceOptions{}.spacing_mm;
  std::string out;  ///< empty: outputs/<name>/workspace
  bool json = false;
};

void print_station(const StationWorkspace& ws, const std::vector<std::filesystem::path>& files) {
  const Ellipse& e = ws.target;
  std::cout << "station " << ws.station << "  target centre (" << fixed(e.center.x(), 2) << ", " << fixed(e.center.y(), 2)
            << ") mm, full axes " << fixed(e.axes.x(), 2) << " x " << fixed(e.axes.y(), 2) << " mm\n";
  std::printf("  %-8s %12s %10s %6s %6s %22s %22s %8s\n", "region", "area (mm2)", "perim (mm)", "comp.", "holes",
              "assembly side (mm2)", "LCI >= min_lci (mm2)", "min_lci");
  auto pm = [](const SampledArea& a) { return fixed(a.area_mm2, 2) + " +- " + fixed(a.error_mm2, 3); };
  for (const MechanismWorkspace& w : ws.mechanisms) {
    const Region& r = w.region;
    std::printf("  %-8s %12s %10s %6d %6d %22s %22s %8s\n", w.mechanism.name.c_str(), fixed(r.area_mm2(), 3).c_str(),
                fixed(r.perimeter_mm(), 3).c_str(), r.components(), r.holes(), pm(w.assembly).c_str(),
                pm(w.lci).c_str(), fixed(w.mechanism.min_lci, 2).c_str());
  }
  if (ws.shared) {
    const Region& r = *ws.shared;
    std::printf("  %-8s %12s %10s %6d %6d %22s %22s %8s\n", "shared", fixed(r.area_mm2(), 3).c_str(),
                fixed(r.perimeter_mm(), 3).c_str(), r.components(), r.holes(), "-", "-", "-");
  }
  std::fflush(stdout);
  std::cout << "  files:";
  for (const auto& f : files) std::cout << " " << f.filename().generic_string();
  std::cout << "\n\n";
}

int run_workspace(const WorkspaceCliOptions& opt) {
  const Design design = load(opt.design);
  WorkspaceOptions options;
  options.spacing_mm = opt.spacing_mm;
  options.mechanism = opt.mechanism;
  try {
    options.validate();
  } catch (const InputError& e) {  // the library names the field, the user typed the flag
    std::string message = e.what();
    if (message.rfind("spacing_mm", 0) == 0) message.replace(0, 10, "--spacing");
    throw InputError(message);
  }
  const auto stations = design.select_stations(opt.station);
  if (stations.empty()) throw InputError("design '" + design.name + "' has no station with a mechanism");
  const std::filesystem::path dir =
      command_output_dir(opt.out, design.name, "workspace");
  const WriteFence fence(dir);  // nothing of this command lands outside it (fivebar/io.hpp)
  const auto progress = terminal_progress("workspace");

  // Analyse every station before writing anything: a bad --mechanism for the second station must
  // not leave the first one's files behind.
  std::vector<StationWorkspace> results;
  for (const Station* s : stations) results.push_back(analyse_workspace(*s, options, progress));

  PlotOptions plot;
  plot.subtitle = "design " + design.name + ", sample spacing " + fixed(options.spacing_mm, 2) + " mm";
  Json doc;
  doc["command"] = "workspace";
  doc["design"] = design.name;
  doc["spacing_mm"] = options.spacing_mm;
  doc["out_dir"] = dir.generic_string();
  doc["stations"] = Json::array();
  if (!opt.json) {
    std::cout << design.name << " workspace, sample spacing " << fixed(options.spacing_mm, 2) << " mm -> "
              << dir.generic_string() << "\n\n";
  }
  std::size_t empty = 0;
  for (const StationWorkspace& ws : results) {
    if (progress) progress(ws.station + ": writing files");
    const auto files = write_workspace_files(dir, ws, plot);
    Json j = to_json(ws);
    j["files"] = Json::array();
    for (const auto& f : files) j["files"].push_back(f.generic_string());
    doc["stations"].push_back(j);
    if (!opt.json) print_station(ws, files);
    for (const auto& w : ws.mechanisms) {
      if (w.region.empty()) {
        ++empty;
        std::cerr << "fivebar workspace: " << ws.station << "/" << w.mechanism.name
                  << " reaches no point in its working mode within its joint limits\n";
      }
    }
  }
  if (opt.json) print_json(doc);
  return empty == 0 ? kOk : kCheckFailed;
}

}  // namespace

void setup_workspace(CLI::App& app) {
  auto [sub, opt] = add_command<WorkspaceCliOptions>(
      app, "workspace",
      "Reachable workspace per mechanism: exact area (mm2), perimeter, components, holes; assembly- and "
      "LCI-restricted areas; the shared region; VTK files and a picture (SVG, PNG)",
      run_workspace);
  add_design_argument(*sub, opt->design);
  add_station_option(*sub, opt->station, "every station");
  sub->add_option("-m,--mechanism", opt->mechanism, "Only this mechanism of each station: lower or upper (default: both)")
      ->check(CLI::IsMember({"lower", "upper"}))
      ->type_name("NAME");
  sub->add_option("--spacing", opt->spacing_mm,
                  "Sample spacing of the fields and restricted areas, in mm (smaller is finer and slower)")
      ->capture_default_str()
      ->type_name("MM");
  add_out_option(*sub, opt->out, "the files", "workspace");
  add_json_flag(*sub, opt->json, "one JSON document (mm, mm2)");
  sub->footer(
      "Files per station S: S-regions.vtp (region boundaries, shared region, target, restricted contours), "
      "S-<mechanism>-field.vti (reach, status, assembly_ok, lci, singularity distances, transmission, force "
      "capability), S-workspace.svg and S-workspace.png.\n" +
      exit_status({.ok = "done", .failed = "a mechanism reaches nothing", .writes = true}));
}

}  // namespace fivebar::cli
