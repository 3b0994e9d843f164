// fivebar parts: OpenSCAD sources, STL renders, mesh and fit checks and the bill of materials of
// a design's printed parts, into OUT/<name>/parts/.

#include <cstdio>
#include <iostream>
#include <memory>

#include "common.hpp"
#include "fivebar/io.hpp"
#include "fivebar/parts.hpp"

namespace fivebar::cli {

namespace {

struct PartsCliOptions {
  std::string design;
  std::string station;
  std::string out;  ///< empty: outputs/<design name>/parts
  bool no_render = false;
  bool json = false;
  int jobs = 2;
};

void print_table(const PartsReport& r, const std::filesystem::path& dir) {
  std::printf("%-8s %-28s %5s %10s %12s %9s %10s %-22s %s\n", "station", "part", "count", "length", "measured",
              "volume", "resin", "render", "checks");
  std::printf("%-8s %-28s %5s %10s %12s %9s %10s %-22s %s\n", "", "", "", "(mm)", "c-c (mm)", "(mm3)", "(ml)", "",
              "");
  for (const PartResult& p : r.parts) {
    const bool link = p.spec.kind == PartKind::proximal_link || p.spec.kind == PartKind::distal_link;
    std::string render(to_string(p.render));
    if (p.render == RenderState::rendered) render += p.copied_from.empty() ? " " + fixed(p.render_seconds, 1) + " s" : " (copy)";
    std::printf("%-8s %-28s %5d %10s %12s %9s %10s %-22s %s\n", p.spec.station.c_str(), p.spec.name.c_str(),
                p.spec.count, link ? fixed(p.spec.length_mm, 3).c_str() : "-",
                p.centre_distance_mm ? fixed(*p.centre_distance_mm, 4).c_str() : "-",
                p.mesh ? fixed(p.mesh->volume_mm3, 1).c_str() : "-",
                p.mesh ? fixed(p.spec.count * p.mesh->volume_mm3 / 1000.0, 3).c_str() : "-", render.c_str(),
                !r.rendered ? "-" : p.passed() ? "passed" : "FAILED");
  }
  std::fflush(stdout);
  std::cout << "\n";
  if (r.rendered) {
    std::cout << r.count(RenderState::rendered) << " rendered, " << r.count(RenderState::up_to_date)
              << " up to date, " << r.count(RenderState::failed) << " failed in " << fixed(r.wall_seconds, 1)
              << " s; resin " << fixed(r.resin_ml(), 2) << " ml for one set\n";
  } else {
    std::cout << "sources only (--no-render): " << r.parts.size() << " .scad files\n";
  }
  std::cout << "parts: " << dir.generic_string() << "/\n"
            << "bill of materials: " << (dir / r.bom_csv).generic_string() << "\n";
  for (const PartResult& p : r.parts) {
    for (const auto& problem : p.problems) std::cerr << "fivebar parts: " << p.spec.label() << ": " << problem << "\n";
  }
}

int run_parts(const PartsCliOptions& opt) {
  const Design design = load(opt.design);
  PartsOptions options;
  options.out_dir = command_output_dir(opt.out, design.name, "parts");
  const WriteFence fence(options.out_dir);  // nothing of this command lands outside it (fivebar/io.hpp)
  if (!opt.station.empty()) options.station = opt.station;
  options.render = !opt.no_render;
  options.jobs = opt.jobs;
  options.progress = terminal_progress("parts");
  PartsReport report;
  try {
    report = build_parts(design, options);
  } catch (const ToolError& e) {
    std::cerr << "fivebar parts: " << e.what() << "\n";
    if (const std::string hint = remedy_hint(e.remedy()); !hint.empty()) std::cerr << "fivebar: hint: " << hint << "\n";
    return kCheckFailed;
  }
  if (opt.json) {
    Json doc{{"command", "parts"}, {"design", design.name}};
    doc.update(to_json(report));
    print_json(doc);
  } else {
    print_table(report, options.out_dir);
  }
  return report.passed() ? kOk : kCheckFailed;
}

}  // namespace

void setup_parts(CLI::App& app) {
  auto [sub, opt] = add_command<PartsCliOptions>(
      app, "parts",
      "Printable parts: OpenSCAD sources, binary STL renders (openscad), mesh and fit checks, bill of materials",
      run_parts);
  add_design_argument(*sub, opt->design);
  add_station_option(*sub, opt->station, "every station");
  add_out_option(*sub, opt->out, "the parts", "parts");
  sub->add_flag("--no-render", opt->no_render, "Write the .scad sources (and a BOM without volumes) only");
  sub->add_option("-j,--jobs", opt->jobs, "openscad processes at once")
      ->capture_default_str()
      ->check(CLI::Range(1, 64))
      ->type_name("N");
  add_json_flag(*sub, opt->json, "one JSON document (mm)");
  sub->footer("Parts whose .scad text and library are unchanged since their last render are not rendered again.\n" +
              exit_status({.ok = "every part rendered and passed its checks",
                           .failed = "a render or check failed or openscad is not installed",
                           .writes = true}));
}

}  // namespace fivebar::cli
