// The `tolerance` product: how far each printed mechanism's tactor can be from where the
// controller believes it is, and whether the target stays covered by the printed devices
// (fivebar/tolerance.hpp); maps under tolerance/ (VTK image data and a picture per station).

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "fivebar/resources/estimates.hpp"
#include "fivebar/sections/tolerance.hpp"
#include "fivebar/tolerance.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {

namespace {

constexpr const char* kPreamble =
    "Each mechanism as printed: link lengths, pin holes and base joints off by the design's `tolerance:` sigmas, "
    "the joint angles off by the calibration offset and the potentiometer's linearity, the pins and shafts "
    "playing in their clearances and the gears in their backlash (every default an assumption to replace with "
    "measurements; lib/include/fivebar/tolerance.hpp). *3σ* is the major semi-axis of the first-order error "
    "ellipse of the tactor (Monte Carlo at the centre beside it), *worst case* every parameter at 3σ with the "
    "worst sign (the farthest corner of the first-order zonotope, exact; ⚠ where the first order is flagged near a "
    "type II singularity, with the Monte Carlo and the nonlinear corners there below the table), *play* the largest displacement the clearances allow (the exact set, not a linearisation), "
    "*resolution* the tactor step of one ADC count. *Robust margin*: the coverage margin minus the error of "
    "each boundary point of the target at the design's `robust_fraction` of printed devices, minimised over the "
    "whole boundary with a certified bound; the Monte Carlo columns count the sampled devices whose own region "
    "covers the target and give their margins' quantile at 1 − `robust_fraction` with a one-sided 95 % lower "
    "confidence bound (order statistic).\n\n";

}  // namespace

Product tolerance_product() {
  Product p;
  p.name = "tolerance";
  p.title = "Manufacturing tolerance and sensing error";
  p.unavailable = [](const Design& d) -> std::optional<std::string> {
    if (!d.get<ToleranceSettings>()) return "the design has no `tolerance:` section (the printer's and sensors' errors)";
    // The one resource rule (fivebar/resources/budget.hpp): beyond the bounds only the study run by itself, confirmed, runs it.
    if (const ResourceEstimate e = tolerance_estimate(d, {}); !within_bounds(e)) {
      return e.what + " is large: " + e.text() + "; lower tolerance.samples, or run the tolerance study by itself and confirm it (docs/reliability.md)";
    }
    return without_mechanisms(d);
  };
  p.build = [](Context& ctx) {
    const Design& d = ctx.design;
    md::Table table({"station", "mechanism", "3σ at centre, first order (mm)", "Monte Carlo (mm)", "worst 3σ, first order (mm)",
                     "worst case, nonlinear corners (mm)", "worst case, first order (mm)", "play (mm)", "resolution (µm/count)",
                     "margin (mm)", "robust margin, first order (mm)", "devices covering (MC)", "MC margin quantile (mm)"},
                    "llrrrrrrrrrrr");
    std::string flagged_md, calibrated_md;
    Json stations = Json::array();
    std::vector<std::string> failed, pictures;
    std::size_t total = 0;
    double fraction = 0.997;
    for (const Station& s : d.stations) {
      if (s.mechanisms().empty()) continue;
      ctx.say("tolerance: station " + s.name);
      std::vector<ToleranceMap> maps;
      for (const Mechanism* m : s.mechanisms()) {
        const ToleranceSources src = tolerance_sources(d, s, *m);
        fraction = src.robust_fraction;
        maps.push_back(tolerance_map(*m, s.name, s.target, src, 0.25));
      }
      Json js = {{"station", s.name}, {"mechanisms", Json::array()}};
      for (const ToleranceMap& map : maps) {
        ++total;
        js["mechanisms"].push_back(to_json(map));
        if (!map.robust.covered) failed.push_back(s.name + "/" + map.mechanism);
        table.row({s.name, map.mechanism, md::fixed(map.centre.ellipse_semi_axes.x(), 3),
                   md::fixed(map.centre_monte_carlo_3sigma_mm, 3), md::fixed(map.worst_3sigma_mm, 3),
                   (map.worst_case_flagged ? "⚠ " : "") + md::fixed(map.worst_case_mm, 3),
                   (map.worst_case_first_order_flagged ? "⚠ " : "") + md::fixed(map.worst_case_first_order_mm, 3),
                   md::fixed(map.worst_play_mm, 3),
                   md::fixed(map.worst_resolution_um, 2), md::fixed(map.robust.margin_mm, 3),
                   (map.robust.covered ? "" : "✗ ") + md::fixed(map.robust.robust_margin_mm, 3),
                   md::fixed(100.0 * map.robust.fraction_monte_carlo, 2) + " % of " +
                       std::to_string(map.robust.samples),
                   map.robust.samples == 0 ? std::string("—")
                                           : md::fixed(map.robust.quantile_margin_mm, 3) + " (≥ " +
                                                 (std::isfinite(map.robust.quantile_lower_mm)
                                                      ? md::fixed(map.robust.quantile_lower_mm, 3)
                                                      : std::string("?")) +
                                                 " at 95 %)"});
        if (map.calibrated) calibrated_md += "- " + s.name + "/" + map.mechanism + " sigmas: " + map.spread_source + ".\n";
        if (!map.near_singular.empty()) {
          double mc = 0.0, corners = 0.0, first = 0.0;
          for (const auto& f : map.near_singular) {
            mc = std::max(mc, f.monte_carlo_3sigma_mm);
            corners = std::max(corners, f.corners.worst_mm);
            first = std::max(first, f.first_order.worst_case_mm);
          }
          flagged_md += "- " + s.name + "/" + map.mechanism + ": first order flagged near a type II singularity at " +
                        std::to_string(map.near_singular.size()) + " of " + std::to_string(map.target_points) +
                        " target points; there 3σ up to " + md::fixed(mc, 3) + " mm by Monte Carlo, worst corner " +
                        md::fixed(corners, 3) + " mm nonlinear against " + md::fixed(first, 3) + " mm first order.\n";
        }
      }
      js["files"] = Json::array();
      for (const auto& [name, bytes] : tolerance_files(s, maps)) {
        const std::string rel = "tolerance/" + name;
        ctx.write_file(rel, bytes);
        js["files"].push_back(rel);
        if (name.ends_with(".png")) pictures.push_back(rel);
      }
      stations.push_back(std::move(js));
    }
    Built b;
    b.result = {{"stations", stations}};
    std::string markdown = kPreamble + table.str() + "\n";
    if (!calibrated_md.empty()) {
      markdown += "Calibrated mechanisms: the calibration's posterior covariance replaces the `tolerance:` sigmas it covers "
                  "(docs/calibrate.md \"Posterior covariance in the design\"):\n\n" + calibrated_md + "\n";
    }
    if (!flagged_md.empty()) markdown += flagged_md + "\n";
    for (const std::string& f : pictures) markdown += "Picture: [" + f + "](" + f + ").\n\n";
    markdown += "Maps for ParaView: `tolerance/<station>-<mechanism>-tolerance.vti` (3σ, worst case, resolution, "
                "play, near_singular and status over the reachable region).\n";
    b.markdown = markdown;
    b.passed = failed.empty();
    const std::string percent = md::fixed(100.0 * fraction, 1) + " %";
    b.check = b.passed ? "all " + std::to_string(total) + " mechanisms cover their target for " + percent +
                             " of printed devices"
                       : std::to_string(failed.size()) + " of " + std::to_string(total) +
                             " mechanisms lose their target on more than " + md::fixed(100.0 - 100.0 * fraction, 1) +
                             " % of printed devices";
    return b;
  };
  return p;
}

}  // namespace fivebar::products
