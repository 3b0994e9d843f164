// fivebar control: the sampled-data loop of every mechanism linearised over its target ellipse
// (ZOH plant, PID with one period of delay; fivebar/control.hpp): spectral radius map, worst pose,
// verdict, gain margins and the damping of the dominant pole; picture, VTK field, CSV, JSON.

#include <iostream>
#include <map>
#include <memory>
#include <optional>

#include "common.hpp"
#include "fivebar/control.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "fivebar/parts.hpp"
#include "tactors.hpp"

namespace fivebar::cli {

namespace {

struct ControlCliOptions {
  std::string design;
  std::string station;
  bool render = false;
  int grid = 41;
  int field = 81;
  std::string out;
  bool json = false;
};

int run_control(const ControlCliOptions& opt) {
  if (opt.grid < 3 || opt.grid > 401) throw InputError("--grid must be within [3, 401]");
  if (opt.field < 3 || opt.field > 801) throw InputError("--field must be within [3, 801]");
  const Design design = load(opt.design);
  const std::vector<const Station*> stations = design.select_stations(opt.station);
  if (stations.empty()) throw InputError("design '" + design.name + "' has no station with a mechanism");
  require_geometry(design);
  // Missing sections are bad input before anything is written.
  for (const Station* s : stations) {
    std::map<std::string, MechanismInertia> none;
    for (const Mechanism* m : s->mechanisms()) none[m->name] = MechanismInertia{};
    (void)loop_models(design, *s, none);
  }
  const std::filesystem::path dir = output_dir(design, opt.out, "control");
  const WriteFence fence(dir);  // nothing of this command lands outside it (fivebar/io.hpp)
  std::optional<Json> parts;
  const std::filesystem::path parts_dir = dir / "parts";
  if (opt.render) {
    PartsOptions po;
    po.out_dir = parts_dir;
    if (!opt.station.empty()) po.station = opt.station;
    po.progress = terminal_progress("control");
    const PartsReport report = build_parts(design, po);
    if (!report.passed()) {
      std::cerr << "fivebar control: the parts' renders failed their checks (see " << parts_dir.generic_string()
                << "); no mass properties\n";
      return kCheckFailed;
    }
    parts = to_json(report);
  }
  ControlOptions co;
  co.stability.grid = opt.grid;
  co.field_cells = opt.field;
  const auto progress = terminal_progress("control");
  make_directories(dir);
  Json doc = {{"command", "control"}, {"design", design.name}};
  Json studies = Json::array();
  std::vector<std::string> files;
  bool stable = true;
  for (const Station* s : stations) {
    if (progress) progress("stability of station " + s->name);
    const auto inertia = station_inertia(design, *s, parts ? &*parts : nullptr, parts_dir);
    const StationControl study = station_control(design, *s, inertia, co);
    stable = stable && study.stable();
    for (const auto& [name, bytes] : control_files(study, *s, "design " + design.name)) {
      const std::filesystem::path path = dir / name;
      write_file_atomic(path, bytes);
      files.push_back(path.generic_string());
    }
    Json j = to_json(study);
    std::string mass;
    for (const auto& [name, in] : inertia) mass += (mass.empty() ? "" : "; ") + name + ": " + in.note;
    j["mass_properties"] = mass;
    studies.push_back(j);
    if (!opt.json) {
      for (const std::string& line : summary_lines(study)) std::cout << line << "\n";
    }
  }
  if (opt.json) {
    doc["stations"] = studies;
    doc["files"] = files;
    print_json(doc);
  } else {
    for (const std::string& f : files) std::cout << "  wrote " << f << "\n";
  }
  if (!stable) {
    std::cerr << "fivebar control: the loop is unstable (max rho >= 1) somewhere on a target (see above)\n";
    return kCheckFailed;
  }
  return kOk;
}

}  // namespace

void setup_control(CLI::App& app) {
  auto opt = std::make_shared<ControlCliOptions>();
  CLI::App* sub = app.add_subcommand(
      "control",
      "Stability of each mechanism's sampled PID loop over its target ellipse: spectral radius of the ZOH plant "
      "linearised at every pose with one period of delay, worst pose, gain margins, damping; picture, VTK, CSV");
  add_design_argument(*sub, opt->design);
  sub->add_option("-s,--station", opt->station, "Only this station (default: every station with a mechanism)")
      ->type_name("NAME");
  sub->add_flag("--render", opt->render,
                "Links' masses from the parts' STL renders (openscad) instead of the closed form (slab with bosses)");
  sub->add_option("--grid", opt->grid, "Grid points per axis over the target ellipse's box (default 41)")
      ->type_name("N");
  sub->add_option("--field", opt->field, "Grid points per axis over each mechanism's reach (default 81)")
      ->type_name("N");
  sub->add_option("-o,--out", opt->out, "Directory for the files (default: outputs/<design>/control)")
      ->type_name("DIR");
  sub->add_flag("--json", opt->json, "Print one JSON document on stdout");
  sub->footer(
      "Needs the design's geometry:, motor: and controller: sections (contact: and print: take their defaults).\n"
      "Files: <station>-stability.svg|.png, <station>-<mechanism>-rho.vti, <station>-stability.csv.\n"
      "Exit status: 0 stable everywhere on every target, 1 unstable somewhere (or a part failed to render),\n"
      "2 bad input, 3 internal error or output not writable.");
  sub->callback([opt]() { finish(run_control(*opt)); });
}

}  // namespace fivebar::cli
