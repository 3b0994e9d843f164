// Work-precision plots with cairo (SVG and PNG surfaces, written to memory).
#include "plot/work_precision_plot.hpp"
#include "plot/canvas.hpp"
#include "plot/style.hpp"

#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <initializer_list>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace fivebar::plot {

namespace {

constexpr double kWidth = 1100, kHeight = 680;
constexpr double kLeft = 100, kRight = 770, kTop = 60, kBottom = 590;  // plot area
constexpr double kLegendX = 790;

using style::Rgb;
constexpr const Rgb (&kPalette)[10] = style::kSeries;  // the house style's series colours

struct Axis {
  double lo, hi;  ///< log10 range, whole decades
  double to_px(double v, double p0, double p1) const { return p0 + (std::log10(v) - lo) / (hi - lo) * (p1 - p0); }
};

Axis make_axis(double vmin, double vmax) {
  if (!(vmin > 0) || !(vmax > 0)) return {0.0, 1.0};
  double lo = std::floor(std::log10(vmin)), hi = std::ceil(std::log10(vmax));
  if (hi - lo < 1) hi = lo + 1;
  if (std::log10(vmin) - lo < 0.05) lo -= 1;  // keep points off the frame
  if (hi - std::log10(vmax) < 0.05) hi += 1;
  return {lo, hi};
}

std::string decade_label(int k) {
  if (k == 0) return "1";
  if (k == 1) return "10";
  char buf[16];
  std::snprintf(buf, sizeof buf, "1e%d", k);
  return buf;
}

void polygon(cairo_t* cr, double x, double y, std::initializer_list<std::pair<double, double>> pts) {
  bool first = true;
  for (const auto& [px, py] : pts) {
    if (first) {
      cairo_move_to(cr, x + px, y + py);
      first = false;
    } else {
      cairo_line_to(cr, x + px, y + py);
    }
  }
  cairo_close_path(cr);
}

/// Eight distinguishable marker shapes (the path is left for fill/stroke).
void marker(cairo_t* cr, int shape, double x, double y) {
  const double r = 5.0;
  cairo_new_path(cr);  // text leaves a current point; an arc would join it with a line
  switch (shape % 8) {
    case 0: cairo_arc(cr, x, y, r, 0, 2 * M_PI); break;
    case 1: cairo_rectangle(cr, x - r, y - r, 2 * r, 2 * r); break;
    case 2: polygon(cr, x, y, {{0, -1.3 * r}, {1.15 * r, 0.8 * r}, {-1.15 * r, 0.8 * r}}); break;
    case 3: polygon(cr, x, y, {{0, -1.35 * r}, {1.1 * r, 0}, {0, 1.35 * r}, {-1.1 * r, 0}}); break;
    case 4: polygon(cr, x, y, {{0, 1.3 * r}, {1.15 * r, -0.8 * r}, {-1.15 * r, -0.8 * r}}); break;
    case 5: {  // plus
      const double a = 0.4 * r, b = 1.2 * r;
      polygon(cr, x, y, {{-a, -b}, {a, -b}, {a, -a}, {b, -a}, {b, a}, {a, a}, {a, b}, {-a, b}, {-a, a}, {-b, a},
                         {-b, -a}, {-a, -a}});
      break;
    }
    case 6: {  // hexagon
      const double c = 1.15 * r, h = 0.5 * c, v = 0.866 * c;
      polygon(cr, x, y, {{c, 0}, {h, v}, {-h, v}, {-c, 0}, {-h, -v}, {h, -v}});
      break;
    }
    default: {  // four-pointed star
      const double b = 1.4 * r, a = 0.45 * r;
      polygon(cr, x, y, {{0, -b}, {a, -a}, {b, 0}, {a, a}, {0, b}, {-a, a}, {-b, 0}, {-a, -a}});
      break;
    }
  }
}

void text(cairo_t* cr, const std::string& s, double x, double y, double size, double align_x = 0.0,
          bool bold = false) {
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, bold ? CAIRO_FONT_WEIGHT_BOLD : CAIRO_FONT_WEIGHT_NORMAL);
  cairo_set_font_size(cr, size);
  cairo_text_extents_t ext;
  cairo_text_extents(cr, s.c_str(), &ext);
  cairo_move_to(cr, x - align_x * ext.x_advance, y);
  cairo_show_text(cr, s.c_str());
}

/// The footnote inside the canvas: wrapped at spaces to the width between the margins, in at most
/// two lines below the x-axis label (the font shrinks until it fits; a word longer than a line is
/// the only thing that can still be cut, by the clip to the canvas less its margin).
void footnote(cairo_t* cr, const std::string& s) {
  constexpr double kMargin = 16;
  const double width = kWidth - 2 * kMargin;
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  std::vector<std::string> lines;
  double size = 11.5;
  for (; size >= 7.5; size -= 1.0) {
    cairo_set_font_size(cr, size);
    lines.clear();
    std::string line;
    std::string word;
    const auto fits = [&](const std::string& t) {
      cairo_text_extents_t ext;
      cairo_text_extents(cr, t.c_str(), &ext);
      return ext.x_advance <= width;
    };
    for (std::size_t i = 0; i <= s.size(); ++i) {
      if (i < s.size() && s[i] != ' ') {
        word += s[i];
        continue;
      }
      if (word.empty()) continue;
      const std::string longer = line.empty() ? word : line + " " + word;
      if (!line.empty() && !fits(longer)) {
        lines.push_back(line);
        line = word;
      } else {
        line = longer;
      }
      word.clear();
    }
    if (!line.empty()) lines.push_back(line);
    if (lines.size() <= 2) break;
  }
  cairo_save(cr);
  cairo_rectangle(cr, kMargin, kBottom + 50, width, kHeight - kMargin / 2 - (kBottom + 50));
  cairo_clip(cr);
  const double step = size * 1.3;
  double y = kHeight - kMargin / 2 - step * double(lines.size() - 1) - 2;
  for (const std::string& line : lines) {
    text(cr, line, kMargin, y, size);
    y += step;
  }
  cairo_restore(cr);
}

/// Breaks a legend label into lines of at most `width` characters at spaces.
std::vector<std::string> wrap(const std::string& s, std::size_t width) {
  std::vector<std::string> lines;
  std::string line, word;
  auto flush_word = [&] {
    if (word.empty()) return;
    if (!line.empty() && line.size() + 1 + word.size() > width) {
      lines.push_back(line);
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
    word.clear();
  };
  for (char c : s) {
    if (c == ' ') {
      flush_word();
    } else {
      word += c;
    }
  }
  flush_word();
  if (!line.empty()) lines.push_back(line);
  return lines;
}

void draw(cairo_t* cr, const PlotSpec& spec) {
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);

  double xmin = std::numeric_limits<double>::infinity(), xmax = 0, ymin = xmin, ymax = 0;
  for (const PlotSeries& s : spec.series) {
    for (const auto& [x, y] : s.points) {
      if (!(x > 0) || !(y > 0) || !std::isfinite(x) || !std::isfinite(y)) continue;
      xmin = std::min(xmin, x);
      xmax = std::max(xmax, x);
      ymin = std::min(ymin, y);
      ymax = std::max(ymax, y);
    }
  }
  const Axis ax = make_axis(xmin, xmax), ay = make_axis(ymin, ymax);
  auto X = [&](double v) { return ax.to_px(v, kLeft, kRight); };
  auto Y = [&](double v) { return ay.to_px(v, kBottom, kTop); };

  // Grid: decades solid, 2..9 faint when there is room.
  cairo_set_line_width(cr, 1.0);
  auto grid = [&](const Axis& a, bool vertical) {
    const int decades = int(a.hi - a.lo);
    const int step = decades > 14 ? 3 : decades > 8 ? 2 : 1;
    for (int k = int(a.lo); k <= int(a.hi); ++k) {
      for (int m = 1; m <= 9; ++m) {
        if (m > 1 && decades > 7) break;
        if (k == int(a.hi) && m > 1) break;
        const double v = m * std::pow(10.0, k);
        const double p = vertical ? a.to_px(v, kLeft, kRight) : a.to_px(v, kBottom, kTop);
        if (m == 1) {
          cairo_set_source_rgb(cr, 0.82, 0.82, 0.82);
        } else {
          cairo_set_source_rgb(cr, 0.93, 0.93, 0.93);
        }
        if (vertical) {
          cairo_move_to(cr, p, kTop);
          cairo_line_to(cr, p, kBottom);
        } else {
          cairo_move_to(cr, kLeft, p);
          cairo_line_to(cr, kRight, p);
        }
        cairo_stroke(cr);
        if (m == 1 && (k - int(a.lo)) % step == 0) {
          cairo_set_source_rgb(cr, 0.15, 0.15, 0.15);
          if (vertical) {
            text(cr, decade_label(k), p, kBottom + 20, 13, 0.5);
          } else {
            text(cr, decade_label(k), kLeft - 8, p + 4.5, 13, 1.0);
          }
        }
      }
    }
  };
  grid(ax, true);
  grid(ay, false);
  cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
  cairo_set_line_width(cr, 1.2);
  cairo_rectangle(cr, kLeft, kTop, kRight - kLeft, kBottom - kTop);
  cairo_stroke(cr);

  // Title and axis labels.
  cairo_set_source_rgb(cr, 0.05, 0.05, 0.05);
  text(cr, spec.title, kWidth / 2, 32, 18, 0.5, true);
  text(cr, spec.x_label, (kLeft + kRight) / 2, kBottom + 46, 14, 0.5);
  cairo_save(cr);
  cairo_translate(cr, 28, (kTop + kBottom) / 2);
  cairo_rotate(cr, -M_PI / 2);
  text(cr, spec.y_label, 0, 0, 14, 0.5);
  cairo_restore(cr);
  if (!spec.footnote.empty()) {
    cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
    footnote(cr, spec.footnote);
  }

  // Series, clipped to the plot area.
  cairo_save(cr);
  cairo_rectangle(cr, kLeft, kTop, kRight - kLeft, kBottom - kTop);
  cairo_clip(cr);
  for (std::size_t i = 0; i < spec.series.size(); ++i) {
    const PlotSeries& s = spec.series[i];
    const Rgb c = kPalette[i % std::size(kPalette)];
    std::vector<std::pair<double, double>> pts;
    for (const auto& [x, y] : s.points)
      if (x > 0 && y > 0 && std::isfinite(x) && std::isfinite(y)) pts.push_back({X(x), Y(y)});
    cairo_set_source_rgb(cr, c.r, c.g, c.b);
    if (s.line && pts.size() > 1) {
      cairo_set_line_width(cr, 2.0);
      cairo_move_to(cr, pts[0].first, pts[0].second);
      for (std::size_t k = 1; k < pts.size(); ++k) cairo_line_to(cr, pts[k].first, pts[k].second);
      cairo_stroke(cr);
    }
    for (const auto& [x, y] : pts) {
      marker(cr, int(i), x, y);
      cairo_fill_preserve(cr);
      cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
      cairo_set_line_width(cr, 0.8);
      cairo_stroke(cr);
      cairo_set_source_rgb(cr, c.r, c.g, c.b);
    }
  }
  cairo_restore(cr);

  // Legend to the right of the plot.
  double ly = kTop + 8;
  for (std::size_t i = 0; i < spec.series.size(); ++i) {
    const PlotSeries& s = spec.series[i];
    const Rgb c = kPalette[i % std::size(kPalette)];
    cairo_set_source_rgb(cr, c.r, c.g, c.b);
    if (s.line) {
      cairo_set_line_width(cr, 2.0);
      cairo_move_to(cr, kLegendX, ly);
      cairo_line_to(cr, kLegendX + 28, ly);
      cairo_stroke(cr);
    }
    marker(cr, int(i), kLegendX + 14, ly);
    cairo_fill_preserve(cr);
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    cairo_set_line_width(cr, 0.8);
    cairo_stroke(cr);
    const auto lines = wrap(s.label, 38);
    for (std::size_t k = 0; k < lines.size(); ++k) {
      text(cr, lines[k], kLegendX + 38, ly + 4.5 + 16 * double(k), 13);
    }
    ly += 16 * double(std::max<std::size_t>(1, lines.size())) + 12;
  }
}

/// RGB24: the accuracy plots have no transparency.
const plot_detail::Surface kSurface{kWidth, kHeight, false, CAIRO_FORMAT_RGB24};

}  // namespace

std::string render_svg(const PlotSpec& spec) {
  return plot_detail::draw_svg(kSurface, [&](cairo_t* cr) { draw(cr, spec); });
}

std::string render_png(const PlotSpec& spec) {
  return plot_detail::draw_png(kSurface, [&](cairo_t* cr) { draw(cr, spec); });
}

}  // namespace fivebar::plot
