// fivebar run: build the products a scene asks for into <out>/<name>/ (docs/architecture.md "Products").

#include <cstdio>
#include <iostream>
#include <memory>

#include "common.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "fivebar/scene.hpp"

namespace fivebar::cli {

namespace {

struct RunOptions {
  std::string design;
  std::string out = "outputs";
  std::vector<std::string> products;
  bool json = false;
  bool quiet = false;
  unsigned jobs = 0;
};

void print_report(const SceneReport& report) {
  std::cout << "scene " << report.design_name << " -> " << report.out_dir.generic_string() << "\n\n";
  for (const auto& p : report.products) {
    std::string state;
    std::string note;
    if (p.state == ProductOutcome::State::built) {
      state = p.passed ? "built, passed" : "built, FAILED";
      if (p.prerequisite && !p.requested) state += " (prerequisite)";
      note = p.check;
    } else {
      state = p.requested ? "NOT BUILT" : "left out";
      note = p.reason;
    }
    std::printf("  %-12s %-16s %s\n", p.name.c_str(), state.c_str(), note.c_str());
  }
  std::fflush(stdout);
  std::cout << "\nsummary: " << report.summary_md.generic_string() << "\n"
            << "         " << report.summary_json.generic_string() << "\n"
            << "         " << report.index_html.generic_string() << " (open it in a browser)\n";
  const auto missing = report.missing();
  if (!missing.empty()) {
    std::cerr << "fivebar run: requested but not built:";
    for (const auto& m : missing) std::cerr << " " << m;
    std::cerr << " (see the summary for why)\n";
  }
}

int run_run(const RunOptions& opt) {
  const Design design = load(opt.design);
  if (opt.out.empty()) throw InputError("--out: empty output directory (give a directory, e.g. --out .)");
  // Every file of the scene lands under --out, whatever a product asks for (fivebar/io.hpp).
  const WriteFence fence(opt.out);
  SceneOptions options;
  options.out_root = opt.out;
  if (!opt.products.empty()) options.products = opt.products;
  if (!opt.quiet) options.progress = terminal_progress("run");  // only for a person watching
  if (opt.jobs > 64) throw InputError("--jobs must be within [0, 64] (0: one per core)");
  options.jobs = opt.jobs;
  const SceneReport report = run_scene(design, options);
  if (opt.json) {
    Json doc = {{"command", "run"}};
    doc.update(report.to_json());
    doc["summary_md"] = report.summary_md.generic_string();
    doc["summary_json"] = report.summary_json.generic_string();
    doc["index_html"] = report.index_html.generic_string();
    print_json(doc);
  } else {
    print_report(report);
  }
  return report.ok() ? kOk : kCheckFailed;
}

}  // namespace

void setup_run(CLI::App& app) {
  auto [sub, opt] = add_command<RunOptions>(
      app, "run",
      "Build the products a scene lists (default: all it has data for) into OUT/<name>/ with summary.md/.json and index.html",
      run_run);
  add_design_argument(*sub, opt->design);
  // The parent of the design's folder, as docs/conventions.md "Output files" says: not add_out_option().
  sub->add_option("-o,--out", opt->out, "Output root; the scene writes OUT/<design name>/")
      ->capture_default_str()
      ->type_name("DIR");
  sub->add_option("-P,--products", opt->products,
                  "Comma-separated products to build instead of the scene's list (known: " + [] {
                    std::string names;
                    for (const auto& n : known_products()) names += (names.empty() ? "" : ", ") + n;
                    return names;
                  }() + ")")
      ->delimiter(',')
      ->type_name("LIST");
  add_json_flag(*sub, opt->json, "the summary as one JSON document");
  sub->add_flag("-q,--quiet", opt->quiet, "No progress lines on stderr");
  sub->add_option("-j,--jobs", opt->jobs,
                  "Products built at once, each after its prerequisites (0: one per core); the outputs do not depend on it")
      ->capture_default_str()
      ->type_name("N");
  sub->footer(exit_status({.ok = "every built product passed",
                           .failed = "a check failed or a requested product could not be built",
                           .writes = true}));
}

}  // namespace fivebar::cli
