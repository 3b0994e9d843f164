// The `calibrate` product: the design's mechanisms fitted to the bench measurements its `bench:`
// section names (fivebar/calibrate.hpp, docs/calibrate.md); writes calibrate/calibration-summary.md
// and calibrate/<design>-calibrated.yaml (the fitted values with their provenance: entries).

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "fivebar/calibrate.hpp"
#include "fivebar/csv_reader.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/provenance.hpp"
#include "fivebar/sections/bench.hpp"
#include "fivebar/sha256.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {

namespace {

std::string read_bench_file(const std::filesystem::path& path, const char* what) {
  return csv::read_bounded(path, calibrate::kMeasurementLimits.max_bytes, std::string(what) + " (bench: section)");
}

}  // namespace

Product calibrate_product() {
  Product p;
  p.name = "calibrate";
  p.title = "Kinematic calibration from the bench";
  p.unavailable = [](const Design& d) -> std::optional<std::string> {
    const BenchSettings* b = d.get<BenchSettings>();
    if (b == nullptr || b->calibration.empty()) return "the design names no bench measurements (`bench.calibration`)";
    // A design copied away from its bench files still runs its other products.
    if (const auto file = BenchSettings::resolve(d, b->calibration); !std::filesystem::exists(file)) {
      return "the bench measurements `" + b->calibration + "` (`bench.calibration`) are not there: " + file.generic_string();
    }
    return without_mechanisms(d);
  };
  p.check_inputs = [](const Design& d) {
    const std::string& name = d.get<BenchSettings>()->calibration;
    BenchSettings::require_inside(d, "calibration", name);  // links followed: not read when it leads out
    (void)calibrate::parse_measurements(read_bench_file(BenchSettings::resolve(d, name), "calibration measurements"), name, d);
  };
  p.build = [](Context& ctx) {
    const Design& d = ctx.design;
    const std::string& name = d.get<BenchSettings>()->calibration;
    const std::filesystem::path file = BenchSettings::resolve(d, name);
    const std::string text = read_bench_file(file, "calibration measurements");
    const auto rows = calibrate::parse_measurements(text, name, d);
    const calibrate::CalibrationResult r = calibrate::calibrate(d, rows, {}, name);
    const calibrate::Source source{name, sha256_hex(text), today_utc()};
    ctx.write_file("calibrate/calibration-summary.md", calibrate::report_markdown(r, source));
    if (r.gate.passed) {  // the quality gate refused: nothing patched (docs/calibrate.md "The quality gate")
      Design patched = calibrate::with_provenance(calibrate::patched_design(d, r), r, source);
      patched.reset<BenchSettings>();  // the patched design lives in the output folder: no relative bench files
      ctx.write_file("calibrate/" + d.name + "-calibrated.yaml", to_yaml(patched));
    }

    Built b;
    std::string md = "The bench measurements `" + name + "` (" + std::to_string(r.poses) + " poses of station " + md::code(r.station) +
                     ", " + format::join(r.mechanisms) + ") fitted by `fivebar calibrate` (docs/calibrate.md): residual RMS " +
                     md::fixed(r.before.rms_mm, 4) + " mm at the design values, " + md::fixed(r.after.rms_mm, 4) +
                     " mm after the fit (measurement sigma " + md::fixed(r.sigma_mm, 4) + " mm, " +
                     (r.sigma_estimated ? "from the residuals" : "given") + "); condition number " +
                     md::fixed(r.condition_number, 1) + ", observability index " + md::fixed(r.observability_index, 4) + ".\n\n";
    md::Table t({"parameter", "design", "fitted", "σ", "unit"}, "lrrrl");
    for (const calibrate::Parameter& q : r.parameters) {
      t.row({md::code(q.key), format::shortest(q.design), md::fixed(q.value, 5), q.identified ? md::fixed(q.sigma, 5) : "held", q.unit});
    }
    md += t.str() + "\n";
    for (const calibrate::Unidentifiable& u : r.unidentifiable) md += "- " + md::code(u.parameter) + " not identifiable: " + u.combination + "\n";
    for (const calibrate::ExcludedPose& e : r.skipped) md += "- line " + std::to_string(e.line) + " (" + e.mechanism + ") skipped: " + e.reason + "\n";
    for (const calibrate::ExcludedPose& e : r.outliers) md += "- line " + std::to_string(e.line) + " (" + e.mechanism + ") " + e.reason + "\n";
    md += "\nQuality gate: " + std::string(r.gate.passed ? "passed" : "refused, nothing patched") + " (solver " + r.gate.solver.termination +
          "; " + (r.gate.tests.empty() ? std::string() : r.gate.tests.front().statement) + ").\n";
    for (const std::string& line : r.gate.refusal_lines()) md += "- not measured: " + line + "\n";
    md += "\n";
    if (r.gate.passed) {
      md += "Files: [`calibrate/" + d.name + "-calibrated.yaml`](calibrate/" + d.name +
            "-calibrated.yaml) (the design with the fitted values, a `provenance:` entry per value and the posterior "
            "correlations), [`calibrate/calibration-summary.md`](calibrate/calibration-summary.md).\n";
    } else {
      md += "Files: [`calibrate/calibration-summary.md`](calibrate/calibration-summary.md).\n";
    }
    b.markdown = md;
    b.result = calibrate::to_json(r);
    b.result["measurements"] = name;
    b.result["patched_design"] = r.gate.passed ? Json("calibrate/" + d.name + "-calibrated.yaml") : Json(nullptr);
    b.passed = !r.requested_unidentifiable && r.gate.passed;
    b.check = std::to_string(r.poses) + " poses, residual RMS " + format::fixed(r.after.rms_mm, 4) + " mm";
    return b;
  };
  return p;
}

}  // namespace fivebar::products
