// The picture of one simulation (fivebar/dynamics.hpp plot_simulation): the reference and the
// actual tactor paths on the fingertip target (as `fivebar pattern` draws its paths), and the
// motor currents and skin forces over time. cairo stays in lib/src/plot/.
#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "fivebar/format.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/error.hpp"
#include "fivebar/workspace/region.hpp"
#include "plot/chart.hpp"
#include "plot/tactor_canvas.hpp"

namespace fivebar {

namespace {

using namespace tactor_plot;
using plot::Line;
using plot::decimated_line;

constexpr double kWidth = 1320.0, kHeight = 700.0;
constexpr double kPadMm = 3.0;

using format::fixed;
using format::general;




Rgb colour_of(const std::string& mechanism) { return style::mechanism_colour(mechanism); }

}  // namespace

RenderedPlot plot_simulation(const Station& station, const SimulationInput& input, const SimulationResult& result) {
  Canvas canvas(kWidth, kHeight);
  cairo_t* cr = canvas.cr();
  const std::size_t nm = input.mechanisms.size();

  // Header.
  text(cr, 20.0, 28.0, "simulate — " + station.name + ", " + input.reference_name, 18.0, kInk, 0.0, true);
  std::string verdict = std::string(to_string(result.status)) + ": " + fixed(result.t_end, 3) + " s simulated in " +
                        std::to_string(result.steps) + " steps";
  for (const MechanismSummary& s : result.summary) {
    verdict += ";  " + s.name + " error max " + fixed(s.max_error_mm, 3) + " mm, peak " +
               fixed(s.peak_current_A, 3) + " A, shear " + fixed(s.peak_shear_N, 2) + " N" +
               (s.slipped ? ", slipped" : "");
  }
  text(cr, 20.0, 48.0, verdict, 11.5, result.ok() ? Rgb{0.10, 0.50, 0.20} : Rgb{0.75, 0.10, 0.10});

  // Left: the paths on the fingertip target.
  std::array<double, 4> b{station.target.center.x() - 0.5 * station.target.axes.x(),
                          station.target.center.y() - 0.5 * station.target.axes.y(),
                          station.target.center.x() + 0.5 * station.target.axes.x(),
                          station.target.center.y() + 0.5 * station.target.axes.y()};
  const double half_axis = 0.5 * std::max(station.target.axes.x(), station.target.axes.y());
  b = {station.target.center.x() - half_axis, station.target.center.y() - half_axis,
       station.target.center.x() + half_axis, station.target.center.y() + half_axis};
  for (const TimeSample& t : result.samples) {
    for (const MechanismSample& m : t.mechanisms) {
      for (const Vec2& p : {m.P_mm, m.P_ref_mm}) {
        if (!std::isfinite(p.x()) || !std::isfinite(p.y())) continue;
        b = {std::min(b[0], p.x()), std::min(b[1], p.y()), std::max(b[2], p.x()), std::max(b[3], p.y())};
      }
    }
  }
  b = {b[0] - kPadMm, b[1] - kPadMm, b[2] + kPadMm, b[3] + kPadMm};
  const Panel panel(cr, 66.0, 80.0, 520.0, 540.0, b);
  cairo_save(cr);
  cairo_rectangle(cr, panel.x(), panel.y(), panel.w(), panel.h());
  cairo_clip(cr);
  for (const Mechanism* m : station.mechanisms()) {
    const Region region = reachable_region(*m);
    panel.begin();
    region_path(cr, region);
    panel.end();
    const Rgb c = colour_of(m->name);
    set_colour(cr, c, 0.06);
    cairo_fill_preserve(cr);
    set_colour(cr, c, 0.35);
    cairo_set_line_width(cr, 1.0);
    cairo_stroke(cr);
  }
  panel.begin();
  ellipse_path(cr, station.target);
  panel.end();
  {
    const double dash[2] = {6.0, 4.0};
    cairo_set_dash(cr, dash, 2, 0.0);
    set_colour(cr, kInk, 0.8);
    cairo_set_line_width(cr, 1.3);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0.0);
  }
  for (std::size_t k = 0; k < nm; ++k) {
    const Rgb c = colour_of(input.mechanisms[k].name);
    for (const bool actual : {false, true}) {
      bool first = true;
      for (const TimeSample& t : result.samples) {
        if (k >= t.mechanisms.size()) continue;
        const Vec2 p = actual ? t.mechanisms[k].P_mm : t.mechanisms[k].P_ref_mm;
        const auto q = panel.px(p);
        if (first) cairo_move_to(cr, q[0], q[1]);
        else cairo_line_to(cr, q[0], q[1]);
        first = false;
      }
      set_colour(cr, actual ? darker(c) : c, actual ? 1.0 : 0.45);
      cairo_set_line_width(cr, actual ? 1.3 : 5.0);
      cairo_stroke(cr);
    }
    if (!result.samples.empty() && k < result.samples.front().mechanisms.size()) {
      const auto q = panel.px(result.samples.front().mechanisms[k].P_mm);
      cairo_arc(cr, q[0], q[1], 3.5, 0.0, 2.0 * std::numbers::pi);
      set_colour(cr, {1, 1, 1});
      cairo_fill_preserve(cr);
      set_colour(cr, c);
      cairo_set_line_width(cr, 1.4);
      cairo_stroke(cr);
    }
  }
  cairo_restore(cr);
  axes(cr, panel, b, tick_step(std::max(b[2] - b[0], b[3] - b[1])));
  double ly = panel.y() + panel.h() + 44.0;
  text(cr, panel.x(), ly, "wide, light: commanded path; thin, dark: simulated tactor; circle: start", 11.0, kInk);
  text(cr, panel.x(), ly + 16.0, "red lower, blue upper; shaded: reachable regions; dashed ellipse: fingertip target",
       11.0, kGrey);

  // Right: currents and skin forces over time.
  const double t_end = result.samples.empty() ? 1.0 : std::max(result.samples.back().t, 1e-6);
  std::vector<Line> currents, forces;
  for (std::size_t k = 0; k < nm; ++k) {
    const std::string& name = input.mechanisms[k].name;
    const Rgb c = colour_of(name);
    Line i1{{}, c, 1.4, false, name + " θ1"}, i2{{}, darker(c), 1.4, true, name + " θ2"};
    Line f{{}, c, 1.4, false, name + " |F|"};
    for (const TimeSample& t : result.samples) {
      if (k >= t.mechanisms.size()) continue;
      const MechanismSample& m = t.mechanisms[k];
      i1.points.push_back({t.t, m.current[0]});
      i2.points.push_back({t.t, m.current[1]});
      f.points.push_back({t.t, m.force_N.norm()});
    }
    currents.push_back(std::move(i1));
    currents.push_back(std::move(i2));
    forces.push_back(std::move(f));
  }
  plot::time_chart(cr, {700.0, 100.0, 590.0, 220.0, "Motor currents (at the controller's samples)", "current (A)", t_end, true},
                   currents);
  plot::time_chart(cr, {700.0, 400.0, 590.0, 220.0, "Shear force on the skin", "|F| (N)", t_end, true}, forces);
  return canvas.render();
}

}  // namespace fivebar
