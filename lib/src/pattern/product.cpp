// The `pattern` product: every pattern of `patterns:` on every station with both mechanisms,
// sampled at its rate and checked sample by sample (reach, singularity, assembly side, joint
// limits, LCI, collision with the priority rule, motor speed); joint trajectories as CSV and one
// picture of the paths per station.

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>

#include "fivebar/format.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/pattern.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {

namespace {

using format::kDegPerRad;

constexpr const char* kPreamble =
    "The skin-deformation patterns of the paper (Fig. 6: stretching, slipping, twisting) and pivoting "
    "(the tactors track two points of the rotating object), sampled at the controller rate. Every sample "
    "of both tactors is checked: reachable in the working mode, not singular, on the design's assembly "
    "side, within the joint limits, LCI ≥ min_lci, collision-free (when the lower tactor collides the "
    "priority rule moves it; the pattern then counts as not renderable) and every motor within "
    "the one joint speed of the export (the smaller of `controller.max_velocity_deg_s` and the motors' "
    "steady speed less friction). The CSV files hold the four motors' joint trajectories "
    "(`time_s,station,mechanism,theta1_deg,theta2_deg,x_mm,y_mm,status,...`).\n\n";

}  // namespace

Product pattern_product() {
  Product p;
  p.name = "pattern";
  p.checks_designs = true;  // re-run on a proposed design (check_design())
  p.title = "Skin-deformation patterns";
  p.unavailable = [](const Design& d) -> std::optional<std::string> {
    if (!d.get<PatternSettings>()) return "the design has no `patterns:` section";
    return without_pairs(d, "collision checks need the link outlines");
  };
  p.build = [](Context& ctx) {
    const Design& d = ctx.design;
    const Geometry& g = *d.get<Geometry>();
    const PatternSettings& settings = *d.get<PatternSettings>();
    Built b;
    Json stations = Json::array();
    std::string markdown = kPreamble;
    markdown += "Motor speed limit: " + md::fixed(settings.max_joint_speed * kDegPerRad, 0) + " deg/s.\n\n";
    md::Table table({"station", "pattern", "verdict", "samples", "min clearance (mm)", "moved (samples, max mm)",
                     "min LCI upper / lower", "peak motor speed (deg/s)", "first failure", "trajectory"},
                    "llcrrrcrll");
    std::vector<std::string> notes, images;
    std::size_t total = 0, failed = 0;
    std::string first_failed;
    for (const Station& s : d.stations) {
      if (!has_pair(s)) {
        notes.push_back("station " + md::code(s.name) + " left out: it does not have both mechanisms");
        continue;
      }
      const std::vector<PatternSpec> specs = settings.for_station(s.name);
      if (specs.empty()) {
        notes.push_back("station " + md::code(s.name) + ": no pattern is given for it");
        continue;
      }
      std::vector<PatternResult> results;
      Json js;
      js["station"] = s.name;
      js["patterns"] = Json::array();
      for (const PatternSpec& spec : specs) {
        ctx.say("pattern: station " + s.name + ", " + std::string(to_string(spec.kind)));
        results.push_back(check_pattern(s, g, spec, pattern_joint_speed_limit(d, s)));
        const PatternResult& r = results.back();
        const std::string csv = "patterns/" + s.name + "-" + std::string(to_string(spec.kind)) + ".csv";
        std::ostringstream text;
        write_trajectory_csv(text, r);
        ctx.write_file(csv, text.str());
        Json jr = to_json(r);
        jr["trajectory_csv"] = csv;
        js["patterns"].push_back(jr);
        ++total;
        if (!r.passed) {
          ++failed;
          if (first_failed.empty()) first_failed = s.name + " " + std::string(to_string(spec.kind)) + ": " + r.first_failure->reason;
        }
        table.row({md::code(s.name), std::string(to_string(spec.kind)), r.passed ? "✓ renderable" : "✗ **not renderable**",
                   std::to_string(r.samples.size()),
                   std::isfinite(r.min_clearance_mm) ? md::fixed(r.min_clearance_mm, 2) : "—",
                   r.moved_samples > 0 ? std::to_string(r.moved_samples) + ", " + md::fixed(r.max_moved_mm, 2) : "0",
                   md::fixed(r.min_lci[0], 3) + " / " + md::fixed(r.min_lci[1], 3),
                   md::fixed(r.peak_joint_speed * kDegPerRad, 1),
                   r.first_failure ? "t = " + md::fixed(r.first_failure->time_s, 2) + " s: " + r.first_failure->reason
                                   : "—",
                   "[csv](" + csv + ")"});
      }
      const RenderedPlot pic = plot_patterns(s, g, results);
      const std::string stem = "patterns/" + s.name;
      ctx.write_file(stem + ".svg", pic.svg);
      ctx.write_file(stem + ".png", pic.png);
      js["files"] = Json::array({stem + ".svg", stem + ".png"});
      stations.push_back(js);
      images.push_back("![patterns of station " + s.name + "](" + stem + ".png)");
    }
    markdown += table.str() + "\n";
    for (const auto& n : notes) markdown += "- " + n + "\n";
    if (!notes.empty()) markdown += "\n";
    for (const auto& image : images) markdown += image + "\n\n";
    b.result = {{"rate_hz", settings.rate_hz},
                {"max_joint_speed_deg_s", settings.max_joint_speed * kDegPerRad},
                {"stations", stations}};
    b.markdown = markdown;
    b.passed = failed == 0;
    b.check = b.passed ? "all " + std::to_string(total) + " patterns renderable"
                       : std::to_string(failed) + " of " + std::to_string(total) + " patterns not renderable (" +
                             first_failed + ")";
    return b;
  };
  return p;
}

}  // namespace fivebar::products
