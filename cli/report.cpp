// fivebar report accuracy | stability: work-precision of every approximate answer, and the
// catalogue of extreme cases against a __float128 reference.

#include <iostream>
#include <memory>

#include "common.hpp"
#include "fivebar/io.hpp"
#include "fivebar/report.hpp"

namespace fivebar::cli {

namespace {

struct ReportOptions {
  std::string design;
  std::string station;
  std::string out;  ///< empty: outputs/<design name>/report
  bool json = false;
  bool quick = false;
  bool quiet = false;
};

std::function<void(std::string_view)> progress_sink(bool quiet) {
  if (quiet) return {};
  return terminal_progress("report");
}

int run_accuracy(const ReportOptions& opt) {
  const Design design = load(opt.design);
  AccuracyOptions options;
  options.quick = opt.quick;
  options.station = opt.station;
  options.progress = progress_sink(opt.quiet);
  // Resolve the output directory before the long computation so that a bad --out fails early.
  const std::filesystem::path dir = command_output_dir(opt.out, design.name, "report");
  const WriteFence fence(dir);  // nothing of this command lands outside it (fivebar/io.hpp)
  const AccuracyReport report = accuracy_report(design, options);
  const auto files = write_accuracy_plots(report, dir);
  if (opt.json) {
    Json doc = to_json(report);
    Json list = Json::array();
    for (const auto& f : files) list.push_back((dir / f).generic_string());
    doc["files"] = list;
    print_json(doc);
  } else {
    std::cout << to_text(report);
    std::cout << "\nplots (SVG and PNG) in " << dir.generic_string() << ":\n";
    for (const auto& f : files)
      if (f.extension() == ".png") std::cout << "  " << f.stem().generic_string() << ".{svg,png}\n";
  }
  return kOk;
}

int run_stability(const ReportOptions& opt) {
  const Design design = load(opt.design);
  StabilityOptions options;
  options.station = opt.station;
  options.progress = progress_sink(opt.quiet);
  const StabilityReport report = stability_report(design, options);
  if (opt.json) {
    print_json(to_json(report));
  } else {
    std::cout << to_text(report);
  }
  if (!report.passed()) {
    std::cerr << "fivebar report stability: " << report.failed() << " of " << report.cases.size()
              << " cases failed (see the FAIL lines)\n";
    return kCheckFailed;
  }
  return kOk;
}

void add_common(CLI::App& sub, ReportOptions& opt) {
  add_design_argument(sub, opt.design);
  add_station_option(sub, opt.station, "every station");
  add_json_flag(sub, opt.json);
  sub.add_flag("-q,--quiet", opt.quiet, "No progress lines on stderr (they are shown only on a terminal anyway)");
}

}  // namespace

void setup_report(CLI::App& app) {
  CLI::App* report = app.add_subcommand(
      "report", "Accuracy against run time (work-precision) and numerical stability on extreme cases");
  report->require_subcommand(1);

  auto [a, acc] = add_command<ReportOptions>(
      *report, "accuracy",
      "Work-precision series (error against run time) of the workspace area (cell counting, marching squares), "
      "the coverage margin and min LCI (sampling), the sampled restricted regions, and FK/IK in float, double, "
      "long double and the library's double paths against a __float128 reference, stratified by distance to "
      "singularity. Writes one SVG and PNG plot per method into --out.",
      run_accuracy);
  add_common(*a, *acc);
  add_out_option(*a, acc->out, "the plots", "report");
  a->add_flag("--quick", acc->quick, "Coarser series and fewer samples (a few seconds instead of ~30 s)");
  a->footer(exit_status({.ok = "success", .writes = true}));

  auto [s, stab] = add_command<ReportOptions>(
      *report, "stability",
      "Extreme cases through FK, IK, Jacobian/LCI, workspace area and coverage: distances 1e-1 ... 1e-16 and 0 to "
      "type I/II singularities, link ratios 1e-4 ... 1e4, scales 1e-3 ... 1e6 mm, coincident bases, equal links, "
      "condition numbers up to 1e14, tangent ellipses; each with its status, error against a __float128 "
      "reference, the bound its conditioning allows, and PASS/FAIL.",
      run_stability);
  add_common(*s, *stab);
  s->footer(exit_status({.ok = "every case passed", .failed = "a case failed"}));
}

}  // namespace fivebar::cli
