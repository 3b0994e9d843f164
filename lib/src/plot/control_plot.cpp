// Picture of a station's stability maps (fivebar/control.hpp stability_plot()).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

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
constexpr double kRhoLow = 0.5;   // bottom of the colour scale
constexpr Rgb kUnstable{0.80, 0.10, 0.10};
constexpr Rgb kOutside{0.88, 0.88, 0.88};

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

Rgb rho_colour(double rho) {
  if (rho >= 1.0) return kUnstable;
  return ramp_colour(std::clamp((rho - kRhoLow) / (1.0 - kRhoLow), 0.0, 1.0));
}

}  // namespace

RenderedPlot stability_plot(const Station& station, const std::vector<StabilityMap>& maps,
                            const std::vector<RhoField>& fields, const std::string& subtitle) {
  if (maps.empty() || maps.size() != fields.size()) {
    throw InputError("station " + station.name + ": the stability picture needs one field per map");
  }
  const double n = static_cast<double>(maps.size());
  const double width = kLeft + n * kPanel + (n - 1.0) * kGap + 40.0;
  const double height = kTop + kPanel + 150.0;
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
    const std::array<double, 4> b{g.x0 - 0.5 * g.spacing, g.y0 - 0.5 * g.spacing,
                                  g.x0 + (g.nx - 0.5) * g.spacing, g.y0 + (g.ny - 0.5) * g.spacing};
    const Panel panel(cr, x0, kTop + 22.0, kPanel, kPanel - 22.0, b);
    const Rgb ink = map.mechanism == "upper" ? kUpperColour : kLowerColour;
    text(cr, x0, kTop + 14.0,
         "(" + std::string(1, char('a' + k)) + ") " + map.mechanism + " mechanism: ρ over its reachable region",
         12.0, kInk, 0.0, true);
    const double half = 0.5 * g.spacing;
    for (int j = 0; j < g.ny; ++j) {
      for (int i = 0; i < g.nx; ++i) {
        const std::size_t idx = std::size_t(j) * std::size_t(g.nx) + std::size_t(i);
        const double rho = f.rho[idx];
        if (!std::isfinite(rho)) continue;
        const auto p0 = panel.px(g.point(i, j) - Vec2(half, half));
        const auto p1 = panel.px(g.point(i, j) + Vec2(half, half));
        cairo_rectangle(cr, p0[0], p1[1], p1[0] - p0[0] + 0.3, p0[1] - p1[1] + 0.3);
        set_colour(cr, rho_colour(rho));
        cairo_fill(cr);
      }
    }
    // Target ellipse, dashed.
    panel.begin();
    ellipse_path(cr, station.target);
    panel.end();
    const double dash[2] = {6.0, 4.0};
    cairo_set_dash(cr, dash, 2, 0.0);
    set_colour(cr, kInk, 0.9);
    cairo_set_line_width(cr, 1.4);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0.0);
    // Worst pose on the target.
    if (!map.poses.empty()) {
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
      text(cr, w[0] + 13.0, w[1] - 8.0, "worst ρ = " + fmt("%.3f", map.max_rho), 11.0, kInk, 0.0, true);
    }
    const double span = std::max(b[2] - b[0], b[3] - b[1]);
    axes(cr, panel, b, span > 40.0 ? 10.0 : 5.0);
    // Colour bar and the figures.
    const double by = kTop + kPanel + 28.0;
    for (int c = 0; c < 100; ++c) {
      cairo_rectangle(cr, x0 + 40.0 + 3.0 * c, by, 3.2, 12.0);
      set_colour(cr, rho_colour(kRhoLow + (1.0 - kRhoLow) * c / 100.0));
      cairo_fill(cr);
    }
    cairo_rectangle(cr, x0 + 343.0, by, 20.0, 12.0);
    set_colour(cr, kUnstable);
    cairo_fill(cr);
    text(cr, x0 + 36.0, by + 10.0, "ρ ≤ " + fmt("%.1f", kRhoLow), 10.0, kInk, 1.0);
    text(cr, x0 + 368.0, by + 10.0, "≥ 1 unstable", 10.0, kInk, 0.0);
    (void)kOutside;
    const std::string verdict = map.stable ? "stable over the target" : "UNSTABLE on the target";
    text(cr, x0, by + 34.0,
         verdict + ": max ρ " + fmt("%.4f", map.max_rho) + " at (" + fmt("%.2f", map.worst_P_mm().x()) + ", " +
             fmt("%.2f", map.worst_P_mm().y()) + ") mm over " + std::to_string(map.poses.size() - map.not_ok) +
             " poses",
         11.0, map.stable ? kInk : kUnstable, 0.0, true);
    text(cr, x0, by + 52.0,
         "dominant pole: damping " + fmt("%.3f", map.damping) + ", " + fmt("%.2f", map.frequency_hz) +
             " Hz;  gain margins: kp ×" + fmt("%.3g", map.kp_margin) + ", kd ×" + fmt("%.3g", map.kd_margin),
         11.0, kInk);
    text(cr, x0, by + 70.0, "dashed: target ellipse; blank: unreachable, singular or outside the joint limits", 10.0,
         kGrey);
  }
  return canvas.render();
}

}  // namespace fivebar
