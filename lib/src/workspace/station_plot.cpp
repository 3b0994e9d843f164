// The picture of a station's workspace (fivebar/workspace/plot.hpp), drawn once with cairo onto an
// SVG or an image surface. The only translation unit that speaks cairo.
//
// Everything is drawn in device units (px = pt) through one data -> device map per panel, so that
// line widths and text sizes do not depend on the data's scale. Data arcs become cairo arcs with
// negated angles because the device's y axis points down.
#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "fivebar/error.hpp"
#include "fivebar/workspace/polyline.hpp"
#include "fivebar/workspace/plot.hpp"
#include "fivebar/format.hpp"
#include "plot/canvas.hpp"
#include "plot/style.hpp"

namespace fivebar {

namespace {

constexpr double kPi = std::numbers::pi;
const char* const kFont = "DejaVu Sans";

// Colours: the house style (plot/style.hpp): the paper's Fig. 4 (lower red, upper blue), a green
// target, a purple shared region.
using style::kGridLine;
using style::kLowerInk;
using style::kNoData;
using style::kUpperInk;
constexpr Rgb kLowerFill = style::kLower;
constexpr Rgb kUpperFill = style::kUpper;
constexpr Rgb kSharedInk = style::kShared;
constexpr Rgb kTargetInk = style::kTarget;
constexpr Rgb kText = style::kInk;
constexpr Rgb kAxis = style::kInk;
constexpr double kFillAlpha = 0.24;

bool is_upper(const Mechanism& m) { return m.name == "upper"; }
Rgb fill_of(const Mechanism& m) { return is_upper(m) ? kUpperFill : kLowerFill; }
Rgb ink_of(const Mechanism& m) { return is_upper(m) ? kUpperInk : kLowerInk; }

void set(cairo_t* cr, const Rgb& c, double alpha = 1.0) { cairo_set_source_rgba(cr, c.r, c.g, c.b, alpha); }

using format::fixed;

enum class Align { left, center, right };

/// Text with its anchor at (x, y): horizontal alignment as given, vertically centred on y.
void text(cairo_t* cr, double x, double y, const std::string& s, double size, Align align = Align::left,
          bool bold = false, const Rgb& colour = kText, double rotate = 0.0) {
  cairo_save(cr);
  cairo_select_font_face(cr, kFont, CAIRO_FONT_SLANT_NORMAL, bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  cairo_text_extents_t ext;
  cairo_text_extents(cr, s.c_str(), &ext);
  cairo_font_extents_t fext;
  cairo_font_extents(cr, &fext);
  cairo_translate(cr, x, y);
  cairo_rotate(cr, rotate);
  const double dx = align == Align::left ? 0.0 : align == Align::center ? -ext.x_advance / 2 : -ext.x_advance;
  const double dy = (fext.ascent - fext.descent) / 2;
  cairo_move_to(cr, dx, dy);
  set(cr, colour);
  cairo_show_text(cr, s.c_str());
  cairo_restore(cr);
}

double text_width(cairo_t* cr, const std::string& s, double size, bool bold) {
  cairo_save(cr);
  cairo_select_font_face(cr, kFont, CAIRO_FONT_SLANT_NORMAL, bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  cairo_text_extents_t ext;
  cairo_text_extents(cr, s.c_str(), &ext);
  cairo_restore(cr);
  return ext.x_advance;
}

/// Data (mm) -> device (px) map of one panel: equal scale on both axes, y up.
struct Frame {
  double left = 0, top = 0, width = 0, height = 0;  // plot box, device
  double xmin = 0, ymin = 0, xmax = 1, ymax = 1;    // data box
  double scale = 1;                                  // px per mm
  double x(double vx) const { return left + (vx - xmin) * scale; }
  double y(double vy) const { return top + height - (vy - ymin) * scale; }
  std::array<double, 2> operator()(const Vec2& p) const { return {x(p.x()), y(p.y())}; }
};

/// Fits the data box into the available device box at equal scale, centred.
Frame fit(const std::array<double, 4>& data, double left, double top, double width, double height) {
  Frame f;
  f.xmin = data[0];
  f.ymin = data[1];
  f.xmax = data[2];
  f.ymax = data[3];
  f.scale = std::min(width / (f.xmax - f.xmin), height / (f.ymax - f.ymin));
  f.width = (f.xmax - f.xmin) * f.scale;
  f.height = (f.ymax - f.ymin) * f.scale;
  f.left = left + (width - f.width) / 2;
  f.top = top + (height - f.height) / 2;
  return f;
}


// --- paths ------------------------------------------------------------------------------------

void piece_path(cairo_t* cr, const Frame& f, const CurvePiece& p) {
  if (!p.is_arc) {
    const auto t = f(p.target);
    cairo_line_to(cr, t[0], t[1]);
    return;
  }
  const auto c = f(p.center);
  const Vec2 a = p.source - p.center;
  const double a0 = std::atan2(a.y(), a.x());
  const double a1 = a0 + p.sweep();
  // y flips: a data angle a is the device angle -a, and counter-clockwise becomes clockwise.
  if (a1 >= a0) {
    cairo_arc_negative(cr, c[0], c[1], p.radius * f.scale, -a0, -a1);
  } else {
    cairo_arc(cr, c[0], c[1], p.radius * f.scale, -a0, -a1);
  }
}

void region_path(cairo_t* cr, const Frame& f, const Region& r) {
  for (const BoundaryLoop& loop : r.loops()) {
    if (loop.pieces.empty()) continue;
    const auto s = f(loop.pieces.front().source);
    cairo_move_to(cr, s[0], s[1]);
    for (const CurvePiece& p : loop.pieces) piece_path(cr, f, p);
    cairo_close_path(cr);
  }
}

void ellipse_path(cairo_t* cr, const Frame& f, const Ellipse& e) {
  cairo_save(cr);
  const auto c = f(e.center);
  cairo_translate(cr, c[0], c[1]);
  cairo_rotate(cr, -e.angle);
  cairo_scale(cr, 0.5 * e.axes.x() * f.scale, 0.5 * e.axes.y() * f.scale);
  cairo_new_sub_path(cr);
  cairo_arc(cr, 0.0, 0.0, 1.0, 0.0, 2 * kPi);
  cairo_close_path(cr);
  cairo_restore(cr);
}

/// Diagonal hatching over the current clip (device lines every `gap` px).
void hatch(cairo_t* cr, double x0, double y0, double x1, double y1, double gap, const Rgb& c, double alpha,
           double width) {
  cairo_save(cr);
  cairo_new_path(cr);
  const double h = y1 - y0;
  for (double x = x0 - h; x < x1; x += gap) {
    cairo_move_to(cr, x, y1);
    cairo_line_to(cr, x + h, y0);
  }
  set(cr, c, alpha);
  cairo_set_line_width(cr, width);
  cairo_stroke(cr);
  cairo_restore(cr);
}

// --- pieces of the picture ----------------------------------------------------------------------

void axes(cairo_t* cr, const Frame& f, const std::string& title) {
  // About one labelled tick per 80 px of the longer side; the same step on both (equal) axes.
  const double step = style::tick_step(std::max(f.xmax - f.xmin, f.ymax - f.ymin), std::max(f.width, f.height) / 80.0);
  const int digits = step < 1.0 ? 1 : 0;  // 1-2-5 steps: 0.5, 0.2, 0.1 need one decimal
  cairo_save(cr);
  cairo_set_line_width(cr, 1.0);
  // Grid lines and tick labels.
  for (double v = std::ceil(f.xmin / step) * step; v <= f.xmax + 1e-9 * step; v += step) {
    const double x = f.x(v);
    set(cr, kGridLine);
    cairo_move_to(cr, x, f.top);
    cairo_line_to(cr, x, f.top + f.height);
    cairo_stroke(cr);
    set(cr, kAxis);
    cairo_move_to(cr, x, f.top + f.height);
    cairo_line_to(cr, x, f.top + f.height + 6);
    cairo_stroke(cr);
    text(cr, x, f.top + f.height + 18, fixed(v, digits), 14, Align::center, false, kAxis);
  }
  for (double v = std::ceil(f.ymin / step) * step; v <= f.ymax + 1e-9 * step; v += step) {
    const double y = f.y(v);
    set(cr, kGridLine);
    cairo_move_to(cr, f.left, y);
    cairo_line_to(cr, f.left + f.width, y);
    cairo_stroke(cr);
    set(cr, kAxis);
    cairo_move_to(cr, f.left - 6, y);
    cairo_line_to(cr, f.left, y);
    cairo_stroke(cr);
    text(cr, f.left - 10, y, fixed(v, digits), 14, Align::right, false, kAxis);
  }
  cairo_restore(cr);
  text(cr, f.left + f.width / 2, f.top + f.height + 42, "x (mm)", 15, Align::center, false, kAxis);
  text(cr, f.left - 52, f.top + f.height / 2, "y (mm)", 15, Align::center, false, kAxis, -kPi / 2);
  text(cr, f.left, f.top - 18, title, 17, Align::left, true);
}

void frame_box(cairo_t* cr, const Frame& f) {
  cairo_save(cr);
  cairo_rectangle(cr, f.left, f.top, f.width, f.height);
  set(cr, kAxis);
  cairo_set_line_width(cr, 1.2);
  cairo_stroke(cr);
  cairo_restore(cr);
}

void clip_to_frame(cairo_t* cr, const Frame& f) {
  cairo_rectangle(cr, f.left, f.top, f.width, f.height);
  cairo_clip(cr);
}

void stroke_halo(cairo_t* cr, double width, const Rgb& colour, double alpha = 1.0) {
  // A white halo under the line keeps it legible over fills and the heat map.
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  cairo_set_source_rgba(cr, 1, 1, 1, 0.85);
  cairo_set_line_width(cr, width + 3.0);
  cairo_stroke_preserve(cr);
  set(cr, colour, alpha);
  cairo_set_line_width(cr, width);
  cairo_stroke(cr);
}

void target_outline(cairo_t* cr, const Frame& f, const Ellipse& e, bool fill, const Rgb& ink) {
  cairo_new_path(cr);
  ellipse_path(cr, f, e);
  if (fill) {
    set(cr, kTargetInk, 0.10);
    cairo_fill_preserve(cr);
  }
  stroke_halo(cr, 2.6, ink);
  const auto c = f(e.center);  // centre cross
  cairo_move_to(cr, c[0] - 6, c[1]);
  cairo_line_to(cr, c[0] + 6, c[1]);
  cairo_move_to(cr, c[0], c[1] - 6);
  cairo_line_to(cr, c[0], c[1] + 6);
  set(cr, ink);
  cairo_set_line_width(cr, 1.5);
  cairo_stroke(cr);
}

void joint(cairo_t* cr, double x, double y, double r, const Rgb& ink) {
  cairo_new_path(cr);
  cairo_arc(cr, x, y, r, 0, 2 * kPi);
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_fill_preserve(cr);
  set(cr, ink);
  cairo_set_line_width(cr, 2.0);
  cairo_stroke(cr);
}

/// Ground symbol at a base joint: a filled triangle pointing at the joint from `away` (unit,
/// device) side, with a short hatched base.
void ground(cairo_t* cr, double x, double y, double ax, double ay, const Rgb& ink) {
  const double len = 17, half = 10;
  const double bx = x + ax * len, by = y + ay * len;  // base centre
  const double px = -ay, py = ax;                    // along the base
  cairo_new_path(cr);
  cairo_move_to(cr, x, y);
  cairo_line_to(cr, bx + px * half, by + py * half);
  cairo_line_to(cr, bx - px * half, by - py * half);
  cairo_close_path(cr);
  set(cr, ink, 0.85);
  cairo_fill(cr);
  cairo_set_line_width(cr, 1.4);
  for (int k = -2; k <= 2; ++k) {
    const double sx = bx + px * k * 4.5, sy = by + py * k * 4.5;
    cairo_move_to(cr, sx, sy);
    cairo_line_to(cr, sx + ax * 5 - px * 4, sy + ay * 5 - py * 4);
  }
  cairo_stroke(cr);
}

void linkage(cairo_t* cr, const Frame& f, const MechanismWorkspace& w, const Vec2& toward) {
  const Mechanism& m = w.mechanism;
  const Rgb ink = ink_of(m);
  const auto o1 = f(m.O1), o2 = f(m.O2);
  // Base line O1-O2 (the frame), dashed.
  cairo_save(cr);
  const double dash[] = {6.0, 4.0};
  cairo_set_dash(cr, dash, 2, 0);
  cairo_move_to(cr, o1[0], o1[1]);
  cairo_line_to(cr, o2[0], o2[1]);
  set(cr, kAxis, 0.8);
  cairo_set_line_width(cr, 1.5);
  cairo_stroke(cr);
  cairo_restore(cr);
  // Ground symbols point away from the target.
  const Vec2 mid = 0.5 * (m.O1 + m.O2);
  Vec2 away = mid - toward;
  away = away.norm() > 0 ? Vec2(away.normalized()) : Vec2(0, -1);
  ground(cr, o1[0], o1[1], away.x(), -away.y(), kAxis);
  ground(cr, o2[0], o2[1], away.x(), -away.y(), kAxis);
  const Pose& p = w.centre;
  if (p.status != Status::unreachable) {
    const auto a1 = f(p.A1), a2 = f(p.A2), tp = f(p.P);
    cairo_new_path(cr);
    cairo_move_to(cr, o1[0], o1[1]);
    cairo_line_to(cr, a1[0], a1[1]);
    cairo_line_to(cr, tp[0], tp[1]);
    cairo_line_to(cr, a2[0], a2[1]);
    cairo_line_to(cr, o2[0], o2[1]);
    stroke_halo(cr, 6.0, ink, 0.92);
    joint(cr, a1[0], a1[1], 5.5, ink);
    joint(cr, a2[0], a2[1], 5.5, ink);
    // Tactor: black dot with a white ring.
    cairo_new_path(cr);
    cairo_arc(cr, tp[0], tp[1], 7.5, 0, 2 * kPi);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_fill(cr);
    cairo_arc(cr, tp[0], tp[1], 5.5, 0, 2 * kPi);
    set(cr, kText);
    cairo_fill(cr);
  }
  joint(cr, o1[0], o1[1], 5.5, kAxis);
  joint(cr, o2[0], o2[1], 5.5, kAxis);
}

/// Heat map of the smallest working-mode LCI of the mechanisms where all of them reach; clipped
/// to the exact shared region (or the only region) so that its edge is the exact boundary.
void lci_map(cairo_t* cr, const Frame& f, const StationWorkspace& ws) {
  const Grid& g = ws.grid;
  if (ws.mechanisms.empty() || g.nx < 1 || g.ny < 1) return;
  cairo_surface_t* img = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, g.nx, g.ny);
  const int stride = cairo_image_surface_get_stride(img);
  cairo_surface_flush(img);
  unsigned char* data = cairo_image_surface_get_data(img);
  for (int j = 0; j < g.ny; ++j) {
    auto* row = reinterpret_cast<std::uint32_t*>(data + std::size_t(g.ny - 1 - j) * std::size_t(stride));
    for (int i = 0; i < g.nx; ++i) {
      const std::size_t k = std::size_t(j) * std::size_t(g.nx) + std::size_t(i);
      double v = std::numeric_limits<double>::infinity();
      for (const MechanismWorkspace& w : ws.mechanisms) v = w.field.reach[k] != 0 ? std::min(v, w.field.lci[k]) : -1.0;
      if (v < 0.0) {
        row[i] = 0;  // transparent
        continue;
      }
      const Rgb c = viridis(v);
      auto byte = [](double x) { return std::uint32_t(std::lround(std::clamp(x, 0.0, 1.0) * 255.0)); };
      row[i] = 0xFF000000u | (byte(c.r) << 16) | (byte(c.g) << 8) | byte(c.b);
    }
  }
  // Extend the reached pixels by two into the unreached ones: the exact clip below draws the edge,
  // and bilinear filtering must not blend the border with transparent samples.
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<std::uint32_t> copy(std::size_t(g.nx) * std::size_t(g.ny));
    for (int r = 0; r < g.ny; ++r)
      std::memcpy(&copy[std::size_t(r) * std::size_t(g.nx)], data + std::size_t(r) * std::size_t(stride), std::size_t(g.nx) * 4);
    for (int r = 0; r < g.ny; ++r) {
      auto* row = reinterpret_cast<std::uint32_t*>(data + std::size_t(r) * std::size_t(stride));
      for (int i = 0; i < g.nx; ++i) {
        if (row[i] != 0) continue;
        for (int dr = -1; dr <= 1 && row[i] == 0; ++dr) {
          for (int di = -1; di <= 1; ++di) {
            const int rr = r + dr, ii = i + di;
            if (rr < 0 || rr >= g.ny || ii < 0 || ii >= g.nx) continue;
            const std::uint32_t v = copy[std::size_t(rr) * std::size_t(g.nx) + std::size_t(ii)];
            if (v != 0) {
              row[i] = v;
              break;
            }
          }
        }
      }
    }
  }
  cairo_surface_mark_dirty(img);
  cairo_save(cr);
  cairo_new_path(cr);
  region_path(cr, f, ws.shared ? *ws.shared : ws.mechanisms.front().region);
  cairo_set_fill_rule(cr, CAIRO_FILL_RULE_EVEN_ODD);
  cairo_clip(cr);
  // Nodes sit at pixel centres: pixel (i, ny-1-j) covers node (i, j) +- h/2.
  const double h = g.spacing;
  cairo_translate(cr, f.x(g.x0 - 0.5 * h), f.y(g.y0 + (g.ny - 0.5) * h));
  cairo_scale(cr, h * f.scale, h * f.scale);
  cairo_set_source_surface(cr, img, 0, 0);
  cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_GOOD);
  cairo_paint(cr);
  cairo_restore(cr);
  cairo_surface_destroy(img);
}

void colour_bar(cairo_t* cr, double x, double y, double w, double h) {
  cairo_pattern_t* grad = cairo_pattern_create_linear(0, y + h, 0, y);
  for (int k = 0; k <= 20; ++k) {
    const Rgb c = viridis(k / 20.0);
    cairo_pattern_add_color_stop_rgb(grad, k / 20.0, c.r, c.g, c.b);
  }
  cairo_rectangle(cr, x, y, w, h);
  cairo_set_source(cr, grad);
  cairo_fill_preserve(cr);
  cairo_pattern_destroy(grad);
  set(cr, kAxis);
  cairo_set_line_width(cr, 1.0);
  cairo_stroke(cr);
  for (int k = 0; k <= 5; ++k) {
    const double v = k / 5.0, yy = y + h - v * h;
    cairo_move_to(cr, x + w, yy);
    cairo_line_to(cr, x + w + 5, yy);
    cairo_stroke(cr);
    text(cr, x + w + 9, yy, fixed(v, 1), 13, Align::left, false, kAxis);
  }
  text(cr, x + w + 44, y + 2, "isotropic", 13, Align::left, false, kAxis);
  text(cr, x + w + 44, y + h - 2, "singular", 13, Align::left, false, kAxis);
}

// --- legend ----------------------------------------------------------------------------------

struct Legend {
  cairo_t* cr;
  double x, y;
  double row = 30;

  void swatch_fill(const Rgb& c, const std::string& label) {
    cairo_rectangle(cr, x, y - 9, 34, 18);
    set(cr, c, kFillAlpha + 0.1);
    cairo_fill_preserve(cr);
    set(cr, c);
    cairo_set_line_width(cr, 1.5);
    cairo_stroke(cr);
    next(label);
  }
  void swatch_hatch(const std::string& label) {
    cairo_save(cr);
    cairo_rectangle(cr, x, y - 9, 34, 18);
    cairo_clip(cr);
    hatch(cr, x, y - 9, x + 34, y + 9, 7, kSharedInk, 0.55, 1.4);
    cairo_restore(cr);
    cairo_rectangle(cr, x, y - 9, 34, 18);
    set(cr, kSharedInk);
    cairo_set_line_width(cr, 2.4);
    cairo_stroke(cr);
    next(label);
  }
  void swatch_line(const Rgb& c, double width, bool dashed, const std::string& label) {
    cairo_save(cr);
    if (dashed) {
      const double d[] = {7.0, 4.0};
      cairo_set_dash(cr, d, 2, 0);
    }
    cairo_move_to(cr, x, y);
    cairo_line_to(cr, x + 34, y);
    set(cr, c);
    cairo_set_line_width(cr, width);
    cairo_stroke(cr);
    cairo_restore(cr);
    next(label);
  }
  void swatch_ellipse(const std::string& label) {
    cairo_new_path(cr);
    cairo_save(cr);
    cairo_translate(cr, x + 17, y);
    cairo_scale(cr, 17, 9);
    cairo_arc(cr, 0, 0, 1, 0, 2 * kPi);
    cairo_restore(cr);
    set(cr, kTargetInk, 0.16);
    cairo_fill_preserve(cr);
    set(cr, kTargetInk);
    cairo_set_line_width(cr, 2.6);
    cairo_stroke(cr);
    next(label);
  }
  void swatch_linkage(const Rgb& ink, const std::string& label) {
    cairo_move_to(cr, x + 2, y + 6);
    cairo_line_to(cr, x + 17, y - 6);
    cairo_line_to(cr, x + 32, y + 6);
    set(cr, ink, 0.92);
    cairo_set_line_width(cr, 5.0);
    cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    cairo_stroke(cr);
    cairo_arc(cr, x + 17, y - 6, 4.5, 0, 2 * kPi);
    set(cr, kText);
    cairo_fill(cr);
    next(label);
  }
  void swatch_ground(const std::string& label) {
    ground(cr, x + 17, y - 6, 0, 1, kAxis);
    joint(cr, x + 17, y - 6, 4.5, kAxis);
    next(label);
  }
  void swatch_nodata(const std::string& label) {
    cairo_rectangle(cr, x, y - 9, 34, 18);
    set(cr, kNoData);
    cairo_fill_preserve(cr);
    set(cr, kAxis);
    cairo_set_line_width(cr, 1.0);
    cairo_stroke(cr);
    next(label);
  }
  void heading(const std::string& label) {
    text(cr, x, y, label, 15, Align::left, true);
    y += row;
  }
  void line(const std::string& label, const Rgb& colour = kText, double size = 14) {
    text(cr, x, y, label, size, Align::left, false, colour);
    y += row * 0.8;
  }
  void next(const std::string& label) {
    text(cr, x + 46, y, label, 14);
    y += row;
  }
};

std::string area_text(double a) { return fixed(a, 1) + " mm²"; }

// --- the whole picture -----------------------------------------------------------------------

/// Smallest box holding every point added, then padded by `rel` of its larger side plus `abs` mm.
struct Box {
  std::array<double, 4> b{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                          -std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  void add(const Vec2& p) {
    b[0] = std::min(b[0], p.x());
    b[1] = std::min(b[1], p.y());
    b[2] = std::max(b[2], p.x());
    b[3] = std::max(b[3], p.y());
  }
  void add(const std::array<double, 4>& r) {
    add(Vec2(r[0], r[1]));
    add(Vec2(r[2], r[3]));
  }
  void add(const Ellipse& e) {
    const double ra = 0.5 * std::max(e.axes.x(), e.axes.y());
    add(e.center - Vec2(ra, ra));
    add(e.center + Vec2(ra, ra));
  }
  std::array<double, 4> padded(double rel, double abs) const {
    const double pad = rel * std::max(b[2] - b[0], b[3] - b[1]) + abs;
    return {b[0] - pad, b[1] - pad, b[2] + pad, b[3] + pad};
  }
};

/// Everything: regions, base joints, target.
std::array<double, 4> overview_box(const StationWorkspace& ws) {
  Box box;
  box.add(ws.target);
  for (const MechanismWorkspace& w : ws.mechanisms) {
    box.add(w.mechanism.O1);
    box.add(w.mechanism.O2);
    if (!w.region.empty()) box.add(w.region.bounds());
  }
  return box.padded(0.04, 1.0);
}

/// Where the heat map lives: the shared region (or the only region) and the target.
std::array<double, 4> detail_box(const StationWorkspace& ws) {
  Box box;
  box.add(ws.target);
  const Region* r = ws.shared ? &*ws.shared : ws.mechanisms.size() == 1 ? &ws.mechanisms.front().region : nullptr;
  if (r != nullptr && !r->empty()) box.add(r->bounds());
  return box.padded(0.06, 0.5);
}

/// The parts of restricted-region contours that are not on the exact region's boundary (where
/// they only repeat it, a sampling step inside): the limits that the restriction itself adds.
std::vector<Polyline> off_boundary(const std::vector<Polyline>& lines, const Region& region, double spacing) {
  std::vector<Polyline> out;
  const double near = 1.5 * spacing;
  for (const Polyline& l : lines) {
    const std::size_t n = l.points.size();
    std::vector<bool> keep(n);
    for (std::size_t k = 0; k < n; ++k) keep[k] = region.boundary_distance(l.points[k]) > near;
    if (std::all_of(keep.begin(), keep.end(), [](bool b) { return b; })) {
      out.push_back(l);
      continue;
    }
    // Split into runs of kept points; a closed line's run may wrap around its start.
    const std::size_t start = std::size_t(std::find(keep.begin(), keep.end(), false) - keep.begin());
    Polyline run;
    const std::size_t count = l.closed ? n : n - start;
    for (std::size_t m = 0; m <= count; ++m) {
      const std::size_t k = l.closed ? (start + m) % n : start + m;
      if (m < count && k < n && keep[k]) {
        run.points.push_back(l.points[k]);
        continue;
      }
      if (run.points.size() >= 2) out.push_back(run);
      run.points.clear();
    }
    if (!l.closed) {  // the part before the first dropped point
      Polyline head;
      head.points.assign(l.points.begin(), l.points.begin() + std::ptrdiff_t(start));
      if (head.points.size() >= 2) out.push_back(head);
    }
  }
  return out;
}

void polylines_path(cairo_t* cr, const Frame& f, const std::vector<Polyline>& lines) {
  for (const Polyline& l : lines) {
    if (l.points.size() < 2) continue;
    const auto a = f(l.points.front());
    cairo_move_to(cr, a[0], a[1]);
    for (std::size_t k = 1; k < l.points.size(); ++k) {
      const auto b = f(l.points[k]);
      cairo_line_to(cr, b[0], b[1]);
    }
    if (l.closed) cairo_close_path(cr);
  }
}

void draw(cairo_t* cr, const StationWorkspace& ws, const PlotOptions& opt) {
  const double W = opt.width_px, H = opt.height_px;
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);

  const std::string title = opt.title.empty() ? "Station " + ws.station + ": reachable workspace" : opt.title;
  text(cr, 40, 34, title, 26, Align::left, true);
  if (!opt.subtitle.empty()) text(cr, 40, 66, opt.subtitle, 15, Align::left, false, kAxis);

  // Layout: the overview panel on the left at full height; on the right the LCI panel (zoomed on
  // the shared region) with its colour bar, and the legend and areas under it.
  const double top = 120, bottom = 70, left_margin = 80, gap = 110, right_margin = 30;
  const double panel_h = H - top - bottom;
  Frame fa = fit(overview_box(ws), left_margin, top, 0.5 * W - left_margin, panel_h);
  fa.left = left_margin;  // left-aligned: the free width goes to the right column
  const std::string title_a = "Reachable regions, linkages at the target centre";
  // The right column starts after panel A and after its title (panel A is narrow for tall data).
  const double col = std::max(fa.left + fa.width + gap, fa.left + text_width(cr, title_a, 17, true) + 60);
  const double bar_room = 110;
  Frame fb = fit(detail_box(ws), col, top, W - col - bar_room - right_margin, 0.56 * panel_h);
  fb.left = col;
  fb.top = top;

  // Contours as polylines (marching squares gives one segment per cell), so that dashes run on.
  std::vector<std::vector<Polyline>> assembly, lci;
  for (const MechanismWorkspace& w : ws.mechanisms) {
    assembly.push_back(off_boundary(chain_segments(w.assembly.contours, 1e-6 * ws.grid.spacing), w.region, ws.grid.spacing));
    lci.push_back(off_boundary(chain_segments(w.lci.contours, 1e-6 * ws.grid.spacing), w.region, ws.grid.spacing));
  }
  const double dash[] = {7.0, 4.0};

  // Panel A: regions, shared region, assembly-side limits, target, linkages.
  axes(cr, fa, title_a);
  cairo_save(cr);
  clip_to_frame(cr, fa);
  for (const MechanismWorkspace& w : ws.mechanisms) {
    cairo_new_path(cr);
    region_path(cr, fa, w.region);
    cairo_set_fill_rule(cr, CAIRO_FILL_RULE_EVEN_ODD);
    set(cr, fill_of(w.mechanism), kFillAlpha);
    cairo_fill_preserve(cr);
    set(cr, fill_of(w.mechanism), 0.9);
    cairo_set_line_width(cr, 1.6);
    cairo_stroke(cr);
  }
  if (ws.shared && !ws.shared->empty()) {
    cairo_save(cr);
    cairo_new_path(cr);
    region_path(cr, fa, *ws.shared);
    cairo_set_fill_rule(cr, CAIRO_FILL_RULE_EVEN_ODD);
    cairo_clip(cr);
    hatch(cr, fa.left, fa.top, fa.left + fa.width, fa.top + fa.height, 10, kSharedInk, 0.5, 1.1);
    cairo_restore(cr);
    cairo_new_path(cr);
    region_path(cr, fa, *ws.shared);
    set(cr, kSharedInk);
    cairo_set_line_width(cr, 2.6);
    cairo_stroke(cr);
  }
  for (std::size_t k = 0; k < ws.mechanisms.size(); ++k) {
    cairo_save(cr);
    cairo_set_dash(cr, dash, 2, 0);
    cairo_new_path(cr);
    polylines_path(cr, fa, assembly[k]);
    set(cr, ink_of(ws.mechanisms[k].mechanism));
    cairo_set_line_width(cr, 1.8);
    cairo_stroke(cr);
    cairo_restore(cr);
  }
  target_outline(cr, fa, ws.target, true, kTargetInk);
  for (const MechanismWorkspace& w : ws.mechanisms) linkage(cr, fa, w, ws.target.center);
  cairo_restore(cr);
  frame_box(cr, fa);

  // Panel B: LCI heat map over the shared region.
  const bool several = ws.mechanisms.size() > 1;
  const bool no_shared = several && (!ws.shared || ws.shared->empty());
  axes(cr, fb,
       no_shared ? "LCI: the mechanisms share no region"
                 : several ? "LCI = 1/cond(J) where both reach (the smaller)" : "LCI = 1/cond(J) in the working mode");
  cairo_save(cr);
  clip_to_frame(cr, fb);
  cairo_rectangle(cr, fb.left, fb.top, fb.width, fb.height);
  set(cr, kNoData);
  cairo_fill(cr);
  if (!no_shared) lci_map(cr, fb, ws);
  for (std::size_t k = 0; k < ws.mechanisms.size(); ++k) {
    const MechanismWorkspace& w = ws.mechanisms[k];
    cairo_new_path(cr);
    region_path(cr, fb, w.region);
    set(cr, fill_of(w.mechanism), 0.9);
    cairo_set_line_width(cr, 1.6);
    cairo_stroke(cr);
    cairo_save(cr);
    cairo_set_dash(cr, dash, 2, 0);
    cairo_new_path(cr);
    polylines_path(cr, fb, w.mechanism.min_lci > 0.0 ? lci[k] : assembly[k]);
    set(cr, ink_of(w.mechanism));
    cairo_set_line_width(cr, 1.8);
    cairo_stroke(cr);
    cairo_restore(cr);
  }
  if (ws.shared && !ws.shared->empty()) {
    cairo_new_path(cr);
    region_path(cr, fb, *ws.shared);
    set(cr, kSharedInk);
    cairo_set_line_width(cr, 2.4);
    cairo_stroke(cr);
  }
  target_outline(cr, fb, ws.target, false, kText);
  for (const MechanismWorkspace& w : ws.mechanisms) {
    if (w.centre.status == Status::unreachable) continue;
    const auto p = fb(w.centre.P);
    cairo_new_path(cr);
    cairo_arc(cr, p[0], p[1], 7.0, 0, 2 * kPi);
    cairo_set_source_rgb(cr, 1, 1, 1);
    cairo_fill(cr);
    cairo_arc(cr, p[0], p[1], 5.0, 0, 2 * kPi);
    set(cr, kText);
    cairo_fill(cr);
  }
  cairo_restore(cr);
  frame_box(cr, fb);
  const double bx = fb.left + fb.width + 24;
  text(cr, bx, fb.top - 18, "LCI", 17, Align::left, true);
  colour_bar(cr, bx, fb.top, 24, fb.height);

  // Legend and areas under panel B, in two columns.
  const double ly = fb.top + fb.height + 80;
  Legend lg{cr, col, ly};
  lg.heading("Legend");
  for (const MechanismWorkspace& w : ws.mechanisms) lg.swatch_fill(fill_of(w.mechanism), w.mechanism.name + " mechanism: reachable region");
  if (ws.shared) lg.swatch_hatch("shared region: both tactors reach");
  for (const MechanismWorkspace& w : ws.mechanisms)
    lg.swatch_line(ink_of(w.mechanism), 1.8, true,
                   w.mechanism.name + ": limit of the assembly side" +
                       (w.mechanism.min_lci > 0.0 ? " (right: of LCI ≥ " + fixed(w.mechanism.min_lci, 2) + ")" : ""));
  lg.swatch_ellipse("target fingertip ellipse");
  for (const MechanismWorkspace& w : ws.mechanisms) {
    lg.swatch_linkage(ink_of(w.mechanism), w.centre.status == Status::unreachable
                                               ? w.mechanism.name + " linkage: target centre unreachable"
                                               : w.mechanism.name + " linkage and tactor");
  }
  lg.swatch_ground("base joint (motor)");
  lg.swatch_nodata(several ? "LCI panel: not reached by both" : "LCI panel: not reached");

  Legend ar{cr, col + 0.55 * (W - col - right_margin), ly};
  ar.heading("Exact areas");
  for (const MechanismWorkspace& w : ws.mechanisms) {
    ar.line(w.mechanism.name + ": " + area_text(w.region.area_mm2()), ink_of(w.mechanism));
  }
  if (ws.shared) ar.line("shared: " + area_text(ws.shared->area_mm2()), kSharedInk);
  ar.y += 10;
  ar.heading("Assembly side (sampled)");
  for (const MechanismWorkspace& w : ws.mechanisms) {
    ar.line(w.mechanism.name + ": " + fixed(w.assembly.area_mm2, 1) + " ± " + fixed(w.assembly.error_mm2, 2) +
                " mm²",
            ink_of(w.mechanism));
  }
  ar.y += 10;
  ar.heading("Target");
  const Ellipse& e = ws.target;
  ar.line(fixed(e.axes.x(), 1) + " × " + fixed(e.axes.y(), 1) + " mm at (" + fixed(e.center.x(), 2) +
              ", " + fixed(e.center.y(), 2) + ")",
          kTargetInk);
}

using plot_detail::append;
using plot_detail::check;

}  // namespace

void PlotOptions::validate() const {
  auto ok = [](int v) { return v >= 200 && v <= 8000; };
  if (!ok(width_px) || !ok(height_px)) {
    throw InputError("picture size " + std::to_string(width_px) + " x " + std::to_string(height_px) +
                     " px: each side must be in [200, 8000]");
  }
}


namespace {
plot_detail::Surface surface_of(const PlotOptions& o) {
  return {double(o.width_px), double(o.height_px), /*svg_unit_px=*/true, CAIRO_FORMAT_ARGB32};
}
}  // namespace

std::string station_svg(const StationWorkspace& ws, const PlotOptions& options) {
  options.validate();
  return plot_detail::draw_svg(surface_of(options), [&](cairo_t* cr) { draw(cr, ws, options); });
}

std::string station_png(const StationWorkspace& ws, const PlotOptions& options) {
  options.validate();
  return plot_detail::draw_png(surface_of(options), [&](cairo_t* cr) { draw(cr, ws, options); });
}

}  // namespace fivebar
