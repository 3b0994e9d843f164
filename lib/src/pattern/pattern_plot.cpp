// Picture of pattern paths over a station's workspace (fivebar/pattern.hpp plot_patterns()).

#include <cmath>
#include <cstdio>
#include <numbers>

#include "fivebar/format.hpp"
#include "fivebar/pattern.hpp"
#include "fivebar/workspace/region.hpp"
#include "plot/tactor_canvas.hpp"

namespace fivebar {

namespace {

using namespace tactor_plot;

constexpr double kPanelW = 560.0;
constexpr double kPanelH = 620.0;
constexpr double kMargin = 46.0;
constexpr double kHeader = 62.0;
constexpr double kFooter = 70.0;
constexpr double kPadMm = 4.0;  // around the target ellipse

using format::fixed;
using format::general;

void marker_x(cairo_t* cr, const std::array<double, 2>& p, double r, const Rgb& c, double width) {
  set_colour(cr, c);
  cairo_set_line_width(cr, width);
  cairo_move_to(cr, p[0] - r, p[1] - r);
  cairo_line_to(cr, p[0] + r, p[1] + r);
  cairo_move_to(cr, p[0] - r, p[1] + r);
  cairo_line_to(cr, p[0] + r, p[1] - r);
  cairo_stroke(cr);
}

void dot(cairo_t* cr, const std::array<double, 2>& p, double r, const Rgb& fill, const Rgb& edge) {
  cairo_arc(cr, p[0], p[1], r, 0.0, 2.0 * std::numbers::pi);
  set_colour(cr, fill);
  cairo_fill_preserve(cr);
  set_colour(cr, edge);
  cairo_set_line_width(cr, 1.2);
  cairo_stroke(cr);
}

/// Polyline through page points of a tactor path.
template <class F>
void polyline(cairo_t* cr, const Panel& panel, std::size_t n, F point, const Rgb& c, double width, double alpha) {
  for (std::size_t k = 0; k < n; ++k) {
    const auto p = panel.px(point(k));
    if (k == 0) {
      cairo_move_to(cr, p[0], p[1]);
    } else {
      cairo_line_to(cr, p[0], p[1]);
    }
  }
  set_colour(cr, c, alpha);
  cairo_set_line_width(cr, width);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  cairo_stroke(cr);
}

void arrow_head(cairo_t* cr, const std::array<double, 2>& from, const std::array<double, 2>& to, const Rgb& c) {
  const double dx = to[0] - from[0], dy = to[1] - from[1];
  const double len = std::hypot(dx, dy);
  if (len < 1e-9) return;
  const double ux = dx / len, uy = dy / len;
  const double s = 11.0;
  cairo_move_to(cr, to[0], to[1]);
  cairo_line_to(cr, to[0] - s * ux + 0.5 * s * uy, to[1] - s * uy - 0.5 * s * ux);
  cairo_line_to(cr, to[0] - s * ux - 0.5 * s * uy, to[1] - s * uy + 0.5 * s * ux);
  cairo_close_path(cr);
  set_colour(cr, c);
  cairo_fill(cr);
}

/// Arrow at the end of a path: from a point a few samples back to the last one.
template <class F>
void path_arrow(cairo_t* cr, const Panel& panel, std::size_t n, F point, const Rgb& c) {
  if (n < 2) return;
  const auto end = panel.px(point(n - 1));
  std::size_t k = n - 1;
  while (k > 0 && std::hypot(panel.px(point(k))[0] - end[0], panel.px(point(k))[1] - end[1]) < 8.0) --k;
  arrow_head(cr, panel.px(point(k)), end, c);
}

void draw_panel(cairo_t* cr, const Station& s, const Geometry& g, const Region& up_region, const Region& low_region,
                const PatternResult& r, double x0, double y0) {
  // The ellipse and the links around it: the paths span a few millimetres only.
  const double half = 0.5 * std::max(s.target.axes.x(), s.target.axes.y()) + kPadMm;
  const std::array<double, 4> bounds{s.target.center.x() - half, s.target.center.y() - half,
                                     s.target.center.x() + half, s.target.center.y() + half};
  const Panel panel(cr, x0 + kMargin, y0 + kHeader, kPanelW - kMargin - 12.0, kPanelH - kHeader - kFooter, bounds);
  const Mechanism& up = *s.upper;
  const Mechanism& low = *s.lower;

  // Title and verdict.
  std::string title = std::string(to_string(r.spec.kind)) + " — " + s.name;
  text(cr, x0 + kMargin, y0 + 22.0, title, 17.0, kInk, 0.0, true);
  std::string verdict;
  Rgb verdict_colour{0.10, 0.50, 0.20};
  if (r.passed) {
    verdict = "renderable: " + std::to_string(r.samples.size()) + " samples at " + general(r.spec.rate_hz) +
              " Hz, min clearance " + fixed(r.min_clearance_mm, 2) + " mm";
  } else {
    verdict_colour = {0.75, 0.10, 0.10};
    verdict = "NOT renderable: " + std::string(to_string(r.first_failure->status)) + " at t = " +
              fixed(r.first_failure->time_s, 2) + " s (" + r.first_failure->mechanism + ")";
  }
  text(cr, x0 + kMargin, y0 + 42.0, verdict, 12.0, verdict_colour);
  std::string params;
  if (r.spec.kind == PatternKind::pivot) {
    params = "amplitude " + general(r.spec.pivot_amplitude * format::kDegPerRad) + " deg, " +
             general(r.spec.pivot_frequency_hz) + " Hz, ";
  } else {
    params = "amplitude " + general(r.spec.amplitude_mm) + " mm, ";
  }
  params += "duration " + general(r.spec.duration_s) + " s, separation " + general(r.spec.separation_mm) + " mm";
  text(cr, x0 + kMargin, y0 + 57.0, params, 11.0, kGrey);

  // Everything inside the panel is clipped to it.
  cairo_save(cr);
  cairo_rectangle(cr, panel.x(), panel.y(), panel.w(), panel.h());
  cairo_clip(cr);

  // Workspace and target.
  panel.begin();
  region_path(cr, low_region);
  panel.end();
  set_colour(cr, kLower, 0.07);
  cairo_fill_preserve(cr);
  set_colour(cr, kLower, 0.45);
  cairo_set_line_width(cr, 1.0);
  cairo_stroke(cr);
  panel.begin();
  region_path(cr, up_region);
  panel.end();
  set_colour(cr, kUpper, 0.07);
  cairo_fill_preserve(cr);
  set_colour(cr, kUpper, 0.45);
  cairo_set_line_width(cr, 1.0);
  cairo_stroke(cr);
  panel.begin();
  ellipse_path(cr, s.target);
  panel.end();
  {
    const double dash[2] = {6.0, 4.0};
    cairo_set_dash(cr, dash, 2, 0.0);
    set_colour(cr, kInk, 0.8);
    cairo_set_line_width(cr, 1.3);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0.0);
  }

  // Links at the first sample (filled) and the last (centre lines).
  if (!r.samples.empty()) {
    const PatternSample& first = r.samples.front();
    const PatternSample& last = r.samples.back();
    panel.begin();
    if (first.upper.pose.status != Status::unreachable) fill_outline(cr, link_outline(up, first.upper.pose, g), kUpper, 0.22);
    if (first.lower.pose.status != Status::unreachable) fill_outline(cr, link_outline(low, first.lower.pose, g), kLower, 0.22);
    if (last.upper.pose.status != Status::unreachable) link_lines(cr, up, last.upper.pose, kUpper, 1.4, 0.8, true);
    if (last.lower.pose.status != Status::unreachable) link_lines(cr, low, last.lower.pose, kLower, 1.4, 0.8, true);
    panel.end();
  }

  // Paths: targets, then the commanded lower path where the priority rule moved it.
  const std::size_t n = r.samples.size();
  const auto up_target = [&](std::size_t k) { return r.samples[k].upper.target; };
  const auto low_target = [&](std::size_t k) { return r.samples[k].lower.target; };
  const auto low_point = [&](std::size_t k) { return r.samples[k].lower.point; };
  polyline(cr, panel, n, up_target, kUpper, 3.2, 1.0);
  polyline(cr, panel, n, low_target, kLower, 3.2, 1.0);
  path_arrow(cr, panel, n, up_target, kUpper);
  path_arrow(cr, panel, n, low_target, kLower);
  if (r.moved_samples > 0) {
    polyline(cr, panel, n, low_point, kMoved, 2.0, 1.0);
    for (std::size_t k = 0; k < n; ++k) {
      if (r.samples[k].moved_mm > 0.0) dot(cr, panel.px(r.samples[k].lower.point), 2.2, kMoved, kMoved);
    }
  }
  if (n > 0) {
    const double tactor_px = 0.5 * g.tactor_diameter * panel.scale();
    const auto draw_tactor = [&](const Vec2& p, const Rgb& c) {
      const auto q = panel.px(p);
      cairo_arc(cr, q[0], q[1], tactor_px, 0.0, 2.0 * std::numbers::pi);
      set_colour(cr, c, 0.18);
      cairo_fill_preserve(cr);
      set_colour(cr, c, 0.9);
      cairo_set_line_width(cr, 1.2);
      cairo_stroke(cr);
    };
    draw_tactor(r.samples.front().upper.point, kUpper);
    draw_tactor(r.samples.front().lower.point, kLower);
    dot(cr, panel.px(r.samples.front().upper.target), 3.5, {1, 1, 1}, kUpper);
    dot(cr, panel.px(r.samples.front().lower.target), 3.5, {1, 1, 1}, kLower);
  }
  for (std::size_t k = 0; k < n; ++k) {
    const PatternSample& sample = r.samples[k];
    const bool bad_up = sample.upper.status != SampleStatus::ok;
    const bool bad_low = sample.lower.status != SampleStatus::ok && sample.lower.status != SampleStatus::collision_moved;
    if (bad_up) marker_x(cr, panel.px(sample.upper.target), 3.0, kInk, 1.2);
    if (bad_low) marker_x(cr, panel.px(sample.lower.target), 3.0, kInk, 1.2);
  }
  if (r.first_failure) {
    const PatternSample& f = r.samples[r.first_failure->index];
    const Vec2 p = r.first_failure->mechanism == "upper" ? f.upper.target : f.lower.target;
    marker_x(cr, panel.px(p), 7.0, kInk, 2.4);
  }
  cairo_restore(cr);
  axes(cr, panel, bounds, 2.0);

  // Footer: the worst margins.
  const double fy = panel.y() + panel.h() + 32.0;
  std::string line1 = "min LCI upper " + fixed(r.min_lci[0], 3) + ", lower " + fixed(r.min_lci[1], 3) +
                      ";  peak motor speed " + fixed(r.peak_joint_speed * format::kDegPerRad, 0) +
                      " deg/s (limit " + fixed(r.max_joint_speed * format::kDegPerRad, 0) + ")";
  text(cr, x0 + kMargin, fy, line1, 11.0, kInk);
  std::string line2 = r.moved_samples > 0 ? "priority rule moved the lower target in " +
                                                std::to_string(r.moved_samples) + " samples, by up to " +
                                                fixed(r.max_moved_mm, 2) + " mm (orange)"
                                          : "no collision: the priority rule never moved the lower target";
  text(cr, x0 + kMargin, fy + 16.0, line2, 11.0, r.moved_samples > 0 ? kMoved : kInk);
}

}  // namespace

RenderedPlot plot_patterns(const Station& s, const Geometry& g, const std::vector<PatternResult>& results) {
  if (!s.lower || !s.upper) throw InputError("station " + s.name + ": the pattern picture needs both mechanisms");
  const std::size_t n = std::max<std::size_t>(results.size(), 1);
  const std::size_t cols = std::min<std::size_t>(n, 2);
  const std::size_t rows = (n + cols - 1) / cols;
  const double legend_h = cols == 1 ? 96.0 : 60.0;
  Canvas canvas(static_cast<double>(cols) * kPanelW + 20.0, static_cast<double>(rows) * kPanelH + legend_h + 10.0);
  cairo_t* cr = canvas.cr();
  const Region up_region = reachable_region(*s.upper);
  const Region low_region = reachable_region(*s.lower);
  for (std::size_t i = 0; i < results.size(); ++i) {
    draw_panel(cr, s, g, up_region, low_region, results[i], 10.0 + static_cast<double>(i % cols) * kPanelW,
               static_cast<double>(i / cols) * kPanelH);
  }
  // Legend, flowing onto as many lines as the width needs.
  double lx = 20.0 + kMargin;
  double ly = static_cast<double>(rows) * kPanelH + 24.0;
  const double right = canvas.width() - 20.0;
  const auto place = [&](double w) {
    if (lx + w > right && lx > 20.0 + kMargin) {
      lx = 20.0 + kMargin;
      ly += 18.0;
    }
  };
  const auto swatch = [&](const Rgb& c, double width, const std::string& label) {
    const double w = 32.0 + text_width(cr, label, 11.0) + 18.0;
    place(w);
    set_colour(cr, c);
    cairo_set_line_width(cr, width);
    cairo_move_to(cr, lx, ly - 4.0);
    cairo_line_to(cr, lx + 26.0, ly - 4.0);
    cairo_stroke(cr);
    text(cr, lx + 32.0, ly, label, 11.0, kInk);
    lx += w;
  };
  const auto note = [&](const std::string& label) {
    const double w = text_width(cr, label, 11.0) + 18.0;
    place(w);
    text(cr, lx, ly, label, 11.0, kGrey);
    lx += w;
  };
  swatch(kUpper, 3.2, "upper tactor path");
  swatch(kLower, 3.2, "lower tactor path");
  swatch(kMoved, 2.0, "lower, moved by the priority rule");
  lx = right;  // the notes start on a new line
  for (const char* item : {"filled: links at the start", "dashed: links at the end", "shaded: reachable regions",
                        "dashed ellipse: fingertip target", "x: failing sample"}) {
    note(item);
  }
  return canvas.render();
}

}  // namespace fivebar
