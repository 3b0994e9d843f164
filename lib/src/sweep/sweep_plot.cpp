// Sweep plots (cairo, SVG and PNG from one drawing routine): a scatter of the first two
// objectives with the Pareto set marked, and for grid sweeps a heat map of the first objective
// over the first two variables (best over the others). Both are streamed from the CSV, so memory
// stays bounded: the scatter keeps a fixed-size deterministic reservoir of points. The heat map's
// cells, and the scatter's points beyond a few thousand, are one embedded raster in the SVG (as
// plotting libraries draw images); axes, labels and the Pareto set stay vectors.
#include <cairo-svg.h>
#include <cairo.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "fivebar/io.hpp"
#include "fivebar/sweep.hpp"
#include "plot/canvas.hpp"
#include "plot/style.hpp"

namespace fivebar {

namespace {

constexpr int kWidth = 860, kHeight = 640;
constexpr std::size_t kReservoir = 20000;

struct Axis {
  double lo = 0, hi = 1;
  std::string label;
  void fit(double a, double b) {
    lo = a;
    hi = b;
    if (!(hi > lo)) {
      lo -= 0.5 * (std::fabs(lo) + 1);
      hi = lo + std::fabs(lo) + 1;
    }
    const double pad = 0.04 * (hi - lo);
    lo -= pad;
    hi += pad;
  }
};

using plot_detail::text;
using style::tick_step;
std::string fmt(double v) { return style::tick_label(v); }

struct Frame {
  double x0 = 90, y0 = 60, x1 = kWidth - 40, y1 = kHeight - 80;  // plot box in pixels
  Axis ax, ay;
  double px(double x) const { return x0 + (x - ax.lo) / (ax.hi - ax.lo) * (x1 - x0); }
  double py(double y) const { return y1 - (y - ay.lo) / (ay.hi - ay.lo) * (y1 - y0); }
};

void axes(cairo_t* cr, const Frame& f, const std::string& title) {
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);
  cairo_set_line_width(cr, 1.0);
  cairo_set_source_rgb(cr, 0.9, 0.9, 0.9);
  const double sx = tick_step(f.ax.hi - f.ax.lo), sy = tick_step(f.ay.hi - f.ay.lo);
  for (double x = std::ceil(f.ax.lo / sx) * sx; x <= f.ax.hi; x += sx) {
    cairo_move_to(cr, f.px(x), f.y0);
    cairo_line_to(cr, f.px(x), f.y1);
  }
  for (double y = std::ceil(f.ay.lo / sy) * sy; y <= f.ay.hi; y += sy) {
    cairo_move_to(cr, f.x0, f.py(y));
    cairo_line_to(cr, f.x1, f.py(y));
  }
  cairo_stroke(cr);
  cairo_set_source_rgb(cr, 0.2, 0.2, 0.2);
  cairo_rectangle(cr, f.x0, f.y0, f.x1 - f.x0, f.y1 - f.y0);
  cairo_stroke(cr);
  for (double x = std::ceil(f.ax.lo / sx) * sx; x <= f.ax.hi; x += sx) text(cr, f.px(x), f.y1 + 18, fmt(x), 12, 0.5);
  for (double y = std::ceil(f.ay.lo / sy) * sy; y <= f.ay.hi; y += sy) text(cr, f.x0 - 8, f.py(y) + 4, fmt(y), 12, 1.0);
  text(cr, 0.5 * (f.x0 + f.x1), kHeight - 30, f.ax.label, 14, 0.5);
  cairo_save(cr);
  cairo_translate(cr, 24, 0.5 * (f.y0 + f.y1));
  cairo_rotate(cr, -M_PI / 2);
  text(cr, 0, 0, f.ay.label, 14, 0.5);
  cairo_restore(cr);
  text(cr, 0.5 * (f.x0 + f.x1), 34, title, 17, 0.5, true);
}

/// Objective value as plotted (footprint positive, in mm^2).
double plotted(const SweepRow& r, const std::string& objective) {
  const double v = r.score(objective);
  return objective == "footprint" || objective == "collision" ? -v : v;
}

std::string label_of(const std::string& objective) {
  if (objective == "margin") return "coverage margin (mm)";
  if (objective == "min_lci") return "min LCI over the ellipse";
  if (objective == "force") return "min force capability (N per N*mm)";
  if (objective == "footprint") return "footprint (mm^2)";
  if (objective == "collision") return "colliding fraction of tactor-position pairs";
  return objective;
}

/// Viridis-like colour map, t in [0, 1], as RGB in [0, 1].
std::array<double, 3> colour_rgb(double t) {
  static const double stops[5][3] = {{0.267, 0.005, 0.329}, {0.230, 0.322, 0.546}, {0.128, 0.567, 0.551},
                                     {0.369, 0.789, 0.383}, {0.993, 0.906, 0.144}};
  t = std::clamp(t, 0.0, 1.0) * 4.0;
  const int i = std::min(3, int(t));
  const double f = t - i;
  return {stops[i][0] + f * (stops[i + 1][0] - stops[i][0]), stops[i][1] + f * (stops[i + 1][1] - stops[i][1]),
          stops[i][2] + f * (stops[i + 1][2] - stops[i][2])};
}
void colour(cairo_t* cr, double t) {
  const auto c = colour_rgb(t);
  cairo_set_source_rgb(cr, c[0], c[1], c[2]);
}

/// Paints an image surface over the rectangle (x0, y0)-(x1, y1) of the plot, pixels kept sharp.
/// In the SVG this is one embedded PNG: a dense field or point cloud costs its pixels, not one
/// element per cell or point, while axes and labels stay vectors.
void paint_raster(cairo_t* cr, cairo_surface_t* image, double x0, double y0, double x1, double y1, bool nearest) {
  const int w = cairo_image_surface_get_width(image), h = cairo_image_surface_get_height(image);
  cairo_save(cr);
  cairo_translate(cr, x0, y0);
  cairo_scale(cr, (x1 - x0) / w, (y1 - y0) / h);
  cairo_set_source_surface(cr, image, 0, 0);
  cairo_pattern_set_filter(cairo_get_source(cr), nearest ? CAIRO_FILTER_NEAREST : CAIRO_FILTER_GOOD);
  cairo_rectangle(cr, 0, 0, w, h);
  cairo_fill(cr);
  cairo_restore(cr);
}

/// Above this many markers a layer is drawn as an embedded raster (one pixel per plot pixel, as in
/// the PNG).
constexpr std::size_t kVectorPoints = 2000;

/// Disc (filled) or ring (stroked, width 2) markers of radius r at pixel positions inside the
/// box (x0, y0)-(x1, y1): vector paths up to kVectorPoints, one raster layer beyond.
void markers(cairo_t* cr, const std::vector<std::pair<double, double>>& at, double r, const std::array<double, 4>& rgba,
             bool ring, double x0, double y0, double x1, double y1) {
  auto draw = [&](cairo_t* c) {
    cairo_set_source_rgba(c, rgba[0], rgba[1], rgba[2], rgba[3]);
    cairo_set_line_width(c, 2.0);
    for (const auto& [x, y] : at) {
      cairo_new_sub_path(c);
      cairo_arc(c, x, y, r, 0, 2 * M_PI);
      if (ring) {
        cairo_stroke(c);
      } else {
        cairo_fill(c);
      }
    }
  };
  if (at.size() <= kVectorPoints) {
    draw(cr);
    return;
  }
  constexpr int kRes = 1;
  const int w = int(std::ceil(x1 - x0)) * kRes, h = int(std::ceil(y1 - y0)) * kRes;
  cairo_surface_t* img = cairo_image_surface_create(CAIRO_FORMAT_ARGB32, w, h);
  cairo_t* ic = cairo_create(img);
  cairo_scale(ic, kRes, kRes);
  cairo_translate(ic, -x0, -y0);
  draw(ic);
  cairo_destroy(ic);
  cairo_surface_flush(img);
  paint_raster(cr, img, x0, y0, x0 + double(w) / kRes, y0 + double(h) / kRes, false);
  cairo_surface_destroy(img);
}


/// Draws with `draw` into an SVG and a PNG next to each other (atomically written).
template <class Draw>
std::vector<std::filesystem::path> save(const std::filesystem::path& dir, const std::string& stem, Draw draw) {
  const RenderedPlot pic = plot_detail::draw_both({double(kWidth), double(kHeight)}, draw);
  const std::string& svg = pic.svg;
  const std::string& png = pic.png;
  write_file_atomic(dir / (stem + ".svg"), svg);
  write_file_atomic(dir / (stem + ".png"), png);
  return {dir / (stem + ".svg"), dir / (stem + ".png")};
}

}  // namespace

std::vector<std::filesystem::path> write_sweep_plots(const std::filesystem::path& csv, const SweepSettings& s,
                                                     const std::vector<SweepRow>& pareto,
                                                     const std::filesystem::path& out_dir) {
  std::vector<std::filesystem::path> files;
  const std::string ox = s.objectives[0];
  const std::string oy = s.objectives.size() > 1 ? s.objectives[1] : (ox == "margin" ? "min_lci" : "margin");
  // One pass over the CSV: reservoir of covered points, ranges, heat-map cells.
  std::vector<std::pair<double, double>> points;
  std::uint64_t seen = 0, covered = 0, total = 0;
  std::uint64_t rng = s.seed * 0x9E3779B97F4A7C15ull + 1;
  double xlo = INFINITY, xhi = -INFINITY, ylo = INFINITY, yhi = -INFINITY;
  const bool heat = s.sample == "grid" && s.vary.size() >= 2 && s.vary[0].n > 1 && s.vary[1].n > 1;
  const int n0 = heat ? s.vary[0].n : 0, n1 = heat ? s.vary[1].n : 0;
  std::vector<double> cells(std::size_t(n0) * std::size_t(n1), std::numeric_limits<double>::quiet_NaN());
  std::uint64_t inner = 1;
  for (std::size_t d = 2; d < s.vary.size(); ++d) inner *= std::uint64_t(s.vary[d].n);
  read_sweep_csv(csv, s, [&](const SweepRow& r, const std::string&) {
    ++total;
    if (!r.covered) return;
    ++covered;
    const double x = plotted(r, ox), y = plotted(r, oy);
    if (std::isnan(x) || std::isnan(y)) return;
    xlo = std::min(xlo, x), xhi = std::max(xhi, x), ylo = std::min(ylo, y), yhi = std::max(yhi, y);
    ++seen;
    if (points.size() < kReservoir) {
      points.emplace_back(x, y);
    } else {
      rng = rng * 6364136223846793005ull + 1442695040888963407ull;
      const std::uint64_t j = (rng >> 11) % seen;
      if (j < kReservoir) points[j] = {x, y};
    }
    if (heat) {
      const std::uint64_t cell = r.index / inner;  // (i0, i1) of the first two variables
      double& c = cells[cell];
      const double v = r.score(ox);
      if (std::isnan(c) || v > c) c = v;
    }
  });
  files = save(out_dir, "sweep_scatter", [&](cairo_t* cr) {
    Frame f;
    f.ax.label = label_of(ox);
    f.ay.label = label_of(oy);
    if (seen) {
      f.ax.fit(xlo, xhi);
      f.ay.fit(ylo, yhi);
    }
    axes(cr, f, "Sweep of " + s.station + ": " + std::to_string(covered) + " of " + std::to_string(total) +
                    " designs cover the target");
    std::vector<std::pair<double, double>> at;
    at.reserve(points.size());
    for (const auto& [x, y] : points) at.emplace_back(f.px(x), f.py(y));
    markers(cr, at, 2.2, {0.25, 0.45, 0.75, 0.45}, false, f.x0, f.y0, f.x1, f.y1);
    at.clear();
    for (const SweepRow& r : pareto) {
      const double x = plotted(r, ox), y = plotted(r, oy);
      if (!std::isnan(x) && !std::isnan(y)) at.emplace_back(f.px(x), f.py(y));
    }
    markers(cr, at, 4.5, {0.85, 0.1, 0.1, 1.0}, false, f.x0, f.y0, f.x1, f.y1);
    // Legend.
    const double lx = f.x1 - 230, ly = f.y0 + 18;
    cairo_set_source_rgba(cr, 1, 1, 1, 0.85);
    cairo_rectangle(cr, lx - 10, ly - 14, 232, 46);
    cairo_fill(cr);
    cairo_set_source_rgba(cr, 0.25, 0.45, 0.75, 0.8);
    cairo_arc(cr, lx, ly, 3, 0, 2 * M_PI);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    text(cr, lx + 12, ly + 4, "covered design" + std::string(seen > kReservoir ? " (sample)" : ""), 12);
    cairo_set_source_rgb(cr, 0.85, 0.1, 0.1);
    cairo_arc(cr, lx, ly + 20, 4.5, 0, 2 * M_PI);
    cairo_fill(cr);
    cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
    text(cr, lx + 12, ly + 24, "Pareto set (" + std::to_string(pareto.size()) + ")", 12);
  });
  if (heat) {
    double lo = INFINITY, hi = -INFINITY;
    for (double c : cells) {
      if (!std::isnan(c)) lo = std::min(lo, c), hi = std::max(hi, c);
    }
    for (const auto& f : save(out_dir, "sweep_heatmap", [&](cairo_t* cr) {
           Frame f;
           f.x1 = kWidth - 130;
           const SweepVariable &v0 = s.vary[0], &v1 = s.vary[1];
           f.ax.lo = v1.lo - 0.5 * (v1.hi - v1.lo) / (n1 - 1);
           f.ax.hi = v1.hi + 0.5 * (v1.hi - v1.lo) / (n1 - 1);
           f.ay.lo = v0.lo - 0.5 * (v0.hi - v0.lo) / (n0 - 1);
           f.ay.hi = v0.hi + 0.5 * (v0.hi - v0.lo) / (n0 - 1);
           f.ax.label = v1.name + " (mm)";
           f.ay.label = v0.name + " (mm)";
           axes(cr, f, label_of(ox) + " over " + v0.name + " x " + v1.name);
           // One pixel per cell (row 0 at the top of the image is the largest first variable).
           cairo_surface_t* img = cairo_image_surface_create(CAIRO_FORMAT_RGB24, n1, n0);
           unsigned char* data = cairo_image_surface_get_data(img);
           const int stride = cairo_image_surface_get_stride(img);
           for (int i = 0; i < n0; ++i) {
             auto* row = reinterpret_cast<std::uint32_t*>(data + std::size_t(n0 - 1 - i) * std::size_t(stride));
             for (int j = 0; j < n1; ++j) {
               const double c = cells[std::size_t(i) * n1 + j];
               const std::array<double, 3> rgb =
                   std::isnan(c) ? std::array<double, 3>{0.86, 0.86, 0.86} : colour_rgb(hi > lo ? (c - lo) / (hi - lo) : 1.0);
               auto byte = [](double v) { return std::uint32_t(std::lround(std::clamp(v, 0.0, 1.0) * 255.0)); };
               row[j] = (byte(rgb[0]) << 16) | (byte(rgb[1]) << 8) | byte(rgb[2]);
             }
           }
           cairo_surface_mark_dirty(img);
           paint_raster(cr, img, f.x0, f.y0, f.x1, f.y1, true);
           cairo_surface_destroy(img);
           std::vector<std::pair<double, double>> at;
           for (const SweepRow& r : pareto) at.emplace_back(f.px(r.values[1]), f.py(r.values[0]));
           markers(cr, at, 5, {0.85, 0.1, 0.1, 1.0}, true, f.x0, f.y0, f.x1, f.y1);
           // Colour bar.
           const double bx = kWidth - 100, by0 = f.y0, by1 = f.y1;
           for (int k = 0; k < 200; ++k) {
             colour(cr, k / 199.0);
             cairo_rectangle(cr, bx, by1 - (k + 1) * (by1 - by0) / 200, 18, (by1 - by0) / 200 + 0.5);
             cairo_fill(cr);
           }
           cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
           const bool negated = ox == "footprint" || ox == "collision";  // scores are -value
           const double shown_lo = negated ? -hi : lo, shown_hi = negated ? -lo : hi;
           text(cr, bx + 22, by1, std::isfinite(lo) ? fmt(negated ? shown_hi : shown_lo) : "-", 11);
           text(cr, bx + 22, by0 + 10, std::isfinite(hi) ? fmt(negated ? shown_lo : shown_hi) : "-", 11);
           text(cr, bx - 4, by0 - 10, "best", 11);
           cairo_set_source_rgb(cr, 0.86, 0.86, 0.86);
           cairo_rectangle(cr, bx, by1 + 26, 18, 12);
           cairo_fill(cr);
           cairo_set_source_rgb(cr, 0.1, 0.1, 0.1);
           text(cr, bx + 22, by1 + 37, "none covered", 11);
         })) {
      files.push_back(f);
    }
  }
  return files;
}

}  // namespace fivebar
