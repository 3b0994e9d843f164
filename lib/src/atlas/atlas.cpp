// Non-dimensional performance atlases of the symmetric five-bar (fivebar/atlas.hpp, docs/atlas.md).

#include "fivebar/atlas.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <sstream>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/io.hpp"
#include "fivebar/kinematics.hpp"

namespace fivebar {

namespace {

using format::fixed;
using format::shortest;

constexpr double kSqrt3 = 1.7320508075688772;

/// The symmetry axis of a mechanism: the bases' midpoint M, the unit base direction u (O1 -> O2;
/// +x for coincident bases) and the normal n left of it.
struct Axis {
  Vec2 M{0.0, 0.0}, u{1.0, 0.0}, n{0.0, 1.0};
  explicit Axis(const Mechanism& m) : M(0.5 * (m.O1 + m.O2)) {
    const Vec2 d = m.O2 - m.O1;
    if (d.norm() > 0.0) u = d / d.norm();
    n = Vec2(-u.y(), u.x());
  }
  double base_angle() const { return std::atan2(u.y(), u.x()); }
};

/// The ellipse of `shape` with semi-major s centred at height y on the axis.
Ellipse ellipse_at(const Axis& axis, const TargetShape& shape, double y, double s) {
  Ellipse e;
  e.center = axis.M + y * axis.n;
  e.axes = Vec2(2.0 * s, 2.0 * shape.aspect * s);
  e.angle = axis.base_angle() + shape.angle;
  return e;
}

/// Points of the filled ellipse: its centre and rings x angles points on concentric rings (as
/// coverage's conditioning samples).
void filled_samples(const Ellipse& e, const CoverageOptions& o, std::vector<double>& px, std::vector<double>& py) {
  px.assign(1, e.center.x());
  py.assign(1, e.center.y());
  const double c = std::cos(e.angle), s = std::sin(e.angle);
  const double a = 0.5 * e.axes.x(), b = 0.5 * e.axes.y();
  for (int ring = 1; ring <= o.rings; ++ring) {
    const double r = double(ring) / o.rings;
    for (int k = 0; k < o.angles; ++k) {
      const double t = 2.0 * std::numbers::pi * k / o.angles;
      const double x = r * a * std::cos(t), y = r * b * std::sin(t);
      px.push_back(e.center.x() + c * x - s * y);
      py.push_back(e.center.y() + s * x + c * y);
    }
  }
}

/// Sampled assembly side: every sample reachable in the working mode and on the design's side.
bool sampled_assembly_ok(const Mechanism& m, const Ellipse& e, const CoverageOptions& o) {
  thread_local std::vector<double> px, py, lci, force;
  thread_local std::vector<std::int8_t> side;
  thread_local std::vector<Status> status;
  filled_samples(e, o, px, py);
  lci.resize(px.size());
  force.resize(px.size());
  side.resize(px.size());
  status.resize(px.size());
  conditioning_batch(m, px, py, lci, force, side, status);
  const auto want = std::int8_t(m.assembly_mode);
  for (std::size_t k = 0; k < px.size(); ++k)
    if (status[k] != Status::ok || side[k] != want) return false;
  return true;
}

/// Smallest |sin| of the tactor angle over the samples of the filled ellipse (0 where a sample is
/// unreachable or singular), and where.
std::pair<double, Vec2> min_transmission(const Mechanism& m, const Ellipse& e, const CoverageOptions& o) {
  std::vector<double> px, py;
  filled_samples(e, o, px, py);
  double best = std::numeric_limits<double>::infinity();
  Vec2 at = e.center;
  for (std::size_t k = 0; k < px.size(); ++k) {
    const Vec2 p(px[k], py[k]);
    const Pose pose = ik(m, p);
    const double v = pose.status == Status::ok ? pose.type2_sin : 0.0;
    if (v < best) {
      best = v;
      at = p;
    }
  }
  return {best, at};
}

/// The search of one mechanism (fivebar/atlas.hpp (a)).
class Search {
 public:
  Search(const Mechanism& m, const TargetShape& shape, const AtlasOptions& o)
      : m_(m), shape_(shape), o_(o), axis_(m), L_(m.length_scale()) {}

  int containments = 0;

  bool inside(double y, double s, double* margin) {
    ++containments;
    const Containment c = containment(m_, ellipse_at(axis_, shape_, y, s));
    *margin = c.margin_mm;
    return c.inside && c.decided;
  }

  /// Largest s inside the region at height y (certified lower end of a bracket of relative width
  /// tol), 0 when the centre is not inside.
  double region_limit(double y, double tol) {
    const double s0 = 1e-9 * L_;
    double m0 = 0.0;
    if (!inside(y, s0, &m0)) return 0.0;
    double lo = s0, mlo = m0;
    double hi = (s0 + m0) / shape_.aspect * (1.0 + 1e-9) + 1e-12 * L_, mhi = 0.0;
    for (int k = 0; inside(y, hi, &mhi); ++k) {  // cannot happen but for rounding: widen
      lo = hi, mlo = mhi;
      hi *= 2.0;
      if (k > 60) return lo;
    }
    // First the Lipschitz step: m(s0 + m0 - d) >= d, so just below s0 + m0 is certainly inside (and
    // for a circle the bracket is then closed); then Illinois regula falsi.
    double s = (s0 + m0) * (1.0 - 0.25 * tol);
    if (!(s > lo && s < hi)) s = 0.5 * (lo + hi);
    int side = 0;  // last side moved: +1 lo, -1 hi
    double width = hi - lo;
    for (int it = 0; it < 200 && hi - lo > tol * hi; ++it) {
      double ms = 0.0;
      if (inside(y, s, &ms)) {
        lo = s, mlo = std::max(ms, 0.0);
        if (side == +1) mhi *= 0.5;
        side = +1;
      } else {
        hi = s, mhi = std::min(ms, 0.0);
        if (side == -1) mlo *= 0.5;
        side = -1;
      }
      const double w = hi - lo;
      const bool slow = w > 0.5 * width;
      width = w;
      s = (slow || !(mlo - mhi > 0.0)) ? lo + 0.5 * w : lo + w * mlo / (mlo - mhi);
      // Regula falsi homes in on the root itself, where the bounds straddle zero and containment()
      // falls back to its exact (CGAL) test: probe a quarter of the tolerance beside the estimate
      // instead, on the side that closes the bracket.
      s += (side == +1 ? 0.25 : -0.25) * tol * hi;
      const double guard = 1e-3 * w;
      s = std::clamp(s, lo + guard, hi - guard);
    }
    return lo;
  }

  /// The scale at which the ellipse of this shape centred at height y passes through q.
  double scale_through(double y, const Vec2& q) const {
    const Vec2 d = q - (axis_.M + y * axis_.n);
    const double t = axis_.base_angle() + shape_.angle, c = std::cos(t), s = std::sin(t);
    const double u = c * d.x() + s * d.y(), v = (-s * d.x() + c * d.y()) / shape_.aspect;
    return std::hypot(u, v);
  }

  /// Largest s <= top at height y whose samples are all on the assembly side (bisection), 0 when
  /// the centre is not.
  double sampled_limit(double y, double top, double tol) {
    if (sampled_assembly_ok(m_, ellipse_at(axis_, shape_, y, top), o_.coverage)) return top;
    if (!sampled_assembly_ok(m_, ellipse_at(axis_, shape_, y, 1e-9 * L_), o_.coverage)) return 0.0;
    double a = 0.0, b = top;
    while (b - a > tol * b) {
      const double mid = 0.5 * (a + b);
      (sampled_assembly_ok(m_, ellipse_at(axis_, shape_, y, mid), o_.coverage) ? a : b) = mid;
    }
    return a;
  }

  /// Largest s at height y inside the region and on the assembly side; `by` says which bound.
  /// `certify` false: the assembly side on the samples only, an upper estimate (a sampled point on
  /// the wrong side is a real crossing; a crossing between samples can be missed). True: the
  /// sampled limit is checked by conditioning() (certified); each crossing it reports bounds s
  /// from above and the sampled bisection runs again below it.
  double limit(double y, double tol, bool certify, std::string* by) {
    const double sc = region_limit(y, tol);
    if (by) *by = "region";
    if (sc <= 0.0 || m_.assembly_mode == AssemblyMode::Any) return sc;
    double a = sampled_limit(y, sc, tol);
    if (a < sc && by) *by = "assembly";
    if (!certify) return a;
    for (int it = 0; it < 60 && a > 0.0; ++it) {
      CoverageResult r;
      conditioning(m_, ellipse_at(axis_, shape_, y, a), o_.coverage, r);
      if (r.assembly_ok && r.decided) return a;
      if (by) *by = "assembly";
      const double through = r.assembly_crossing ? scale_through(y, *r.assembly_crossing) : a;
      // Below the crossing (or, undecided without one, half-way down).
      a = through < a ? sampled_limit(y, through * (1.0 - tol), tol) : 0.5 * a;
    }
    return 0.0;
  }

  InscribedTarget run() {
    InscribedTarget out;
    // On the axis both bases are at d(y) = sqrt(y^2 + h^2) (h half the spacing): the centre is in
    // both legs' annuli for r_in <= d <= r_out, an interval of |y|.
    const double r_out = std::min(m_.L[0] + m_.L[2], m_.L[1] + m_.L[3]);
    const double r_in = std::max(std::abs(m_.L[0] - m_.L[2]), std::abs(m_.L[1] - m_.L[3]));
    const double half = 0.5 * (m_.O2 - m_.O1).norm();
    const double y_hi = std::sqrt(std::max(0.0, (r_out - half) * (r_out + half)));
    const double y_lo = std::sqrt(std::max(0.0, (r_in - half) * (r_in + half)));
    if (!(y_hi > y_lo)) return finish(out);
    const double span = y_hi - y_lo;
    const int sides = m_.assembly_mode == AssemblyMode::Any ? 2 : 1;
    const double sign0 = m_.assembly_mode == AssemblyMode::Minus ? -1.0 : 1.0;
    const double coarse = std::max(o_.rel_tol, 1e-3);
    // Scan: |y| = y_lo + (k + 0.5) / N * (y_hi - y_lo) on each side.
    std::vector<double> ys, ss;
    for (int side = 0; side < sides; ++side) {
      const double sg = side == 0 ? sign0 : -sign0;
      for (int k = 0; k < o_.heights; ++k) {
        const double y = sg * (y_lo + (k + 0.5) / o_.heights * span);
        ys.push_back(y);
        ss.push_back(limit(y, coarse, false, nullptr));
      }
    }
    // The sampled limits bound the certified ones from above: certify the heights in decreasing
    // order of their sampled limit until none left can beat the best certified one.
    std::vector<std::size_t> order(ys.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(), [&](std::size_t p, std::size_t q) { return ss[p] > ss[q]; });
    double yb = 0.0, sb = 0.0;
    for (const std::size_t k : order) {
      if (!(ss[k] > sb * (1.0 + coarse))) break;
      const double c = limit(ys[k], coarse, true, nullptr);
      if (c > sb) yb = ys[k], sb = c;
    }
    if (!(sb > 0.0)) return finish(out);
    // Golden section (on the sampled limits) over the two intervals around the best height,
    // within the scanned range; the height found is certified below and kept if it beats yb.
    const double step = span / o_.heights;
    const double sg = yb < 0.0 ? -1.0 : 1.0;
    double lo = std::max(std::abs(yb) - step, y_lo), hi = std::min(std::abs(yb) + step, y_hi);
    if (sg < 0.0) std::swap(lo, hi), lo = -lo, hi = -hi;
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
    double f1 = limit(x1, o_.rel_tol, false, nullptr), f2 = limit(x2, o_.rel_tol, false, nullptr);
    while (hi - lo > o_.rel_tol * span) {
      if (f1 >= f2) {
        hi = x2, x2 = x1, f2 = f1, x1 = hi - g * (hi - lo), f1 = limit(x1, o_.rel_tol, false, nullptr);
      } else {
        lo = x1, x1 = x2, f1 = f2, x2 = lo + g * (hi - lo), f2 = limit(x2, o_.rel_tol, false, nullptr);
      }
    }
    double y_best = f1 >= f2 ? x1 : x2;
    std::string by;
    double s_best = limit(y_best, o_.rel_tol, true, &by);
    if (s_best < sb) {
      y_best = yb;
      s_best = limit(y_best, o_.rel_tol, true, &by);
    }
    if (!(s_best > 0.0)) return finish(out);
    out.status = AtlasStatus::ok;
    out.scale = s_best;
    out.height = y_best;
    out.target = ellipse_at(axis_, shape_, y_best, s_best);
    out.limited_by = by;
    // (b), (c) over the concentric ellipse of fraction * s*.
    const Ellipse inner = ellipse_at(axis_, shape_, y_best, o_.fraction * s_best);
    CoverageResult r;
    conditioning(m_, inner, o_.coverage, r);
    out.min_lci = r.min_lci;
    out.min_lci_point = r.min_lci_point;
    const auto [t, at] = min_transmission(m_, inner, o_.coverage);
    out.min_transmission_sin = t;
    out.min_transmission_point = at;
    return finish(out);
  }

 private:
  InscribedTarget finish(InscribedTarget& out) {
    out.containments = containments;
    return out;
  }

  const Mechanism& m_;
  TargetShape shape_;
  const AtlasOptions& o_;
  Axis axis_;
  double L_;
};

Json point_json(const DesignPoint& p) {
  return Json{{"r1", p.r1}, {"r2", p.r2}, {"r3", p.r3}};
}

Json nullable(bool ok, double v) { return ok ? Json(v) : Json(nullptr); }

double scale_of(const InscribedTarget& f) { return f.scale; }
double lci_of(const InscribedTarget& f) { return f.min_lci; }
double transmission_of(const InscribedTarget& f) { return f.min_transmission_sin; }

/// The cell of largest `value` among those with a workspace and s* >= min_scale (nullptr if none).
template <class Value>
const AtlasCell* best_cell(const Atlas& a, Value value, double min_scale) {
  const AtlasCell* top = nullptr;
  for (const AtlasCell& c : a.cells) {
    if (c.figures.status != AtlasStatus::ok || c.figures.scale < min_scale) continue;
    if (!top || value(c.figures) > value(top->figures)) top = &c;
  }
  return top;
}

}  // namespace

// --- Design space ---------------------------------------------------------------------------------

Vec2 chart_of(const DesignPoint& p) { return {(p.r2 - p.r1) / kSqrt3, p.r3}; }

DesignPoint point_at_chart(double x, double y) {
  DesignPoint p;
  p.r3 = y;
  p.r1 = 0.5 * (3.0 - y) - 0.5 * kSqrt3 * x;
  p.r2 = 0.5 * (3.0 - y) + 0.5 * kSqrt3 * x;
  p.D_mm = 1.0;
  return p;
}

bool in_design_space(const DesignPoint& p) { return p.r1 > 0.0 && p.r2 > 0.0 && p.r3 > 0.0; }

std::optional<DesignPoint> design_point(const Mechanism& m, std::string* why) {
  const double scale = m.length_scale();
  const double tol = 1e-9 * scale;
  if (std::abs(m.L[0] - m.L[1]) > tol || std::abs(m.L[2] - m.L[3]) > tol) {
    if (why) {
      *why = "mechanism " + m.name + " is not symmetric (links " + shortest(m.L[0]) + ", " + shortest(m.L[1]) +
             ", " + shortest(m.L[2]) + ", " + shortest(m.L[3]) +
             " mm): the atlas is of five-bars with L1 = L2 and L3 = L4";
    }
    return std::nullopt;
  }
  const double b = (m.O2 - m.O1).norm();
  DesignPoint p;
  p.D_mm = (0.5 * (m.L[0] + m.L[1]) + 0.5 * (m.L[2] + m.L[3]) + b) / 3.0;
  if (!(p.D_mm > 0.0)) {
    if (why) *why = "mechanism " + m.name + " has no length";
    return std::nullopt;
  }
  p.r1 = 0.5 * (m.L[0] + m.L[1]) / p.D_mm;
  p.r2 = 0.5 * (m.L[2] + m.L[3]) / p.D_mm;
  p.r3 = b / p.D_mm;
  return p;
}

Mechanism atlas_mechanism(const DesignPoint& p, WorkingMode working_mode, AssemblyMode assembly_mode) {
  Mechanism m;
  m.name = "atlas";
  const double D = p.D_mm;
  m.O1 = Vec2(-0.5 * p.r3 * D, 0.0);
  m.O2 = Vec2(0.5 * p.r3 * D, 0.0);
  m.L = {p.r1 * D, p.r1 * D, p.r2 * D, p.r2 * D};
  m.working_mode = working_mode;
  m.assembly_mode = assembly_mode;
  return m;
}

TargetShape TargetShape::of(const Ellipse& e, const Mechanism& m, bool mirrored) {
  TargetShape s;
  const double major = std::max(e.axes.x(), e.axes.y());
  s.aspect = major > 0.0 ? std::min(e.axes.x(), e.axes.y()) / major : 1.0;
  const double major_angle = e.axes.x() >= e.axes.y() ? e.angle : e.angle + 0.5 * std::numbers::pi;
  double rel = major_angle - Axis(m).base_angle();
  if (mirrored) rel = -rel;
  // An ellipse's axis is a line: the angle is defined modulo pi; keep it in (-pi/2, pi/2].
  rel = std::remainder(rel, std::numbers::pi);
  if (rel <= -0.5 * std::numbers::pi) rel += std::numbers::pi;
  s.angle = rel;
  return s;
}

void AtlasOptions::validate() const {
  if (!(cells >= 3 && cells <= 401)) throw InputError("cells = " + std::to_string(cells) + ": must be in [3, 401]");
  if (!(heights >= 2 && heights <= 400))
    throw InputError("heights = " + std::to_string(heights) + ": must be in [2, 400]");
  if (!(fraction > 0.0 && fraction <= 1.0)) throw InputError("fraction = " + shortest(fraction) + ": must be in (0, 1]");
  if (!(rel_tol >= 1e-9 && rel_tol <= 1e-2)) throw InputError("rel_tol = " + shortest(rel_tol) + ": must be in [1e-9, 1e-2]");
  if (!(shape.aspect > 0.0 && shape.aspect <= 1.0))
    throw InputError("shape.aspect = " + shortest(shape.aspect) + ": must be in (0, 1] (minor / major)");
  if (!std::isfinite(shape.angle)) throw InputError("shape.angle: must be finite");
  if (!(coverage.rings >= 1 && coverage.rings <= 100 && coverage.angles >= 4 && coverage.angles <= 1000))
    throw InputError("coverage: rings in [1, 100] and angles in [4, 1000]");
  if (threads < 0 || threads > 1024) throw InputError("threads = " + std::to_string(threads) + ": must be in [0, 1024]");
  Mechanism probe;
  probe.L = {1.0, 1.0, 1.0, 1.0};
  probe.working_mode = working_mode;
  probe.assembly_mode = assembly_mode;
  probe.validate();
}

std::string_view to_string(AtlasStatus status) {
  switch (status) {
    case AtlasStatus::ok: return "ok";
    case AtlasStatus::no_workspace: return "no_workspace";
    case AtlasStatus::outside: return "outside";
  }
  return "unknown";
}

std::size_t Atlas::count(AtlasStatus status) const {
  return std::size_t(std::count_if(cells.begin(), cells.end(),
                                   [&](const AtlasCell& c) { return c.figures.status == status; }));
}

// --- Figures ----------------------------------------------------------------------------------------

InscribedTarget inscribed_target(const Mechanism& m, const TargetShape& shape, const AtlasOptions& options) {
  options.validate();
  return Search(m, shape, options).run();
}

Atlas performance_atlas(const AtlasOptions& options) {
  options.validate();
  Atlas a;
  a.options = options;
  a.spacing = 2.0 * kSqrt3 / options.cells;
  a.nx = options.cells;
  a.ny = int(3.0 / a.spacing);
  a.x0 = -kSqrt3 + 0.5 * a.spacing;
  a.y0 = 0.5 * a.spacing;
  a.cells.resize(std::size_t(a.nx) * std::size_t(a.ny));
  for (int j = 0; j < a.ny; ++j) {
    for (int i = 0; i < a.nx; ++i) {
      AtlasCell& c = a.cells[std::size_t(j) * std::size_t(a.nx) + std::size_t(i)];
      c.chart = Vec2(a.x0 + i * a.spacing, a.y0 + j * a.spacing);
      c.point = point_at_chart(c.chart.x(), c.chart.y());
      c.figures.status = in_design_space(c.point) ? AtlasStatus::no_workspace : AtlasStatus::outside;
    }
  }
  const auto t0 = std::chrono::steady_clock::now();
  const std::int64_t n = std::int64_t(a.cells.size());
  std::string error;
#ifdef _OPENMP
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();
#endif
  // Each cell is independent and deterministic: the atlas does not depend on the thread count.
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
  for (std::int64_t k = 0; k < n; ++k) {
    AtlasCell& c = a.cells[std::size_t(k)];
    if (c.figures.status == AtlasStatus::outside) continue;
    try {
      const Mechanism m = atlas_mechanism(c.point, options.working_mode, options.assembly_mode);
      c.figures = Search(m, options.shape, options).run();
    } catch (const std::exception& e) {
#pragma omp critical(fivebar_atlas_error)
      if (error.empty()) error = e.what();
    }
  }
  if (!error.empty()) throw std::runtime_error("atlas: " + error);
  a.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return a;
}

Atlas performance_atlas(const Station& station, AtlasOptions options) {
  const Mechanism* m = station.lower ? &*station.lower : station.upper ? &*station.upper : nullptr;
  const bool mirrored = !station.lower && station.upper;
  std::string why;
  std::optional<DesignPoint> point;
  if (!m) {
    why = "station " + station.name + " has no mechanism";
  } else {
    point = design_point(*m, &why);
    options.shape = TargetShape::of(station.target, *m, mirrored);
    options.working_mode = mirrored ? WorkingMode{std::int8_t(-m->working_mode.sign1), std::int8_t(-m->working_mode.sign2)}
                                    : m->working_mode;
    options.assembly_mode = mirrored ? AssemblyMode(-std::int8_t(m->assembly_mode)) : m->assembly_mode;
  }
  Atlas a = performance_atlas(options);
  if (!point) {
    a.station_note = why;
    return a;
  }
  AtlasStation s;
  s.station = station.name;
  s.mechanism = m->name;
  s.point = *point;
  s.chart = chart_of(*point);
  DesignPoint unit = *point;
  unit.D_mm = 1.0;
  s.figures = inscribed_target(atlas_mechanism(unit, options.working_mode, options.assembly_mode), options.shape, options);
  s.target_scale = 0.5 * std::max(station.target.axes.x(), station.target.axes.y()) / point->D_mm;
  const CoverageResult own = coverage(*m, station.target, options.coverage);
  s.target_covered = own.covered;
  s.target_min_lci = own.min_lci;
  s.target_min_transmission_sin = min_transmission(*m, station.target, options.coverage).first;
  if (m->joint_limits) a.station_note = "the station's joint limits are not part of the atlas family";
  a.station = s;
  return a;
}

bool add_mark(Atlas& atlas, const std::string& label, const Mechanism& m, std::string* why) {
  const std::optional<DesignPoint> point = design_point(m, why);
  if (!point) return false;
  AtlasMark mark;
  mark.label = label;
  mark.point = *point;
  mark.chart = chart_of(*point);
  DesignPoint unit = *point;
  unit.D_mm = 1.0;
  const AtlasOptions& o = atlas.options;
  mark.figures = inscribed_target(atlas_mechanism(unit, o.working_mode, o.assembly_mode), o.shape, o);
  atlas.marks.push_back(std::move(mark));
  return true;
}

// --- Outputs ----------------------------------------------------------------------------------------

Json to_json(const Atlas& a) {
  const AtlasOptions& o = a.options;
  Json j;
  j["normalisation"] = "D = (L1 + L3 + b) / 3, r1 = L1 / D, r2 = L3 / D, r3 = b / D (b the base spacing)";
  j["chart"] = "x = (r2 - r1) / sqrt(3), y = r3";
  j["grid"] = {{"nx", a.nx}, {"ny", a.ny}, {"x0", a.x0}, {"y0", a.y0}, {"spacing", a.spacing}};
  j["shape"] = {{"aspect", o.shape.aspect}, {"angle_deg", angle_deg(o.shape.angle)}};
  j["working_mode"] = to_string(o.working_mode);
  j["assembly_mode"] = to_string(o.assembly_mode);
  j["fraction"] = o.fraction;
  j["counts"] = {{"ok", a.count(AtlasStatus::ok)},
                 {"no_workspace", a.count(AtlasStatus::no_workspace)},
                 {"outside", a.count(AtlasStatus::outside)}};
  const auto best_of = [&](Json& into, const char* key, auto value, double min_scale) {
    const AtlasCell* top = best_cell(a, value, min_scale);
    if (!top) {
      into[key] = nullptr;
      return;
    }
    into[key] = {{"value", value(top->figures)}, {"point", point_json(top->point)},
                 {"chart", {top->chart.x(), top->chart.y()}}};
  };
  Json best = Json::object();
  best_of(best, "inscribed_scale_D", scale_of, 0.0);
  best_of(best, "min_lci", lci_of, 0.0);
  best_of(best, "min_transmission_sin", transmission_of, 0.0);
  j["best"] = best;
  if (a.station) {
    // Among the designs whose inscribed target holds the station's own (s* >= its scale).
    Json holding = Json::object();
    best_of(holding, "min_lci", lci_of, a.station->target_scale);
    best_of(holding, "min_transmission_sin", transmission_of, a.station->target_scale);
    j["best_holding_station_target"] = holding;
  } else {
    j["best_holding_station_target"] = nullptr;
  }
  if (a.station) {
    const AtlasStation& s = *a.station;
    const bool ok = s.figures.status == AtlasStatus::ok;
    std::size_t below = 0;
    for (const AtlasCell& c : a.cells)
      if (c.figures.status == AtlasStatus::ok && c.figures.scale < s.figures.scale) ++below;
    const std::size_t with = a.count(AtlasStatus::ok);
    // "station" and "mechanism" name them (docs/conventions.md "JSON documents"); the figures follow.
    j["station"] = s.station;
    j["mechanism"] = s.mechanism;
    j["station_figures"] = {
        {"status", std::string(to_string(s.figures.status))},
        {"point", point_json(s.point)},
        {"D_mm", s.point.D_mm},
        {"chart", {s.chart.x(), s.chart.y()}},
        {"inscribed_scale_D", nullable(ok, s.figures.scale)},
        {"inscribed_semi_major_mm", nullable(ok, s.figures.scale * s.point.D_mm)},
        {"height_mm", nullable(ok, s.figures.height * s.point.D_mm)},
        {"limited_by", ok ? Json(s.figures.limited_by) : Json(nullptr)},
        {"min_lci", nullable(ok, s.figures.min_lci)},
        {"min_transmission_sin", nullable(ok, s.figures.min_transmission_sin)},
        {"scale_percentile", nullable(with > 0, 100.0 * double(below) / double(std::max<std::size_t>(with, 1)))},
        {"target_scale_D", s.target_scale},
        {"target_semi_major_mm", s.target_scale * s.point.D_mm},
        {"target_over_inscribed", nullable(ok && s.figures.scale > 0.0, s.target_scale / s.figures.scale)},
        {"target_covered", s.target_covered},
        {"target_min_lci", s.target_min_lci},
        {"target_min_transmission_sin", s.target_min_transmission_sin},
    };
  } else {
    j["station"] = nullptr;
    j["mechanism"] = nullptr;
    j["station_figures"] = nullptr;
  }
  j["station_note"] = a.station_note;
  Json marks = Json::array();
  for (const AtlasMark& m : a.marks) {
    const bool ok = m.figures.status == AtlasStatus::ok;
    marks.push_back({{"label", m.label},
                     {"status", std::string(to_string(m.figures.status))},
                     {"point", point_json(m.point)},
                     {"D_mm", m.point.D_mm},
                     {"chart", {m.chart.x(), m.chart.y()}},
                     {"inscribed_scale_D", nullable(ok, m.figures.scale)},
                     {"inscribed_semi_major_mm", nullable(ok, m.figures.scale * m.point.D_mm)},
                     {"min_lci", nullable(ok, m.figures.min_lci)},
                     {"min_transmission_sin", nullable(ok, m.figures.min_transmission_sin)}});
  }
  j["marks"] = marks;
  j["seconds"] = a.seconds;
  return j;
}

std::vector<std::string> summary_lines(const Atlas& a) {
  const AtlasOptions& o = a.options;
  std::vector<std::string> out;
  const std::size_t designs = a.cells.size() - a.count(AtlasStatus::outside);
  out.push_back("atlas: " + std::to_string(a.nx) + " x " + std::to_string(a.ny) + " grid over r1 + r2 + r3 = 3 (step " +
                fixed(a.spacing, 4) + "), " + std::to_string(designs) + " designs, " +
                std::to_string(a.count(AtlasStatus::ok)) + " with a workspace, in " + fixed(a.seconds, 2) +
                " s; target aspect " + fixed(o.shape.aspect, 3) + " at " + fixed(angle_deg(o.shape.angle), 1) +
                " deg, working mode " + to_string(o.working_mode) + ", assembly " + to_string(o.assembly_mode) +
                "; LCI and transmission over " + fixed(o.fraction, 2) + " of the inscribed target");
  const auto best_line = [&](const std::string& what, auto value, double min_scale) {
    const AtlasCell* top = best_cell(a, value, min_scale);
    if (!top) return;
    out.push_back(what + " " + fixed(value(top->figures), 4) + " at (r1, r2, r3) = (" + fixed(top->point.r1, 3) +
                  ", " + fixed(top->point.r2, 3) + ", " + fixed(top->point.r3, 3) + ")");
  };
  best_line("largest inscribed target: s* (semi-major) =", scale_of, 0.0);
  best_line("best conditioning: min LCI", lci_of, 0.0);
  best_line("best transmission: min |sin| of the tactor angle", transmission_of, 0.0);
  if (a.station) {
    const std::string among = " among the designs that hold the station's target (s* >= " + fixed(a.station->target_scale, 4) + "):";
    best_line("best conditioning" + among + " min LCI", lci_of, a.station->target_scale);
    best_line("best transmission" + among, transmission_of, a.station->target_scale);
  }
  if (a.station) {
    const AtlasStation& s = *a.station;
    std::string line = "station " + s.station + " (" + s.mechanism + "): (r1, r2, r3) = (" + fixed(s.point.r1, 3) +
                       ", " + fixed(s.point.r2, 3) + ", " + fixed(s.point.r3, 3) + "), D = " + fixed(s.point.D_mm, 3) +
                       " mm: ";
    if (s.figures.status == AtlasStatus::ok) {
      std::size_t below = 0;
      for (const AtlasCell& c : a.cells)
        if (c.figures.status == AtlasStatus::ok && c.figures.scale < s.figures.scale) ++below;
      const std::size_t with = std::max<std::size_t>(a.count(AtlasStatus::ok), 1);
      line += "s* = " + fixed(s.figures.scale, 4) + " D = " + fixed(s.figures.scale * s.point.D_mm, 3) +
              " mm (limited by the " + s.figures.limited_by + ", above " + fixed(100.0 * double(below) / double(with), 1) +
              " % of the designs with a workspace); its target " + fixed(s.target_scale, 4) + " D = " +
              fixed(100.0 * s.target_scale / s.figures.scale, 1) + " % of it; min LCI " + fixed(s.figures.min_lci, 4) +
              ", transmission " + fixed(s.figures.min_transmission_sin, 4) + " over " + fixed(o.fraction, 2) + " s*";
    } else {
      line += "no workspace on the design's side";
    }
    out.push_back(line);
    out.push_back("station " + s.station + " own target: " + (s.target_covered ? "covered" : "NOT covered") +
                  ", min LCI " + fixed(s.target_min_lci, 4) + ", transmission " +
                  fixed(s.target_min_transmission_sin, 4));
  }
  for (const AtlasMark& m : a.marks) {
    std::string line = "mark " + m.label + ": (r1, r2, r3) = (" + fixed(m.point.r1, 3) + ", " + fixed(m.point.r2, 3) +
                       ", " + fixed(m.point.r3, 3) + "), D = " + fixed(m.point.D_mm, 3) + " mm: ";
    if (m.figures.status == AtlasStatus::ok) {
      line += "s* = " + fixed(m.figures.scale, 4) + " D = " + fixed(m.figures.scale * m.point.D_mm, 3) +
              " mm, min LCI " + fixed(m.figures.min_lci, 4) + ", transmission " + fixed(m.figures.min_transmission_sin, 4);
    } else {
      line += "no workspace on the design's side";
    }
    out.push_back(line);
  }
  if (!a.station_note.empty()) out.push_back("note: " + a.station_note);
  return out;
}

std::string atlas_csv(const Atlas& a) {
  std::ostringstream os;
  os << "chart_x,chart_y,r1,r2,r3,status,scale_D,height_D,min_lci,min_transmission_sin,limited_by\n";
  for (const AtlasCell& c : a.cells) {
    if (c.figures.status == AtlasStatus::outside) continue;
    const bool ok = c.figures.status == AtlasStatus::ok;
    os << shortest(c.chart.x()) << ',' << shortest(c.chart.y()) << ',' << shortest(c.point.r1) << ','
       << shortest(c.point.r2) << ',' << shortest(c.point.r3) << ',' << to_string(c.figures.status) << ','
       << (ok ? shortest(c.figures.scale) : "") << ',' << (ok ? shortest(c.figures.height) : "") << ','
       << (ok ? shortest(c.figures.min_lci) : "") << ',' << (ok ? shortest(c.figures.min_transmission_sin) : "")
       << ',' << (ok ? c.figures.limited_by : "") << '\n';
  }
  return os.str();
}

std::vector<std::pair<std::string, std::string>> atlas_files(const Atlas& atlas, const std::string& stem,
                                                             const std::string& subtitle) {
  if (!is_safe_name(stem)) throw InputError("atlas file stem '" + stem + "': not a safe file name");
  const RenderedPlot plot = plot_atlas(atlas, subtitle);
  return {{stem + ".csv", atlas_csv(atlas)},
          {stem + ".vti", atlas_vti(atlas)},
          {stem + ".svg", plot.svg},
          {stem + ".png", plot.png},
          {stem + ".json", to_json(atlas).dump(2) + "\n"}};
}

std::vector<std::filesystem::path> write_atlas_files(const std::filesystem::path& dir, const Atlas& atlas,
                                                     const std::string& stem, const std::string& subtitle) {
  const auto files = atlas_files(atlas, stem, subtitle);
  make_directories(dir);
  std::vector<std::filesystem::path> out;
  for (const auto& [name, bytes] : files) {
    write_file_atomic(dir / name, bytes);
    out.push_back(dir / name);
  }
  return out;
}

}  // namespace fivebar
