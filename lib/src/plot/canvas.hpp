#pragma once
// The one place where a cairo drawing becomes bytes (private to lib/src/plot/): every picture is
// drawn by a function of a cairo_t*, once onto an SVG surface and once onto a PNG image of the same
// size, and every cairo error becomes an exception naming what was being drawn.

#include <cairo-svg.h>
#include <cairo.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "fivebar/rendered_plot.hpp"

namespace fivebar::plot_detail {

/// cairo_write_func_t: appends the bytes to the std::string passed as `closure`.
inline cairo_status_t append(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

/// Throws std::runtime_error("cairo: <what>: <cairo's message>") unless `status` is success.
inline void check(cairo_status_t status, const char* what) {
  if (status != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error(std::string("cairo: ") + what + ": " + cairo_status_to_string(status));
  }
}

/// How a picture's surfaces are made.
struct Surface {
  double width = 0.0;   ///< SVG size in points, PNG size in pixels (rounded up)
  double height = 0.0;
  bool svg_unit_px = false;                   ///< SVG document unit px instead of pt
  cairo_format_t png_format = CAIRO_FORMAT_ARGB32;
};

/// `draw(cr)` onto an SVG document.
template <class Draw>
std::string draw_svg(const Surface& s, Draw&& draw) {
  std::string out;
  cairo_surface_t* surface = cairo_svg_surface_create_for_stream(append, &out, s.width, s.height);
  if (s.svg_unit_px) cairo_svg_surface_set_document_unit(surface, CAIRO_SVG_UNIT_PX);
  cairo_t* cr = cairo_create(surface);
  draw(cr);
  const cairo_status_t drawn = cairo_status(cr);
  cairo_destroy(cr);
  cairo_surface_finish(surface);
  const cairo_status_t finished = cairo_surface_status(surface);
  cairo_surface_destroy(surface);
  check(drawn, "drawing the SVG");
  check(finished, "finishing the SVG");
  return out;
}

/// `draw(cr)` onto a PNG image.
template <class Draw>
std::string draw_png(const Surface& s, Draw&& draw) {
  cairo_surface_t* surface = cairo_image_surface_create(s.png_format, static_cast<int>(s.width + 0.999999),
                                                        static_cast<int>(s.height + 0.999999));
  cairo_t* cr = cairo_create(surface);
  draw(cr);
  const cairo_status_t drawn = cairo_status(cr);
  cairo_destroy(cr);
  std::string out;
  const cairo_status_t written =
      drawn == CAIRO_STATUS_SUCCESS ? cairo_surface_write_to_png_stream(surface, append, &out) : drawn;
  cairo_surface_destroy(surface);
  check(drawn, "drawing the PNG");
  check(written, "encoding the PNG");
  return out;
}

/// Both formats of one drawing.
template <class Draw>
RenderedPlot draw_both(const Surface& s, Draw&& draw) {
  return {draw_svg(s, draw), draw_png(s, draw)};
}

/// Text at (x, y) in the sans-serif face; `align` 0 left, 0.5 centred, 1 right of x.
inline void text(cairo_t* cr, double x, double y, const std::string& s, double size, double align = 0.0, bool bold = false) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  cairo_text_extents_t e;
  cairo_text_extents(cr, s.c_str(), &e);
  cairo_move_to(cr, x - align * e.width, y);
  cairo_show_text(cr, s.c_str());
}

}  // namespace fivebar::plot_detail
