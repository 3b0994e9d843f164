#include "fivebar/csv_reader.hpp"
#include "fivebar/format.hpp"
#include "fivebar/scene.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <fstream>
#include <functional>
#include <mutex>
#include <thread>
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

/// The summary.json an earlier run left in `out_dir`, or "" (none, unreadable, or past 16 MiB: a
/// summary is kilobytes, so a link to /dev/zero is ignored unread, as a missing one is).
std::string earlier_summary(const std::filesystem::path& out_dir) {
  try {
    return csv::read_bounded(out_dir / "summary.json", std::uintmax_t{16} << 20, "summary");
  } catch (const InputError&) {
    return {};
  }
}

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
                       {"wall_s", p.wall_s},
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

  md::Table table({"product", "state", "check", "time (s)", "files"}, "lllrl");
  for (const auto& p : products) {
    if (p.state == ProductOutcome::State::built) {
      std::string files;
      for (const auto& f : p.files) files += (files.empty() ? "" : ", ") + md::code(f.generic_string());
      std::string state = p.prerequisite && !p.requested ? "built (prerequisite)" : "built";
      table.row({md::code(p.name), state, (p.passed ? "✓ " : "✗ ") + p.check, md::fixed(p.wall_s, 2),
                 files.empty() ? "—" : files});
    } else {
      table.row({md::code(p.name), p.requested ? "**not built** (requested)" : "left out", p.reason, "—", "—"});
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

  // Every input file of what will be built is checked before the output folder exists.
  for (const auto& name : known) {
    const Product* p = find(name);
    if (needed.count(name) == 0 || !p->check_inputs) continue;
    if (p->unavailable && p->unavailable(design)) continue;
    p->check_inputs(design);
  }
  report.out_dir = resolve_output_dir(options.out_root, design.name);
  make_directories(report.out_dir);

  // What each product needs first: its prerequisites and the products it reads when they are built
  // (Product::after) that this scene builds. Left-out products are decided up front, in order.
  const std::size_t n = known.size();
  report.products.resize(n);
  std::vector<const Product*> product(n);
  std::vector<std::vector<std::size_t>> deps(n);
  std::vector<char> pending(n, 0);
  std::map<std::string, std::size_t> index;
  for (std::size_t k = 0; k < n; ++k) {
    const std::string& name = known[k];
    ProductOutcome& outcome = report.products[k];
    outcome.name = name;
    outcome.requested = listed && requested.count(name) > 0;
    outcome.prerequisite = needed.count(name) > 0 && !wanted(name);
    product[k] = find(name);
    index[name] = k;
    if (needed.count(name) == 0) {
      outcome.reason = "not listed in the scene's products";
      continue;
    }
    if (auto why = product[k]->unavailable ? product[k]->unavailable(design) : std::nullopt) {
      outcome.reason = *why;
      continue;
    }
    std::vector<std::string> missing_pre;
    for (const auto& pre : product[k]->prerequisites) {
      const auto it = index.find(pre);  // prerequisites come earlier in the list
      if (it == index.end() || !pending[it->second]) {
        missing_pre.push_back(pre);
      } else {
        deps[k].push_back(it->second);
      }
    }
    if (!missing_pre.empty()) {
      outcome.reason = "needs " + join(missing_pre, ", ") + ", which could not be built";
      continue;
    }
    for (const auto& after : product[k]->after) {
      const auto it = index.find(after);
      if (it != index.end() && pending[it->second]) deps[k].push_back(it->second);
    }
    pending[k] = 1;
  }

  // Critical path: each product's time (an earlier run's, from the summary.json in the output
  // folder, else Product::cost_s) plus the longest chain of products waiting on it. Dependencies
  // come earlier in the list, so one pass from the end gives every chain.
  std::map<std::string, double> measured;
  {
    const std::string text = earlier_summary(report.out_dir);
    if (!text.empty()) {
      const json earlier = json::parse(text, nullptr, false);
      if (!earlier.is_discarded() && earlier.is_object() && earlier.contains("built") && earlier["built"].is_array()) {
        for (const json& b : earlier["built"]) {
          if (b.is_object() && b.contains("name") && b["name"].is_string() && b.contains("wall_s") &&
              b["wall_s"].is_number()) {
            measured[b["name"].get<std::string>()] = b["wall_s"].get<double>();
          }
        }
      }
    }
  }
  std::vector<double> chain(n, 0.0);
  for (std::size_t k = n; k-- > 0;) {
    if (!pending[k]) continue;
    const auto it = measured.find(known[k]);
    chain[k] += it != measured.end() ? it->second : product[k]->cost_s;
    for (const std::size_t d : deps[k]) chain[d] = std::max(chain[d], chain[k]);
  }

  // Build: a worker takes, of the products whose dependencies are built, the one heading the
  // longest chain (the first in list order among equals); each sees the results of its
  // dependencies only, so that nothing depends on the timing.
  std::map<std::string, json> results;
  std::mutex lock;
  std::condition_variable changed;
  std::vector<char> started(n, 0), done(n, 0);
  std::exception_ptr failure;
  std::mutex say_lock;
  const std::function<void(std::string_view)> progress =
      options.progress ? std::function<void(std::string_view)>([&](std::string_view line) {
        const std::lock_guard<std::mutex> guard(say_lock);
        options.progress(line);
      })
                       : std::function<void(std::string_view)>();
  const auto worker = [&] {
    std::unique_lock<std::mutex> guard(lock);
    for (;;) {
      std::size_t pick = n;
      bool left = false;
      for (std::size_t k = 0; k < n && !failure; ++k) {
        if (!pending[k] || started[k]) continue;
        left = true;
        if (std::all_of(deps[k].begin(), deps[k].end(), [&](std::size_t d) { return done[d] != 0; }) &&
            (pick == n || chain[k] > chain[pick])) {
          pick = k;
        }
      }
      if (failure || !left) return;
      if (pick == n) {
        changed.wait(guard);
        continue;
      }
      started[pick] = 1;
      std::map<std::string, json> inputs;
      for (const std::size_t d : deps[pick]) inputs[known[d]] = results.at(known[d]);
      guard.unlock();
      ProductOutcome& outcome = report.products[pick];
      try {
        if (progress) progress("building " + known[pick]);
        const auto t0 = std::chrono::steady_clock::now();
        Context ctx{design, report.out_dir, inputs, progress, {}, {}};
        ctx.check_design = [&registry](const Design& d, const std::filesystem::path& root) {
          return check_design_with(d, root, registry);
        };
        Built result = product[pick]->build(ctx);
        outcome.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        outcome.state = ProductOutcome::State::built;
        outcome.passed = result.passed;
        outcome.check = result.check;
        outcome.result = result.result;
        outcome.files = ctx.files;
        outcome.title = product[pick]->title;
        outcome.markdown = std::move(result.markdown);
        guard.lock();
        results[known[pick]] = std::move(result.result);
      } catch (...) {
        guard.lock();
        if (!failure) failure = std::current_exception();
      }
      done[pick] = 1;
      changed.notify_all();
    }
  };
  const unsigned jobs = std::max(1u, options.jobs ? options.jobs : std::thread::hardware_concurrency());
  {
    std::vector<std::thread> pool;
    for (unsigned k = 1; k < jobs; ++k) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
  }
  if (failure) std::rethrow_exception(failure);

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
    // The products' own files, bounded as every read (docs/reliability.md): one past 256 MiB is
    // linked, not inlined.
    try {
      return csv::read_bounded(dir / rel, std::uintmax_t{256} << 20, "product file");
    } catch (const InputError&) {
      return std::nullopt;
    }
  };
  report.index_html = report.out_dir / "index.html";
  write_file_atomic(report.index_html, md::to_html_page(markdown, "fivebar: " + design.name, files));
  return report;
}

}  // namespace fivebar
