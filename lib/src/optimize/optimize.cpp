// The problem of an `optimize:` section (fivebar/optimize.hpp): variables by key path, the staged
// evaluation of a candidate, fronts. The search itself (pagmo2, NLopt) is lib/src/optimize/optimize_search.cpp.
#include "fivebar/optimize.hpp"

#include <algorithm>
#include <atomic>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>

#include "fivebar/control.hpp"
#include "fivebar/design/edit.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/format.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/sections/tolerance.hpp"
#include "fivebar/sections/sweep.hpp"
#include "fivebar/sweep.hpp"
#include "design/design_keys.hpp"

namespace fivebar {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
/// Grid per axis of the loop stage's stability map over a target (the export gate's).
constexpr int kLoopGrid = 21;
/// CVODE tolerance of the simulation stage (the export gate's).
constexpr double kSimulationRtol = 1e-4;

enum Figure : int { margin, min_lci, force, footprint, collision, robust, max_rho, kp_margin, tracking_error, saturation };

}  // namespace

const char* to_string(OptimizeVerdict v) {
  switch (v) {
    case OptimizeVerdict::invalid: return "invalid";
    case OptimizeVerdict::not_covered: return "not covered";
    case OptimizeVerdict::cheap_constraint: return "cheap constraint";
    case OptimizeVerdict::loop_constraint: return "loop constraint";
    case OptimizeVerdict::simulation_constraint: return "simulation constraint";
    case OptimizeVerdict::feasible: return "feasible";
  }
  return "?";
}

double optimize_infeasible_offset(OptimizeVerdict v) {
  switch (v) {
    case OptimizeVerdict::invalid: return 5e12;
    case OptimizeVerdict::not_covered: return 4e12;
    case OptimizeVerdict::cheap_constraint: return 3e12;
    case OptimizeVerdict::loop_constraint: return 2e12;
    case OptimizeVerdict::simulation_constraint: return 1e12;
    case OptimizeVerdict::feasible: return 0.0;
  }
  return 5e12;
}

struct OptimizeProblem::Impl {
  Design base;
  OptimizeSettings s;
  std::vector<std::string> stations;  ///< optimised, file order
  std::vector<std::size_t> station_index;  ///< into base.stations
  std::vector<std::vector<DesignKey>> fast;  ///< per variable, when every key is a station's number
  std::vector<std::vector<std::size_t>> fast_station;  ///< per variable and key: index into the evaluated stations
  bool all_fast = true;
  std::array<bool, 4> stage{};     ///< by OptimizeStage value
  std::vector<bool> figure;        ///< asked for by an objective or a constraint
  std::vector<std::size_t> objective_figure;  ///< optimize_figures() index of each objective
};

OptimizeProblem::OptimizeProblem(const Design& design)
    : OptimizeProblem(design, [&]() -> const OptimizeSettings& {
        if (!design.get<OptimizeSettings>()) throw InputError("design '" + design.name + "' has no optimize: section");
        return *design.get<OptimizeSettings>();
      }()) {}

OptimizeProblem::OptimizeProblem(const Design& design, const OptimizeSettings& settings) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  settings.validate();
  m.s = settings;
  m.base = design;
  m.base.reset<OptimizeSettings>();
  m.base.reset<SweepSettings>();
  m.stations = optimize_station_names(design, settings);
  if (m.stations.empty()) throw InputError("optimize: no station with a mechanism is optimised");
  for (const std::string& n : m.stations) {
    for (std::size_t i = 0; i < m.base.stations.size(); ++i) {
      if (m.base.stations[i].name == n) m.station_index.push_back(i);
    }
  }
  // Every key resolved once, in one reading of the design (fivebar/design/edit.hpp): the canonical
  // spelling, and where a station's number lives (the fast path sets it without the YAML round trip).
  for (OptimizeVariable& v : m.s.variables) {
    const std::vector<DesignKey> resolved = design_keys(m.base, v.keys);  // ValidationError naming a key that leads nowhere
    std::vector<DesignKey> keys;
    std::vector<std::size_t> where;
    for (std::size_t i = 0; i < resolved.size(); ++i) {
      v.keys[i] = resolved[i].path;
      const DesignKey& k = resolved[i];
      const auto at = std::find(m.stations.begin(), m.stations.end(), k.station);
      if (k.field == DesignKey::Field::other || at == m.stations.end()) {
        m.all_fast = false;
        continue;
      }
      const Station& st = m.base.stations[m.station_index[std::size_t(at - m.stations.begin())]];
      if ((k.field == DesignKey::Field::link || k.field == DesignKey::Field::base) && !(k.upper ? st.upper : st.lower)) {
        m.all_fast = false;  // the slow path reports it
      }
      keys.push_back(k);
      where.push_back(std::size_t(at - m.stations.begin()));
    }
    m.fast.push_back(std::move(keys));
    m.fast_station.push_back(std::move(where));
  }
  m.figure.assign(optimize_figures().size(), false);
  auto ask = [&](const std::string& name) {
    const int i = optimize_figure_index(name);
    m.figure[std::size_t(i)] = true;
    m.stage[std::size_t(optimize_figures()[std::size_t(i)].stage)] = true;
  };
  for (const auto& o : m.s.objectives) {
    ask(o.figure);
    m.objective_figure.push_back(std::size_t(optimize_figure_index(o.figure)));
  }
  for (const auto& c : m.s.constraints) ask(c.figure);
  m.stage[std::size_t(OptimizeStage::cheap)] = true;
}

OptimizeProblem::~OptimizeProblem() = default;

const OptimizeSettings& OptimizeProblem::settings() const { return impl_->s; }
const Design& OptimizeProblem::design() const { return impl_->base; }
const std::vector<std::string>& OptimizeProblem::stations() const { return impl_->stations; }
std::size_t OptimizeProblem::dimension() const { return impl_->s.variables.size(); }
bool OptimizeProblem::fast_path() const { return impl_->all_fast; }
bool OptimizeProblem::needs(OptimizeStage stage) const { return impl_->stage[std::size_t(stage)]; }

std::vector<double> OptimizeProblem::lower() const {
  std::vector<double> v;
  for (const auto& x : impl_->s.variables) v.push_back(x.lo);
  return v;
}
std::vector<double> OptimizeProblem::upper() const {
  std::vector<double> v;
  for (const auto& x : impl_->s.variables) v.push_back(x.hi);
  return v;
}

std::vector<double> OptimizeProblem::reference_values() const {
  std::vector<double> v;
  for (const auto& x : impl_->s.variables) v.push_back(design_number(impl_->base, x.keys.front()));
  return v;
}

std::vector<double> OptimizeProblem::snap(const std::vector<double>& x) const {
  const auto& vars = impl_->s.variables;
  std::vector<double> out(vars.size());
  // + 0.0: -0 and 0 are one design (and one cache key).
  for (std::size_t d = 0; d < out.size(); ++d) out[d] = vars[d].snap(d < x.size() ? x[d] : vars[d].lo) + 0.0;
  return out;
}

namespace {
std::atomic<std::uint64_t> g_evaluate_calls{0};
}  // namespace

std::uint64_t optimize_evaluate_calls() { return g_evaluate_calls.load(); }

Design OptimizeProblem::design_at(const std::vector<double>& x) const {
  const Impl& m = *impl_;
  std::vector<std::pair<std::string, double>> values;
  for (std::size_t d = 0; d < m.s.variables.size(); ++d) {
    const double v = m.s.variables[d].snap(x[d]);
    for (const std::string& k : m.s.variables[d].keys) values.emplace_back(k, v);
  }
  Design out = with_design_numbers(m.base, values);
  out.products.reset();
  return out;
}

OptimizeCandidate OptimizeProblem::evaluate(const std::vector<double>& x_in) const {
  const Impl& m = *impl_;
  g_evaluate_calls.fetch_add(1, std::memory_order_relaxed);
  OptimizeCandidate c;
  c.figures.assign(optimize_figures().size(), kNaN);
  c.x = snap(x_in);

  // --- apply the values ---
  std::optional<Design> changed;  // the slow path's design (and the later stages')
  std::vector<Station> stations;
  try {
    if (m.all_fast) {
      for (std::size_t i : m.station_index) stations.push_back(m.base.stations[i]);
      for (std::size_t d = 0; d < c.x.size(); ++d) {
        for (std::size_t i = 0; i < m.fast[d].size(); ++i) set_station_number(stations[m.fast_station[d][i]], m.fast[d][i], c.x[d]);
      }
      const Geometry* g = m.base.get<Geometry>();
      for (const Station& st : stations) {
        try {
          check_station_edit(st, g);  // the rules of an edited station, stated once
        } catch (const ValidationError& e) {
          throw ValidationError(detail::key_join(detail::key_child("stations", st.name), e.key()), e.rule());
        }
      }
    } else {
      changed = design_at(c.x);
      for (const std::string& n : m.stations) stations.push_back(*changed->station(n));
    }
  } catch (const InputError& e) {
    c.verdict = OptimizeVerdict::invalid;
    c.status = std::string("invalid: ") + e.what();
    c.violation = 1.0;
    return c;
  }
  const Design& d = changed ? *changed : m.base;

  // --- cheap: coverage first, then the other figures of the sweep's path ---
  StationFigureRequest request;
  request.collision_spacing_mm = m.figure[collision] ? m.s.collision_spacing_mm : 0.0;
  request.robust = m.figure[robust];
  double fig_margin = std::numeric_limits<double>::infinity(), fig_lci = fig_margin, fig_force = fig_margin;
  double fig_footprint = 0.0, fig_collision = kNaN, fig_robust = std::numeric_limits<double>::infinity();
  for (const Station& st : stations) {
    const SweepRow row = evaluate_station_figures(d, st, request);
    const double mg = row.score("margin");
    if (!std::isnan(mg)) fig_margin = std::min(fig_margin, mg);
    if (!row.covered) {
      c.figures[margin] = std::isinf(fig_margin) ? kNaN : fig_margin;
      c.verdict = OptimizeVerdict::not_covered;
      c.status = st.name + ": " + row.status;
      c.violation = (std::isnan(mg) || mg >= 0.0 ? 0.0 : -mg) + 1e-3;
      return c;
    }
    fig_lci = std::min(fig_lci, row.min_lci);
    fig_force = std::min(fig_force, row.min_force_capability);
    fig_footprint += row.footprint_mm2;
    if (!std::isnan(row.collision_fraction)) fig_collision = std::isnan(fig_collision) ? row.collision_fraction
                                                                                        : std::max(fig_collision, row.collision_fraction);
    if (request.robust) fig_robust = std::min(fig_robust, row.robust_margin_mm);
  }
  c.figures[margin] = fig_margin;
  c.figures[min_lci] = fig_lci;
  c.figures[force] = fig_force;
  c.figures[footprint] = fig_footprint;
  c.figures[collision] = fig_collision;
  c.figures[robust] = request.robust ? fig_robust : kNaN;

  // Constraints and objectives of one stage: a missing figure fails the stage.
  auto check_stage = [&](OptimizeStage stage, OptimizeVerdict verdict) {
    double violation = 0.0;
    std::string why;
    for (const OptimizeConstraint& k : m.s.constraints) {
      const int i = optimize_figure_index(k.figure);
      if (optimize_figures()[std::size_t(i)].stage != stage) continue;
      const double v = c.figures[std::size_t(i)];
      double amount = 0.0;
      if (std::isnan(v)) amount = 1.0;
      else amount = k.at_least ? k.bound - v : v - k.bound;
      if (amount > 0.0 || std::isnan(v)) {
        violation += amount;
        if (why.empty()) why = k.text() + " violated: " + k.figure + " = " + (std::isnan(v) ? "not computed" : format::shortest(v));
      }
    }
    for (const OptimizeObjective& o : m.s.objectives) {
      const int i = optimize_figure_index(o.figure);
      if (optimize_figures()[std::size_t(i)].stage == stage && std::isnan(c.figures[std::size_t(i)])) {
        violation += 1.0;
        if (why.empty()) why = "objective " + o.figure + " not computed";
      }
    }
    if (why.empty()) return true;
    c.verdict = verdict;
    c.status = why;
    c.violation = violation;
    return false;
  };
  if (!check_stage(OptimizeStage::cheap, OptimizeVerdict::cheap_constraint)) return c;

  // --- loop: the stability map of every mechanism over its target ---
  if (m.stage[std::size_t(OptimizeStage::loop)] || m.stage[std::size_t(OptimizeStage::simulation)]) {
    Design full = changed ? *changed : m.base;
    if (!changed) {
      for (std::size_t i = 0; i < stations.size(); ++i) full.stations[m.station_index[i]] = stations[i];
    }
    try {
      if (m.stage[std::size_t(OptimizeStage::loop)]) {
        double rho = 0.0, kp = std::numeric_limits<double>::infinity();
        bool any = false;
        StabilityOptions so;
        so.grid = kLoopGrid;
        so.margins = m.figure[kp_margin];
        for (const Station& st : stations) {
          const auto inertia = station_inertia(full, st, nullptr, {});
          const std::vector<Vec2> points = ellipse_lattice(st.target, so.grid);
          for (const LoopModel& loop : loop_models(full, st, inertia)) {
            const StabilityMap map = stability_map(loop, points, so);
            if (map.poses.size() == map.not_ok) {
              c.verdict = OptimizeVerdict::loop_constraint;
              c.status = st.name + "/" + map.mechanism + ": no pose of the target is reachable and regular";
              c.violation = 1.0;
              return c;
            }
            any = true;
            rho = std::max(rho, map.max_rho);
            kp = std::min(kp, map.kp_margin);
          }
        }
        if (any) {
          c.figures[max_rho] = rho;
          if (m.figure[kp_margin]) c.figures[kp_margin] = kp;
        }
        if (!check_stage(OptimizeStage::loop, OptimizeVerdict::loop_constraint)) return c;
      }
      if (m.stage[std::size_t(OptimizeStage::simulation)]) {
        double err = 0.0, sat = 0.0;
        bool any = false;
        SimulationOptions sim;
        sim.rtol = kSimulationRtol;
        sim.record = false;
        for (const Station& st : stations) {
          if (!(st.lower && st.upper)) continue;
          const auto inertia = station_inertia(full, st, nullptr, {});
          SimulationRequest req;
          req.station = st.name;
          for (const SimulationInput& in : simulation_inputs(full, req, inertia)) {
            if (!in.unusable.empty()) {
              c.verdict = OptimizeVerdict::simulation_constraint;
              c.status = st.name + " " + in.reference_name + ": not simulated: " + in.unusable;
              c.violation = 1.0;
              return c;
            }
            const SimulationResult r = simulate(in, sim);
            if (!r.ok()) {
              c.verdict = OptimizeVerdict::simulation_constraint;
              c.status = st.name + " " + in.reference_name + ": the simulation did not finish: " + r.reason;
              c.violation = 1.0;
              return c;
            }
            for (const MechanismSummary& ms : r.summary) {
              any = true;
              err = std::max(err, ms.max_error_mm);
              sat = std::max(sat, r.t_end > 0.0 ? ms.saturation_s / r.t_end : 0.0);
            }
          }
        }
        if (any) {
          c.figures[tracking_error] = err;
          c.figures[saturation] = sat;
        }
        if (!check_stage(OptimizeStage::simulation, OptimizeVerdict::simulation_constraint)) return c;
      }
    } catch (const InputError& e) {
      c.verdict = m.stage[std::size_t(OptimizeStage::loop)] ? OptimizeVerdict::loop_constraint : OptimizeVerdict::simulation_constraint;
      c.status = e.what();
      c.violation = 1.0;
      return c;
    }
  }
  c.verdict = OptimizeVerdict::feasible;
  c.status = "feasible";
  c.violation = 0.0;
  return c;
}

std::vector<double> OptimizeProblem::fitness(const OptimizeCandidate& c) const {
  const auto& obj = impl_->s.objectives;
  std::vector<double> f(obj.size());
  if (!c.feasible()) {
    const double v = optimize_infeasible_offset(c.verdict) + std::min(std::max(c.violation, 0.0), 1e11);
    std::fill(f.begin(), f.end(), v);
    return f;
  }
  for (std::size_t i = 0; i < obj.size(); ++i) {
    const double v = c.figures[impl_->objective_figure[i]];
    f[i] = obj[i].maximise ? -v : v;
  }
  return f;
}

bool optimize_dominates(const OptimizeProblem& p, const OptimizeCandidate& a, const OptimizeCandidate& b) {
  const auto fa = p.fitness(a), fb = p.fitness(b);
  bool better = false;
  for (std::size_t i = 0; i < fa.size(); ++i) {
    if (fa[i] > fb[i]) return false;
    if (fa[i] < fb[i]) better = true;
  }
  return better;
}

std::vector<OptimizeCandidate> optimize_front(const OptimizeProblem& p, const std::vector<OptimizeCandidate>& candidates) {
  std::vector<OptimizeCandidate> front;
  std::vector<std::vector<double>> ff;
  for (const OptimizeCandidate& c : candidates) {
    if (!c.feasible()) continue;
    const auto f = p.fitness(c);
    bool dominated = false;
    for (std::size_t k = 0; k < front.size() && !dominated; ++k) {
      bool no_worse = true, better = false;
      for (std::size_t i = 0; i < f.size(); ++i) {
        if (ff[k][i] > f[i]) no_worse = false;
        if (ff[k][i] < f[i]) better = true;
      }
      dominated = no_worse && (better || ff[k] == f);  // equal points: the earlier one stays
    }
    if (dominated) continue;
    for (std::size_t k = front.size(); k-- > 0;) {
      bool no_worse = true, better = false;
      for (std::size_t i = 0; i < f.size(); ++i) {
        if (f[i] > ff[k][i]) no_worse = false;
        if (f[i] < ff[k][i]) better = true;
      }
      if (no_worse && better) {
        front.erase(front.begin() + std::ptrdiff_t(k));
        ff.erase(ff.begin() + std::ptrdiff_t(k));
      }
    }
    front.push_back(c);
    ff.push_back(f);
  }
  return front;
}

std::vector<std::vector<double>> normalised_objectives(const OptimizeProblem& p, const std::vector<OptimizeCandidate>& candidates,
                                                       const std::vector<double>& ideal, const std::vector<double>& nadir) {
  std::vector<std::vector<double>> out;
  for (const OptimizeCandidate& c : candidates) {
    if (!c.feasible()) continue;
    auto f = p.fitness(c);
    for (std::size_t i = 0; i < f.size(); ++i) {
      const double range = nadir[i] - ideal[i];
      f[i] = range > 0.0 ? (f[i] - ideal[i]) / range : 0.0;
    }
    out.push_back(std::move(f));
  }
  return out;
}

void OptimizeStageCounts::add(const OptimizeCandidate& c) {
  ++evaluated;
  switch (c.verdict) {
    case OptimizeVerdict::invalid: ++invalid; break;
    case OptimizeVerdict::not_covered: ++not_covered; break;
    case OptimizeVerdict::cheap_constraint: ++cheap; break;
    case OptimizeVerdict::loop_constraint: ++loop; break;
    case OptimizeVerdict::simulation_constraint: ++simulation; break;
    case OptimizeVerdict::feasible: ++feasible; break;
  }
}

Json OptimizeStageCounts::to_json() const {
  return Json{{"evaluated", evaluated}, {"invalid", invalid}, {"not_covered", not_covered}, {"cheap_constraint", cheap},
              {"loop_constraint", loop}, {"simulation_constraint", simulation}, {"feasible", feasible}};
}

OptimizeSettings every_figure_settings(const Design& design, const OptimizeSettings& settings) {
  OptimizeSettings all = settings;
  bool pair = false;
  for (const std::string& n : optimize_station_names(design, settings)) {
    const Station* st = design.station(n);
    pair = pair || (st && st->lower && st->upper);
  }
  const bool loop = pair && design.get<Geometry>() && design.get<MotorSettings>() && design.get<ControllerSettings>();
  for (const OptimizeFigure& f : optimize_figures()) {
    const std::string name(f.name);
    if (name == "collision" && !(pair && design.get<Geometry>())) continue;
    if (name == "robust" && !design.get<ToleranceSettings>()) continue;
    if (f.stage != OptimizeStage::cheap && !loop) continue;
    if (f.stage == OptimizeStage::simulation && !design.get<PatternSettings>()) continue;
    all.constraints.push_back({name, true, -1e300});
  }
  return all;
}

std::vector<std::array<std::string, 3>> optimize_comparison(const OptimizeProblem& p, const OptimizeResult& r) {
  std::vector<std::array<std::string, 3>> rows;
  const OptimizeCandidate* chosen = !r.chosen_full.x.empty() ? &r.chosen_full
                                    : r.polished             ? &*r.polished
                                    : r.chosen               ? &*r.chosen
                                                             : nullptr;
  const OptimizeCandidate& given = !r.reference_full.x.empty() ? r.reference_full : r.reference;
  const auto& vars = p.settings().variables;
  for (std::size_t d = 0; d < vars.size(); ++d) {
    auto value = [](double v) { return std::isnan(v) ? std::string("-") : format::fixed(v, 4); };
    rows.push_back({vars[d].name, value(given.x.size() > d ? given.x[d] : kNaN), chosen ? value(chosen->x[d]) : "-"});
  }
  const auto& figs = optimize_figures();
  for (std::size_t i = 0; i < figs.size(); ++i) {
    const double a = given.figures.size() > i ? given.figures[i] : kNaN;
    const double b = chosen ? chosen->figures[i] : kNaN;
    if (std::isnan(a) && std::isnan(b)) continue;
    auto cell = [](double v) { return std::isnan(v) ? std::string("-") : format::fixed(v, std::fabs(v) >= 100 ? 1 : 4); };
    rows.push_back({std::string(figs[i].name) + (figs[i].unit.empty() ? "" : " (" + std::string(figs[i].unit) + ")"), cell(a), cell(b)});
  }
  rows.push_back({"verdict", r.reference.status, r.polished ? r.polished->status : r.chosen ? r.chosen->status : "-"});
  return rows;
}


}  // namespace fivebar
