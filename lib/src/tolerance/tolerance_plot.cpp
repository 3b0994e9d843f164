// Picture of a station's tolerance maps (fivebar/tolerance.hpp plot_tolerance()): per mechanism,
// the 3-sigma tactor error over the target with error ellipses at a grid of poses, and the
// extent of the clearance play set.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <numbers>

#include "fivebar/format.hpp"
#include "fivebar/error.hpp"
#include "fivebar/tolerance.hpp"
#include "plot/tactor_canvas.hpp"

namespace fivebar {

namespace {

using namespace tactor_plot;

constexpr double kPanel = 400.0;  // panel width and height, pixels
constexpr double kLeft = 56.0;
constexpr double kTop = 70.0;
constexpr double kGap = 80.0;
constexpr double kRow = kPanel + 126.0;

using format::fixed;
using format::general;

std::array<double, 4> ellipse_bounds(const Ellipse& e, double pad) {
  const double r = 0.5 * std::max(e.axes.x(), e.axes.y());
  return {e.center.x() - r - pad, e.center.y() - r - pad, e.center.x() + r + pad, e.center.y() + r + pad};
}

/// The map's cells inside `bounds`, coloured by value / top on the ramp (grey where not ok): one
/// image pixel per cell, scaled with nearest-neighbour sampling, so that neighbouring cells meet
/// without seams (in PNG and SVG alike), and clipped to the bounds the axes frame.
void cells(cairo_t* cr, const Panel& panel, const ToleranceMap& map, const std::vector<double>& values, double top,
           const std::array<double, 4>& b) {
  const double sp = map.spacing_mm;
  const auto index_range = [sp](double lo, double hi, double origin, int n) {
    const int first = std::max(0, static_cast<int>(std::floor((lo - origin) / sp)) - 1);
    const int last = std::min(n - 1, static_cast<int>(std::ceil((hi - origin) / sp)) + 1);
    return std::array<int, 2>{first, last};
  };
  const auto [i0, i1] = index_range(b[0], b[2], map.x0, map.nx);
  const auto [j0, j1] = index_range(b[1], b[3], map.y0, map.ny);
  if (i1 < i0 || j1 < j0) return;
  const int w = i1 - i0 + 1, h = j1 - j0 + 1;
  cairo_surface_t* image = cairo_image_surface_create(CAIRO_FORMAT_RGB24, w, h);
  if (cairo_surface_status(image) != CAIRO_STATUS_SUCCESS) {
    cairo_surface_destroy(image);
    return;
  }
  cairo_surface_flush(image);
  unsigned char* data = cairo_image_surface_get_data(image);
  const int stride = cairo_image_surface_get_stride(image);
  const auto byte = [](double v) { return static_cast<std::uint32_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); };
  for (int j = j0; j <= j1; ++j) {
    // Image rows run downwards, the station's y upwards.
    auto* row = reinterpret_cast<std::uint32_t*>(data + static_cast<std::ptrdiff_t>(stride) * (j1 - j));
    for (int i = i0; i <= i1; ++i) {
      const std::size_t k = static_cast<std::size_t>(j) * static_cast<std::size_t>(map.nx) + static_cast<std::size_t>(i);
      const Rgb c = map.field_status[k] != static_cast<std::uint8_t>(Status::ok) ? Rgb{0.88, 0.88, 0.88}
                                                                                 : viridis(top > 0.0 ? values[k] / top : 0.0);
      row[i - i0] = (byte(c.r) << 16) | (byte(c.g) << 8) | byte(c.b);
    }
  }
  cairo_surface_mark_dirty(image);
  const double half = 0.5 * sp;
  const auto corner_lo = panel.px(Vec2(map.x0 + sp * i0 - half, map.y0 + sp * j0 - half));  // lower left
  const auto corner_hi = panel.px(Vec2(map.x0 + sp * i1 + half, map.y0 + sp * j1 + half));  // upper right
  const auto frame_lo = panel.px(Vec2(b[0], b[1]));
  const auto frame_hi = panel.px(Vec2(b[2], b[3]));
  cairo_save(cr);
  cairo_rectangle(cr, frame_lo[0], frame_hi[1], frame_hi[0] - frame_lo[0], frame_lo[1] - frame_hi[1]);
  cairo_clip(cr);
  cairo_translate(cr, corner_lo[0], corner_hi[1]);
  cairo_scale(cr, (corner_hi[0] - corner_lo[0]) / w, (corner_lo[1] - corner_hi[1]) / h);
  cairo_set_source_surface(cr, image, 0.0, 0.0);
  cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
  cairo_paint(cr);
  cairo_restore(cr);
  cairo_surface_destroy(image);
}

void ellipse_outline(cairo_t* cr, const Panel& panel, const Ellipse& e) {
  panel.begin();
  ellipse_path(cr, e);
  panel.end();
  const double dash[2] = {6.0, 4.0};
  cairo_set_dash(cr, dash, 2, 0.0);
  set_colour(cr, Rgb{1.0, 1.0, 1.0}, 0.95);
  cairo_set_line_width(cr, 1.6);
  cairo_stroke(cr);
  cairo_set_dash(cr, nullptr, 0, 0.0);
}

void colour_bar(cairo_t* cr, double x0, double y, double top, const std::string& unit) {
  for (int k = 0; k < 100; ++k) {
    cairo_rectangle(cr, x0 + 40.0 + 2.6 * k, y, 2.8, 11.0);
    set_colour(cr, viridis(k / 99.0));
    cairo_fill(cr);
  }
  text(cr, x0 + 36.0, y + 10.0, "0", 10.0, kInk, 1.0);
  text(cr, x0 + 306.0, y + 10.0, general(top, 3) + " " + unit, 10.0, kInk, 0.0);
}

}  // namespace

RenderedPlot plot_tolerance(const Station& s, const std::vector<ToleranceMap>& maps) {
  if (maps.empty()) throw InputError("station " + s.name + ": no tolerance map to draw");
  const double width = kLeft + 2.0 * kPanel + kGap + 40.0;
  const double height = kTop + kRow * static_cast<double>(maps.size()) + 10.0;
  Canvas canvas(width, height);
  cairo_t* cr = canvas.cr();
  text(cr, kLeft, 28.0, "Manufacturing tolerance and sensing error — station " + s.name, 19.0, kInk, 0.0, true);
  text(cr, kLeft, 50.0,
       "Where the printed device's tactor can be when the controller believes it is at the nominal point "
       "(first order, 3 sigma; play: the exact clearance set).",
       12.0, kInk);
  for (std::size_t r = 0; r < maps.size(); ++r) {
    const ToleranceMap& map = maps[r];
    const double y0 = kTop + kRow * static_cast<double>(r);
    const auto b = ellipse_bounds(map.target, 1.5);
    // (a) 3-sigma error with error ellipses.
    {
      const double x0 = kLeft;
      double top = 0.0;
      for (std::size_t k = 0; k < map.field_3sigma_mm.size(); ++k) {
        const Vec2 p(map.x0 + map.spacing_mm * static_cast<double>(k % static_cast<std::size_t>(map.nx)),
                     map.y0 + map.spacing_mm * static_cast<double>(k / static_cast<std::size_t>(map.nx)));
        if (p.x() >= b[0] && p.x() <= b[2] && p.y() >= b[1] && p.y() <= b[3]) top = std::max(top, map.field_3sigma_mm[k]);
      }
      const Panel panel(cr, x0, y0 + 30.0, kPanel, kPanel - 30.0, b);
      text(cr, x0, y0 + 14.0, "(" + std::string(1, char('a' + 2 * r)) + ") " + map.mechanism +
                                  ": 3-sigma tactor error (mm) and its ellipses, true scale",
           12.0, kInk, 0.0, true);
      cells(cr, panel, map, map.field_3sigma_mm, top, b);
      ellipse_outline(cr, panel, map.target);
      // Error ellipses at a 6 x 6 sub-grid of the target grid (every fourth of its 21 per axis).
      const double magnify = 1.0;
      const double ca = std::cos(map.target.angle), sa = std::sin(map.target.angle);
      for (std::size_t k = 0; k < map.target_points_mm.size(); ++k) {
        const ToleranceEstimate& e = map.target_estimates[k];
        if (e.status != Status::ok) continue;
        const Vec2 d = map.target_points_mm[k] - map.target.center;
        const double u = 20.0 * (ca * d.x() + sa * d.y()) / map.target.axes.x();   // grid index - 10
        const double v = 20.0 * (-sa * d.x() + ca * d.y()) / map.target.axes.y();
        const long iu = std::lround(u + 10.0), iv = std::lround(v + 10.0);
        if (iu % 4 != 0 || iv % 4 != 0) continue;
        const auto c = panel.px(map.target_points_mm[k]);
        cairo_save(cr);
        cairo_translate(cr, c[0], c[1]);
        cairo_rotate(cr, -e.ellipse_angle);
        const double ax = std::max(0.3, magnify * e.ellipse_semi_axes.x() * panel.scale());
        const double ay = std::max(0.3, magnify * e.ellipse_semi_axes.y() * panel.scale());
        cairo_scale(cr, ax, ay);
        cairo_arc(cr, 0.0, 0.0, 1.0, 0.0, 2.0 * std::numbers::pi);
        cairo_restore(cr);
        set_colour(cr, Rgb{1.0, 1.0, 1.0}, 0.9);
        cairo_set_line_width(cr, 1.0);
        cairo_stroke(cr);
      }
      const auto w = panel.px(map.worst_3sigma_at);
      cairo_arc(cr, w[0], w[1], 4.0, 0.0, 2.0 * std::numbers::pi);
      set_colour(cr, kLower);
      cairo_fill(cr);
      // Where the first order is not to be trusted (near_singular): black crosses.
      for (const auto& f : map.near_singular) {
        const auto c = panel.px(f.at);
        cairo_move_to(cr, c[0] - 4.0, c[1] - 4.0);
        cairo_line_to(cr, c[0] + 4.0, c[1] + 4.0);
        cairo_move_to(cr, c[0] - 4.0, c[1] + 4.0);
        cairo_line_to(cr, c[0] + 4.0, c[1] - 4.0);
        set_colour(cr, kInk);
        cairo_set_line_width(cr, 1.6);
        cairo_stroke(cr);
      }
      axes(cr, panel, b, 2.0);
      colour_bar(cr, x0, y0 + kPanel + 28.0, top, "mm");
      text(cr, x0 + 40.0, y0 + kPanel + 56.0,
           "worst over the target " + fixed(map.worst_3sigma_mm, 3) + " mm first order (red dot); worst case " +
               fixed(map.worst_case_mm, 3) + " mm nonlinear (first order " + fixed(map.worst_case_first_order_mm, 3) + ")",
           10.5, kInk);
      if (!map.near_singular.empty()) {
        double mc = 0.0;
        for (const auto& f : map.near_singular) mc = std::max(mc, f.monte_carlo_3sigma_mm);
        text(cr, x0 + 40.0, y0 + kPanel + 88.0,
             std::to_string(map.near_singular.size()) + " points near singular (x): first order not trusted; Monte Carlo "
                 "3-sigma there up to " + fixed(mc, 3) + " mm",
             10.5, kInk);
      }
      text(cr, x0 + 40.0, y0 + kPanel + 72.0,
           "robust margin " + fixed(map.robust.robust_margin_mm, 3) + " mm at " +
               fixed(100.0 * map.robust.fraction, 1) + " % of printed devices (first order)" +
               (map.robust.samples > 0 ? "; Monte Carlo " + fixed(100.0 * map.robust.fraction_monte_carlo, 2) + " % cover" : std::string()),
           10.5, kInk);
    }
    // (b) Play set extent.
    {
      const double x0 = kLeft + kPanel + kGap;
      double top = 0.0;
      for (std::size_t k = 0; k < map.field_play_mm.size(); ++k) {
        const Vec2 p(map.x0 + map.spacing_mm * static_cast<double>(k % static_cast<std::size_t>(map.nx)),
                     map.y0 + map.spacing_mm * static_cast<double>(k / static_cast<std::size_t>(map.nx)));
        if (p.x() >= b[0] && p.x() <= b[2] && p.y() >= b[1] && p.y() <= b[3]) top = std::max(top, map.field_play_mm[k]);
      }
      const Panel panel(cr, x0, y0 + 30.0, kPanel, kPanel - 30.0, b);
      text(cr, x0, y0 + 14.0,
           "(" + std::string(1, char('b' + 2 * r)) + ") " + map.mechanism + ": play of the joints' clearances (mm)",
           12.0, kInk, 0.0, true);
      cells(cr, panel, map, map.field_play_mm, top, b);
      ellipse_outline(cr, panel, map.target);
      const auto w = panel.px(map.worst_play_at);
      cairo_arc(cr, w[0], w[1], 4.0, 0.0, 2.0 * std::numbers::pi);
      set_colour(cr, kLower);
      cairo_fill(cr);
      axes(cr, panel, b, 2.0);
      colour_bar(cr, x0, y0 + kPanel + 28.0, top, "mm");
      text(cr, x0 + 40.0, y0 + kPanel + 56.0,
           "largest play over the target " + fixed(map.worst_play_mm, 3) + " mm (red dot); at the centre " +
               fixed(map.centre_play.extent_mm, 3) + " mm",
           10.5, kInk);
      text(cr, x0 + 40.0, y0 + kPanel + 72.0, "grey: unreachable or singular (no estimate)", 10.5, kInk);
    }
  }
  return canvas.render();
}

}  // namespace fivebar
