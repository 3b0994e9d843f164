// The studies from Python (docs/python.md): workspace and coverage with NumPy fields and polylines,
// sweeps and optimisation as columns (dict of arrays, ready for pandas.DataFrame), simulations as
// time series, tolerance, control and the export gate. Long calls run through Interruptible:
// progress callbacks, Ctrl-C raising KeyboardInterrupt, the GIL released.
// Every function returns plain dicts (and the Pose / Mechanism / CoverageResult objects); the
// package (fivebar/__init__.py) wraps them into result objects.

#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <chrono>
#include <cmath>
#include <limits>

#include "bindings.hpp"
#include "fivebar/control.hpp"
#include "fivebar/coverage/coverage.hpp"
#include "fivebar/coverage/report.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/optimize.hpp"
#include "fivebar/workspace/polyline.hpp"
#include "fivebar/workspace/station.hpp"
#include "fivebar/sweep.hpp"
#include "fivebar/tolerance.hpp"

namespace fivebar::python {

namespace {

using Columns = py::dict;

py::dict grid_dict(const Grid& g) {
  py::dict d;
  d["x0"] = g.x0;
  d["y0"] = g.y0;
  d["spacing_mm"] = g.spacing;
  d["nx"] = g.nx;
  d["ny"] = g.ny;
  py::array_t<double> x(g.nx), y(g.ny);
  for (int i = 0; i < g.nx; ++i) x.mutable_at(i) = g.x0 + i * g.spacing;
  for (int j = 0; j < g.ny; ++j) y.mutable_at(j) = g.y0 + j * g.spacing;
  d["x"] = x;
  d["y"] = y;
  return d;
}

/// A region's boundary as closed polylines (n x 2, mm; first point not repeated) and hole flags.
void add_region(py::dict& d, const Region& r) {
  d["area_mm2"] = r.area_mm2();
  d["perimeter_mm"] = r.perimeter_mm();
  d["components"] = r.components();
  d["holes"] = r.holes();
  const auto b = r.bounds();
  d["bounds"] = py::make_tuple(b[0], b[1], b[2], b[3]);
  py::list loops, hole;
  for (const BoundaryLoop& loop : r.loops()) {
    loops.append(points_array(discretise(loop)));
    hole.append(loop.hole);
  }
  d["boundary"] = loops;
  d["boundary_is_hole"] = hole;
}

py::list contour_list(const SampledArea& a, double spacing) {
  py::list out;
  for (const Polyline& p : chain_segments(a.contours, spacing * 1e-6)) out.append(points_array(p.points));
  return out;
}

py::dict workspace(const Station& station, double spacing_mm, const std::string& mechanism, const py::object& progress) {
  WorkspaceOptions options;
  options.spacing_mm = spacing_mm;
  options.mechanism = mechanism;
  options.validate();
  Interruptible run;
  auto ws = std::make_shared<StationWorkspace>();
  run.run([&] {
    *ws = analyse_workspace(station, options, [&](std::string_view line) { run.call(progress, std::string(line)); });
  });
  py::dict d;
  d["station"] = ws->station;
  d["target"] = ws->target;
  d["grid"] = grid_dict(ws->grid);
  const std::vector<py::ssize_t> shape{ws->grid.ny, ws->grid.nx};
  py::dict mechs;
  for (const MechanismWorkspace& mw : ws->mechanisms) {
    py::dict md;
    md["mechanism"] = mw.mechanism;
    add_region(md, mw.region);
    const WorkspaceField& f = mw.field;
    py::dict fields;
    fields["reach"] = view(ws, f.reach.data(), shape);
    fields["status"] = view(ws, f.status.data(), shape);
    fields["assembly_ok"] = view(ws, f.assembly_ok.data(), shape);
    fields["lci"] = view(ws, f.lci.data(), shape);
    fields["type1_distance_mm"] = view(ws, f.type1_distance_mm.data(), shape);
    fields["type1_sin"] = view(ws, f.type1_sin.data(), shape);
    fields["type2_sin"] = view(ws, f.type2_sin.data(), shape);
    fields["transmission_deg"] = view(ws, f.transmission_deg.data(), shape);
    fields["force_capability"] = view(ws, f.force_capability.data(), shape);
    md["fields"] = fields;
    md["assembly_area_mm2"] = mw.assembly.area_mm2;
    md["assembly_error_mm2"] = mw.assembly.error_mm2;
    md["assembly_contours"] = contour_list(mw.assembly, ws->grid.spacing);
    md["lci_area_mm2"] = mw.lci.area_mm2;
    md["lci_error_mm2"] = mw.lci.error_mm2;
    md["lci_contours"] = contour_list(mw.lci, ws->grid.spacing);
    md["centre"] = mw.centre;
    mechs[py::str(mw.mechanism.name)] = md;
  }
  d["mechanisms"] = mechs;
  if (ws->shared) {
    py::dict sd;
    add_region(sd, *ws->shared);
    d["shared"] = sd;
  } else {
    d["shared"] = py::none();
  }
  d["summary"] = to_python(to_json(*ws));
  return d;
}

// --- Sweep -----------------------------------------------------------------------------------------

py::dict sweep(const Design& design, int threads, std::uint64_t chunk, const py::object& progress) {
  const SweepSettings* s = design.get<SweepSettings>();
  if (!s) throw InputError(design.name + ": the design has no sweep: section");
  const int nthreads = sweep_threads(threads);
  if (chunk == 0) throw InputError("chunk = 0: must be >= 1");
  const std::uint64_t total = sweep_size(*s);
  // The rows of the library's per-design evaluation (the CLI's sweep evaluates the same function),
  // in index order; the columns are filled after, with the GIL held.
  std::vector<SweepRow> rows(total);
  Interruptible run;
  std::uint64_t done = 0;
  run.run([&] {
    const auto t0 = std::chrono::steady_clock::now();
    while (done < total && !run.stopped()) {
      const std::int64_t first = std::int64_t(done);
      const std::int64_t n = std::int64_t(std::min<std::uint64_t>(chunk, total - done));
#pragma omp parallel for schedule(dynamic, 64) num_threads(nthreads)
      for (std::int64_t k = first; k < first + n; ++k) {
        try {
          rows[std::size_t(k)] = evaluate_sweep_design(design, *s, std::uint64_t(k));
        } catch (const std::exception& e) {  // as the CLI's sweep: a row saying so, and the sweep goes on
          SweepRow& r = rows[std::size_t(k)];
          r = SweepRow{};
          r.index = std::uint64_t(k);
          r.values = sweep_point(*s, std::uint64_t(k));
          r.status = std::string("error: ") + e.what();
        }
      }
      done += std::uint64_t(n);
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      run.call(progress, done, total, seconds);
    }
  });
  ParetoArchive archive(s->objectives);
  for (const SweepRow& r : rows) archive.insert(r);
  std::vector<std::uint8_t> on_front(total, 0);
  for (const SweepRow& r : archive.rows()) on_front[r.index] = 1;

  const auto n = py::ssize_t(total);
  Columns c;
  py::array_t<std::uint64_t> index(n);
  for (py::ssize_t k = 0; k < n; ++k) index.mutable_at(k) = rows[std::size_t(k)].index;
  c["index"] = index;
  for (std::size_t v = 0; v < s->vary.size(); ++v) {
    py::array_t<double> col(n);
    for (py::ssize_t k = 0; k < n; ++k) col.mutable_at(k) = rows[std::size_t(k)].values[v];
    c[py::str(s->vary[v].name + "_mm")] = col;
  }
  py::list status;
  py::array_t<bool> covered(n), pareto(n);
  for (py::ssize_t k = 0; k < n; ++k) {
    status.append(py::str(rows[std::size_t(k)].status));
    covered.mutable_at(k) = rows[std::size_t(k)].covered;
    pareto.mutable_at(k) = on_front[std::size_t(k)] != 0;
  }
  c["status"] = py::module_::import("numpy").attr("array")(status, py::arg("dtype") = "object");
  c["covered"] = covered;
  const std::pair<const char*, double SweepRow::*> metrics[] = {
      {"margin_lower_mm", &SweepRow::margin_lower_mm}, {"margin_upper_mm", &SweepRow::margin_upper_mm},
      {"margin_shared_mm", &SweepRow::margin_shared_mm}, {"min_lci", &SweepRow::min_lci},
      {"min_force_capability", &SweepRow::min_force_capability}, {"footprint_w_mm", &SweepRow::footprint_w_mm},
      {"footprint_h_mm", &SweepRow::footprint_h_mm}, {"footprint_mm2", &SweepRow::footprint_mm2},
      {"collision_fraction", &SweepRow::collision_fraction}, {"robust_margin_mm", &SweepRow::robust_margin_mm}};
  for (const auto& [name, field] : metrics) {
    py::array_t<double> col(n);
    for (py::ssize_t k = 0; k < n; ++k) col.mutable_at(k) = rows[std::size_t(k)].*field;
    c[name] = col;
  }
  c["pareto"] = pareto;
  return c;
}

// --- Optimisation ---------------------------------------------------------------------------------

py::dict candidate_dict(const OptimizeProblem& p, const OptimizeCandidate& c) {
  py::dict d;
  py::dict x;
  const auto& vars = p.settings().variables;
  for (std::size_t k = 0; k < vars.size() && k < c.x.size(); ++k) x[py::str(vars[k].name)] = c.x[k];
  d["x"] = x;
  py::dict figures;
  const auto& figs = optimize_figures();
  for (std::size_t k = 0; k < figs.size() && k < c.figures.size(); ++k) {
    if (!std::isnan(c.figures[k])) figures[py::str(std::string(figs[k].name))] = c.figures[k];
  }
  d["figures"] = figures;
  d["verdict"] = to_string(c.verdict);
  d["status"] = c.status;
  d["violation"] = c.violation;
  d["feasible"] = c.feasible();
  return d;
}

/// Candidates as columns: one per variable (file units), one per figure (NaN where not computed:
/// the verdict says why), verdict, status, violation, feasible.
Columns candidate_columns(const OptimizeProblem& p, const std::vector<OptimizeCandidate>& cs) {
  const auto n = py::ssize_t(cs.size());
  Columns c;
  const auto& vars = p.settings().variables;
  for (std::size_t v = 0; v < vars.size(); ++v) {
    py::array_t<double> col(n);
    for (py::ssize_t k = 0; k < n; ++k) col.mutable_at(k) = cs[std::size_t(k)].x[v];
    c[py::str(vars[v].name)] = col;
  }
  const auto& figs = optimize_figures();
  for (std::size_t f = 0; f < figs.size(); ++f) {
    py::array_t<double> col(n);
    for (py::ssize_t k = 0; k < n; ++k) {
      const auto& fig = cs[std::size_t(k)].figures;
      col.mutable_at(k) = f < fig.size() ? fig[f] : std::numeric_limits<double>::quiet_NaN();
    }
    c[py::str(std::string(figs[f].name))] = col;
  }
  py::list verdict, status;
  py::array_t<double> violation(n);
  py::array_t<bool> feasible(n);
  for (py::ssize_t k = 0; k < n; ++k) {
    const OptimizeCandidate& x = cs[std::size_t(k)];
    verdict.append(to_string(x.verdict));
    status.append(x.status);
    violation.mutable_at(k) = x.violation;
    feasible.mutable_at(k) = x.feasible();
  }
  auto np = py::module_::import("numpy");
  c["verdict"] = np.attr("array")(verdict, py::arg("dtype") = "object");
  c["status"] = np.attr("array")(status, py::arg("dtype") = "object");
  c["violation"] = violation;
  c["feasible"] = feasible;
  return c;
}

std::vector<double> vector_of(const py::object& x, std::size_t dim, const char* name) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(x);
  if (!a) {
    PyErr_Clear();
    throw py::type_error(std::string(name) + ": expected a sequence of numbers");
  }
  if (a.ndim() != 1 || std::size_t(a.size()) != dim) {
    throw py::value_error(std::string(name) + ": expected " + std::to_string(dim) + " values (one per variable), got shape " +
                          py::str(py::tuple(py::cast(std::vector<py::ssize_t>(a.shape(), a.shape() + a.ndim())))).cast<std::string>());
  }
  std::vector<double> v(a.data(), a.data() + a.size());
  for (std::size_t k = 0; k < v.size(); ++k) {
    if (!std::isfinite(v[k])) throw py::value_error(std::string(name) + "[" + std::to_string(k) + "] is not finite");
  }
  return v;
}

Columns evaluate_many(const OptimizeProblem& p, const py::object& X_obj, int threads, const py::object& progress) {
  auto X = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(X_obj);
  if (!X) {
    PyErr_Clear();
    throw py::type_error("X: expected a 2-D array of candidates (rows) by variables (columns)");
  }
  const std::size_t d = p.dimension();
  if (X.ndim() != 2 || std::size_t(X.shape(1)) != d) {
    throw py::value_error("X: expected shape (n, " + std::to_string(d) + "), got " +
                          py::str(py::tuple(py::cast(std::vector<py::ssize_t>(X.shape(), X.shape() + X.ndim())))).cast<std::string>());
  }
  const std::size_t n = std::size_t(X.shape(0));
  const double* data = X.data();
  for (std::size_t k = 0; k < n * d; ++k) {
    if (!std::isfinite(data[k])) {
      throw py::value_error("X[" + std::to_string(k / d) + ", " + std::to_string(k % d) + "] is not finite");
    }
  }
  const int nthreads = sweep_threads(threads);
  std::vector<OptimizeCandidate> out(n);
  Interruptible run;
  run.run([&] {
    const std::size_t chunk = 256;
    for (std::size_t first = 0; first < n && !run.stopped(); first += chunk) {
      const std::int64_t end = std::int64_t(std::min(n, first + chunk));
#pragma omp parallel for schedule(dynamic, 1) num_threads(nthreads)
      for (std::int64_t k = std::int64_t(first); k < end; ++k) {
        out[std::size_t(k)] = p.evaluate(std::vector<double>(data + std::size_t(k) * d, data + std::size_t(k + 1) * d));
      }
      run.call(progress, std::min(n, first + chunk), n);
    }
  });
  return candidate_columns(p, out);
}

py::dict optimize(const Design& design, const std::filesystem::path& out_dir, std::uint64_t evaluations, double seconds,
                  int threads, bool plots, bool full_figures, bool resume, const py::object& progress) {
  OptimizeProblem problem(design);
  OptimizeOptions o;
  o.out_dir = out_dir;
  o.evaluations = evaluations;
  o.seconds = seconds;
  o.threads = threads;
  o.plots = plots;
  o.full_figures = full_figures;
  o.resume = resume;
  Interruptible run;
  o.stop = run.stop();
  o.progress = [&](std::uint64_t done, std::uint64_t budget, double s, std::size_t front) {
    run.call(progress, done, budget, s, front);
  };
  OptimizeResult r;
  run.run([&] { r = run_optimize(design, o); });
  py::dict d;
  d["algorithm"] = r.algorithm;
  d["evaluations"] = r.evaluations;
  d["rounds"] = r.rounds;
  d["seconds"] = r.seconds;
  d["budget_time"] = r.budget_time;
  d["front"] = candidate_columns(problem, r.front);
  d["chosen"] = r.chosen ? py::object(candidate_dict(problem, *r.chosen)) : py::object(py::none());
  d["polished"] = r.polished ? py::object(candidate_dict(problem, *r.polished)) : py::object(py::none());
  d["reference"] = candidate_dict(problem, r.reference);
  d["chosen_design"] = r.chosen_design ? py::cast(std::make_shared<Design>(*r.chosen_design)) : py::object(py::none());
  py::list hv;
  for (const auto& [e, v] : r.hypervolume) hv.append(py::make_tuple(e, v));
  d["hypervolume"] = hv;
  std::vector<std::string> files;
  for (const auto& f : r.files) files.push_back(f.generic_string());
  d["files"] = files;
  d["summary"] = to_python(r.to_json(problem));
  return d;
}

// --- Simulation -----------------------------------------------------------------------------------

std::map<std::string, MechanismInertia> closed_form_station_inertia(const Design& design, const Station& s) {
  // Closed-form masses (the CLI's --no-render): no OpenSCAD render from Python.
  return station_inertia(design, s, nullptr, {});
}

py::dict simulation_dict(const SimulationInput& in, const SimulationResult& r) {
  py::dict d;
  d["station"] = in.station;
  d["reference"] = in.reference_name;
  d["status"] = std::string(to_string(r.status));
  d["reason"] = r.reason;
  d["t_end"] = r.t_end;
  d["steps"] = r.steps;
  const auto n = py::ssize_t(r.samples.size());
  py::array_t<double> t(n);
  for (py::ssize_t k = 0; k < n; ++k) t.mutable_at(k) = r.samples[std::size_t(k)].t;
  d["t"] = t;
  py::dict mechs;
  for (std::size_t m = 0; m < in.mechanisms.size(); ++m) {
    auto pairs = [&](auto get) {
      py::array_t<double> a({n, py::ssize_t(2)});
      auto w = a.mutable_unchecked<2>();
      for (py::ssize_t k = 0; k < n; ++k) {
        const auto& ms = r.samples[std::size_t(k)].mechanisms;
        const auto v = m < ms.size() ? get(ms[m]) : std::array<double, 2>{0.0, 0.0};
        w(k, 0) = v[0];
        w(k, 1) = v[1];
      }
      return a;
    };
    auto vec = [](const Vec2& p) { return std::array<double, 2>{p.x(), p.y()}; };
    py::dict md;
    md["theta_ref"] = pairs([](const MechanismSample& s) { return s.theta_ref; });
    md["theta"] = pairs([](const MechanismSample& s) { return s.theta; });
    md["w"] = pairs([](const MechanismSample& s) { return s.w; });
    md["current_A"] = pairs([](const MechanismSample& s) { return s.current; });
    md["duty"] = pairs([](const MechanismSample& s) { return s.duty; });
    md["voltage_V"] = pairs([](const MechanismSample& s) { return s.voltage; });
    md["P_ref_mm"] = pairs([&](const MechanismSample& s) { return vec(s.P_ref_mm); });
    md["P_mm"] = pairs([&](const MechanismSample& s) { return vec(s.P_mm); });
    md["force_N"] = pairs([&](const MechanismSample& s) { return vec(s.force_N); });
    py::array_t<bool> slipping(n);
    py::array_t<double> energy(n);
    for (py::ssize_t k = 0; k < n; ++k) {
      const auto& ms = r.samples[std::size_t(k)].mechanisms;
      slipping.mutable_at(k) = m < ms.size() && ms[m].slipping;
      energy.mutable_at(k) = m < ms.size() ? ms[m].energy_J : 0.0;
    }
    md["slipping"] = slipping;
    md["energy_J"] = energy;
    mechs[py::str(in.mechanisms[m].name)] = md;
  }
  d["mechanisms"] = mechs;
  d["summary"] = to_python(to_json(in, r));
  return d;
}

py::list simulate_design(const Design& design, const std::string& station, const std::optional<std::string>& pattern,
                         bool step, double rtol, double max_wall_s, const py::object& progress) {
  SimulationRequest request;
  std::vector<const Station*> stations;
  if (!station.empty()) {
    stations.push_back(&design.require_station(station));
  } else {
    for (const Station& s : design.stations) {
      if (s.lower && s.upper) stations.push_back(&s);
    }
    if (stations.empty()) throw InputError("design '" + design.name + "' has no station with both mechanisms");
  }
  if (pattern) {
    request.pattern = parse_pattern_kind(*pattern);
    if (!request.pattern) throw InputError("pattern = '" + *pattern + "': expected stretch, slip, twist or pivot");
  }
  request.step = step;
  if (!(rtol >= 1e-14 && rtol <= 1e-2)) throw InputError("rtol must be within [1e-14, 1e-2]");
  if (!(max_wall_s > 0.0 && max_wall_s <= 1e6)) throw InputError("max_wall_s must be > 0 and <= 1e6 s");
  SimulationOptions options;
  options.rtol = rtol;
  options.max_wall_s = max_wall_s;
  std::vector<std::pair<SimulationInput, SimulationResult>> runs;
  Interruptible run;
  run.run([&] {
    for (const Station* s : stations) {
      request.station = s->name;
      const auto inertia = closed_form_station_inertia(design, *s);
      for (const SimulationInput& in : simulation_inputs(design, request, inertia)) {
        if (run.stopped()) return;
        run.call(progress, s->name + " " + in.reference_name);
        runs.emplace_back(in, simulate(in, options));
      }
    }
  });
  py::list out;
  for (const auto& [in, r] : runs) out.append(simulation_dict(in, r));
  return out;
}

// --- Tolerance, control, export gate -------------------------------------------------------------

std::vector<const Station*> stations_of(const Design& design, const std::string& station) {
  if (!station.empty()) return {&design.require_station(station)};
  return design.select_stations("");
}

py::list tolerance(const Design& design, const std::string& station, double spacing_mm, const py::object& progress) {
  if (!(spacing_mm > 0.0) || !std::isfinite(spacing_mm)) throw InputError("spacing_mm must be > 0 mm");
  std::vector<std::shared_ptr<ToleranceMap>> maps;
  Interruptible run;
  run.run([&] {
    for (const Station* s : stations_of(design, station)) {
      for (const Mechanism* m : s->mechanisms()) {
        if (run.stopped()) return;
        run.call(progress, s->name + " " + m->name);
        const ToleranceSources src = tolerance_sources(design, *s, *m);
        maps.push_back(std::make_shared<ToleranceMap>(tolerance_map(*m, s->name, s->target, src, spacing_mm)));
      }
    }
  });
  py::list out;
  for (const auto& map : maps) {
    py::dict d;
    d["station"] = map->station;
    d["mechanism"] = map->mechanism;
    Grid g;
    g.x0 = map->x0;
    g.y0 = map->y0;
    g.spacing = map->spacing_mm;
    g.nx = map->nx;
    g.ny = map->ny;
    d["grid"] = grid_dict(g);
    const std::vector<py::ssize_t> shape{map->ny, map->nx};
    py::dict fields;
    fields["status"] = view(map, map->field_status.data(), shape);
    fields["three_sigma_mm"] = view(map, map->field_3sigma_mm.data(), shape);
    fields["worst_case_first_order_mm"] = view(map, map->field_worst_case_mm.data(), shape);
    fields["resolution_um"] = view(map, map->field_resolution_um.data(), shape);
    fields["play_mm"] = view(map, map->field_play_mm.data(), shape);
    d["fields"] = fields;
    d["robust_covered"] = map->robust.covered;
    d["robust_margin_mm"] = map->robust.robust_margin_mm;
    d["worst_3sigma_mm"] = map->worst_3sigma_mm;
    d["worst_case_mm"] = map->worst_case_mm;
    d["worst_case_first_order_mm"] = map->worst_case_first_order_mm;
    d["summary"] = to_python(to_json(*map));
    out.append(d);
  }
  return out;
}

py::list control(const Design& design, const std::string& station, const py::object& progress) {
  std::vector<std::pair<const Station*, std::shared_ptr<StationControl>>> studies;
  Interruptible run;
  run.run([&] {
    for (const Station* s : stations_of(design, station)) {
      if (run.stopped()) return;
      run.call(progress, "stability of station " + s->name);
      studies.emplace_back(s, std::make_shared<StationControl>(
                                  station_control(design, *s, closed_form_station_inertia(design, *s))));
    }
  });
  py::list out;
  for (const auto& [s, study] : studies) {
    py::dict d;
    d["station"] = study->station;
    d["stable"] = study->stable();
    py::dict fields;
    for (std::size_t k = 0; k < study->fields.size() && k < study->maps.size(); ++k) {
      const RhoField& f = study->fields[k];
      py::dict fd;
      fd["grid"] = grid_dict(f.grid);
      const std::vector<py::ssize_t> shape{f.grid.ny, f.grid.nx};
      fd["rho"] = view(study, f.rho.data(), shape);
      fd["status"] = view(study, f.status.data(), shape);
      fd["max_rho"] = study->maps[k].max_rho;
      fd["stable"] = study->maps[k].stable;
      fd["kp_margin"] = study->maps[k].kp_margin;
      fd["kd_margin"] = study->maps[k].kd_margin;
      fields[py::str(study->maps[k].mechanism)] = fd;
    }
    d["mechanisms"] = fields;
    d["summary"] = to_python(to_json(*study));
    out.append(d);
  }
  return out;
}

py::dict export_gate_dict(const Design& design, const std::vector<std::string>& stations, const py::object& progress) {
  ExportOptions options;
  options.stations = stations;
  Interruptible run;
  options.progress = [&](std::string_view line) { run.call(progress, std::string(line)); };
  ExportGate gate;
  run.run([&] { gate = export_gate(design, options); });
  py::dict d;
  d["passed"] = gate.passed();
  d["stations"] = gate.stations;
  py::list checks;
  for (const GateCheck& c : gate.checks) {
    py::dict cd;
    cd["kind"] = c.kind;
    cd["subject"] = c.subject;
    cd["passed"] = c.passed;
    cd["detail"] = c.detail;
    checks.append(cd);
  }
  d["checks"] = checks;
  d["reasons"] = gate.reasons();
  py::list joints;
  for (const JointSweep& j : gate.joints) joints.append(py::make_tuple(j.name, j.lo, j.hi));
  d["joints"] = joints;
  d["validation"] = to_python(gate.validation);
  d["summary"] = to_python(to_json(gate));
  return d;
}

}  // namespace

void register_studies(py::module_& m) {
  py::class_<CoverageResult>(m, "CoverageResult",
                             "Does a mechanism (or the shared region) reach every point of the target ellipse, with "
                             "margin (mm), within joint limits, away from singularities (docs/coverage.md).")
      .def_readonly("covered", &CoverageResult::covered)
      .def_readonly("inside", &CoverageResult::inside)
      .def_readonly("margin_mm", &CoverageResult::margin_mm)
      .def_readonly("margin_error_mm", &CoverageResult::margin_error_mm)
      .def_readonly("decided", &CoverageResult::decided)
      .def_readonly("covered_fraction", &CoverageResult::covered_fraction)
      .def_property_readonly("worst_point", [](const CoverageResult& c) { return pair(c.worst_point); }, "mm")
      .def_readonly("min_lci", &CoverageResult::min_lci)
      .def_property_readonly("min_lci_point", [](const CoverageResult& c) { return pair(c.min_lci_point); }, "mm")
      .def_readonly("min_force_capability", &CoverageResult::min_force_capability, "N per N*mm")
      .def_readonly("lci_ok", &CoverageResult::lci_ok)
      .def_readonly("assembly_ok", &CoverageResult::assembly_ok)
      .def_readonly("method", &CoverageResult::method)
      .def_readonly("reason", &CoverageResult::reason)
      .def("to_dict", [](const CoverageResult& c) { return to_python(to_json(c)); }, "As the CLI's JSON (mm, deg).")
      .def("__repr__", [](const CoverageResult& c) {
        return "CoverageResult(covered=" + std::string(c.covered ? "True" : "False") +
               ", margin_mm=" + std::to_string(c.margin_mm) + ", min_lci=" + std::to_string(c.min_lci) + ")";
      });

  m.def("_coverage_station", [](const Station& s, const std::optional<Ellipse>& target) {
    StationCoverage c;
    {
      py::gil_scoped_release nogil;
      c = station_coverage(s, target);
    }
    py::dict d;
    d["station"] = c.station;
    d["covered"] = c.covered();
    d["lower"] = c.lower;
    d["upper"] = c.upper;
    d["shared"] = c.shared;
    d["summary"] = to_python(to_json(c, s.name));
    return d;
  }, py::arg("station"), py::arg("target") = py::none());
  m.def("_coverage_mechanism", [](const Mechanism& x, const Ellipse& e) {
    py::gil_scoped_release nogil;
    return coverage(x, e);
  }, py::arg("mechanism"), py::arg("target"));
  m.def("_workspace", &workspace, py::arg("station"), py::arg("spacing_mm"), py::arg("mechanism"), py::arg("progress"));
  m.def("_sweep", &sweep, py::arg("design"), py::arg("threads"), py::arg("chunk"), py::arg("progress"));
  m.def("_optimize", &optimize, py::arg("design"), py::arg("out_dir"), py::arg("evaluations"), py::arg("seconds"),
        py::arg("threads"), py::arg("plots"), py::arg("full_figures"), py::arg("resume"), py::arg("progress"));
  m.def("_simulate", &simulate_design, py::arg("design"), py::arg("station"), py::arg("pattern"), py::arg("step"),
        py::arg("rtol"), py::arg("max_wall_s"), py::arg("progress"));
  m.def("_tolerance", &tolerance, py::arg("design"), py::arg("station"), py::arg("spacing_mm"), py::arg("progress"));
  m.def("_control", &control, py::arg("design"), py::arg("station"), py::arg("progress"));
  m.def("_export_gate", &export_gate_dict, py::arg("design"), py::arg("stations"), py::arg("progress"));

  py::class_<OptimizeProblem, std::shared_ptr<OptimizeProblem>>(
      m, "Problem",
      "The optimisation problem of a design's optimize: section (docs/optimize.md), for external optimisers "
      "(scipy, pymoo): evaluate() runs the library's staged evaluation in process. Variables in file units.")
      .def(py::init([](const Design& d) { return std::make_shared<OptimizeProblem>(d); }), py::arg("design"))
      .def_property_readonly("dimension", &OptimizeProblem::dimension)
      .def_property_readonly("lower", &OptimizeProblem::lower, "Lower bounds of the variables.")
      .def_property_readonly("upper", &OptimizeProblem::upper, "Upper bounds of the variables.")
      .def_property_readonly("variables", [](const OptimizeProblem& p) {
        std::vector<std::string> names;
        for (const auto& v : p.settings().variables) names.push_back(v.name);
        return names;
      }, "Variable names, in the order of x.")
      .def_property_readonly("objectives", [](const OptimizeProblem& p) {
        std::vector<std::pair<std::string, bool>> o;
        for (const auto& x : p.settings().objectives) o.emplace_back(x.figure, x.maximise);
        return o;
      }, "(figure, maximise) per objective.")
      .def_property_readonly("figures", [](const OptimizeProblem&) {
        std::vector<std::string> names;
        for (const auto& f : optimize_figures()) names.emplace_back(f.name);
        return names;
      }, "Every figure a candidate may carry.")
      .def("reference_values", &OptimizeProblem::reference_values, "The design's own values of the variables.")
      .def("design_at", [](const OptimizeProblem& p, const py::object& x) {
        return std::make_shared<Design>(p.design_at(vector_of(x, p.dimension(), "x")));
      }, py::arg("x"), "The complete design with x applied (InputError when x breaks a rule of a design file).")
      .def("evaluate", [](const OptimizeProblem& p, const py::object& x) {
        const auto v = vector_of(x, p.dimension(), "x");
        OptimizeCandidate c;
        {
          py::gil_scoped_release nogil;
          c = p.evaluate(v);
        }
        return candidate_dict(p, c);
      }, py::arg("x"),
         "Evaluates one candidate through the stages -> {x, figures, verdict, status, violation, feasible}.")
      .def("fitness", [](const OptimizeProblem& p, const py::object& x) {
        const auto v = vector_of(x, p.dimension(), "x");
        std::vector<double> f;
        {
          py::gil_scoped_release nogil;
          f = p.fitness(p.evaluate(v));
        }
        return f;
      }, py::arg("x"),
         "The vector to minimise (one value per objective; infeasible candidates penalised by Deb's rules).")
      .def("evaluate_many", &evaluate_many, py::arg("X"), py::kw_only(), py::arg("threads") = 0,
           py::arg("progress") = py::none(),
           "Evaluates the rows of X (n x dimension) in parallel -> columns (dict of arrays) for pandas.");
}

}  // namespace fivebar::python
