// The `sweep:` section (fivebar/sections/sweep.hpp): a link-dimension sweep of one station.
#include "fivebar/sections/sweep.hpp"

#include <algorithm>

#include "fivebar/sections/geometry.hpp"
#include "sections/rules.hpp"
#include "sections/section.hpp"

namespace fivebar {

using rules::format_number;
using rules::joined;

const std::vector<std::string>& sweep_variable_names() {
  static const std::vector<std::string> names{"L1", "L2", "L3", "L4", "L12", "L34",
                                              "spacing", "upper_height", "ellipse_a", "ellipse_b"};
  return names;
}

const std::vector<std::string>& sweep_objective_names() {
  static const std::vector<std::string> names{"margin", "min_lci", "force", "footprint", "collision", "robust"};
  return names;
}

void SweepSettings::validate() const {
  if (station.empty()) throw ValidationError("station", "is required: the station to sweep");
  if (!mechanism.empty() && mechanism != "lower" && mechanism != "upper") {
    throw ValidationError("mechanism", "= " + detail::quoted(mechanism) + ": must be lower or upper");
  }
  if (vary.empty()) throw ValidationError("vary", "must name at least one variable");
  const auto& names = sweep_variable_names();
  long double grid = 1.0L;
  for (std::size_t i = 0; i < vary.size(); ++i) {
    const SweepVariable& v = vary[i];
    const std::string key = detail::key_child("vary", v.name);
    if (std::find(names.begin(), names.end(), v.name) == names.end()) {
      throw ValidationError(key, "unknown variable (known: " + joined(names) + ")");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (vary[j].name == v.name) throw ValidationError(key, "is varied twice");
    }
    if (!(v.lo >= ranges::kMinLengthMm) || !(v.hi >= v.lo) || !(v.hi <= rules::kMaxLengthMm)) {
      throw ValidationError(key, "= [" + format_number(v.lo) + ", " + format_number(v.hi) +
                                     "] mm: needs 1e-09 <= lo <= hi <= 1e12");
    }
    if (v.n < 1 || v.n > 100000000) {
      throw ValidationError(key, "= " + std::to_string(v.n) + " points: must be 1 ... 1e8");
    }
    if (v.lo == v.hi && v.n > 1) throw ValidationError(key, "lo = hi: use n = 1");
    grid *= v.n;
  }
  // Tied and single names must not both move the same link.
  auto has = [&](const char* n) {
    return std::any_of(vary.begin(), vary.end(), [&](const SweepVariable& v) { return v.name == n; });
  };
  if (has("L12") && (has("L1") || has("L2"))) throw ValidationError("vary.L12", "conflicts with L1 / L2");
  if (has("L34") && (has("L3") || has("L4"))) throw ValidationError("vary.L34", "conflicts with L3 / L4");
  if (sample != "grid" && sample != "random" && sample != "sobol") {
    throw ValidationError("sample", "= " + detail::quoted(sample) + ": must be grid, random or sobol");
  }
  if (sample == "grid" && grid > 1e15L) throw ValidationError("vary", "the grid has more than 1e15 designs");
  if (sample != "grid" && count == 0) throw ValidationError("count", "is required for " + sample + " sampling");
  if (count > std::uint64_t(1e15)) throw ValidationError("count", "must be at most 1e15");
  if (!(collision_spacing_mm == 0.0 || (collision_spacing_mm >= 0.05 && collision_spacing_mm <= 1e6))) {
    throw ValidationError("collision_spacing_mm", "= " + format_number(collision_spacing_mm) +
                                                      " mm: must be 0 (off) or 0.05 ... 1e6");
  }
  if (objectives.empty()) throw ValidationError("objectives", "must name at least one objective");
  const auto& known = sweep_objective_names();
  for (std::size_t i = 0; i < objectives.size(); ++i) {
    if (std::find(known.begin(), known.end(), objectives[i]) == known.end()) {
      throw ValidationError(detail::key_index("objectives", i),
                            "= " + detail::quoted(objectives[i]) + ": unknown objective (known: " + joined(known) + ")");
    }
    for (std::size_t j = 0; j < i; ++j) {
      if (objectives[j] == objectives[i]) {
        throw ValidationError(detail::key_index("objectives", i), "= " + detail::quoted(objectives[i]) + ": listed twice");
      }
    }
  }
}

namespace sections {
namespace {

void load(const Value& v, Design& design) {
  SweepSettings sw;
  const auto all = v.entries({"station", "mechanism", "vary", "sample", "count", "seed", "objectives",
                              "collision_spacing_mm"},
                             "(station, mechanism, vary, sample, count, seed, objectives, collision_spacing_mm)");
  sw.station = require(all, "station", v).text("must be a station name");
  if (const Value* m = find(all, "mechanism")) sw.mechanism = m->text("must be lower or upper");
  const Value& vary = require(all, "vary", v);
  for (const Value& var : vary.entries({}, "of variable names to [lo, hi, n]", /*any_key=*/true)) {
    const auto items = var.items(3, "a list [lo, hi, n] (mm, mm, points)");
    SweepVariable sv;
    sv.name = var.name();
    sv.lo = items[0].number("mm");
    sv.hi = items[1].number("mm");
    sv.n = int(items[2].whole(1, 1e8));
    sw.vary.push_back(sv);
  }
  if (const Value* sample = find(all, "sample")) sw.sample = sample->text("must be grid, random or sobol");
  if (const Value* count = find(all, "count")) sw.count = count->whole(1, 1e15);
  if (const Value* seed = find(all, "seed")) sw.seed = seed->whole(0, 9007199254740992.0);
  sw.collision_spacing_mm = number_or(all, "collision_spacing_mm", sw.collision_spacing_mm, "mm");
  if (const Value* obj = find(all, "objectives")) {
    sw.objectives.clear();
    for (const Value& o : obj->list("must be a list of objectives")) {
      sw.objectives.push_back(o.text("must be an objective name"));
    }
  }
  design.set(std::move(sw));
}

void validate(const Design& design) {
  const SweepSettings* sweep = design.get<SweepSettings>();
  if (sweep == nullptr) return;
  rules::validate_nested("sweep", [&] { sweep->validate(); });
  const Station* st = design.station(sweep->station);
  if (st == nullptr) {
    throw ValidationError("sweep.station", "= " + detail::quoted(sweep->station) + ": no such station in the design");
  }
  if (!sweep->mechanism.empty() && st->mechanism(sweep->mechanism) == nullptr) {
    throw ValidationError("sweep.mechanism", "= " + detail::quoted(sweep->mechanism) + ": station " +
                                                 detail::quoted(sweep->station) + " has no such mechanism");
  }
  const auto& obj = sweep->objectives;
  const auto it = std::find(obj.begin(), obj.end(), "collision");
  if (it != obj.end()) {
    const std::string key = detail::key_index("sweep.objectives", std::size_t(it - obj.begin()));
    if (design.get<Geometry>() == nullptr) {
      throw ValidationError(key, "= \"collision\": needs the geometry: section (link outlines)");
    }
    if (!st->lower || !st->upper) {
      throw ValidationError(key, "= \"collision\": station " + detail::quoted(sweep->station) +
                                     " needs both a lower and an upper mechanism");
    }
    if (sweep->collision_spacing_mm == 0.0) {
      throw ValidationError(key, "= \"collision\": sweep.collision_spacing_mm is 0 (collision fraction off)");
    }
  }
}

void write(const Design& design, Out& top) {
  const SweepSettings* sw = design.get<SweepSettings>();
  if (sw == nullptr) return;
  Out& o = top.add("sweep", Out::map());
  o.add("station", Out::plain(sw->station));
  if (!sw->mechanism.empty()) o.add("mechanism", Out::plain(sw->mechanism));
  Out& vary = o.add("vary", Out::map());
  for (const SweepVariable& v : sw->vary) {
    Out& range = vary.add(v.name, Out::list());
    range.push(Out::number(v.lo));
    range.push(Out::number(v.hi));
    range.push(Out::integer(v.n));
  }
  o.add("sample", Out::plain(sw->sample));
  if (sw->count) o.add("count", Out::integer(static_cast<long long>(sw->count)));
  o.add("seed", Out::integer(static_cast<long long>(sw->seed)));
  Out& objectives = o.add("objectives", Out::list());
  for (const auto& name : sw->objectives) objectives.push(Out::plain(name));
  o.add("collision_spacing_mm", Out::number(sw->collision_spacing_mm));
}

}  // namespace

Section sweep_section() { return {SweepSettings::kKey, &load, &validate, &write}; }

}  // namespace sections
}  // namespace fivebar
