// Measured against fitted (fivebar/identify/identify.hpp identify_plot): the logged position with
// the open-loop simulations of the IDIM-LS and output-error models above, the logged drive with the
// inverse model's prediction below. Drawn on the house canvas (lib/src/plot/tactor_canvas.hpp).

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>

#include "fivebar/identify/identify.hpp"
#include "plot/tactor_canvas.hpp"

namespace fivebar::identify {

namespace {

using namespace tactor_plot;

constexpr double kWidth = 1200.0, kHeight = 760.0;

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

double nice_step(double span) {
  if (!(span > 0.0) || !std::isfinite(span)) return 1.0;
  const double raw = span / 6.0;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10.0 * p;
}

struct Line {
  std::vector<std::pair<double, double>> points;
  Rgb colour;
  double width;
  bool dashed;
  std::string label;
};

/// At most ~3000 points of a series (every k-th sample).
Line line(const std::vector<double>& t, const std::vector<double>& y, Rgb c, double w, bool dashed, std::string label) {
  Line l{{}, c, w, dashed, std::move(label)};
  if (y.empty() || t.size() != y.size()) return l;
  const std::size_t step = std::max<std::size_t>(1, y.size() / 3000);
  for (std::size_t i = 0; i < y.size(); i += step) l.points.emplace_back(t[i] - t.front(), y[i]);
  return l;
}

void chart(cairo_t* cr, double x, double y, double w, double h, const std::string& title, const std::string& y_label,
           const std::vector<Line>& lines, double t_end) {
  double lo = 1e300, hi = -1e300;
  for (const Line& l : lines)
    for (const auto& p : l.points) {
      lo = std::min(lo, p.second);
      hi = std::max(hi, p.second);
    }
  if (!(hi > lo)) {
    lo = 0.0;
    hi = 1.0;
  }
  const double pad = 0.05 * (hi - lo);
  lo -= pad;
  hi += pad;
  const auto px = [&](double t, double v) {
    return std::array<double, 2>{x + t / std::max(t_end, 1e-12) * w, y + h - (v - lo) / (hi - lo) * h};
  };
  text(cr, x, y - 10.0, title, 13.0, kInk, 0.0, true);
  cairo_set_line_width(cr, 0.6);
  const double ys = nice_step(hi - lo);
  for (double v = std::ceil(lo / ys) * ys; v <= hi; v += ys) {
    const auto p = px(0.0, v);
    set_colour(cr, kGrey, 0.3);
    cairo_move_to(cr, x, p[1]);
    cairo_line_to(cr, x + w, p[1]);
    cairo_stroke(cr);
    text(cr, x - 6.0, p[1] + 4.0, fmt("%g", std::abs(v) < 1e-12 * ys ? 0.0 : v), 10.0, kInk, 1.0);
  }
  const double ts = nice_step(t_end);
  for (double t = 0.0; t <= t_end * (1 + 1e-9); t += ts) {
    const auto p = px(t, lo);
    set_colour(cr, kGrey, 0.3);
    cairo_move_to(cr, p[0], y);
    cairo_line_to(cr, p[0], y + h);
    cairo_stroke(cr);
    text(cr, p[0], y + h + 14.0, fmt("%g", t), 10.0, kInk, 0.5);
  }
  set_colour(cr, kInk);
  cairo_set_line_width(cr, 1.0);
  cairo_rectangle(cr, x, y, w, h);
  cairo_stroke(cr);
  text(cr, x + w, y + h + 30.0, "time (s)", 11.0, kInk, 1.0);
  cairo_save(cr);
  cairo_translate(cr, x - 52.0, y + 0.5 * h);
  cairo_rotate(cr, -0.5 * std::numbers::pi);
  text(cr, 0.0, 0.0, y_label, 11.0, kInk, 0.5);
  cairo_restore(cr);
  cairo_save(cr);
  cairo_rectangle(cr, x, y, w, h);
  cairo_clip(cr);
  for (const Line& l : lines) {
    if (l.points.empty()) continue;
    set_colour(cr, l.colour, 0.95);
    cairo_set_line_width(cr, l.width);
    if (l.dashed) {
      const double dash[2] = {5.0, 3.0};
      cairo_set_dash(cr, dash, 2, 0.0);
    }
    bool first = true;
    for (const auto& p : l.points) {
      const auto q = px(p.first, p.second);
      if (first) cairo_move_to(cr, q[0], q[1]);
      else cairo_line_to(cr, q[0], q[1]);
      first = false;
    }
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0.0);
  }
  cairo_restore(cr);
  double lx = x + w - 8.0;
  for (auto it = lines.rbegin(); it != lines.rend(); ++it) {
    if (it->points.empty()) continue;
    const double tw = text_width(cr, it->label, 10.0);
    lx -= tw + 34.0;
    set_colour(cr, it->colour);
    cairo_set_line_width(cr, it->width);
    if (it->dashed) {
      const double dash[2] = {5.0, 3.0};
      cairo_set_dash(cr, dash, 2, 0.0);
    }
    cairo_move_to(cr, lx, y + 14.0);
    cairo_line_to(cr, lx + 22.0, y + 14.0);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0.0);
    text(cr, lx + 26.0, y + 18.0, it->label, 10.0, kInk);
  }
}

}  // namespace

RenderedPlot identify_plot(const JointIdentification& r, bool validation) {
  const Series& s = validation ? r.validation_series : r.series;
  const Fit& fi = validation ? *r.validation_idim : r.estimation_idim;
  const Fit* fo = validation ? (r.validation_oe ? &*r.validation_oe : nullptr) : (r.output_error ? &r.estimation_oe : nullptr);
  Canvas canvas(kWidth, kHeight);
  cairo_t* cr = canvas.cr();
  const std::string pos_unit = r.linear ? "position (m)" : "angle (rad)";
  const std::string drive_unit = r.drive_column;
  text(cr, 20.0, 28.0, "identify — " + r.joint + (validation ? ", validation log" : ", estimation log"), 18.0, kInk, 0.0, true);
  std::string line1 = "position fit (open-loop simulation): IDIM-LS " +
                      (fi.simulated ? fmt("%.1f %%", fi.position_fit_percent) : std::string("diverged"));
  if (fo) line1 += ", output error " + (fo->simulated ? fmt("%.1f %%", fo->position_fit_percent) : std::string("diverged"));
  line1 += ";  drive fit (inverse model) " + fmt("%.1f %%", fi.drive_fit_percent) + ", relative error " +
           fmt("%.2f %%", fi.drive_relative_error_percent);
  text(cr, 20.0, 50.0, line1, 11.5, kInk);
  const double t_end = s.time.empty() ? 1.0 : s.time.back() - s.time.front();
  chart(cr, 90.0, 90.0, kWidth - 120.0, 270.0, "position: measured and simulated", pos_unit,
        {line(s.time, s.position, kInk, 1.2, false, "measured"),
         line(s.time, s.position_idim, kLowerColour, 1.0, false, "IDIM-LS model"),
         line(s.time, s.position_oe, kUpperColour, 1.0, true, "output-error model")},
        t_end);
  chart(cr, 90.0, 430.0, kWidth - 120.0, 270.0, "drive: measured (decimated) and predicted by the inverse model",
        drive_unit,
        {line(s.drive_time, s.drive, kInk, 1.2, false, "measured"),
         line(s.drive_time, s.drive_idim, kLowerColour, 1.0, false, "IDIM-LS prediction")},
        t_end);
  return canvas.render();
}

}  // namespace fivebar::identify
