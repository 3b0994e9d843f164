// Output of `fivebar report accuracy`: JSON (units in the keys), text tables and the
// work-precision plots.
#include <algorithm>
#include <map>
#include <sstream>

#include "fivebar/io.hpp"
#include "fivebar/report.hpp"
#include "plot/work_precision_plot.hpp"
#include "report/format.hpp"

namespace fivebar {

namespace {

using report_fmt::pad;
using report_fmt::sci;
using report_fmt::fixed;

Json opt(const std::optional<double>& v) { return v ? Json(*v) : Json(nullptr); }

std::string unit_suffix(const std::string& unit) { return unit == "1" ? "" : "_" + unit; }

Json series_json(const WorkSeries& s) {
  Json j;
  j["method"] = s.method;
  j["note"] = s.note;
  Json pts = Json::array();
  const std::string u = unit_suffix(s.unit);
  for (const WorkPoint& p : s.points) {
    Json q;
    if (s.resolution == "h_mm") {
      q["h_mm"] = p.resolution > 0 ? Json(p.resolution) : Json(nullptr);
    } else {
      q[s.resolution] = p.resolution;
    }
    q["time_s"] = p.time_s;
    q["value" + u] = p.value;
    q["error" + u] = p.error;
    q["estimate" + u] = opt(p.estimate);
    pts.push_back(q);
  }
  j["points"] = pts;
  j["order"] = opt(s.order);
  j["error_vs_time_slope"] = opt(s.time_slope);
  return j;
}

Json study_json(const PrecisionStudy& st) {
  Json j;
  j["problem"] = st.problem;
  j["stratified_by"] = st.stratified_by;
  Json strata = Json::array();
  for (std::size_t i = 0; i < st.strata.size(); ++i) {
    Json s;
    s["sin_range"] = {st.strata[i][0], std::min(1.0, st.strata[i][1])};
    s["order_in_eps"] = i < st.order.size() ? opt(st.order[i]) : Json(nullptr);
    Json methods = Json::array();
    for (const PrecisionMethod& m : st.methods) {
      const PrecisionCell& c = m.cells[i];
      methods.push_back({{"method", m.name},
                         {"library", m.library},
                         {"unit_roundoff", m.unit_roundoff},
                         {"samples", c.samples},
                         {"failed", c.failed},
                         {"max_error_mm", c.max_error_mm},
                         {"rms_error_mm", c.rms_error_mm},
                         {"max_error_ulp", c.max_error_ulp},
                         {"rms_error_ulp", c.rms_error_ulp},
                         {"ns_per_call", c.ns_per_call}});
    }
    s["methods"] = methods;
    strata.push_back(s);
  }
  j["strata"] = strata;
  return j;
}

Json dynamics_json(const DynamicsAccuracy& d) {
  Json j;
  if (!d.skipped.empty()) {
    j["skipped"] = d.skipped;
    return j;
  }
  j["station"] = d.station;
  j["scenario"] = d.scenario;
  j["duration_s"] = d.duration_s;
  j["reference"] = "CVODE BDF at rtol " + report_fmt::sci(d.reference_rtol, 0) + " on the same model";
  j["default_rtol"] = d.default_rtol;
  j["stiffness_ratio_definition"] = "T_loop R / L";
  Json series = Json::array();
  for (const DynamicsSeries& s : d.series) {
    Json a;
    a["integrator"] = s.integrator;
    a["pwm"] = s.pwm;
    a["stiffness_ratio"] = s.stiffness_ratio;
    a["error_vs_time_slope"] = opt(s.time_slope);
    Json pts = Json::array();
    for (const DynamicsPoint& p : s.points) {
      pts.push_back({{"rtol", p.rtol},
                     {"time_s", p.time_s},
                     {"error_mm", p.error_mm},
                     {"steps", p.steps},
                     {"rhs_evaluations", p.rhs_evaluations},
                     {"status", p.status}});
    }
    a["points"] = pts;
    series.push_back(a);
  }
  j["series"] = series;
  Json st = Json::array();
  for (const StiffnessPoint& p : d.stiffness) {
    st.push_back({{"stiffness_ratio", p.stiffness_ratio},
                  {"l_over_r_s", p.l_over_r_s},
                  {"bdf_steps_per_simulated_s", p.steps_per_s[0]},
                  {"erk_steps_per_simulated_s", p.steps_per_s[1]},
                  {"bdf_wall_s_per_simulated_s", p.wall_per_s[0]},
                  {"erk_wall_s_per_simulated_s", p.wall_per_s[1]},
                  {"bdf_status", p.status[0]},
                  {"erk_status", p.status[1]}});
  }
  j["stiffness"] = st;
  j["crossover_stiffness_ratio"] = opt(d.crossover_ratio);
  return j;
}

void dynamics_table(std::ostringstream& out, const DynamicsAccuracy& d) {
  out << "\nDynamics: CVODE BDF against ARKODE explicit RK (Dormand-Prince 5(4))";
  if (!d.skipped.empty()) {
    out << ": not studied, " << d.skipped << "\n";
    return;
  }
  out << ", station " << d.station << ": " << d.scenario << "\n";
  out << "  error: max over the samples and both tactors of |P - P_ref| (mm), P_ref from BDF at rtol "
      << sci(d.reference_rtol, 0) << "; stiffness ratio S = T_loop R / L\n";
  out << "  " << pad("integrator", 12) << pad("PWM", 10) << pad("S", 8, true) << pad("rtol", 9, true)
      << pad("time (s)", 11, true) << pad("steps", 9, true) << pad("error (mm)", 12, true) << "  status\n";
  for (const DynamicsSeries& s : d.series) {
    for (const DynamicsPoint& p : s.points) {
      out << "  " << pad(s.integrator, 12) << pad(s.pwm, 10) << pad(sci(s.stiffness_ratio, 0), 8, true)
          << pad(sci(p.rtol, 0), 9, true) << pad(sci(p.time_s, 2), 11, true) << pad(std::to_string(p.steps), 9, true)
          << pad(sci(p.error_mm, 2), 12, true) << "  " << p.status << "\n";
    }
  }
  out << "  Steps per simulated second at the default rtol " << sci(d.default_rtol, 0) << " as L shrinks:\n";
  out << "  " << pad("S", 8) << pad("L/R (s)", 10, true) << pad("BDF steps/s", 14, true) << pad("ERK steps/s", 14, true)
      << pad("BDF wall/s", 12, true) << pad("ERK wall/s", 12, true) << "  status (BDF, ERK)\n";
  for (const StiffnessPoint& p : d.stiffness) {
    out << "  " << pad(sci(p.stiffness_ratio, 0), 8) << pad(sci(p.l_over_r_s, 1), 10, true)
        << pad(sci(p.steps_per_s[0], 2), 14, true) << pad(sci(p.steps_per_s[1], 2), 14, true)
        << pad(sci(p.wall_per_s[0], 2), 12, true) << pad(sci(p.wall_per_s[1], 2), 12, true) << "  " << p.status[0]
        << ", " << p.status[1] << "\n";
  }
  out << "  crossover (ERK's steps overtake BDF's): "
      << (d.crossover_ratio ? "S = " + sci(*d.crossover_ratio, 1) : std::string("not within the range")) << "\n";
}

std::string label(const MechanismAccuracy& m) { return m.station + "/" + m.mechanism; }

void series_table(std::ostringstream& out, const std::vector<WorkSeries>& series) {
  if (series.empty()) return;
  const std::string u = series.front().unit == "mm2" ? "mm²" : series.front().unit;
  const bool samples = series.front().resolution == "samples";
  out << "  " << pad("method", 26) << pad(samples ? "N" : "h (mm)", 10, true) << pad("time (s)", 11, true)
      << pad("value" + (u == "1" ? std::string() : " (" + u + ")"), 18, true)
      << pad("error" + (u == "1" ? std::string() : " (" + u + ")"), 14, true) << pad("own estimate", 14, true) << "\n";
  for (const WorkSeries& s : series) {
    for (const WorkPoint& p : s.points) {
      const std::string res = p.resolution > 0 ? (samples ? fixed(p.resolution, 0) : fixed(p.resolution, 4)) : "—";
      out << "  " << pad(s.method, 26) << pad(res, 10, true)
          << pad(sci(p.time_s, 2), 11, true) << pad(fixed(p.value, s.unit == "1" ? 8 : 6), 18, true)
          << pad(sci(p.error, 2), 14, true) << pad(sci(p.estimate, 2), 14, true) << "\n";
    }
  }
  std::string orders;
  for (const WorkSeries& s : series) {
    if (!s.order) continue;
    orders += (orders.empty() ? "" : "; ") + s.method + " p = " + fixed(*s.order, 2);
    if (s.time_slope) orders += " (error ~ time^" + fixed(*s.time_slope, 2) + ")";
  }
  if (!orders.empty()) out << "  fitted order (error ~ h^p): " << orders << "\n";
}

std::string order_text(const std::optional<double>& p) { return p ? fixed(*p, 2) : "—"; }

void study_table(std::ostringstream& out, const PrecisionStudy& st) {
  out << "\n" << (st.problem == "fk" ? "FK" : "IK") << " against the __float128 reference, stratified by "
      << st.stratified_by << "\n";
  out << "  error: " << (st.problem == "fk" ? "|P - P_ref| (mm)" : "max_i L_i |theta_i - theta_i,ref| (mm)")
      << "; ulp = ulp of the length scale in the method's arithmetic\n";
  out << "  " << pad("|sin| in", 14) << pad("method", 14) << pad("n", 6, true) << pad("fail", 6, true)
      << pad("max err (mm)", 14, true) << pad("rms err (mm)", 14, true) << pad("max ulp", 10, true)
      << pad("rms ulp", 10, true) << pad("ns/call", 10, true) << "\n";
  for (std::size_t i = 0; i < st.strata.size(); ++i) {
    for (const PrecisionMethod& m : st.methods) {
      const PrecisionCell& c = m.cells[i];
      out << "  " << pad(&m == &st.methods.front() ? report_fmt::range(st.strata[i][0], st.strata[i][1]) : "", 14)
          << pad(m.name, 14) << pad(std::to_string(c.samples), 6, true) << pad(std::to_string(c.failed), 6, true)
          << pad(sci(c.max_error_mm, 2), 14, true) << pad(sci(c.rms_error_mm, 2), 14, true)
          << pad(sci(c.max_error_ulp, 1), 10, true) << pad(sci(c.rms_error_ulp, 1), 10, true)
          << pad(fixed(c.ns_per_call, 1), 10, true) << "\n";
    }
    out << "  " << pad("", 14) << "order in eps (float, double, long double): " << order_text(st.order[i]) << "\n";
  }
}

// --- plots -------------------------------------------------------------------------------------

std::string legend(const std::string& who, const WorkSeries& s) {
  std::string l = who.empty() ? s.method : who + ": " + s.method;
  if (s.order) {
    l += ", order p = " + fixed(*s.order, 2);
  } else if (s.points.size() == 1) {
    l += " (single run)";
  }
  return l;
}

plot::PlotSpec station_plot(const AccuracyReport& r, const std::string& station, const std::string& kind) {
  plot::PlotSpec spec;
  spec.x_label = "run time (s), median of repeats after a warm-up";
  for (const MechanismAccuracy& m : r.mechanisms) {
    if (m.station != station || !m.mirror_of.empty()) continue;  // a mirror image repeats its twin's lines
    const std::vector<WorkSeries>* list = kind == "area"         ? &m.area
                                          : kind == "restricted" ? &m.restricted
                                          : kind == "tolerance"  ? &m.tolerance
                                                                 : &m.coverage;
    for (const WorkSeries& s : *list) {
      const bool wanted = kind == "area" || kind == "restricted" || kind == "tolerance" ||
                          (kind == "margin" ? s.unit == "mm" : s.unit == "1");
      if (!wanted || s.points.empty()) continue;
      plot::PlotSeries ps;
      ps.label = legend(m.mechanism, s);
      ps.line = s.points.size() > 1;
      for (const WorkPoint& p : s.points) ps.points.push_back({p.time_s, p.error});
      spec.series.push_back(std::move(ps));
    }
  }
  if (kind == "area") {
    spec.title = "Workspace area, station " + station + ": error against run time";
    spec.y_label = "|area - exact CGAL area| (mm²)";
    spec.footnote = "The grid spacing h halves along each line; error ~ h^p. Exact region and closed form: single runs "
                    "against the annuli closed form in __float128.";
  } else if (kind == "restricted") {
    spec.title = "Sampled restricted regions, station " + station;
    spec.y_label = "|area - area on a 16x finer grid| (mm²)";
    spec.footnote = "restricted_area (adaptive marching squares) of the assembly- and LCI-restricted regions and of a "
                    "thin island (LCI within 2 % of its largest value); the grid spacing halves along each line.";
  } else if (kind == "tolerance") {
    spec.title = "Tolerance estimates at the target centre, station " + station;
    spec.y_label = "|estimate - reference| (mm)";
    spec.footnote = "3-sigma tactor error (0.05 mm, 0.5 deg): Monte Carlo of N devices (N x10 along the line) and the "
                    "first order against 1e6 devices; play (0.1 mm a leg): sampled devices and first order against "
                    "the exact set.";
  } else if (kind == "margin") {
    spec.title = "Coverage margin, station " + station;
    spec.y_label = "|margin - coverage() margin| (mm)";
    spec.footnote = "Sampled: min signed distance over N boundary points (N doubles along the line); coverage() "
                    "against the margin in __float128.";
  } else {
    spec.title = "Minimum LCI over the target ellipse, station " + station;
    spec.y_label = "|min LCI - refined minimum| (LCI is dimensionless)";
    spec.footnote = "Sampled: 1 + 8 n² points over the filled ellipse (n doubles along the line); coverage(): its "
                    "sampling plus compass search.";
  }
  for (const MechanismAccuracy& m : r.mechanisms) {
    if (m.station == station && !m.mirror_of.empty()) {
      spec.footnote += " " + label(m) + " is the mirror image of " + m.mirror_of + ": the same lines.";
    }
  }
  return spec;
}

plot::PlotSpec study_plot(const PrecisionStudy& st) {
  plot::PlotSpec spec;
  const bool fk = st.problem == "fk";
  spec.title = std::string(fk ? "FK" : "IK") + " work-precision against __float128, by " + st.stratified_by;
  spec.x_label = "time per call (ns), median of repeats after a warm-up";
  spec.y_label = fk ? "rms |P - P_ref| over the stratum (mm)" : "rms max_i L_i |Δθ_i| over the stratum (mm)";
  for (std::size_t i = 0; i < st.strata.size(); ++i) {
    plot::PlotSeries ps;
    ps.label = "|sin| in " + report_fmt::range(st.strata[i][0], st.strata[i][1]) + ": float, double, long double; " +
               "error ~ eps^" + order_text(st.order[i]);
    for (int k = 0; k < 3; ++k) {
      const PrecisionCell& c = st.methods[k].cells[i];
      if (c.samples > c.failed) ps.points.push_back({c.ns_per_call, c.rms_error_mm});
    }
    spec.series.push_back(std::move(ps));
  }
  for (const PrecisionMethod& m : st.methods) {
    if (!m.library) continue;
    plot::PlotSeries ps;
    ps.label = m.name + " (library, double), one marker per stratum";
    ps.line = false;
    for (const PrecisionCell& c : m.cells)
      if (c.samples > c.failed) ps.points.push_back({c.ns_per_call, c.rms_error_mm});
    spec.series.push_back(std::move(ps));
  }
  spec.footnote = "Lines join float (left), double and long double of the same formulas; |sin| conditions the "
                  "problem (error ~ eps L / |sin|). Zero errors are not drawn.";
  return spec;
}

plot::PlotSpec dynamics_plot(const DynamicsAccuracy& d) {
  plot::PlotSpec spec;
  spec.title = "Dynamics work-precision, station " + d.station + ": BDF against explicit RK";
  spec.x_label = "run time (s)";
  spec.y_label = "max |P - P_ref| over the samples (mm)";
  for (const DynamicsSeries& s : d.series) {
    plot::PlotSeries ps;
    ps.label = std::string(s.integrator == "bdf" ? "CVODE BDF" : "ARKODE ERK") + ", " + s.pwm + " PWM, S = " +
               sci(s.stiffness_ratio, 0);
    for (const DynamicsPoint& p : s.points)
      if (p.status == "ok") ps.points.push_back({p.time_s, p.error_mm});
    spec.series.push_back(std::move(ps));
  }
  spec.footnote = "rtol from " + sci(d.series.empty() || d.series[0].points.empty() ? 0.0 : d.series[0].points.front().rtol, 0) +
                  " (first point) to " + sci(d.series.empty() || d.series[0].points.empty() ? 0.0 : d.series[0].points.back().rtol, 0) +
                  " along each line; reference BDF at rtol " + sci(d.reference_rtol, 0) +
                  ". S = T_loop R / L; zero errors are not drawn.";
  return spec;
}

plot::PlotSpec stiffness_plot(const DynamicsAccuracy& d) {
  plot::PlotSpec spec;
  spec.title = "Integrator steps per simulated second as the motor inductance shrinks";
  spec.x_label = "stiffness ratio S = T_loop R / L";
  spec.y_label = "steps per simulated second";
  for (std::size_t k = 0; k < 2; ++k) {
    plot::PlotSeries ps;
    ps.label = k == 0 ? "CVODE BDF" : "ARKODE ERK (Dormand-Prince 5(4))";
    for (const StiffnessPoint& p : d.stiffness) ps.points.push_back({p.stiffness_ratio, p.steps_per_s[k]});
    spec.series.push_back(std::move(ps));
  }
  spec.footnote = "rtol " + sci(d.default_rtol, 0) + "; crossover " +
                  (d.crossover_ratio ? "at S = " + sci(*d.crossover_ratio, 1) : std::string("not within the range")) +
                  ". Runs stopped by the step bound count their rate over the part simulated.";
  return spec;
}

}  // namespace

Json to_json(const AccuracyReport& r) {
  Json j;
  j["command"] = "report accuracy";
  j["design"] = r.design;
  j["quick"] = r.quick;
  j["seconds"] = r.seconds;
  j["references"] = {
      {"area", "exact CGAL region; without joint limits also the annuli closed form in __float128"},
      {"coverage", "coverage() margin (and the margin in __float128 without joint limits); min LCI refined locally"},
      {"restricted", "restricted_area on a grid 16x finer than the finest of the series"},
      {"kinematics", "FK/IK in __float128 (law of cosines with Heron products)"}};
  Json ms = Json::array();
  for (const MechanismAccuracy& m : r.mechanisms) {
    Json a;
    a["station"] = m.station;
    a["mechanism"] = m.mechanism;
    a["mirror_of"] = m.mirror_of.empty() ? Json(nullptr) : Json(m.mirror_of);
    a["mirror_line_y_mm"] = m.mirror_of.empty() ? Json(nullptr) : Json(m.mirror_line_y_mm);
    Json area;
    area["exact_mm2"] = m.exact_area_mm2;
    area["closed_form_mm2"] = opt(m.closed_form_area_mm2);
    area["quad_closed_form_mm2"] = opt(m.quad_area_mm2);
    area["series"] = Json::array();
    for (const WorkSeries& s : m.area) area["series"].push_back(series_json(s));
    a["area"] = area;
    Json cov;
    cov["margin_mm"] = m.margin_mm;
    cov["margin_quad_mm"] = opt(m.margin_quad_mm);
    cov["min_lci"] = m.min_lci;
    cov["min_lci_reference"] = m.min_lci_reference;
    cov["series"] = Json::array();
    for (const WorkSeries& s : m.coverage) cov["series"].push_back(series_json(s));
    a["coverage"] = cov;
    Json rs;
    rs["lci_threshold"] = m.lci_threshold;
    rs["lci_threshold_from_design"] = m.lci_threshold_from_design;
    rs["reference_h_mm"] = m.reference_spacing_mm;
    rs["assembly_area_reference_mm2"] = m.assembly_area_reference_mm2;
    rs["lci_area_reference_mm2"] = m.lci_area_reference_mm2;
    rs["thin_lci_threshold"] = m.thin_lci_threshold;
    rs["thin_lci_area_reference_mm2"] = m.thin_lci_area_reference_mm2;
    rs["series"] = Json::array();
    for (const WorkSeries& s : m.restricted) rs["series"].push_back(series_json(s));
    a["restricted"] = rs;
    Json tol;
    tol["reference_3sigma_mm"] = m.tolerance_reference_3sigma_mm;
    tol["reference_samples"] = m.tolerance_reference_samples;
    tol["play_extent_mm"] = m.play_extent_mm;
    tol["series"] = Json::array();
    for (const WorkSeries& s : m.tolerance) tol["series"].push_back(series_json(s));
    a["tolerance"] = tol;
    ms.push_back(a);
  }
  j["mechanisms"] = ms;
  j["fk"] = study_json(r.fk);
  j["ik"] = study_json(r.ik);
  j["dynamics"] = dynamics_json(r.dynamics);
  return j;
}

std::string to_text(const AccuracyReport& r) {
  std::ostringstream out;
  out << "fivebar report accuracy: design " << r.design << (r.quick ? " (quick)" : "") << ", " << fixed(r.seconds, 1)
      << " s\n";
  out << "Times are medians of repeated runs after a warm-up; errors against exact or __float128 references.\n";
  for (const MechanismAccuracy& m : r.mechanisms) {
    out << "\n== " << label(m) << " ==\n";
    if (!m.mirror_of.empty()) {
      out << "The mirror image of " << m.mirror_of << " across y = " << fixed(m.mirror_line_y_mm, 3)
          << " mm (bases, modes, joint limits and target reflected): the same regions, margins and conditioning; "
             "its figures are "
          << m.mirror_of << "'s, not measured again.\n";
      continue;
    }
    out << "Workspace area: exact (CGAL) " << fixed(m.exact_area_mm2, 9) << " mm²";
    if (m.quad_area_mm2) {
      out << "; annuli closed form in quad " << fixed(*m.quad_area_mm2, 9) << " mm² (CGAL differs by "
          << sci(std::fabs(m.exact_area_mm2 - *m.quad_area_mm2), 1) << ")";
    }
    out << "\n";
    series_table(out, m.area);
    out << "Coverage of the target: margin " << fixed(m.margin_mm, 9) << " mm by coverage()";
    if (m.margin_quad_mm) out << " (quad: " << fixed(*m.margin_quad_mm, 9) << " mm)";
    out << "; min LCI " << fixed(m.min_lci, 9) << " by coverage(), refined minimum " << fixed(m.min_lci_reference, 9)
        << "\n";
    std::vector<WorkSeries> cov_lci, cov_margin;
    for (const WorkSeries& s : m.coverage) {
      if (!s.points.empty()) (s.unit == "1" ? cov_lci : cov_margin).push_back(s);
    }
    series_table(out, cov_margin);
    series_table(out, cov_lci);
    out << "Restricted regions (LCI >= " << fixed(m.lci_threshold, 2)
        << (m.lci_threshold_from_design ? ", the design's min_lci" : ", illustrative: the design sets no min_lci")
        << "); reference: h = " << fixed(m.reference_spacing_mm, 4) << " mm, assembly "
        << fixed(m.assembly_area_reference_mm2, 6) << " mm², LCI " << fixed(m.lci_area_reference_mm2, 6) << " mm²\n";
    series_table(out, m.restricted);
    out << "Tolerance estimates at the target centre: Monte Carlo reference 3-sigma "
        << fixed(m.tolerance_reference_3sigma_mm, 6) << " mm (" << m.tolerance_reference_samples
        << " devices), exact play set " << fixed(m.play_extent_mm, 6) << " mm\n";
    series_table(out, m.tolerance);
  }
  study_table(out, r.fk);
  study_table(out, r.ik);
  dynamics_table(out, r.dynamics);
  return out.str();
}

std::vector<std::filesystem::path> write_accuracy_plots(const AccuracyReport& r, const std::filesystem::path& dir) {
  make_directories(dir);
  std::vector<std::pair<std::string, plot::PlotSpec>> plots;
  std::vector<std::string> stations;
  for (const MechanismAccuracy& m : r.mechanisms)
    if (std::find(stations.begin(), stations.end(), m.station) == stations.end()) stations.push_back(m.station);
  for (const std::string& s : stations) {
    for (const char* kind : {"area", "margin", "min_lci", "restricted", "tolerance"}) {
      plots.push_back({"accuracy_" + s + "_" + kind, station_plot(r, s, kind)});
    }
  }
  if (!r.fk.methods.empty()) plots.push_back({"accuracy_fk", study_plot(r.fk)});
  if (!r.ik.methods.empty()) plots.push_back({"accuracy_ik", study_plot(r.ik)});
  if (r.dynamics.skipped.empty() && !r.dynamics.series.empty()) {
    plots.push_back({"accuracy_dynamics", dynamics_plot(r.dynamics)});
    plots.push_back({"accuracy_dynamics_stiffness", stiffness_plot(r.dynamics)});
  }
  std::vector<std::filesystem::path> written;
  for (const auto& [name, spec] : plots) {
    write_file_atomic(dir / (name + ".svg"), plot::render_svg(spec));
    written.push_back(name + ".svg");
    write_file_atomic(dir / (name + ".png"), plot::render_png(spec));
    written.push_back(name + ".png");
  }
  return written;
}

}  // namespace fivebar
