// Picture of a station's collision map (fivebar/collision.hpp plot_collision_map()).

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "fivebar/format.hpp"
#include "fivebar/collision.hpp"
#include "plot/tactor_canvas.hpp"

namespace fivebar {

namespace {

using namespace tactor_plot;

constexpr double kPanel = 430.0;   // panel width and height, pixels
constexpr double kLeft = 50.0;
constexpr double kTop = 78.0;
constexpr double kGap = 70.0;

using format::fixed;
using format::general;

std::array<double, 4> ellipse_bounds(const Ellipse& e, double pad) {
  const double r = 0.5 * std::max(e.axes.x(), e.axes.y());
  return {e.center.x() - r - pad, e.center.y() - r - pad, e.center.x() + r + pad, e.center.y() + r + pad};
}

/// Square cells of the map's grid, coloured by `colour(i)` (nullopt: skip).
template <class F>
void cells(cairo_t* cr, const Panel& panel, const CollisionMap& map, F colour) {
  const double half = 0.5 * map.spacing_mm;
  for (std::size_t i = 0; i < map.points.size(); ++i) {
    const auto c = colour(i);
    if (!c) continue;
    const auto p0 = panel.px(map.points[i] - Vec2(half, half));
    const auto p1 = panel.px(map.points[i] + Vec2(half, half));
    cairo_rectangle(cr, p0[0], p1[1], p1[0] - p0[0] + 0.3, p0[1] - p1[1] + 0.3);
    set_colour(cr, *c);
    cairo_fill(cr);
  }
}

void ellipse_outline(cairo_t* cr, const Panel& panel, const Ellipse& e) {
  panel.begin();
  ellipse_path(cr, e);
  panel.end();
  const double dash[2] = {6.0, 4.0};
  cairo_set_dash(cr, dash, 2, 0.0);
  set_colour(cr, kInk, 0.85);
  cairo_set_line_width(cr, 1.3);
  cairo_stroke(cr);
  cairo_set_dash(cr, nullptr, 0, 0.0);
}

}  // namespace

RenderedPlot plot_collision_map(const Station& s, const Geometry& g, const CollisionMap& map) {
  if (!s.lower || !s.upper) throw InputError("station " + s.name + ": the collision picture needs both mechanisms");
  const double width = kLeft + 3.0 * kPanel + 2.0 * kGap + 30.0;
  const double height = kTop + kPanel + 120.0;
  Canvas canvas(width, height);
  cairo_t* cr = canvas.cr();

  text(cr, kLeft, 28.0, "Collision map — station " + s.name, 19.0, kInk, 0.0, true);
  std::string summary = std::to_string(map.points.size()) + " tactor positions in the target ellipse (grid " +
                        general(map.spacing_mm) + " mm), " + std::to_string(map.pairs) + " usable pairs: " +
                        fixed(100.0 * map.colliding_fraction, 1) + " % collide (clearance < " +
                        general(g.min_clearance) + " mm).";
  text(cr, kLeft, 50.0, summary, 12.5, kInk);
  std::string sep = map.any_free ? "Closest collision-free pair: " + fixed(map.min_free_separation_mm, 2) + " mm apart" : "No collision-free pair";
  if (map.any_colliding) sep += ";  every pair farther apart than " + fixed(map.max_colliding_separation_mm, 2) + " mm is free.";
  text(cr, kLeft, 67.0, sep, 12.5, kInk);

  // (a) Fraction of lower positions colliding, per upper position.
  {
    const double x0 = kLeft;
    const auto b = ellipse_bounds(map.target, 1.0);
    const Panel panel(cr, x0, kTop + 22.0, kPanel, kPanel - 22.0, b);
    text(cr, x0, kTop + 14.0, "(a) upper tactor here: share of lower positions that collide", 12.0, kInk, 0.0, true);
    cells(cr, panel, map, [&](std::size_t i) -> std::optional<Rgb> {
      if (!map.upper_ok[i]) return kGrey;
      return viridis(map.upper_fraction[i]);
    });
    ellipse_outline(cr, panel, map.target);
    axes(cr, panel, b, 2.0);
    // Colour bar.
    const double by = kTop + kPanel + 30.0;
    for (int k = 0; k < 100; ++k) {
      cairo_rectangle(cr, x0 + 40.0 + 3.0 * k, by, 3.2, 12.0);
      set_colour(cr, viridis(k / 99.0));
      cairo_fill(cr);
    }
    text(cr, x0 + 36.0, by + 10.0, "0 %", 10.0, kInk, 1.0);
    text(cr, x0 + 345.0, by + 10.0, "100 %", 10.0, kInk, 0.0);
    cairo_rectangle(cr, x0 + 40.0, by + 22.0, 12.0, 10.0);
    set_colour(cr, kGrey);
    cairo_fill(cr);
    text(cr, x0 + 58.0, by + 31.0, "not usable by the upper mechanism", 10.0, kInk);
  }

  // (b) Upper tactor at the centre: which lower positions collide, and the priority rule.
  {
    const double x0 = kLeft + kPanel + kGap;
    const auto b = ellipse_bounds(map.target, 1.0);
    const Panel panel(cr, x0, kTop + 22.0, kPanel, kPanel - 22.0, b);
    text(cr, x0, kTop + 14.0, "(b) upper tactor at the centre: lower positions", 12.0, kInk, 0.0, true);
    const Rgb free_colour{0.62, 0.85, 0.62}, hit_colour{0.93, 0.55, 0.52};
    cells(cr, panel, map, [&](std::size_t i) -> std::optional<Rgb> {
      if (map.centre_collides.empty() || map.centre_collides[i] == 2) return Rgb{0.85, 0.85, 0.85};
      return map.centre_collides[i] ? hit_colour : free_colour;
    });
    const Pose centre_up = map.centre_rule.upper;
    if (centre_up.status != Status::unreachable) {
      panel.begin();
      fill_outline(cr, link_outline(*s.upper, centre_up, g), kUpper, 0.45);
      panel.end();
      const auto c = panel.px(centre_up.P);
      cairo_arc(cr, c[0], c[1], 0.5 * g.tactor_diameter * panel.scale(), 0.0, 2.0 * std::numbers::pi);
      set_colour(cr, kUpper, 0.9);
      cairo_set_line_width(cr, 1.5);
      cairo_stroke(cr);
    }
    if (map.centre_rule.status == PriorityStatus::moved) {
      const auto from = panel.px(map.centre_rule.lower_target);
      const auto to = panel.px(map.centre_rule.lower_point);
      cairo_move_to(cr, from[0], from[1]);
      cairo_line_to(cr, to[0], to[1]);
      set_colour(cr, kLower);
      cairo_set_line_width(cr, 2.0);
      cairo_stroke(cr);
      cairo_arc(cr, to[0], to[1], 0.5 * g.tactor_diameter * panel.scale(), 0.0, 2.0 * std::numbers::pi);
      set_colour(cr, kLower, 0.9);
      cairo_stroke(cr);
      cairo_arc(cr, to[0], to[1], 3.0, 0.0, 2.0 * std::numbers::pi);
      cairo_fill(cr);
    }
    ellipse_outline(cr, panel, map.target);
    axes(cr, panel, b, 2.0);
    const double by = kTop + kPanel + 30.0;
    const auto key = [&](double x, const Rgb& c, const std::string& label) {
      cairo_rectangle(cr, x, by, 12.0, 10.0);
      set_colour(cr, c);
      cairo_fill(cr);
      text(cr, x + 17.0, by + 9.0, label, 10.0, kInk);
    };
    key(x0 + 10.0, free_colour, "free");
    key(x0 + 70.0, hit_colour, "collides");
    key(x0 + 150.0, Rgb{0.85, 0.85, 0.85}, "not usable (lower)");
    std::string rule = "priority rule, both targets at the centre: " + std::string(to_string(map.centre_rule.status));
    if (map.centre_rule.status == PriorityStatus::moved) {
      rule += ", lower moved " + fixed(map.centre_rule.moved_mm, 2) + " mm (red)";
    }
    text(cr, x0 + 10.0, by + 30.0, rule, 10.5, kInk);
  }

  // (c) Colliding fraction against the tactor separation.
  {
    const double x0 = kLeft + 2.0 * (kPanel + kGap);
    const double y0 = kTop + 22.0, w = kPanel, h = kPanel - 22.0;
    text(cr, x0, kTop + 14.0, "(c) share of pairs that collide, by tactor separation", 12.0, kInk, 0.0, true);
    const double max_sep = map.bins.empty() ? 1.0 : map.bins.back().hi_mm;
    set_colour(cr, kGrey);
    cairo_set_line_width(cr, 1.0);
    cairo_rectangle(cr, x0 + 0.5, y0 + 0.5, w - 1.0, h - 1.0);
    cairo_stroke(cr);
    const auto X = [&](double mm) { return x0 + w * mm / max_sep; };
    const auto Y = [&](double f) { return y0 + h * (1.0 - f); };
    for (const SeparationBin& bin : map.bins) {
      if (bin.pairs == 0) continue;
      const double f = double(bin.colliding) / double(bin.pairs);
      cairo_rectangle(cr, X(bin.lo_mm) + 0.5, Y(f), X(bin.hi_mm) - X(bin.lo_mm) - 1.0, Y(0.0) - Y(f));
      set_colour(cr, viridis(f));
      cairo_fill(cr);
    }
    for (int k = 0; k <= 4; ++k) {
      const double f = 0.25 * k;
      text(cr, x0 - 4.0, Y(f) + 3.5, (fixed(100.0 * f, 0) + " %"), 10.0, kGrey, 1.0);
    }
    for (double mm = 0.0; mm <= max_sep + 1e-9; mm += 2.0) {
      text(cr, X(mm), y0 + h + 13.0, general(mm), 10.0, kGrey, 0.5);
    }
    text(cr, x0 + 0.5 * w, y0 + h + 28.0, "tactor separation |P_upper - P_lower| (mm)", 11.0, kInk, 0.5);
    const auto vline = [&](double mm, const Rgb& c, const std::string& label, double ty) {
      cairo_move_to(cr, X(mm), y0);
      cairo_line_to(cr, X(mm), y0 + h);
      const double dash[2] = {5.0, 3.0};
      cairo_set_dash(cr, dash, 2, 0.0);
      set_colour(cr, c);
      cairo_set_line_width(cr, 1.5);
      cairo_stroke(cr);
      cairo_set_dash(cr, nullptr, 0, 0.0);
      // Label on the side of the line with room, on a white box so that the bars do not hide it.
      const bool left = X(mm) > x0 + 0.6 * w;
      const double tw = text_width(cr, label, 10.5);
      const double tx = left ? X(mm) - 6.0 - tw : X(mm) + 6.0;
      cairo_rectangle(cr, tx - 3.0, ty - 11.0, tw + 6.0, 15.0);
      cairo_set_source_rgba(cr, 1.0, 1.0, 1.0, 0.9);
      cairo_fill(cr);
      text(cr, tx, ty, label, 10.5, c);
    };
    if (map.any_free) vline(map.min_free_separation_mm, Rgb{0.10, 0.50, 0.20}, "closest free pair " + fixed(map.min_free_separation_mm, 2) + " mm", y0 + h - 30.0);
    if (map.any_colliding) vline(map.max_colliding_separation_mm, kLower, "farthest colliding pair " + fixed(map.max_colliding_separation_mm, 2) + " mm", y0 + 16.0);
  }
  return canvas.render();
}

}  // namespace fivebar
