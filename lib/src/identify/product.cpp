// The `identify` product: the motor, friction and inertia of the joints of the bench log the
// design's `bench:` section names (fivebar/identify.hpp, docs/identify.md), by IDIM-LS (IDIM-IV for a
// closed-loop log, one with its reference column); writes
// identify/identify.json and identify/<design>-identified.yaml (the identified motor keys with
// their provenance: entries). The output-error refinement and the plots are `fivebar identify`'s.

#include <filesystem>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>

#include "fivebar/csv_reader.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/identify.hpp"
#include "fivebar/provenance.hpp"
#include "fivebar/provenance/gate.hpp"
#include "fivebar/sections/bench.hpp"
#include "fivebar/sha256.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {

Product identify_product() {
  Product p;
  p.name = "identify";
  p.title = "Motor and friction identification from the bench";
  p.unavailable = [](const Design& d) -> std::optional<std::string> {
    const BenchSettings* b = d.get<BenchSettings>();
    if (b == nullptr || b->identification.empty()) return "the design names no identification log (`bench.identification`)";
    // A design copied away from its bench files still runs its other products.
    if (const auto file = BenchSettings::resolve(d, b->identification); !std::filesystem::exists(file)) {
      return "the identification log `" + b->identification + "` (`bench.identification`) is not there: " + file.generic_string();
    }
    return std::nullopt;
  };
  p.check_inputs = [](const Design& d) {
    // Readable, with a header, before the output folder exists (the rows are read by build).
    BenchSettings::require_inside(d, "identification", d.get<BenchSettings>()->identification);
    const std::filesystem::path file = BenchSettings::resolve(d, d.get<BenchSettings>()->identification);
    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(file.generic_string() + ": cannot be read (bench.identification)");
    (void)csv::Reader(in, file.generic_string());
  };
  p.build = [](Context& ctx) {
    const Design& d = ctx.design;
    const std::string& name = d.get<BenchSettings>()->identification;
    const std::filesystem::path file = BenchSettings::resolve(d, name);
    identify::IdentifyLog log = identify::read_identify_log(file);
    log.path = name;
    identify::require_log_joints_in(d, log);
    identify::IdentifyOptions o;
    o.output_error = false;  // IDIM-LS only: the refinement is `fivebar identify`'s (it simulates)
    // A log whose every joint carries its reference (theta_ref_rad) was taken under the design's PID:
    // IDIM-IV, as `fivebar identify --closed-loop` (docs/identify.md "Closed loop").
    bool closed = true;
    for (const identify::JointLog& j : log.joints) closed = closed && !j.reference.empty();
    const std::vector<identify::IdentifyLog> logs{std::move(log)};
    const std::vector<identify::JointIdentification> results = identify::identify_motor_rig(d, {&logs, {name}, nullptr, {}, {}, 0.0, closed}, o);
    Json doc = {{"log", name}, {"method", closed ? "IDIM-IV" : "IDIM-LS"}, {"joints", Json::array()}};
    for (const auto& r : results) doc["joints"].push_back(identify::to_json(r));
    // The patched design is written into <output>/identify/: the log recorded relative to it.
    MeasurementSource source{recorded_source(file, ctx.dir / "identify"), sha256_file(file), today_utc(),
                             closed ? "fivebar identify --rig motor --closed-loop: inverse dynamic model by instrumental variables under the "
                                      "design's PID (IDIM-IV), standard deviation"
                                    : "fivebar identify --rig motor: inverse dynamic model by least squares (IDIM-LS), standard deviation"};
    // The quality gate decides what is written as measured (docs/identify.md "The quality gate").
    identify::Patch patch = identify::patch_design(d, results, source, false);
    doc["gate"] = gate::to_json(patch.gate);
    doc["patched"] = patch.patched;
    doc["not_patched"] = patch.not_patched;
    const std::vector<std::string>& keys = patch.patched;
    std::string patched_file;
    if (patch.design) {
      patch.design->reset<BenchSettings>();  // the patched design lives in the output folder
      patched_file = "identify/" + d.name + "-identified.yaml";
      ctx.write_file(patched_file, to_yaml(*patch.design));
      doc["patched_design"] = patched_file;
    }
    ctx.write_file("identify/identify.json", doc.dump(2) + "\n");

    Built b;
    std::string md = "The bench log `" + name + "` fitted by `fivebar identify --rig motor` (" +
                     (closed ? std::string("closed loop: IDIM-IV under the design's PID") : std::string("IDIM-LS")) +
                     ", docs/identify.md; the output-error refinement and the plots are the command's).\n\n";
    md::Table t({"joint", "parameter", "value", "σ", ""}, "llrrl");
    for (const auto& r : results) {
      for (const identify::Parameter& q : r.parameters) {
        if (!q.identified) continue;
        t.row({md::code(r.joint), md::code(q.key), format::general(q.value, 5), format::general(q.sigma, 3),
               std::find(keys.begin(), keys.end(), q.key) != keys.end() ? "patched" : ""});
      }
    }
    md += t.str() + "\n";
    for (const auto& r : results) {
      md += "- " + md::code(r.joint) + ": drive fit " + md::fixed(r.estimation_idim.drive_fit_percent, 1) + " % (inverse model)";
      if (!r.unidentifiable.empty()) md += "; not identifiable from this log (held at the prior): " + format::join(r.unidentifiable);
      md += "\n";
    }
    md += "\nQuality gate: " + std::string(patch.gate.reasons.empty() ? "passed" : "refused, nothing patched") + " (" +
          patch.gate.solver.termination + ").\n";
    for (const gate::ResidualTest& test : patch.gate.tests) md += "- " + test.statement + "\n";
    for (const std::string& s : patch.not_patched) md += "- not patched: " + s + "\n";
    md += "\nFiles: [`identify/identify.json`](identify/identify.json)";
    if (!patched_file.empty()) md += ", [`" + patched_file + "`](" + patched_file + ") (the identified motor keys with their `provenance:` entries)";
    md += ".\n";
    b.markdown = md;
    b.result = doc;
    b.check = std::to_string(results.size()) + " joint(s), " + std::to_string(keys.size()) + " design key(s) measured" +
              (patch.gate.reasons.empty() ? "" : " (the quality gate refused the fit)");
    b.passed = patch.gate.reasons.empty();
    return b;
  };
  return p;
}

}  // namespace fivebar::products
