#pragma once
// A small cairo canvas for the pictures of the studies (collision, pattern, simulate, control,
// tolerance, identify, atlas) (private to lib; cairo stays in
// lib/src/plot/). Drawing goes to a recording surface that render() replays into SVG and PNG
// bytes; panels map millimetres (y up) to pixels with equal aspect.

#include <cairo.h>

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/collision.hpp"
#include "fivebar/workspace/region.hpp"
#include "plot/style.hpp"

namespace fivebar::tactor_plot {

// Colours, the colour map and the tick rule are the house style's (plot/style.hpp).
using namespace fivebar::style;

/// Whole picture: a white page of width x height pixels.
class Canvas {
 public:
  Canvas(double width_px, double height_px);
  ~Canvas();
  Canvas(const Canvas&) = delete;
  Canvas& operator=(const Canvas&) = delete;
  cairo_t* cr() const { return cr_; }
  double width() const { return width_; }
  double height() const { return height_; }
  /// Replays the drawing into SVG and PNG bytes.
  RenderedPlot render() const;

 private:
  double width_, height_;
  cairo_surface_t* surface_;
  cairo_t* cr_;
};

/// A rectangle of the page showing [xmin, xmax] x [ymin, ymax] mm with equal aspect, centred.
class Panel {
 public:
  Panel(cairo_t* cr, double x_px, double y_px, double w_px, double h_px, std::array<double, 4> bounds_mm);
  /// Page pixels of a station point.
  std::array<double, 2> px(const Vec2& p) const;
  double scale() const { return scale_; }  ///< pixels per mm
  /// Sets cairo's matrix to millimetres (y up) and clips to the panel; end() restores.
  void begin() const;
  void end() const;
  double x() const { return x_; }
  double y() const { return y_; }
  double w() const { return w_; }
  double h() const { return h_; }

 private:
  cairo_t* cr_;
  double x_, y_, w_, h_;
  double scale_, ox_, oy_;  ///< page = (ox + s x, oy - s y)
};

void set_colour(cairo_t* cr, const Rgb& c, double alpha = 1.0);
/// Text with its left baseline (align 0), centre (0.5) or right end (1) at (x, y) page pixels.
void text(cairo_t* cr, double x, double y, std::string_view s, double size, const Rgb& c, double align = 0.0,
          bool bold = false);
/// Width in pixels of `s` as text() draws it.
double text_width(cairo_t* cr, std::string_view s, double size, bool bold = false);
/// Adds the region's boundary loops (mm) to the current path; call inside Panel::begin/end.
void region_path(cairo_t* cr, const Region& region);
/// Adds the filled ellipse's outline (mm) to the current path.
void ellipse_path(cairo_t* cr, const Ellipse& e);
/// Fills the outline's capsules of the planes in [plane_lo, plane_hi] as one translucent layer (mm space).
void fill_outline(cairo_t* cr, const std::vector<OutlinePart>& parts, const Rgb& c, double alpha);
/// Strokes the centre lines of the four links (mm space; width in pixels).
void link_lines(cairo_t* cr, const Mechanism& m, const Pose& pose, const Rgb& c, double width_px, double alpha,
                bool dashed);
/// Axis ticks and labels (mm) along the panel's bottom and left edges.
void axes(cairo_t* cr, const Panel& panel, std::array<double, 4> bounds_mm, double step_mm);

}  // namespace fivebar::tactor_plot
