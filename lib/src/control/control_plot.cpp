// Picture of a station's stability maps (fivebar/control.hpp stability_plot()).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>

#include "fivebar/format.hpp"
#include "fivebar/control.hpp"
#include "fivebar/error.hpp"
#include "plot/tactor_canvas.hpp"

namespace fivebar {

namespace {

using namespace tactor_plot;

constexpr double kPanel = 470.0;  // panel width and height, pixels
constexpr double kLeft = 50.0;
constexpr double kTop = 92.0;
constexpr double kGap = 70.0;
constexpr Rgb kUnstable{0.80, 0.10, 0.10};
constexpr Rgb kOutside{0.88, 0.88, 0.88};

using format::fixed;
using format::general;

/// The colour scale: [lo, hi] of the finite rho below 1 over every field (one scale for the
/// picture), red at and above 1.
struct Scale {
  double lo = 0.0, hi = 1.0;
  Rgb operator()(double rho) const {
    if (rho >= 1.0) return kUnstable;
    return viridis(hi > lo ? std::clamp((rho - lo) / (hi - lo), 0.0, 1.0) : 1.0);
  }
};

}  // namespace

RenderedPlot stability_plot(const Station& station, const std::vector<StabilityMap>& maps,
                            const std::vector<RhoField>& fields, const std::string& subtitle) {
  if (maps.empty() || maps.size() != fields.size()) {
    throw InputError("station " + station.name + ": the stability picture needs one field per map");
  }
  const double n = static_cast<double>(maps.size());
  const double width = kLeft + n * kPanel + (n - 1.0) * kGap + 40.0;
  const double height = kTop + kPanel + 150.0;
  Scale colour{1.0, 0.0};
  for (const RhoField& f : fields) {
    for (double r : f.rho) {
      if (!std::isfinite(r) || r >= 1.0) continue;
      colour.lo = std::min(colour.lo, r);
      colour.hi = std::max(colour.hi, r);
    }
  }
  if (colour.lo > colour.hi) colour = {0.0, 1.0};
  Canvas canvas(width, height);
  cairo_t* cr = canvas.cr();
  text(cr, kLeft, 28.0, "Loop stability — station " + station.name, 19.0, kInk, 0.0, true);
  text(cr, kLeft, 50.0,
       "Spectral radius ρ of the sampled loop (ZOH plant linearised at each pose, skin in stick, PID with one "
       "period of delay); ρ < 1 is stable.",
       12.5, kInk);
  if (!subtitle.empty()) text(cr, kLeft, 68.0, subtitle, 12.0, kGrey);

  for (std::size_t k = 0; k < maps.size(); ++k) {
    const StabilityMap& map = maps[k];
    const RhoField& f = fields[k];
    const double x0 = kLeft + double(k) * (kPanel + kGap);
    const Grid& g = f.grid;
    std::array<double, 4> b{g.x0 - 0.5 * g.spacing, g.y0 - 0.5 * g.spacing, g.x0 + (g.nx - 0.5) * g.spacing,
                            g.y0 + (g.ny - 0.5) * g.spacing};
    if (g.nx == 0 || g.ny == 0) {  // nothing reachable: the target's box
      const double r = 0.5 * std::max(station.target.axes.x(), station.target.axes.y()) + 1.0;
      b = {station.target.center.x() - r, station.target.center.y() - r, station.target.center.x() + r,
           station.target.center.y() + r};
    }
    const Panel panel(cr, x0, kTop + 22.0, kPanel, kPanel - 22.0, b);
    const Rgb ink = map.mechanism == "upper" ? kUpper : kLower;
    text(cr, x0, kTop + 14.0,
         "(" + std::string(1, char('a' + k)) + ") " + map.mechanism + " mechanism: ρ over its reachable region",
         12.0, kInk, 0.0, true);
    // The field as one raster (one pixel per grid point, drawn nearest): an SVG stays small.
    if (g.nx > 0 && g.ny > 0) {
      cairo_surface_t* img = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, g.nx, g.ny);
      cairo_surface_flush(img);
      unsigned char* data = cairo_image_surface_get_data(img);
      const int stride = cairo_image_surface_get_stride(img);
      for (int j = 0; j < g.ny; ++j) {
        auto* row = reinterpret_cast<std::uint32_t*>(data + std::ptrdiff_t(g.ny - 1 - j) * stride);
        for (int i = 0; i < g.nx; ++i) {
          const double rho = f.rho[std::size_t(j) * std::size_t(g.nx) + std::size_t(i)];
          if (!std::isfinite(rho)) {
            row[i] = 0u;  // transparent
            continue;
          }
          const Rgb c = colour(rho);
          const auto byte = [](double v) { return std::uint32_t(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); };
          row[i] = 0xFF000000u | (byte(c.r) << 16) | (byte(c.g) << 8) | byte(c.b);
        }
      }
      cairo_surface_mark_dirty(img);
      const auto top_left = panel.px(Vec2(b[0], b[3]));
      const double cell = g.spacing * panel.scale();
      cairo_save(cr);
      cairo_rectangle(cr, panel.x(), panel.y(), panel.w(), panel.h());
      cairo_clip(cr);
      cairo_translate(cr, top_left[0], top_left[1]);
      cairo_scale(cr, cell, cell);
      cairo_set_source_surface(cr, img, 0.0, 0.0);
      cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
      cairo_rectangle(cr, 0.0, 0.0, g.nx, g.ny);
      cairo_fill(cr);
      cairo_restore(cr);
      cairo_surface_destroy(img);
    }
    // Target ellipse, dashed.
    panel.begin();
    ellipse_path(cr, station.target);
    panel.end();
    set_colour(cr, Rgb{1.0, 1.0, 1.0}, 0.9);  // a halo: the ramp's dark end is behind it
    cairo_set_line_width(cr, 3.4);
    cairo_stroke_preserve(cr);
    const double dash[2] = {6.0, 4.0};
    cairo_set_dash(cr, dash, 2, 0.0);
    set_colour(cr, kInk, 0.9);
    cairo_set_line_width(cr, 1.4);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0.0);
    // Worst pose on the target.
    if (map.poses.size() > map.not_ok) {
      const auto w = panel.px(map.worst_P_mm());
      cairo_set_line_width(cr, 2.2);
      set_colour(cr, kInk);
      cairo_move_to(cr, w[0] - 7, w[1] - 7);
      cairo_line_to(cr, w[0] + 7, w[1] + 7);
      cairo_move_to(cr, w[0] - 7, w[1] + 7);
      cairo_line_to(cr, w[0] + 7, w[1] - 7);
      cairo_stroke(cr);
      cairo_arc(cr, w[0], w[1], 10.0, 0.0, 2.0 * std::numbers::pi);
      set_colour(cr, ink);
      cairo_stroke(cr);
      const std::string label = "worst ρ = " + fixed(map.max_rho, 4);
      const double tw = text_width(cr, label, 11.0, true);
      cairo_rectangle(cr, w[0] + 10.0, w[1] - 21.0, tw + 6.0, 17.0);
      set_colour(cr, Rgb{1.0, 1.0, 1.0}, 0.85);
      cairo_fill(cr);
      text(cr, w[0] + 13.0, w[1] - 8.0, label, 11.0, kInk, 0.0, true);
    }
    const double span = std::max(b[2] - b[0], b[3] - b[1]);
    axes(cr, panel, b, span > 40.0 ? 10.0 : 5.0);
    // Colour bar and the figures.
    const double by = kTop + kPanel + 28.0;
    for (int c = 0; c < 100; ++c) {
      cairo_rectangle(cr, x0 + 40.0 + 3.0 * c, by, 3.2, 12.0);
      set_colour(cr, colour(colour.lo + (colour.hi - colour.lo) * c / 99.0));
      cairo_fill(cr);
    }
    cairo_rectangle(cr, x0 + 343.0, by, 20.0, 12.0);
    set_colour(cr, kUnstable);
    cairo_fill(cr);
    text(cr, x0 + 36.0, by + 10.0, fixed(colour.lo, 4), 10.0, kInk, 1.0);
    text(cr, x0 + 340.0, by + 24.0, fixed(colour.hi, 4), 10.0, kInk, 1.0);
    text(cr, x0 + 368.0, by + 10.0, "≥ 1 unstable", 10.0, kInk, 0.0);
    (void)kOutside;
    const std::string verdict = map.stable ? "stable over the target" : "UNSTABLE on the target";
    text(cr, x0, by + 34.0,
         verdict + ": max ρ " + fixed(map.max_rho, 4) + " at (" + fixed(map.worst_P_mm().x(), 2) + ", " +
             fixed(map.worst_P_mm().y(), 2) + ") mm over " + std::to_string(map.poses.size() - map.not_ok) +
             " poses",
         11.0, map.stable ? kInk : kUnstable, 0.0, true);
    text(cr, x0, by + 52.0,
         "dominant pole: damping " + fixed(map.damping, 3) + ", " + fixed(map.frequency_hz, 2) +
             " Hz; least-damped oscillation: " + fixed(map.oscillatory_damping, 3) + " at " +
             fixed(map.oscillatory_frequency_hz, 2) + " Hz",
         11.0, kInk);
    text(cr, x0, by + 70.0,
         "gain margins (factor keeping max ρ < 1): kp ×" + general(map.kp_margin, 3) + ", kd ×" +
             general(map.kd_margin, 3),
         11.0, kInk);
    text(cr, x0, by + 88.0, "dashed: target ellipse; blank: unreachable, singular or outside the joint limits", 10.0,
         kGrey);
  }
  return canvas.render();
}

}  // namespace fivebar
