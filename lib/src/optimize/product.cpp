// The `optimize` product: the scene's `optimize:` section run in full (pagmo2 islands on every
// core, NLopt polish), the chosen design re-checked by the exact coverage, collision and pattern
// products, and a summary comparing it with the design as given.

#include <cmath>

#include "fivebar/optimize.hpp"
#include "fivebar/scene.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {

Product optimize_product() {
  Product p;
  p.name = "optimize";
  p.cost_s = 1.5;  // the showcase's search (scheduler hint only, Product::cost_s)
  p.title = "Dimensional synthesis (multi-objective optimisation)";
  p.unavailable = [](const Design& d) -> std::optional<std::string> {
    if (!d.get<OptimizeSettings>()) return "the design has no optimize: section";
    return std::nullopt;
  };
  p.build = [](Context& ctx) {
    const Design& d = ctx.design;
    const OptimizeProblem problem(d);
    const OptimizeSettings& s = problem.settings();
    OptimizeOptions o;
    o.out_dir = ctx.dir / "optimize";
    o.progress = [&ctx](std::uint64_t done, std::uint64_t budget, double, std::size_t front) {
      ctx.say("optimize: " + std::to_string(done) + " of " + std::to_string(budget) + " candidates, front " +
              std::to_string(front));
    };
    OptimizeResult r = run_optimize(d, o);
    for (const auto& f : r.files) ctx.record(std::filesystem::relative(f, ctx.dir));
    std::optional<SceneReport> check;
    if (r.chosen_design) {
      ctx.say("optimize: re-checking the chosen design");
      check = ctx.check_design(*r.chosen_design, o.out_dir);
      const auto base = std::filesystem::relative(check->out_dir, ctx.dir);
      for (const auto& pr : check->products) {
        for (const auto& f : pr.files) ctx.record(base / f);
      }
      for (const auto& f : {check->summary_md, check->summary_json, check->index_html}) {
        ctx.record(std::filesystem::relative(f, ctx.dir));
      }
    }

    Built b;
    Json j = r.to_json(problem);
    Json rc = Json::array();
    bool recheck_ok = true;
    if (check) {
      for (const auto& pr : check->products) {
        if (pr.state != ProductOutcome::State::built) continue;
        rc.push_back(Json{{"product", pr.name}, {"passed", pr.passed}, {"check", pr.check}});
        recheck_ok = recheck_ok && pr.passed;
      }
    }
    j["recheck"] = check ? rc : Json(nullptr);
    b.result = j;

    std::string md = r.algorithm + " on " + std::to_string(s.islands) + " islands of " + std::to_string(s.population) +
                     " over " + std::to_string(s.variables.size()) + " variables (";
    for (std::size_t i = 0; i < s.variables.size(); ++i) md += (i ? ", " : "") + s.variables[i].name;
    md += "); objectives ";
    for (std::size_t i = 0; i < s.objectives.size(); ++i) {
      md += (i ? ", " : "") + std::string(s.objectives[i].maximise ? "max " : "min ") + s.objectives[i].figure;
    }
    md += s.constraints.empty() ? "" : "; constraints ";
    for (std::size_t i = 0; i < s.constraints.size(); ++i) md += (i ? ", " : "") + s.constraints[i].text();
    md += ". " + std::to_string(r.evaluations) + " candidates (" + std::to_string(r.distinct) +
          " distinct designs, each evaluated once: the cache answered " + std::to_string(r.cache_hits) +
          " requests) in " + md::fixed(r.seconds, 2) + " s (seed " + std::to_string(s.seed) + "); the front has " + std::to_string(r.front.size()) + " designs, hypervolume " +
          (r.hypervolume.empty() ? std::string("-") : md::fixed(r.hypervolume.back().second, 4)) +
          " of the normalised objectives.\n\n";
    md::Table stages({"stage", "candidates rejected"}, "lr");
    stages.row({"invalid (a rule of the design file)", std::to_string(r.stages.invalid)});
    stages.row({"coverage (certified containment, conditioning)", std::to_string(r.stages.not_covered)});
    stages.row({"cheap constraints", std::to_string(r.stages.cheap)});
    stages.row({"loop constraints (stability map)", std::to_string(r.stages.loop)});
    stages.row({"simulation constraints (patterns)", std::to_string(r.stages.simulation)});
    stages.row({"**feasible**", std::to_string(r.stages.feasible)});
    md += stages.str() + "\n";
    if (r.chosen) {
      md += "The chosen design (" + s.choose + " of the front" + (r.polished ? ", polished by COBYLA in " +
            std::to_string(r.polish_evaluations) + " evaluations" : "") + ") beside the design as given:\n\n";
      md::Table cmp({"variable or figure", "given", "chosen"}, "lrr");
      for (const auto& row : optimize_comparison(problem, r)) cmp.row({row[0], row[1], row[2]});
      md += cmp.str() + "\n";
      if (check) {
        md += "Re-checked by the exact products (`optimize/" + check->design_name + "/summary.md`): ";
        bool first = true;
        for (const auto& pr : check->products) {
          if (pr.state != ProductOutcome::State::built) continue;
          md += std::string(first ? "" : "; ") + pr.name + " " + (pr.passed ? "passed" : "**FAILED**") + " (" + pr.check + ")";
          first = false;
        }
        md += ".\n\n";
      }
    } else {
      md += "No candidate satisfied every constraint: nothing is chosen (see `optimize/candidates.csv`).\n\n";
    }
    for (const Json& a : r.atlases) {
      md += "Non-dimensional performance atlas of station `" + a["station"].get<std::string>() + "`'s family " +
            "(docs/atlas.md), the design as given and the chosen one marked: `optimize/atlas-" +
            a["station"].get<std::string>() + ".svg`.\n\n";
    }
    md += "Files: `optimize/front.csv` and `front.json` (the Pareto front), `optimize/candidates.csv` (every candidate "
          "and the stage that rejected it), `optimize/chosen.yaml` (a complete design file), "
          "`optimize/hypervolume.svg` (convergence), `optimize/front.svg` (the front in parallel coordinates).\n";
    b.markdown = md;
    b.passed = r.chosen.has_value() && recheck_ok;
    b.check = r.chosen ? std::to_string(r.front.size()) + " designs on the front; the chosen one " +
                             (recheck_ok ? "passes" : "FAILS") + " the exact re-check"
                       : "no feasible design among " + std::to_string(r.evaluations) + " candidates";
    return b;
  };
  return p;
}

}  // namespace fivebar::products
