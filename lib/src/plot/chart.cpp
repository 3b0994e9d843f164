// The time-series chart of the simulation and identification pictures (plot/chart.hpp).

#include "plot/chart.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "fivebar/format.hpp"
#include "plot/tactor_canvas.hpp"

namespace fivebar::plot {

Line decimated_line(const std::vector<double>& t, const std::vector<double>& y, Rgb colour, double width,
                    bool dashed, std::string label) {
  Line l{{}, colour, width, dashed, std::move(label)};
  if (y.empty() || t.size() != y.size()) return l;
  const std::size_t step = std::max<std::size_t>(1, y.size() / 3000);
  for (std::size_t i = 0; i < y.size(); i += step) l.points.emplace_back(t[i] - t.front(), y[i]);
  return l;
}

void time_chart(cairo_t* cr, const ChartLayout& c, const std::vector<Line>& lines) {
  using namespace style;
  using tactor_plot::set_colour;
  using tactor_plot::text;
  using tactor_plot::text_width;
  const double x = c.x, y = c.y, w = c.w, h = c.h, t_end = c.t_end;
  double lo = c.include_zero ? 0.0 : 1e300, hi = c.include_zero ? 0.0 : -1e300;
  for (const Line& l : lines)
    for (const auto& p : l.points) {
      if (!std::isfinite(p.second)) continue;
      lo = std::min(lo, p.second);
      hi = std::max(hi, p.second);
    }
  if (!(hi > lo)) {
    if (lo > hi) lo = 0.0;  // no finite point at all
    hi = lo + 1.0;
  }
  const double pad = 0.05 * (hi - lo);
  lo -= pad;
  hi += pad;
  const auto px = [&](double t, double v) {
    return std::array<double, 2>{x + t / std::max(t_end, 1e-12) * w, y + h - (v - lo) / (hi - lo) * h};
  };
  text(cr, x, y - 10.0, c.title, 13.0, kInk, 0.0, true);
  // Grid and ticks.
  cairo_set_line_width(cr, 0.6);
  const double ys = tick_step(hi - lo);
  for (double v = std::ceil(lo / ys) * ys; v <= hi; v += ys) {
    const auto p = px(0.0, v);
    set_colour(cr, kGrey, 0.3);
    cairo_move_to(cr, x, p[1]);
    cairo_line_to(cr, x + w, p[1]);
    cairo_stroke(cr);
    text(cr, x - 6.0, p[1] + 4.0, format::general(std::abs(v) < 1e-12 * ys ? 0.0 : v), 10.0, kInk, 1.0);
  }
  const double ts = tick_step(t_end);
  for (double t = 0.0; t <= t_end * (1 + 1e-9); t += ts) {
    const auto p = px(t, lo);
    set_colour(cr, kGrey, 0.3);
    cairo_move_to(cr, p[0], y);
    cairo_line_to(cr, p[0], y + h);
    cairo_stroke(cr);
    text(cr, p[0], y + h + 14.0, format::general(t), 10.0, kInk, 0.5);
  }
  set_colour(cr, kInk);
  cairo_set_line_width(cr, 1.0);
  cairo_rectangle(cr, x, y, w, h);
  cairo_stroke(cr);
  text(cr, x + w, y + h + 30.0, "time (s)", 11.0, kInk, 1.0);
  // y label, rotated.
  cairo_save(cr);
  cairo_translate(cr, x - c.y_label_gap, y + 0.5 * h);
  cairo_rotate(cr, -0.5 * std::numbers::pi);
  text(cr, 0.0, 0.0, c.y_label, 11.0, kInk, 0.5);
  cairo_restore(cr);
  // Lines, clipped to the frame.
  const double dash[2] = {5.0, 3.0};
  cairo_save(cr);
  cairo_rectangle(cr, x, y, w, h);
  cairo_clip(cr);
  for (const Line& l : lines) {
    if (l.points.empty()) continue;
    set_colour(cr, l.colour, 0.95);
    cairo_set_line_width(cr, l.width);
    if (l.dashed) cairo_set_dash(cr, dash, 2, 0.0);
    bool first = true;
    for (const auto& p : l.points) {
      if (!std::isfinite(p.second)) {
        first = true;  // a gap, not a line to nowhere
        continue;
      }
      const auto q = px(p.first, p.second);
      if (first) cairo_move_to(cr, q[0], q[1]);
      else cairo_line_to(cr, q[0], q[1]);
      first = false;
    }
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0.0);
  }
  cairo_restore(cr);
  // Legend along the top right, inside the frame.
  double lx = x + w - 8.0;
  for (auto it = lines.rbegin(); it != lines.rend(); ++it) {
    if (it->points.empty()) continue;
    const double tw = text_width(cr, it->label, 10.0);
    lx -= tw + 34.0;
    set_colour(cr, it->colour);
    cairo_set_line_width(cr, it->width);
    if (it->dashed) cairo_set_dash(cr, dash, 2, 0.0);
    cairo_move_to(cr, lx, y + 14.0);
    cairo_line_to(cr, lx + 22.0, y + 14.0);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0.0);
    text(cr, lx + 26.0, y + 18.0, it->label, 10.0, kInk);
  }
}

}  // namespace fivebar::plot
