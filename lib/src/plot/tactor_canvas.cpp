// Cairo canvas shared by the collision-map and pattern pictures (see tactor_canvas.hpp).

#include "plot/tactor_canvas.hpp"
#include "plot/canvas.hpp"

#include "fivebar/format.hpp"

#include <cairo-svg.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

namespace fivebar::tactor_plot {

namespace {

using plot_detail::append;
using plot_detail::check;

}  // namespace

Canvas::Canvas(double width_px, double height_px) : width_(width_px), height_(height_px) {
  const cairo_rectangle_t extents{0.0, 0.0, width_px, height_px};
  surface_ = cairo_recording_surface_create(CAIRO_CONTENT_COLOR_ALPHA, &extents);
  cr_ = cairo_create(surface_);
  cairo_set_source_rgb(cr_, 1.0, 1.0, 1.0);
  cairo_paint(cr_);
  cairo_set_line_join(cr_, CAIRO_LINE_JOIN_ROUND);
}

Canvas::~Canvas() {
  cairo_destroy(cr_);
  cairo_surface_destroy(surface_);
}

RenderedPlot Canvas::render() const {
  check(cairo_status(cr_), "drawing");
  // The picture was recorded once; both formats replay the recording.
  return plot_detail::draw_both({width_, height_}, [this](cairo_t* cr) {
    cairo_set_source_surface(cr, surface_, 0.0, 0.0);
    cairo_paint(cr);
  });
}

Panel::Panel(cairo_t* cr, double x_px, double y_px, double w_px, double h_px, std::array<double, 4> b)
    : cr_(cr), x_(x_px), y_(y_px), w_(w_px), h_(h_px) {
  const double bw = std::max(b[2] - b[0], 1e-9), bh = std::max(b[3] - b[1], 1e-9);
  scale_ = std::min(w_px / bw, h_px / bh);
  ox_ = x_px + 0.5 * (w_px - scale_ * bw) - scale_ * b[0];
  oy_ = y_px + 0.5 * (h_px + scale_ * bh) + scale_ * b[1];
}

std::array<double, 2> Panel::px(const Vec2& p) const { return {ox_ + scale_ * p.x(), oy_ - scale_ * p.y()}; }

void Panel::begin() const {
  cairo_save(cr_);
  cairo_rectangle(cr_, x_, y_, w_, h_);
  cairo_clip(cr_);
  cairo_translate(cr_, ox_, oy_);
  cairo_scale(cr_, scale_, -scale_);
}

void Panel::end() const { cairo_restore(cr_); }

void set_colour(cairo_t* cr, const Rgb& c, double alpha) { cairo_set_source_rgba(cr, c.r, c.g, c.b, alpha); }

void text(cairo_t* cr, double x, double y, std::string_view s, double size, const Rgb& c, double align, bool bold) {
  const std::string str(s);
  cairo_save(cr);
  cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  cairo_text_extents_t ext;
  cairo_text_extents(cr, str.c_str(), &ext);
  set_colour(cr, c);
  cairo_move_to(cr, x - align * ext.x_advance, y);
  cairo_show_text(cr, str.c_str());
  cairo_restore(cr);
}

double text_width(cairo_t* cr, std::string_view s, double size, bool bold) {
  const std::string str(s);
  cairo_save(cr);
  cairo_select_font_face(cr, "DejaVu Sans", CAIRO_FONT_SLANT_NORMAL, bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  cairo_text_extents_t ext;
  cairo_text_extents(cr, str.c_str(), &ext);
  cairo_restore(cr);
  return ext.x_advance;
}

void region_path(cairo_t* cr, const Region& region) {
  for (const BoundaryLoop& loop : region.loops()) {
    bool first = true;
    for (const CurvePiece& piece : loop.pieces) {
      if (first) cairo_move_to(cr, piece.source.x(), piece.source.y());
      first = false;
      if (!piece.is_arc) {
        cairo_line_to(cr, piece.target.x(), piece.target.y());
        continue;
      }
      const double a0 = std::atan2(piece.source.y() - piece.center.y(), piece.source.x() - piece.center.x());
      const double a1 = std::atan2(piece.target.y() - piece.center.y(), piece.target.x() - piece.center.x());
      if (piece.ccw) {
        cairo_arc(cr, piece.center.x(), piece.center.y(), piece.radius, a0, a1);
      } else {
        cairo_arc_negative(cr, piece.center.x(), piece.center.y(), piece.radius, a0, a1);
      }
    }
    cairo_close_path(cr);
  }
}

void ellipse_path(cairo_t* cr, const Ellipse& e) {
  constexpr int kSteps = 180;
  for (int k = 0; k <= kSteps; ++k) {
    const Vec2 p = e.boundary_point(2.0 * std::numbers::pi * k / kSteps);
    if (k == 0) {
      cairo_move_to(cr, p.x(), p.y());
    } else {
      cairo_line_to(cr, p.x(), p.y());
    }
  }
  cairo_close_path(cr);
}

void fill_outline(cairo_t* cr, const std::vector<OutlinePart>& parts, const Rgb& c, double alpha) {
  cairo_push_group(cr);
  set_colour(cr, c, 1.0);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  for (const OutlinePart& part : parts) {
    if (part.name == "tactor") continue;  // drawn by the caller, above everything
    for (int i = 0; i < part.count; ++i) {
      const Capsule& cap = part.shapes[i];
      cairo_set_line_width(cr, 2.0 * cap.radius);
      cairo_move_to(cr, cap.a.x(), cap.a.y());
      cairo_line_to(cr, cap.b.x(), cap.b.y());
      cairo_stroke(cr);
    }
  }
  cairo_pop_group_to_source(cr);
  cairo_paint_with_alpha(cr, alpha);
}

void link_lines(cairo_t* cr, const Mechanism& m, const Pose& pose, const Rgb& c, double width_px, double alpha,
                bool dashed) {
  cairo_move_to(cr, m.O1.x(), m.O1.y());
  cairo_line_to(cr, pose.A1.x(), pose.A1.y());
  cairo_line_to(cr, pose.P.x(), pose.P.y());
  cairo_line_to(cr, pose.A2.x(), pose.A2.y());
  cairo_line_to(cr, m.O2.x(), m.O2.y());
  cairo_save(cr);
  cairo_identity_matrix(cr);
  set_colour(cr, c, alpha);
  cairo_set_line_width(cr, width_px);
  if (dashed) {
    const double dash[2] = {4.0, 3.0};
    cairo_set_dash(cr, dash, 2, 0.0);
  }
  cairo_stroke(cr);
  cairo_restore(cr);
}

void axes(cairo_t* cr, const Panel& panel, std::array<double, 4> b, double step) {
  cairo_save(cr);
  set_colour(cr, kGrey);
  cairo_set_line_width(cr, 1.0);
  cairo_rectangle(cr, panel.x() + 0.5, panel.y() + 0.5, panel.w() - 1.0, panel.h() - 1.0);
  cairo_stroke(cr);
  for (double x = std::ceil(b[0] / step) * step; x <= b[2] + 1e-9; x += step) {
    const auto p = panel.px(Vec2(x, b[1]));
    if (p[0] < panel.x() + 8 || p[0] > panel.x() + panel.w() - 8) continue;
    cairo_move_to(cr, p[0], panel.y() + panel.h());
    cairo_line_to(cr, p[0], panel.y() + panel.h() - 5.0);
    cairo_stroke(cr);
    text(cr, p[0], panel.y() + panel.h() + 13.0, format::general(x), 10.0, kGrey, 0.5);
  }
  for (double y = std::ceil(b[1] / step) * step; y <= b[3] + 1e-9; y += step) {
    const auto p = panel.px(Vec2(b[0], y));
    if (p[1] < panel.y() + 8 || p[1] > panel.y() + panel.h() - 8) continue;
    cairo_move_to(cr, panel.x(), p[1]);
    cairo_line_to(cr, panel.x() + 5.0, p[1]);
    cairo_stroke(cr);
    text(cr, panel.x() - 4.0, p[1] + 3.5, format::general(y), 10.0, kGrey, 1.0);
  }
  cairo_restore(cr);
}

}  // namespace fivebar::tactor_plot
