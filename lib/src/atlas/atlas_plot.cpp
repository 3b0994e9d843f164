// Picture of a performance atlas (fivebar/atlas.hpp plot_atlas()): one panel per figure of merit
// over the design triangle, its colour bar, and the station marked.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <numbers>
#include <string>

#include "fivebar/format.hpp"
#include "fivebar/atlas.hpp"
#include "plot/tactor_canvas.hpp"

namespace fivebar {

namespace {

using namespace tactor_plot;

constexpr double kSqrt3 = 1.7320508075688772;
constexpr double kPanelW = 400.0;  // panel width, pixels
constexpr double kPanelH = 350.0;
constexpr double kLeft = 40.0;
constexpr double kTop = 96.0;
constexpr double kGap = 50.0;
constexpr Rgb kNoWorkspace{0.86, 0.86, 0.86};
constexpr Rgb kStation{0.95, 0.20, 0.55};

using format::fixed;
using format::general;

struct Figure {
  std::string title, unit;
  std::function<double(const InscribedTarget&)> value;
};

void triangle_path(cairo_t* cr, const Panel& panel) {
  const auto a = panel.px(Vec2(-kSqrt3, 0.0));
  const auto b = panel.px(Vec2(kSqrt3, 0.0));
  const auto c = panel.px(Vec2(0.0, 3.0));
  cairo_move_to(cr, a[0], a[1]);
  cairo_line_to(cr, b[0], b[1]);
  cairo_line_to(cr, c[0], c[1]);
  cairo_close_path(cr);
}

}  // namespace

RenderedPlot plot_atlas(const Atlas& atlas, const std::string& subtitle) {
  const std::vector<Figure> figures = {
      {"(a) inscribed target s* (semi-major, units of D)", "D", [](const InscribedTarget& f) { return f.scale; }},
      {"(b) min LCI over " + fixed(atlas.options.fraction, 2) + " s*", "",
       [](const InscribedTarget& f) { return f.min_lci; }},
      {"(c) min |sin| tactor angle over " + fixed(atlas.options.fraction, 2) + " s*", "",
       [](const InscribedTarget& f) { return f.min_transmission_sin; }},
  };
  const double n = double(figures.size());
  const double width = kLeft + n * kPanelW + (n - 1.0) * kGap + 30.0;
  const double height = kTop + kPanelH + 140.0;
  Canvas canvas(width, height);
  cairo_t* cr = canvas.cr();
  const AtlasOptions& o = atlas.options;
  text(cr, kLeft, 28.0, "Performance atlas of the symmetric five-bar", 19.0, kInk, 0.0, true);
  text(cr, kLeft, 48.0,
       "D = (L1 + L3 + b) / 3, r1 = L1/D, r2 = L3/D, r3 = b/D (b: base spacing), r1 + r2 + r3 = 3; designs of one "
       "shape and different sizes are one point.",
       11.5, kInk);
  text(cr, kLeft, 64.0,
       "Target: aspect " + fixed(o.shape.aspect, 3) + ", major axis at " +
           fixed(o.shape.angle * format::kDegPerRad, 1) +
           " deg to the base line, centred on the symmetry axis at its best height; working mode " +
           to_string(o.working_mode) + ", assembly " + to_string(o.assembly_mode) + ", no joint limits.",
       11.5, kInk);
  const std::string grid = std::to_string(atlas.cells.size() - atlas.count(AtlasStatus::outside)) + " designs";
  text(cr, kLeft, 80.0, subtitle.empty() ? grid : subtitle + " — " + grid, 11.0, kGrey);

  const std::array<double, 4> bounds{-kSqrt3 - 0.12, -0.22, kSqrt3 + 0.12, 3.12};
  for (std::size_t k = 0; k < figures.size(); ++k) {
    const Figure& fig = figures[k];
    const double x0 = kLeft + double(k) * (kPanelW + kGap);
    const Panel panel(cr, x0, kTop + 20.0, kPanelW, kPanelH - 20.0, bounds);
    text(cr, x0, kTop + 12.0, fig.title, 12.0, kInk, 0.0, true);
    // Colour scale: 0 to the largest value over the designs with a workspace.
    double hi = 0.0;
    const AtlasCell* top = nullptr;
    for (const AtlasCell& c : atlas.cells) {
      if (c.figures.status != AtlasStatus::ok) continue;
      const double v = fig.value(c.figures);
      if (std::isfinite(v) && (!top || v > hi)) hi = v, top = &c;
    }
    const auto colour = [&](double v) { return viridis(hi > 0.0 ? v / hi : 0.0); };
    // Designs whose inscribed target is smaller than the station's own target are veiled.
    const double veil = atlas.station ? atlas.station->target_scale : 0.0;
    // The cells as one raster (one pixel per cell, drawn nearest), clipped to the triangle.
    if (atlas.nx > 0 && atlas.ny > 0) {
      cairo_surface_t* img = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, atlas.nx, atlas.ny);
      cairo_surface_flush(img);
      unsigned char* data = cairo_image_surface_get_data(img);
      const int stride = cairo_image_surface_get_stride(img);
      const auto byte = [](double v) { return std::uint32_t(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); };
      const auto cell_colour = [&](const AtlasCell& c) {
        Rgb rgb = c.figures.status == AtlasStatus::ok ? colour(fig.value(c.figures)) : kNoWorkspace;
        if (veil > 0.0 && c.figures.status == AtlasStatus::ok && c.figures.scale < veil) {
          rgb = {0.55 * rgb.r + 0.45, 0.55 * rgb.g + 0.45, 0.55 * rgb.b + 0.45};
        }
        return rgb;
      };
      for (int j = 0; j < atlas.ny; ++j) {
        auto* row = reinterpret_cast<std::uint32_t*>(data + std::ptrdiff_t(atlas.ny - 1 - j) * stride);
        for (int i = 0; i < atlas.nx; ++i) {
          // A cell off the triangle takes its row's nearest design (the raster is clipped to the
          // triangle, whose edges cut through cells): no gaps along the edges.
          int from = -1;
          for (int d = 0; d < atlas.nx && from < 0; ++d) {
            for (int q : {i - d, i + d})
              if (from < 0 && q >= 0 && q < atlas.nx && atlas.at(q, j).figures.status != AtlasStatus::outside) from = q;
          }
          const Rgb rgb = from < 0 ? kNoWorkspace : cell_colour(atlas.at(from, j));
          row[i] = 0xFF000000u | (byte(rgb.r) << 16) | (byte(rgb.g) << 8) | byte(rgb.b);
        }
      }
      cairo_surface_mark_dirty(img);
      const auto top_left = panel.px(Vec2(atlas.x0 - 0.5 * atlas.spacing, atlas.y0 + (atlas.ny - 0.5) * atlas.spacing));
      const double cell = atlas.spacing * panel.scale();
      cairo_save(cr);
      triangle_path(cr, panel);
      cairo_clip(cr);
      cairo_translate(cr, top_left[0], top_left[1]);
      cairo_scale(cr, cell, cell);
      cairo_set_source_surface(cr, img, 0.0, 0.0);
      cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
      cairo_rectangle(cr, 0.0, 0.0, atlas.nx, atlas.ny);
      cairo_fill(cr);
      cairo_restore(cr);
      cairo_surface_destroy(img);
    }
    // The triangle, the line r3 = 2 (no overlap of the legs' annuli above it), the vertices.
    triangle_path(cr, panel);
    set_colour(cr, kInk);
    cairo_set_line_width(cr, 1.2);
    cairo_stroke(cr);
    {
      const auto a = panel.px(Vec2(-0.5 * kSqrt3 * 1.0, 2.0));
      const auto b = panel.px(Vec2(0.5 * kSqrt3 * 1.0, 2.0));
      const double dash[2] = {4.0, 3.0};
      cairo_set_dash(cr, dash, 2, 0.0);
      cairo_move_to(cr, a[0], a[1]);
      cairo_line_to(cr, b[0], b[1]);
      set_colour(cr, kGrey);
      cairo_set_line_width(cr, 1.0);
      cairo_stroke(cr);
      cairo_set_dash(cr, nullptr, 0, 0.0);
      text(cr, b[0] + 6.0, b[1] + 4.0, "r3 = 2", 9.5, kGrey);
    }
    {
      const auto a = panel.px(Vec2(-kSqrt3, 0.0));
      const auto b = panel.px(Vec2(kSqrt3, 0.0));
      const auto c = panel.px(Vec2(0.0, 3.0));
      text(cr, a[0], a[1] + 15.0, "r1 = 3 (proximal)", 10.0, kInk, 0.0);
      text(cr, b[0], b[1] + 15.0, "r2 = 3 (distal)", 10.0, kInk, 1.0);
      text(cr, c[0] + 8.0, c[1] + 4.0, "r3 = 3 (base)", 10.0, kInk, 0.0);
    }
    // Best cell and the station.
    if (top) {
      const auto p = panel.px(top->chart);
      cairo_new_path(cr);
      cairo_arc(cr, p[0], p[1], 5.0, 0.0, 2.0 * std::numbers::pi);
      set_colour(cr, Rgb{1.0, 1.0, 1.0});
      cairo_set_line_width(cr, 2.0);
      cairo_stroke(cr);
    }
    if (atlas.station) {
      const AtlasStation& s = *atlas.station;
      const auto p = panel.px(s.chart);
      cairo_new_path(cr);
      cairo_set_line_width(cr, 3.6);
      set_colour(cr, Rgb{1.0, 1.0, 1.0}, 0.9);
      cairo_move_to(cr, p[0] - 7, p[1] - 7);
      cairo_line_to(cr, p[0] + 7, p[1] + 7);
      cairo_move_to(cr, p[0] - 7, p[1] + 7);
      cairo_line_to(cr, p[0] + 7, p[1] - 7);
      cairo_stroke(cr);
      cairo_set_line_width(cr, 2.0);
      set_colour(cr, kStation);
      cairo_move_to(cr, p[0] - 7, p[1] - 7);
      cairo_line_to(cr, p[0] + 7, p[1] + 7);
      cairo_move_to(cr, p[0] - 7, p[1] + 7);
      cairo_line_to(cr, p[0] + 7, p[1] - 7);
      cairo_stroke(cr);
      const bool ok = s.figures.status == AtlasStatus::ok;
      const std::string label = s.station + (ok ? ": " + fixed(fig.value(s.figures), 3) : ": none");
      const double tw = text_width(cr, label, 11.0, true);
      cairo_rectangle(cr, p[0] + 9.0, p[1] - 20.0, tw + 6.0, 16.0);
      set_colour(cr, Rgb{1.0, 1.0, 1.0}, 0.85);
      cairo_fill(cr);
      text(cr, p[0] + 12.0, p[1] - 8.0, label, 11.0, kInk, 0.0, true);
    }
    // Other designs on top (add_mark()).
    for (const AtlasMark& m : atlas.marks) {
      const auto p = panel.px(m.chart);
      cairo_new_path(cr);
      cairo_move_to(cr, p[0], p[1] - 7.0);
      cairo_line_to(cr, p[0] + 7.0, p[1]);
      cairo_line_to(cr, p[0], p[1] + 7.0);
      cairo_line_to(cr, p[0] - 7.0, p[1]);
      cairo_close_path(cr);
      set_colour(cr, Rgb{1.0, 1.0, 1.0});
      cairo_fill_preserve(cr);
      set_colour(cr, kInk);
      cairo_set_line_width(cr, 1.6);
      cairo_stroke(cr);
      const bool ok = m.figures.status == AtlasStatus::ok;
      const std::string label = m.label + (ok ? ": " + fixed(fig.value(m.figures), 3) : ": none");
      const double tw = text_width(cr, label, 10.5, false);
      cairo_rectangle(cr, p[0] + 9.0, p[1] + 2.0, tw + 6.0, 15.0);
      set_colour(cr, Rgb{1.0, 1.0, 1.0}, 0.85);
      cairo_fill(cr);
      text(cr, p[0] + 12.0, p[1] + 13.0, label, 10.5, kInk);
    }
    // Colour bar and the figures.
    const double by = kTop + kPanelH + 14.0;
    for (int c = 0; c < 100; ++c) {
      cairo_rectangle(cr, x0 + 40.0 + 2.6 * c, by, 2.8, 12.0);
      set_colour(cr, colour(hi * c / 99.0));
      cairo_fill(cr);
    }
    cairo_rectangle(cr, x0 + 310.0, by, 16.0, 12.0);
    set_colour(cr, kNoWorkspace);
    cairo_fill(cr);
    text(cr, x0 + 36.0, by + 10.0, "0", 10.0, kInk, 1.0);
    text(cr, x0 + 300.0, by + 24.0, fixed(hi, 4), 10.0, kInk, 1.0);
    text(cr, x0 + 330.0, by + 10.0, "no workspace", 10.0, kInk, 0.0);
    if (top) {
      text(cr, x0, by + 42.0,
           "best " + fixed(hi, 4) + " (circle) at (r1, r2, r3) = (" + fixed(top->point.r1, 3) + ", " +
               fixed(top->point.r2, 3) + ", " + fixed(top->point.r3, 3) + ")",
           11.0, kInk);
    }
    if (atlas.station) {
      const AtlasStation& s = *atlas.station;
      const bool ok = s.figures.status == AtlasStatus::ok;
      text(cr, x0, by + 60.0,
           "station " + s.station + " (cross): " + (ok ? fixed(fig.value(s.figures), 4) : std::string("no workspace")),
           11.0, kInk, 0.0, true);
      if (k == 0) {
        text(cr, x0, by + 78.0,
             "at (r1, r2, r3) = (" + fixed(s.point.r1, 3) + ", " + fixed(s.point.r2, 3) + ", " +
                 fixed(s.point.r3, 3) + "), D = " + fixed(s.point.D_mm, 2) + " mm",
             10.5, kInk);
        if (ok) {
          text(cr, x0, by + 96.0,
               "its own target: " + fixed(s.target_scale, 4) + " D (" +
                   fixed(100.0 * s.target_scale / s.figures.scale, 1) + " % of s*); s* = " +
                   fixed(s.figures.scale * s.point.D_mm, 2) + " mm, limited by the " + s.figures.limited_by,
               10.5, kInk);
        }
        text(cr, x0, by + 114.0,
             "veiled: designs whose s* is below the station's target (" + fixed(s.target_scale, 4) + " D)", 10.0,
             kGrey);
      } else {
        text(cr, x0, by + 78.0,
             std::string("over its own target: ") + (k == 1 ? "min LCI " : "") +
                 fixed(k == 1 ? s.target_min_lci : s.target_min_transmission_sin, 4),
             10.5, kInk);
        // The best design that holds the station's target.
        const AtlasCell* held = nullptr;
        for (const AtlasCell& c : atlas.cells) {
          if (c.figures.status != AtlasStatus::ok || c.figures.scale < s.target_scale) continue;
          if (!held || fig.value(c.figures) > fig.value(held->figures)) held = &c;
        }
        if (held) {
          text(cr, x0, by + 96.0,
               "best holding its target: " + fixed(fig.value(held->figures), 4) + " at (" +
                   fixed(held->point.r1, 3) + ", " + fixed(held->point.r2, 3) + ", " +
                   fixed(held->point.r3, 3) + ")",
               10.5, kInk);
        }
      }
    } else if (!atlas.station_note.empty() && k == 0) {
      text(cr, x0, by + 60.0, atlas.station_note, 10.0, kGrey);
    }
  }
  return canvas.render();
}

}  // namespace fivebar
