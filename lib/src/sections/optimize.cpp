// The `optimize:` section (fivebar/sections/optimize.hpp): a multi-objective dimensional synthesis.
#include "fivebar/sections/optimize.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <set>

#include "fivebar/design/edit.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/sections/tolerance.hpp"
#include "sections/rules.hpp"
#include "sections/section.hpp"

namespace fivebar {

using rules::format_number;
using rules::joined;

const std::vector<OptimizeFigure>& optimize_figures() {
  using S = OptimizeStage;
  static const std::vector<OptimizeFigure> figures{
      {"margin", "mm", true, S::cheap, "certified coverage margin: the smallest over the optimised stations' mechanisms"},
      {"min_lci", "", true, S::cheap, "worst local conditioning index over the targets"},
      {"force", "N per N*mm", true, S::cheap, "worst force capability over the targets"},
      {"footprint", "mm^2", false, S::cheap, "bounding-box area of the linkages over their targets, summed over the stations"},
      {"collision", "", false, S::cheap, "largest fraction of tactor-position pairs whose mechanisms collide"},
      {"robust", "mm", true, S::cheap, "smallest robust margin (kept by tolerance.robust_fraction of printed devices)"},
      {"max_rho", "", false, S::loop, "largest closed-loop spectral radius over the targets (< 1: stable)"},
      {"kp_margin", "", true, S::loop, "smallest factor on kp that keeps every loop stable over its target"},
      {"tracking_error", "mm", false, S::simulation, "largest simulated tactor tracking error over the patterns"},
      {"saturation", "", false, S::simulation, "largest share of a simulated pattern's time a motor is saturated"},
  };
  return figures;
}

int optimize_figure_index(std::string_view name) {
  const auto& f = optimize_figures();
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (f[i].name == name) return int(i);
  }
  return -1;
}

double OptimizeVariable::snap(double x) const {
  double v = std::clamp(x, lo, hi);
  if (step > 0.0) {
    double k = std::round((v - lo) / step);
    if (lo + k * step > hi) k -= 1.0;  // the last step below hi when hi - lo is not a multiple
    v = lo + k * step;
  }
  return v;
}

std::string OptimizeConstraint::text() const {
  return figure + (at_least ? " >= " : " <= ") + format_number(bound);
}

std::string OptimizeSettings::resolved_algorithm() const {
  if (algorithm != "auto") return algorithm;
  return objectives.size() > 1 ? "hybrid" : "cmaes";
}

namespace {

std::vector<std::string> figure_names() {
  std::vector<std::string> names;
  for (const auto& f : optimize_figures()) names.emplace_back(f.name);
  return names;
}

}  // namespace

void OptimizeSettings::validate() const {
  if (variables.empty()) throw ValidationError("variables", "must name at least one variable");
  std::set<std::string> keys_seen;
  for (const OptimizeVariable& v : variables) {
    const std::string key = detail::key_child("variables", v.name);
    if (v.keys.empty()) throw ValidationError(key, "needs `key` (or `keys`, tied): the design number it sets");
    for (std::size_t i = 0; i < v.keys.size(); ++i) {
      const std::string& k = v.keys[i];
      if (k.starts_with("optimize") || k.starts_with("sweep") || k == "name" || k.starts_with("products")) {
        throw ValidationError(v.keys.size() > 1 ? detail::key_index(key + ".keys", i) : key + ".key",
                              "= " + detail::quoted(k) + ": not a number of the device");
      }
      if (!keys_seen.insert(k).second) {
        throw ValidationError(v.keys.size() > 1 ? detail::key_index(key + ".keys", i) : key + ".key",
                              "= " + detail::quoted(k) + ": set by two variables");
      }
    }
    if (!std::isfinite(v.lo) || !std::isfinite(v.hi) || !(v.lo < v.hi)) {
      throw ValidationError(key + ".range", "= [" + format_number(v.lo) + ", " + format_number(v.hi) +
                                                "]: needs finite lo < hi");
    }
    if (!(v.step >= 0.0) || v.step > v.hi - v.lo) {
      throw ValidationError(key + ".step", "= " + format_number(v.step) + ": must be 0 (continuous) ... hi - lo");
    }
  }
  if (objectives.empty()) throw ValidationError("objectives", "must name at least one objective");
  for (std::size_t i = 0; i < objectives.size(); ++i) {
    if (optimize_figure_index(objectives[i].figure) < 0) {
      throw ValidationError(detail::key_index("objectives", i), "= " + detail::quoted(objectives[i].figure) +
                                                                     ": unknown figure (known: " + joined(figure_names()) + ")");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (objectives[j].figure == objectives[i].figure) {
        throw ValidationError(detail::key_index("objectives", i), "= " + detail::quoted(objectives[i].figure) + ": listed twice");
      }
    }
  }
  for (std::size_t i = 0; i < constraints.size(); ++i) {
    if (optimize_figure_index(constraints[i].figure) < 0) {
      throw ValidationError(detail::key_index("constraints", i), "= " + detail::quoted(constraints[i].figure) +
                                                                      ": unknown figure (known: " + joined(figure_names()) + ")");
    }
    if (!std::isfinite(constraints[i].bound)) throw ValidationError(detail::key_index("constraints", i), "bound must be finite");
  }
  const std::string alg = resolved_algorithm();
  const std::vector<std::string> multi{"hybrid", "nsga2", "moead"}, single{"cmaes", "sade"};
  const bool is_multi = std::find(multi.begin(), multi.end(), alg) != multi.end();
  const bool is_single = std::find(single.begin(), single.end(), alg) != single.end();
  if (!is_multi && !is_single) {
    throw ValidationError("algorithm", "= " + detail::quoted(algorithm) + ": must be auto, hybrid, nsga2, moead, cmaes or sade");
  }
  if (is_multi && objectives.size() < 2) {
    throw ValidationError("algorithm", "= " + detail::quoted(alg) + ": needs two or more objectives (cmaes or sade for one)");
  }
  if (is_single && objectives.size() != 1) {
    throw ValidationError("algorithm", "= " + detail::quoted(alg) + ": optimises one objective (hybrid, nsga2 or moead for more)");
  }
  if (population < 8 || population > 10000) {
    throw ValidationError("population", "= " + std::to_string(population) + ": must be 8 ... 10000");
  }
  if (alg == "nsga2" && population % 4 != 0) {
    throw ValidationError("population", "= " + std::to_string(population) + ": NSGA-II needs a multiple of 4");
  }
  if (islands < 1 || islands > 64) throw ValidationError("islands", "= " + std::to_string(islands) + ": must be 1 ... 64");
  if (generations_per_round < 1 || generations_per_round > 1000) {
    throw ValidationError("generations_per_round", "= " + std::to_string(generations_per_round) + ": must be 1 ... 1000");
  }
  if (evaluations < 1 || evaluations > std::uint64_t(1e9)) throw ValidationError("evaluations", "must be 1 ... 1e9");
  if (evaluations < std::uint64_t(population) * std::uint64_t(islands)) {
    throw ValidationError("evaluations", "= " + std::to_string(evaluations) + ": less than the initial populations (population " +
                                             std::to_string(population) + " x islands " + std::to_string(islands) + ")");
  }
  if (!(seconds > 0.0) || seconds > 1e7) throw ValidationError("seconds", "= " + format_number(seconds) + " s: must be > 0 and <= 1e7");
  if (polish_evaluations > 100000) throw ValidationError("polish_evaluations", "must be 0 ... 100000");
  if (choose != "knee") {
    const bool is_objective = std::any_of(objectives.begin(), objectives.end(),
                                          [&](const OptimizeObjective& o) { return o.figure == choose; });
    if (!is_objective) {
      throw ValidationError("choose", "= " + detail::quoted(choose) + ": must be knee or one of the objectives' figures");
    }
  }
  if (atlas_cells < 5 || atlas_cells > 401) {
    throw ValidationError("atlas_cells", "= " + std::to_string(atlas_cells) + ": must be 5 ... 401");
  }
  if (!(collision_spacing_mm >= 0.05 && collision_spacing_mm <= 1e6)) {
    throw ValidationError("collision_spacing_mm", "= " + format_number(collision_spacing_mm) + " mm: must be 0.05 ... 1e6");
  }
}

std::vector<std::string> optimize_station_names(const Design& design, const OptimizeSettings& settings) {
  std::set<std::string> named;
  bool every = false;
  std::vector<std::string> keys;
  for (const OptimizeVariable& v : settings.variables) keys.insert(keys.end(), v.keys.begin(), v.keys.end());
  // Resolved once (any spelling of a station's key names the station; fivebar/design/edit.hpp).
  for (const DesignKey& k : design_keys(design, keys)) {
    if (k.station.empty()) every = true;
    else named.insert(k.station);
  }
  std::vector<std::string> out;
  for (const Station& s : design.stations) {
    if (s.mechanisms().empty()) continue;
    if (every || named.count(s.name)) out.push_back(s.name);
  }
  return out;
}

namespace sections {
namespace {

/// "margin", "max margin" or "min footprint".
OptimizeObjective parse_objective(const Value& v) {
  const std::string text = v.text("must be a figure name, optionally after min or max");
  OptimizeObjective o;
  std::string name = text;
  std::optional<bool> dir;
  if (text.starts_with("max ")) dir = true, name = text.substr(4);
  else if (text.starts_with("min ")) dir = false, name = text.substr(4);
  while (!name.empty() && name.front() == ' ') name.erase(name.begin());
  const int i = optimize_figure_index(name);
  if (i < 0) v.fail_value("unknown figure (known: " + joined(figure_names()) + ")");
  o.figure = name;
  o.maximise = dir.value_or(optimize_figures()[std::size_t(i)].maximise);
  return o;
}

/// "FIGURE >= BOUND" / "FIGURE <= BOUND" (> and < read as the same bound), or "covered".
OptimizeConstraint parse_constraint(const Value& v) {
  const std::string text = v.text("must be a constraint such as \"robust >= 0\"");
  const auto op = text.find_first_of("<>");
  if (op == std::string::npos) {
    v.fail_value("must read FIGURE >= BOUND or FIGURE <= BOUND (e.g. \"robust >= 0\", \"collision <= 0\")");
  }
  auto trim = [](std::string s) {
    while (!s.empty() && s.front() == ' ') s.erase(s.begin());
    while (!s.empty() && s.back() == ' ') s.pop_back();
    return s;
  };
  OptimizeConstraint c;
  c.figure = trim(text.substr(0, op));
  c.at_least = text[op] == '>';
  std::size_t after = op + 1;
  if (after < text.size() && text[after] == '=') ++after;
  const std::string bound = trim(text.substr(after));
  const auto r = std::from_chars(bound.data(), bound.data() + bound.size(), c.bound);
  if (bound.empty() || r.ec != std::errc{} || r.ptr != bound.data() + bound.size() || !std::isfinite(c.bound)) {
    v.fail_value("the bound '" + bound + "' is not a finite number");
  }
  if (optimize_figure_index(c.figure) < 0) v.fail_value("unknown figure '" + c.figure + "' (known: " + joined(figure_names()) + ")");
  return c;
}

void load(const Value& v, Design& design) {
  OptimizeSettings o;
  const auto all = v.entries({"variables", "objectives", "constraints", "algorithm", "population", "islands",
                              "generations_per_round", "evaluations", "seconds", "seed", "polish", "polish_evaluations",
                              "choose", "atlas", "atlas_cells", "collision_spacing_mm"},
                             "(variables, objectives, constraints, algorithm, population, islands, "
                             "generations_per_round, evaluations, seconds, seed, polish, polish_evaluations, choose, atlas, "
                             "atlas_cells, collision_spacing_mm)");
  for (const Value& var : require(all, "variables", v).entries({}, "of variable names to {key, range, step}", true)) {
    OptimizeVariable ov;
    ov.name = var.name();
    const auto e = var.entries({"key", "keys", "range", "step"}, "(key or keys, range, step)");
    const Value* key = find(e, "key");
    const Value* keys = find(e, "keys");
    if (key && keys) keys->fail("give key or keys (tied), not both");
    if (key) ov.keys.push_back(key->text("must be a key path of the design"));
    if (keys) {
      for (const Value& k : keys->list("must be a list of key paths (tied: all take the variable's value)")) {
        ov.keys.push_back(k.text("must be a key path of the design"));
      }
    }
    if (!key && !keys) var.fail_missing("key");
    const auto range = require(e, "range", var).items(2, "a list [lo, hi] in the key's file unit");
    ov.lo = range[0].number("");
    ov.hi = range[1].number("");
    ov.step = number_or(e, "step", 0.0, "");
    o.variables.push_back(std::move(ov));
  }
  for (const Value& obj : require(all, "objectives", v).list("must be a list of figures")) {
    o.objectives.push_back(parse_objective(obj));
  }
  if (const Value* cons = find(all, "constraints")) {
    for (const Value& c : cons->list("must be a list of constraints such as \"robust >= 0\"")) {
      o.constraints.push_back(parse_constraint(c));
    }
  }
  if (const Value* a = find(all, "algorithm")) o.algorithm = a->text("must be auto, hybrid, nsga2, moead, cmaes or sade");
  if (const Value* p = find(all, "population")) o.population = int(p->whole(8, 10000));
  if (const Value* p = find(all, "islands")) o.islands = int(p->whole(1, 64));
  if (const Value* p = find(all, "generations_per_round")) o.generations_per_round = int(p->whole(1, 1000));
  if (const Value* p = find(all, "evaluations")) o.evaluations = p->whole(1, 1e9);
  o.seconds = number_or(all, "seconds", o.seconds, "s");
  if (const Value* p = find(all, "seed")) o.seed = p->whole(0, 9007199254740992.0);
  if (const Value* p = find(all, "polish")) {
    const std::string t = p->text("must be true or false");
    if (t != "true" && t != "false") p->fail_value("must be true or false");
    o.polish = t == "true";
  }
  if (const Value* p = find(all, "polish_evaluations")) o.polish_evaluations = p->whole(0, 100000);
  if (const Value* p = find(all, "choose")) o.choose = p->text("must be knee or an objective's figure");
  if (const Value* p = find(all, "atlas")) {
    const std::string t = p->text("must be true or false");
    if (t != "true" && t != "false") p->fail_value("must be true or false");
    o.atlas = t == "true";
  }
  if (const Value* p = find(all, "atlas_cells")) o.atlas_cells = int(p->whole(5, 401));
  o.collision_spacing_mm = number_or(all, "collision_spacing_mm", o.collision_spacing_mm, "mm");
  design.set(std::move(o));
}

void validate(const Design& design) {
  const OptimizeSettings* o = design.get<OptimizeSettings>();
  if (o == nullptr) return;
  rules::validate_nested("optimize", [&] { o->validate(); });
  // Every key leads to a number of this design, resolved once in one reading of the design (time
  // linear in the keys), and each number is set by one variable only whatever the spelling
  // (links[2], links[02], stations["index"]...: one canonical key, fivebar/design/edit.hpp).
  std::vector<std::string> keys, labels;
  for (const OptimizeVariable& v : o->variables) {
    const std::string var = detail::key_child("optimize.variables", v.name);
    for (std::size_t i = 0; i < v.keys.size(); ++i) {
      keys.push_back(v.keys[i]);
      labels.push_back(v.keys.size() > 1 ? detail::key_index(var + ".keys", i) : var + ".key");
    }
  }
  std::vector<DesignKey> resolved;
  try {
    resolved = design_keys(design, keys);
  } catch (const ValidationError& e) {
    const auto at = std::find(keys.begin(), keys.end(), e.key());
    const std::string label = at == keys.end() ? std::string("optimize.variables") : labels[std::size_t(at - keys.begin())];
    throw ValidationError(label, "= " + detail::quoted(e.key()) + ": " + e.rule());
  }
  std::map<std::string, std::size_t> first;  // canonical key -> its first label
  for (std::size_t i = 0; i < resolved.size(); ++i) {
    const auto [it, fresh] = first.emplace(resolved[i].path, i);
    if (!fresh) {
      throw ValidationError(labels[i], "= " + detail::quoted(keys[i]) + ": the number " + detail::quoted(resolved[i].path) +
                                           ", already set by " + labels[it->second] + " = " + detail::quoted(keys[it->second]) +
                                           " (each number in one variable only)");
    }
  }
  const std::vector<std::string> stations = optimize_station_names(design, *o);
  if (stations.empty()) throw ValidationError("optimize.variables", "no station with a mechanism is optimised");
  bool pair = false, patterns_station = false;
  for (const std::string& s : stations) {
    const Station* st = design.station(s);
    pair = pair || (st->lower && st->upper);
  }
  patterns_station = pair && design.get<PatternSettings>() != nullptr;
  auto check_data = [&](const std::string& figure, const std::string& key) {
    const OptimizeFigure& f = optimize_figures()[std::size_t(optimize_figure_index(figure))];
    auto missing = [&](const std::string& what) {
      throw ValidationError(key, "= " + detail::quoted(figure) + ": the design lacks the data for it: " + what);
    };
    if (figure == "collision") {
      if (!design.get<Geometry>()) missing("no geometry: section (link outlines)");
      if (!pair) missing("no optimised station has both a lower and an upper mechanism");
    }
    if (figure == "robust" && !design.get<ToleranceSettings>()) missing("no tolerance: section (the printed device's errors)");
    if (f.stage != OptimizeStage::cheap) {
      if (!design.get<Geometry>()) missing("no geometry: section (the links' masses)");
      if (!design.get<MotorSettings>()) missing("no motor: section");
      if (!design.get<ControllerSettings>()) missing("no controller: section");
      if (!pair) missing("no optimised station has both a lower and an upper mechanism");
    }
    if (f.stage == OptimizeStage::simulation && !patterns_station) missing("no patterns: section to simulate");
  };
  for (std::size_t i = 0; i < o->objectives.size(); ++i) {
    check_data(o->objectives[i].figure, detail::key_index("optimize.objectives", i));
  }
  for (std::size_t i = 0; i < o->constraints.size(); ++i) {
    check_data(o->constraints[i].figure, detail::key_index("optimize.constraints", i));
  }
}

void write(const Design& design, Out& top) {
  const OptimizeSettings* o = design.get<OptimizeSettings>();
  if (o == nullptr) return;
  Out& out = top.add("optimize", Out::map());
  Out& vars = out.add("variables", Out::map());
  for (const OptimizeVariable& v : o->variables) {
    Out& var = vars.add(v.name, Out::map(true));
    if (v.keys.size() == 1) {
      var.add("key", Out::plain(v.keys[0]));
    } else {
      Out& keys = var.add("keys", Out::list());
      for (const auto& k : v.keys) keys.push(Out::plain(k));
    }
    Out& range = var.add("range", Out::list());
    range.push(Out::number(v.lo));
    range.push(Out::number(v.hi));
    if (v.step > 0.0) var.add("step", Out::number(v.step));
  }
  Out& objectives = out.add("objectives", Out::list());
  for (const OptimizeObjective& ob : o->objectives) {
    const bool natural = optimize_figures()[std::size_t(optimize_figure_index(ob.figure))].maximise == ob.maximise;
    objectives.push(natural ? Out::plain(ob.figure) : Out::quoted((ob.maximise ? "max " : "min ") + ob.figure));
  }
  if (!o->constraints.empty()) {
    Out& cons = out.add("constraints", Out::list());
    for (const OptimizeConstraint& c : o->constraints) cons.push(Out::quoted(c.text()));
  }
  out.add("algorithm", Out::plain(o->algorithm));
  out.add("population", Out::integer(o->population));
  out.add("islands", Out::integer(o->islands));
  out.add("generations_per_round", Out::integer(o->generations_per_round));
  out.add("evaluations", Out::integer(static_cast<long long>(o->evaluations)));
  out.add("seconds", Out::number(o->seconds));
  out.add("seed", Out::integer(static_cast<long long>(o->seed)));
  out.add("polish", Out::plain(o->polish ? "true" : "false"));
  out.add("polish_evaluations", Out::integer(static_cast<long long>(o->polish_evaluations)));
  out.add("choose", Out::plain(o->choose));
  out.add("atlas", Out::plain(o->atlas ? "true" : "false"));
  out.add("atlas_cells", Out::integer(o->atlas_cells));
  out.add("collision_spacing_mm", Out::number(o->collision_spacing_mm));
}

}  // namespace

Section optimize_section() { return {OptimizeSettings::kKey, &load, &validate, &write}; }

}  // namespace sections
}  // namespace fivebar
