#include "fivebar/format.hpp"
#include "fivebar/scene.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>
#include <map>
#include <set>

#include "design/design_keys.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "fivebar/json.hpp"
#include "fivebar/version.hpp"
#include "products/html.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar {
using json = Json;

namespace {

using format::join;

}  // namespace

bool SceneReport::ok() const {
  return missing().empty() && std::all_of(products.begin(), products.end(), [](const ProductOutcome& p) {
           return p.state != ProductOutcome::State::built || p.passed;
         });
}

std::vector<std::string> SceneReport::missing() const {
  std::vector<std::string> out;
  for (const auto& p : products) {
    if (p.requested && p.state == ProductOutcome::State::left_out) out.push_back(p.name);
  }
  return out;
}

json SceneReport::to_json() const {
  json built = json::array();
  json left_out = json::array();
  json results = json::object();
  for (const auto& p : products) {
    if (p.state == ProductOutcome::State::built) {
      json files = json::array();
      for (const auto& f : p.files) files.push_back(f.generic_string());
      built.push_back({{"name", p.name},
                       {"requested", p.requested},
                       {"prerequisite", p.prerequisite},
                       {"passed", p.passed},
                       {"check", p.check},
                       {"files", files}});
      results[p.name] = p.result;
    } else {
      left_out.push_back({{"name", p.name}, {"requested", p.requested}, {"reason", p.reason}});
    }
  }
  json j;
  j["fivebar_version"] = std::string(version());
  j["design"] = design_name;
  j["design_file"] = design_source.generic_string();
  j["out_dir"] = out_dir.generic_string();
  j["stations"] = json::array();
  for (const auto& [name, mechanisms] : stations) {
    j["stations"].push_back({{"station", name}, {"mechanisms", mechanisms}});
  }
  j["products_listed"] = products_listed;
  j["ok"] = ok();
  j["missing"] = missing();
  j["built"] = built;
  j["left_out"] = left_out;
  j["results"] = results;
  return j;
}

std::string SceneReport::to_markdown() const {
  std::string out;
  out += "# fivebar scene " + md::code(design_name) + "\n\n";
  out += "Built by fivebar " + std::string(version()) + " from " +
         (design_source.empty() ? std::string("an in-memory design") : md::code(design_source.generic_string())) +
         " into " + md::code(out_dir.generic_string()) + ". Lengths in mm, angles in degrees, " +
         "frames as in docs/conventions.md of the fivebar repository (x from a station's first lower base joint toward its second, y upward).\n\n";
  std::string station_list;
  for (const auto& [name, mechanisms] : stations) {
    station_list += (station_list.empty() ? "" : ", ") + md::code(name) + " (" + join(mechanisms, ", ") + ")";
  }
  out += "Stations: " + (station_list.empty() ? std::string("none") : station_list) + ".\n\n";
  out += ok() ? "**Result: every built product passed its check.**\n\n"
              : "**Result: attention needed** — see the products marked ✗ below.\n\n";

  md::Table table({"product", "state", "check", "files"}, "llll");
  for (const auto& p : products) {
    if (p.state == ProductOutcome::State::built) {
      std::string files;
      for (const auto& f : p.files) files += (files.empty() ? "" : ", ") + md::code(f.generic_string());
      std::string state = p.prerequisite && !p.requested ? "built (prerequisite)" : "built";
      table.row({md::code(p.name), state, (p.passed ? "✓ " : "✗ ") + p.check, files.empty() ? "—" : files});
    } else {
      table.row({md::code(p.name), p.requested ? "**not built** (requested)" : "left out", p.reason, "—"});
    }
  }
  out += "## Products\n\n";
  out += products_listed ? "The products listed for this scene, and what they needed:\n\n"
                         : "No product list given: every product this design has data for is built.\n\n";
  out += table.str() + "\n";
  for (const auto& p : products) {
    if (p.state != ProductOutcome::State::built) continue;
    out += "## " + p.title + " (" + md::code(p.name) + ")\n\n" + p.markdown;
    if (!p.markdown.empty() && p.markdown.back() != '\n') out += "\n";
    out += "\n";
  }
  return out;
}

SceneReport run_scene(const Design& design, const SceneOptions& options) {
  return products::run_scene_with(design, options, products::registry());
}

SceneReport check_design(const Design& design, const std::filesystem::path& out_root) {
  return products::check_design_with(design, out_root, products::registry());
}

SceneReport products::check_design_with(const Design& design, const std::filesystem::path& out_root,
                                        const std::vector<Product>& registry) {
  std::vector<std::string> checks;
  for (const Product& p : registry) {
    if (p.checks_designs && !(p.unavailable && p.unavailable(design))) checks.push_back(p.name);
  }
  SceneOptions o;
  o.out_root = out_root;
  o.products = checks;
  return run_scene_with(design, o, registry);
}

SceneReport products::run_scene_with(const Design& design, const SceneOptions& options,
                                     const std::vector<Product>& registry) {
  const auto find = [&registry](std::string_view name) -> const Product* {
    for (const Product& p : registry) {
      if (p.name == name) return &p;
    }
    return nullptr;
  };
  std::vector<std::string> known;
  for (const Product& p : registry) known.push_back(p.name);

  SceneReport report;
  report.design_name = design.name;
  report.design_source = design.source;
  for (const Station& s : design.stations) {
    std::vector<std::string> mechanisms;
    for (const Mechanism* m : s.mechanisms()) mechanisms.push_back(m->name);
    report.stations.emplace_back(s.name, std::move(mechanisms));
  }

  // Which products were asked for: the option overrides the file; neither = everything available.
  std::optional<std::vector<std::string>> listed = options.products ? options.products : design.products;
  std::set<std::string> requested;
  if (listed) {
    for (const auto& name : *listed) {
      if (find(name) == nullptr) throw InputError("unknown product " + detail::quoted(name) + " (known: " + join(known, ", ") + ")");
      requested.insert(name);
    }
  }
  report.products_listed = listed.has_value();
  const auto wanted = [&](const std::string& name) { return !listed || requested.count(name) > 0; };

  // Prerequisites of what is wanted, transitively.
  std::set<std::string> needed;
  std::vector<std::string> stack;
  for (const auto& name : known) {
    if (wanted(name)) stack.push_back(name);
  }
  while (!stack.empty()) {
    const std::string name = stack.back();
    stack.pop_back();
    if (!needed.insert(name).second) continue;
    for (const auto& pre : find(name)->prerequisites) stack.push_back(pre);
  }

  report.out_dir = resolve_output_dir(options.out_root, design.name);
  make_directories(report.out_dir);

  std::map<std::string, json> results;
  std::set<std::string> built;
  for (const auto& name : known) {
    ProductOutcome outcome;
    outcome.name = name;
    outcome.requested = listed && requested.count(name) > 0;
    outcome.prerequisite = needed.count(name) > 0 && !wanted(name);
    const Product* product = find(name);
    if (needed.count(name) == 0) {
      outcome.reason = "not listed in the scene's products";
    } else if (auto why = product->unavailable ? product->unavailable(design) : std::nullopt) {
      outcome.reason = *why;
    } else {
      std::vector<std::string> missing_pre;
      for (const auto& pre : product->prerequisites) {
        if (built.count(pre) == 0) missing_pre.push_back(pre);
      }
      if (!missing_pre.empty()) {
        outcome.reason = "needs " + join(missing_pre, ", ") + ", which could not be built";
      } else {
        if (options.progress) options.progress("building " + name);
        Context ctx{design, report.out_dir, results, options.progress, {}, {}};
        ctx.check_design = [&registry](const Design& d, const std::filesystem::path& root) {
          return check_design_with(d, root, registry);
        };
        Built result = product->build(ctx);
        outcome.state = ProductOutcome::State::built;
        outcome.passed = result.passed;
        outcome.check = result.check;
        outcome.result = result.result;
        outcome.files = ctx.files;
        results[name] = std::move(result.result);
        built.insert(name);
        outcome.title = product->title;
        outcome.markdown = std::move(result.markdown);
      }
    }
    report.products.push_back(std::move(outcome));
  }

  report.summary_md = report.out_dir / "summary.md";
  report.summary_json = report.out_dir / "summary.json";
  write_file_atomic(report.summary_json, report.to_json().dump(2) + "\n");
  const std::string markdown = report.to_markdown();
  write_file_atomic(report.summary_md, markdown);
  // The same text as a page: pictures by relative link, animations inline (products/html.hpp).
  md::HtmlFiles files;
  const std::filesystem::path dir = report.out_dir;
  files.exists = [dir](const std::string& rel) {
    std::error_code ec;
    return std::filesystem::is_regular_file(dir / rel, ec);
  };
  files.read = [dir](const std::string& rel) -> std::optional<std::string> {
    std::ifstream in(dir / rel, std::ios::binary);
    if (!in) return std::nullopt;
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  };
  report.index_html = report.out_dir / "index.html";
  write_file_atomic(report.index_html, md::to_html_page(markdown, "fivebar: " + design.name, files));
  return report;
}

}  // namespace fivebar
