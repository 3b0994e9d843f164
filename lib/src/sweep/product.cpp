// The `sweep` product: the scene's `sweep:` section run in full (every core), with its CSV, Pareto
// set, best design file and plots under sweep/, and a summary of the best designs.

#include <cmath>

#include "fivebar/sweep.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {
using json = Json;

namespace {

json row_json(const SweepSettings& s, const SweepRow& r) {
  json j;
  j["index"] = r.index;
  json values = json::object();
  for (std::size_t d = 0; d < s.vary.size(); ++d) values[s.vary[d].name + "_mm"] = r.values[d];
  j["values"] = values;
  auto opt = [](double v) { return std::isnan(v) ? json(nullptr) : json(v); };
  j["margin_mm"] = opt(r.score("margin"));
  j["min_lci"] = opt(r.min_lci);
  j["min_force_capability"] = opt(r.min_force_capability);
  j["footprint_mm2"] = opt(r.footprint_mm2);
  j["collision_fraction"] = opt(r.collision_fraction);
  return j;
}

}  // namespace

Product sweep_product() {
  Product p;
  p.name = "sweep";
  p.title = "Link-dimension sweep";
  p.unavailable = [](const Design& d) -> std::optional<std::string> {
    if (!d.get<SweepSettings>()) return "the design has no sweep: section";
    return std::nullopt;
  };
  p.build = [](Context& ctx) {
    const SweepSettings& s = *ctx.design.get<SweepSettings>();
    SweepOptions o;
    o.out_dir = ctx.dir / "sweep";
    o.progress = [&ctx](std::uint64_t done, std::uint64_t total, double) {
      if (done == total) ctx.say("sweep: " + std::to_string(done) + " designs evaluated");
    };
    const SweepResult r = run_sweep(ctx.design, o);
    for (const auto& f : r.files) ctx.record(std::filesystem::relative(f, ctx.dir));

    Built b;
    json j;
    j["station"] = s.station;
    j["mechanism"] = s.mechanism.empty() ? json(nullptr) : json(s.mechanism);
    j["sample"] = s.sample;
    j["seed"] = s.seed;
    j["objectives"] = s.objectives;
    j["designs"] = r.total;
    j["covered"] = r.covered;
    j["invalid"] = r.invalid;
    j["seconds"] = r.seconds;
    j["designs_per_s"] = r.designs_per_s;
    j["pareto"] = json::array();
    for (const auto& row : r.pareto) j["pareto"].push_back(row_json(s, row));
    j["best"] = r.best ? row_json(s, *r.best) : json(nullptr);
    b.result = j;

    std::string md = "Station `" + s.station + "`" + (s.mechanism.empty() ? "" : ", mechanism `" + s.mechanism + "`") +
                     ", " + s.sample + " sampling of ";
    for (std::size_t d = 0; d < s.vary.size(); ++d) {
      const auto& v = s.vary[d];
      md += (d ? ", " : "") + v.name + " in [" + md::fixed(v.lo, 2) + ", " + md::fixed(v.hi, 2) + "] mm" +
            (s.sample == "grid" ? " (" + std::to_string(v.n) + " values)" : "");
    }
    md += ": " + std::to_string(r.total) + " designs in " + md::fixed(r.seconds, 2) + " s (" +
          md::fixed(r.designs_per_s, 0) + " designs/s); " + std::to_string(r.covered) +
          " cover the target with the design's thresholds.\n\n";
    std::vector<std::string> header{"design"};
    for (const auto& v : s.vary) header.push_back(v.name + " (mm)");
    for (const char* h : {"margin (mm)", "min LCI", "min force (N per N*mm)", "footprint (mm^2)", "colliding pairs"}) {
      header.push_back(h);
    }
    md::Table t(header);
    auto add = [&](const SweepRow& row, const std::string& label) {
      std::vector<std::string> cells{label};
      for (double v : row.values) cells.push_back(md::fixed(v, 3));
      cells.push_back(md::fixed(row.score("margin"), 3));
      cells.push_back(md::fixed(row.min_lci, 3));
      cells.push_back(md::fixed(row.min_force_capability, 4));
      cells.push_back(md::fixed(row.footprint_mm2, 1));
      cells.push_back(std::isnan(row.collision_fraction) ? "-" : md::fixed(100.0 * row.collision_fraction, 1) + " %");
      t.row(cells);
    };
    if (r.best) add(*r.best, "**best** #" + std::to_string(r.best->index));
    std::size_t shown = 0;
    for (const auto& row : r.pareto) {
      if (shown++ == 12) break;
      add(row, "Pareto #" + std::to_string(row.index));
    }
    md += "Best by the objectives in order (" ;
    for (std::size_t i = 0; i < s.objectives.size(); ++i) md += (i ? ", " : "") + s.objectives[i];
    md += ") and the Pareto set" + std::string(r.pareto.size() > 12 ? " (first 12 of " + std::to_string(r.pareto.size()) + ")" : "") +
          ":\n\n" + t.str() + "\n";
    md += "Files: `sweep/sweep.csv` (one row per design), `sweep/pareto.csv`, `sweep/best.yaml` (a ready design "
          "file), `sweep/sweep_scatter.svg`" + std::string(s.sample == "grid" && s.vary.size() > 1 ? ", `sweep/sweep_heatmap.svg`" : "") +
          ".\n";
    b.markdown = md;
    b.passed = r.best.has_value();
    b.check = r.best ? std::to_string(r.covered) + " of " + std::to_string(r.total) + " designs cover the target"
                     : "no design of the sweep covers the target";
    return b;
  };
  return p;
}

}  // namespace fivebar::products
