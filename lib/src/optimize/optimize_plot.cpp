// Pictures of an optimisation (lib/src/optimize/optimize_plot.hpp), in the house style of the sweep's.
#include "optimize/optimize_plot.hpp"

#include <cairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "plot/canvas.hpp"
#include "plot/style.hpp"

namespace fivebar::detail {

namespace {

constexpr double kWidth = 900, kHeight = 600;

using plot_detail::text;
using style::tick_step;
std::string fmt(double v) { return style::tick_label(v); }

}  // namespace

RenderedPlot hypervolume_plot(const std::vector<std::pair<std::uint64_t, double>>& curve, const std::string& title) {
  const double x0 = 90, y0 = 60, x1 = kWidth - 40, y1 = kHeight - 80;
  double xmax = 1, ymax = 0;
  for (const auto& [e, h] : curve) {
    xmax = std::max(xmax, double(e));
    ymax = std::max(ymax, h);
  }
  if (!(ymax > 0)) ymax = 1;
  ymax *= 1.05;
  auto px = [&](double x) { return x0 + x / xmax * (x1 - x0); };
  auto py = [&](double y) { return y1 - y / ymax * (y1 - y0); };
  return plot_detail::draw_both({kWidth, kHeight}, [&](cairo_t* cr) {
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    cairo_set_line_width(cr, 1.0);
    cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
    const double sx = tick_step(xmax), sy = tick_step(ymax);
    for (double x = 0; x <= xmax; x += sx) {
      cairo_move_to(cr, px(x), y0);
      cairo_line_to(cr, px(x), y1);
    }
    for (double y = 0; y <= ymax; y += sy) {
      cairo_move_to(cr, x0, py(y));
      cairo_line_to(cr, x1, py(y));
    }
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
    cairo_rectangle(cr, x0, y0, x1 - x0, y1 - y0);
    cairo_stroke(cr);
    for (double x = 0; x <= xmax; x += sx) text(cr, px(x), y1 + 18, fmt(x), 12, 0.5);
    for (double y = 0; y <= ymax; y += sy) text(cr, x0 - 8, py(y) + 4, fmt(y), 12, 1.0);
    text(cr, 0.5 * (x0 + x1), kHeight - 30, "candidates evaluated", 14, 0.5);
    cairo_save(cr);
    cairo_translate(cr, 24, 0.5 * (y0 + y1));
    cairo_rotate(cr, -M_PI / 2);
    text(cr, 0, 0, "hypervolume of the front (normalised objectives)", 14, 0.5);
    cairo_restore(cr);
    text(cr, 0.5 * (x0 + x1), 34, title, 17, 0.5, true);
    cairo_set_source_rgb(cr, 0.12, 0.47, 0.71);
    cairo_set_line_width(cr, 2.0);
    for (std::size_t i = 0; i < curve.size(); ++i) {
      const double x = px(double(curve[i].first)), y = py(curve[i].second);
      if (i == 0) cairo_move_to(cr, x, y);
      else cairo_line_to(cr, x, y);
    }
    cairo_stroke(cr);
    for (const auto& [e, h] : curve) {
      cairo_new_sub_path(cr);
      cairo_arc(cr, px(double(e)), py(h), 3, 0, 2 * M_PI);
    }
    cairo_fill(cr);
  });
}

RenderedPlot parallel_coordinates_plot(const std::vector<ParallelAxis>& axes, const std::vector<std::vector<double>>& rows,
                                       int chosen, const std::vector<double>& reference, const std::string& title,
                                       std::size_t colour_axis) {
  const double x0 = 70, y0 = 80, x1 = kWidth - 150, y1 = kHeight - 110;
  const std::size_t n = axes.size();
  auto ax = [&](std::size_t i) { return n > 1 ? x0 + double(i) / double(n - 1) * (x1 - x0) : 0.5 * (x0 + x1); };
  auto ay = [&](std::size_t i, double v) {
    const double lo = axes[i].lo, hi = axes[i].hi;
    const double t = hi > lo ? (v - lo) / (hi - lo) : 0.5;
    return y1 - std::clamp(t, -0.05, 1.05) * (y1 - y0);
  };
  auto line = [&](cairo_t* cr, const std::vector<double>& r) {
    bool pen = false;
    for (std::size_t i = 0; i < n && i < r.size(); ++i) {
      if (!std::isfinite(r[i])) {
        pen = false;
        continue;
      }
      if (!pen) cairo_move_to(cr, ax(i), ay(i, r[i]));
      else cairo_line_to(cr, ax(i), ay(i, r[i]));
      pen = true;
    }
    cairo_stroke(cr);
  };
  return plot_detail::draw_both({kWidth, kHeight}, [&](cairo_t* cr) {
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_paint(cr);
    text(cr, 0.5 * (x0 + x1), 34, title, 17, 0.5, true);
    // Front points, coloured by their value on the colour axis (blue to yellow).
    cairo_set_line_width(cr, 1.2);
    const std::size_t ci = std::min(colour_axis, n - 1);
    for (std::size_t k = 0; k < rows.size(); ++k) {
      if (int(k) == chosen) continue;
      const double lo = axes[ci].lo, hi = axes[ci].hi;
      const double t = ci < rows[k].size() && hi > lo && std::isfinite(rows[k][ci]) ? std::clamp((rows[k][ci] - lo) / (hi - lo), 0.0, 1.0) : 0.5;
      cairo_set_source_rgba(cr, 0.2 + 0.6 * t, 0.4 + 0.3 * t, 0.8 - 0.6 * t, 0.55);
      line(cr, rows[k]);
    }
    if (!reference.empty()) {
      const double dash[] = {6.0, 4.0};
      cairo_set_dash(cr, dash, 2, 0);
      cairo_set_line_width(cr, 2.0);
      cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
      line(cr, reference);
      cairo_set_dash(cr, nullptr, 0, 0);
    }
    if (chosen >= 0 && std::size_t(chosen) < rows.size()) {
      cairo_set_line_width(cr, 3.5);
      cairo_set_source_rgb(cr, 0.84, 0.15, 0.16);
      line(cr, rows[std::size_t(chosen)]);
    }
    // Axes with their ranges.
    cairo_set_line_width(cr, 1.0);
    for (std::size_t i = 0; i < n; ++i) {
      cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
      cairo_move_to(cr, ax(i), y0);
      cairo_line_to(cr, ax(i), y1);
      cairo_stroke(cr);
      text(cr, ax(i), y0 - 8, fmt(axes[i].hi), 11, 0.5);
      text(cr, ax(i), y1 + 16, fmt(axes[i].lo), 11, 0.5);
      cairo_save(cr);
      cairo_translate(cr, ax(i) + 4, y1 + 28);
      cairo_rotate(cr, M_PI / 7);
      text(cr, 0, 0, axes[i].label, 12, 0.0);
      cairo_restore(cr);
    }
    // Legend.
    const double ly = kHeight - 18;
    cairo_set_line_width(cr, 3.5);
    cairo_set_source_rgb(cr, 0.84, 0.15, 0.16);
    cairo_move_to(cr, x0, ly - 4);
    cairo_line_to(cr, x0 + 30, ly - 4);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    text(cr, x0 + 36, ly, "chosen", 12);
    const double dash[] = {6.0, 4.0};
    cairo_set_dash(cr, dash, 2, 0);
    cairo_set_line_width(cr, 2.0);
    cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
    cairo_move_to(cr, x0 + 110, ly - 4);
    cairo_line_to(cr, x0 + 140, ly - 4);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0);
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    text(cr, x0 + 146, ly, "design as given", 12);
    cairo_set_line_width(cr, 1.2);
    cairo_set_source_rgba(cr, 0.2, 0.4, 0.8, 0.8);
    cairo_move_to(cr, x0 + 270, ly - 4);
    cairo_line_to(cr, x0 + 300, ly - 4);
    cairo_stroke(cr);
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    text(cr, x0 + 306, ly, "Pareto front (" + std::to_string(rows.size()) + " designs)", 12);
  });
}

}  // namespace fivebar::detail
