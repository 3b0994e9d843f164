// The `export` product: the design's `controller:` section, validated by the export gate and, when
// it passes, written as ROS 2 parameters, JSON and a C++17 header under export/ (fivebar/export/export.hpp).
// A refused export writes nothing and fails the product's check with every reason.

#include <algorithm>
#include <numbers>
#include <string>

#include "fivebar/format.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/provenance.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {

namespace {

using format::kDegPerRad;

constexpr const char* kPreamble =
    "The configuration of the device's ROS controller (paper Sec. II-D: an IK module per mechanism, FK of the "
    "measured joints for collision checks with the upper mechanism's priority, a PID per motor), written only "
    "when the export gate passes: every mechanism covers its target, the LCI over the target stays above the "
    "threshold, the joint limits hold over the whole target, each joint's range reads within the ADC range, "
    "the target and the patterns keep a margin inside each joint's usable range (the potentiometers' travel and "
    "the links' hard stops: docs/urdf.md), the declared patterns are renderable and, with the motors' data, the "
    "sampled PID loop is stable at every pose of each target and every pattern, simulated, keeps its tracking "
    "error and saturation within `controller.max_tracking_error_mm` and `controller.max_saturation_fraction`. The "
    "three files hold the same values (SI units); `fivebar export --check FILE DESIGN` confirms a file still "
    "matches the design. Each station also gets a URDF with a `<ros2_control>` block and the transmissions "
    "(gearing, rotor inertia) and an MJCF for MuJoCo with the loops closed, the motors as actuators and the "
    "reflected rotor inertia as armature (docs/urdf.md, docs/mjcf.md; masses and meshes from the parts' STL "
    "renders when the scene built them).\n\n";

/// The validated figures of the export gate (its `fivebar.validation` block) with what each rests
/// on (fivebar/provenance.hpp figure_bases(), the one table): a markdown table, a row per mechanism
/// and set of groups, and the same per figure as JSON records for summary.json.
void rests_on(const Design& d, const Json& validation, std::string& markdown, Json& records) {
  records = Json::array();
  md::Table table({"mechanism", "validated figures", "rest on"}, "lll");
  for (const auto& [station, mechanisms] : validation.items()) {
    for (const auto& [mechanism, figures] : mechanisms.items()) {
      const std::string subject = station + "/" + mechanism;
      std::vector<std::pair<std::string, std::vector<std::string>>> rows;  // rests-on text -> figures
      for (const FigureBasis& basis : figure_bases()) {
        if (!figures.contains(basis.key) || !figures.at(basis.key).is_number()) continue;
        const double v = figures.at(basis.key).get<double>();
        const std::string text = rests_on_text(d, basis.key, station, mechanism);
        records.push_back({{"subject", subject}, {"figure", basis.key}, {"value", v}, {"groups", basis.groups},
                           {"assumed", figure_assumed(d, basis.key, station, mechanism)},
                           {"text", rests_on_line(d, basis.key, v, station, mechanism)}});
        auto it = std::find_if(rows.begin(), rows.end(), [&](const auto& r) { return r.first == text; });
        if (it == rows.end()) rows.push_back({text, {figure_text(basis.key, v)}});
        else it->second.push_back(figure_text(basis.key, v));
      }
      for (const auto& [text, list] : rows) table.row({md::code(subject), format::join(list), text});
    }
  }
  if (table.empty()) return;
  markdown += "What each validated figure rests on (assumed: no `provenance:` entry; docs/calibrate.md \"What each figure "
              "rests on\"):\n\n" + table.str() + "\n";
}

}  // namespace

Product export_product() {
  Product p;
  p.name = "export";
  p.title = "Controller export";
  p.unavailable = [](const Design& d) -> std::optional<std::string> {
    if (!d.get<ControllerSettings>()) return "the design has no `controller:` section";
    return std::nullopt;
  };
  p.after = {"parts"};  // the URDF's masses and meshes from the parts' renders, when built
  p.build = [](Context& ctx) {
    const Design& d = ctx.design;
    ExportOptions options;
    options.progress = ctx.progress;
    options.urdf = true;
    options.mjcf = true;
    // The URDF's masses and meshes from the parts' STL renders when the scene built them (the
    // parts product comes first in products.def); the closed form otherwise (fivebar/export/urdf.hpp).
    if (const Json* parts = ctx.result_of("parts")) {
      options.urdf_options.parts = parts;
      options.urdf_options.parts_dir = ctx.dir / "parts";
      options.urdf_options.mesh_prefix = "../parts";
    }
    const ExportResult r = export_controller(d, all_export_formats(), ctx.dir / "export", options);
    // Paths inside export/: the MuJoCo bundles are folders (fivebar/export/mjcf.hpp).
    const auto rel = [&](const std::filesystem::path& f) {
      return std::filesystem::path("export") / f.lexically_relative(ctx.dir / "export");
    };
    for (const auto& f : r.files) ctx.record(rel(f));

    Built b;
    std::string markdown = kPreamble;
    markdown += "Node " + md::code(d.get<ControllerSettings>()->node) + ", design hash " + md::code(r.hash) + ".\n\n";
    md::Table checks({"check", "subject", "verdict", "detail"}, "llcl");
    for (const GateCheck& c : r.gate.checks) {
      checks.row({c.kind, md::code(c.subject), c.passed ? "✓" : "✗ **failed**", c.detail});
    }
    markdown += checks.str() + "\n";
    if (!r.gate.joints.empty()) {
      md::Table joints({"joint", "angles over the target (deg)"}, "lr");
      for (const JointSweep& j : r.gate.joints) {
        joints.row({md::code(j.name), md::fixed(j.lo * kDegPerRad, 2) + " … " + md::fixed(j.hi * kDegPerRad, 2)});
      }
      markdown += joints.str() + "\n";
    }
    markdown += "Rests on assumed values (no `provenance:` entry, docs/calibrate.md): " +
                (r.gate.assumed.empty() ? std::string("none") : format::join(r.gate.assumed)) + ".\n\n";
    Json records;
    rests_on(d, r.gate.validation, markdown, records);
    Json files = Json::array();
    if (r.gate.passed()) {
      markdown += "Files:";
      for (const auto& f : r.files) {
        const std::string path = rel(f).generic_string();
        files.push_back(path);
        if (path.find("/assets/") != std::string::npos) continue;  // the bundles' mesh copies: listed in JSON only
        markdown += " [" + md::code(path) + "](" + path + ")";
      }
      markdown += ".\n";
    } else {
      markdown += "**Export refused**: no file written.\n";
    }
    b.result = {{"node", d.get<ControllerSettings>()->node}, {"design_hash", r.hash}, {"exported", r.gate.passed()},
                {"files", files}, {"gate", to_json(r.gate)}, {"rests_on", records}};
    b.markdown = markdown;
    b.passed = r.gate.passed();
    const auto reasons = r.gate.reasons();
    b.check = b.passed ? "gate passed (" + std::to_string(r.gate.checks.size()) + " checks); " +
                             std::to_string(r.files.size()) + " files, hash " + r.hash
                       : "export refused: " + std::to_string(reasons.size()) + " check(s) failed (" + reasons.front() + ")";
    return b;
  };
  return p;
}

}  // namespace fivebar::products
