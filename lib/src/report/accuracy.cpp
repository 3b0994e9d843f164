// `fivebar report accuracy`: work-precision series of the workspace area, the coverage numbers,
// the sampled restricted regions and FK/IK in float, double, long double and the library's double
// paths, each against an exact or high-precision reference (report.hpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <random>

#include "fivebar/coverage/coverage.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/report.hpp"
#include "fivebar/tolerance.hpp"
#include "fivebar/workspace/region.hpp"
#include "report/precision.hpp"
#include "report/quad.hpp"

namespace fivebar {

namespace {

using quadref::quad;
using quadref::QVec;
using Clock = std::chrono::steady_clock;
constexpr double kPi = std::numbers::pi;

/// The LCI threshold of the LCI-restricted region when the design sets none: a usable-dexterity
/// level inside the paper device's workspace (LCI 0.72 at the index target's centre).
constexpr double kIllustrativeLci = 0.25;
/// Errors below this fraction of the reference value are at the reference's own precision and are
/// left out of the order fits.
constexpr double kFitFloorRel = 1e-12;

// --- timing --------------------------------------------------------------------------------------

struct Timing {
  int min_repeats, max_repeats;
  double budget_s;  ///< aim for about this much time per point after the warm-up
  double long_run_s;  ///< a warm-up at least this long is followed by a single timed run
  bool time_long_warmup;  ///< quick mode: a long warm-up run is itself the measurement
};
Timing timing_for(bool quick) { return quick ? Timing{1, 3, 0.01, 0.02, true} : Timing{3, 9, 0.15, 0.1, false}; }

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// Median wall time of run() over repeats after one warm-up run: as many repeats as fit in the
/// budget (at least min_repeats); runs longer than long_run_s are timed once more (quick mode:
/// not at all, the warm-up is the measurement: caches matter little at that length).
template <class F>
double median_time(const Timing& t, F&& run) {
  auto once = [&] {
    const auto t0 = Clock::now();
    run();
    return seconds_since(t0);
  };
  const double warm = once();
  if (warm >= t.long_run_s) return t.time_long_warmup ? warm : once();
  const int n = std::clamp(int(t.budget_s / std::max(warm, 1e-9)), t.min_repeats, t.max_repeats);
  std::vector<double> times(n);
  for (double& v : times) v = once();
  std::sort(times.begin(), times.end());
  return n % 2 ? times[n / 2] : 0.5 * (times[n / 2 - 1] + times[n / 2]);
}

void say(const AccuracyOptions& o, const std::string& message) {
  if (o.progress) o.progress(message);
}

/// Grid series are fitted on their three finest points, where the error is asymptotic (coarse
/// grids resolve neither the lens corners nor the holes of a workspace); sampling series on all.
constexpr std::size_t kGridFitPoints = 3;
constexpr std::size_t kAllPoints = 1000;

void fit(WorkSeries& s, double floor, std::size_t last_points) {
  std::vector<double> x, y, t;
  const std::size_t first = s.points.size() > last_points ? s.points.size() - last_points : 0;
  for (std::size_t k = first; k < s.points.size(); ++k) {
    const WorkPoint& p = s.points[k];
    x.push_back(p.resolution);
    y.push_back(p.error);
    t.push_back(p.time_s);
  }
  s.order = fit_log_slope(x, y, floor);
  s.time_slope = fit_log_slope(t, y, floor);
}

// --- workspace area ------------------------------------------------------------------------------

void area_study(const Mechanism& m, const Region& region, double region_time_s, const AccuracyOptions& o,
                MechanismAccuracy& out) {
  const Timing tm = timing_for(o.quick);
  out.exact_area_mm2 = region.area_mm2();
  const auto b = region.bounds();
  const double extent = std::max(b[2] - b[0], b[3] - b[1]);
  const int k_lo = 5, k_hi = o.quick ? 9 : 10;

  WorkSeries cells{"cell counting", "h_mm", "mm2", {}, {}, {}, "reachable grid nodes x h^2 (sample_field)"};
  WorkSeries squares{"marching squares", "h_mm", "mm2", {}, {}, {},
                     "restricted_area(reach): adaptive marching squares; estimate = its own error estimate"};
  for (int k = k_lo; k <= k_hi; ++k) {
    const double h = extent / double(1 << k);
    const Grid grid = Grid::covering(b, h, h);
    double count_area = 0.0;
    const double t_cells = median_time(tm, [&] {
      const WorkspaceField f = sample_field(m, grid);
      std::size_t n = 0;
      for (std::uint8_t r : f.reach) n += r;
      count_area = double(n) * h * h;
    });
    cells.points.push_back({h, t_cells, count_area, std::fabs(count_area - out.exact_area_mm2), {}});
    SampledArea sa;
    const double t_ms = median_time(tm, [&] { sa = restricted_area(m, Restriction::reach, grid); });
    squares.points.push_back({h, t_ms, sa.area_mm2, std::fabs(sa.area_mm2 - out.exact_area_mm2), sa.error_mm2});
  }
  const double floor = kFitFloorRel * out.exact_area_mm2;
  fit(cells, floor, kAllPoints);  // lattice-point counting fluctuates: use every level
  fit(squares, floor, kGridFitPoints);
  out.area.push_back(std::move(cells));
  out.area.push_back(std::move(squares));

  if (!m.joint_limits) {
    // Without joint limits the area has a closed form: check the exact region and the double
    // closed form against it in quad.
    const quad qa = quadref::annuli_area(quadref::QMechanism(m));
    out.quad_area_mm2 = double(qa);
    double cf = 0.0;
    const double t_cf = median_time(tm, [&] { cf = annuli_intersection_area(m); });
    out.closed_form_area_mm2 = cf;
    out.area.push_back({"exact region (CGAL)", "h_mm", "mm2",
                        {{0.0, region_time_s, out.exact_area_mm2, double(quadref::qabs(quad(out.exact_area_mm2) - qa)), {}}},
                        {}, {}, "reachable_region() + Green's theorem, against the annuli closed form in quad"});
    out.area.push_back({"closed form (double)", "h_mm", "mm2",
                        {{0.0, t_cf, cf, double(quadref::qabs(quad(cf) - qa)), {}}},
                        {}, {}, "annuli_intersection_area(), against the same in quad"});
  }
}

// --- coverage ------------------------------------------------------------------------------------

double ellipse_perimeter(const Ellipse& e) {
  const double a = 0.5 * e.axes.x(), b = 0.5 * e.axes.y();
  const double hh = (a - b) * (a - b) / ((a + b) * (a + b));
  return kPi * (a + b) * (1 + 3 * hh / (10 + std::sqrt(4 - 3 * hh)));  // Ramanujan
}

/// Point at fraction r of the way from the centre to the boundary point at parameter t.
Vec2 ellipse_point(const Ellipse& e, double r, double t) {
  const double c = std::cos(e.angle), s = std::sin(e.angle);
  const double x = 0.5 * r * e.axes.x() * std::cos(t), y = 0.5 * r * e.axes.y() * std::sin(t);
  return e.center + Vec2(c * x - s * y, s * x + c * y);
}

double lci_at(const Mechanism& m, const Vec2& p) {
  double px = p.x(), py = p.y(), l = 0.0;
  Status st;
  lci_batch(m, {&px, 1}, {&py, 1}, {&l, 1}, {&st, 1});
  return l;
}

/// Local minimum of the LCI over the filled ellipse from (r, t): pattern search in the ellipse's
/// polar parameters with r clamped to [0, 1], so that minima on the boundary are found as well.
double refine_min_lci(const Mechanism& m, const Ellipse& e, double r, double t, double step_r, double step_t) {
  double best = lci_at(m, ellipse_point(e, r, t));
  for (int it = 0; it < 4000 && (step_r > 1e-13 || step_t > 1e-13); ++it) {
    bool moved = false;
    for (int dr = -1; dr <= 1; ++dr) {
      for (int dt = -1; dt <= 1; ++dt) {
        if (dr == 0 && dt == 0) continue;
        const double rn = std::clamp(r + dr * step_r, 0.0, 1.0), tn = t + dt * step_t;
        const double v = lci_at(m, ellipse_point(e, rn, tn));
        if (v < best) {
          best = v;
          r = rn;
          t = tn;
          moved = true;
        }
      }
    }
    if (!moved) {
      step_r *= 0.5;
      step_t *= 0.5;
    }
  }
  return best;
}

void coverage_study(const Mechanism& m, const Region& region, const Ellipse& target, const AccuracyOptions& o,
                    MechanismAccuracy& out) {
  const Timing tm = timing_for(o.quick);
  CoverageResult cov;
  const double t_cov = median_time(tm, [&] { cov = coverage(m, region, target); });
  out.margin_mm = cov.margin_mm;
  out.min_lci = cov.min_lci;
  if (!m.joint_limits) out.margin_quad_mm = double(quadref::annuli_margin(quadref::QMechanism(m), target));

  // Margin: the smallest signed distance to the region boundary over boundary samples.
  const double perimeter = ellipse_perimeter(target);
  // Samples at half steps of the parameter: a symmetric target's worst point (an axis end) is not
  // hit by construction, so the series shows the method's convergence rather than luck.
  WorkSeries margin{"sampled margin", "h_mm", "mm", {}, {}, {},
                    "min over N ellipse boundary points (half-step parameters) of Region::signed_distance, "
                    "against coverage()"};
  for (int j = 0, jmax = o.quick ? 6 : 10; j <= jmax; ++j) {
    const int n = 16 << j;
    double v = 0.0;
    const double t = median_time(tm, [&] {
      v = std::numeric_limits<double>::infinity();
      for (int k = 0; k < n; ++k) v = std::min(v, region.signed_distance(target.boundary_point(2 * kPi * (k + 0.5) / n)));
    });
    margin.points.push_back({perimeter / n, t, v, std::fabs(v - cov.margin_mm), {}});
  }
  fit(margin, 1e-13 * m.length_scale(), kAllPoints);

  // Min LCI: rings x angles over the filled ellipse (lci_batch), then a local refinement of the
  // finest sampling's minimum as the reference.
  const double a_max = 0.5 * std::max(target.axes.x(), target.axes.y());
  WorkSeries lci{"sampled min LCI", "h_mm", "1", {}, {}, {},
                 "min of lci_batch over 1 + 8 n^2 points (n rings, 8 n half-step angles), against the refined minimum"};
  double best_r = 0.0, best_t = 0.0;
  int n_fine = 1;
  std::vector<double> px, py, lv;
  std::vector<Status> st;
  for (int n = 1, nmax = o.quick ? 32 : 256; n <= nmax; n *= 2) {
    px.assign(1, target.center.x());
    py.assign(1, target.center.y());
    std::vector<std::pair<double, double>> rt{{0.0, 0.0}};
    for (int ring = 1; ring <= n; ++ring) {
      for (int k = 0; k < 8 * n; ++k) {
        const double r = double(ring) / n, t = 2 * kPi * (k + 0.5) / (8 * n);
        const Vec2 p = ellipse_point(target, r, t);
        px.push_back(p.x());
        py.push_back(p.y());
        rt.push_back({r, t});
      }
    }
    lv.resize(px.size());
    st.resize(px.size());
    double v = 0.0;
    std::size_t arg = 0;
    const double t = median_time(tm, [&] {
      lci_batch(m, px, py, lv, st);
      arg = std::size_t(std::min_element(lv.begin(), lv.end()) - lv.begin());
      v = lv[arg];
    });
    best_r = rt[arg].first;
    best_t = rt[arg].second;
    n_fine = n;
    lci.points.push_back({a_max / n, t, v, 0.0, {}});
  }
  double ref = refine_min_lci(m, target, best_r, best_t, 1.0 / n_fine, 2 * kPi / (8 * n_fine));
  if (cov.min_lci > 0.0) {
    // Also from coverage()'s own minimiser (both are local searches: keep the lower).
    const Vec2 q = cov.min_lci_point - target.center;
    const double c = std::cos(target.angle), s = std::sin(target.angle);
    const double lx = (c * q.x() + s * q.y()) / (0.5 * target.axes.x()),
                 ly = (-s * q.x() + c * q.y()) / (0.5 * target.axes.y());
    const double r0 = std::min(1.0, std::hypot(lx, ly)), t0 = std::atan2(ly, lx);
    ref = std::min(ref, refine_min_lci(m, target, r0, t0, 1.0 / n_fine, 2 * kPi / (8 * n_fine)));
  }
  ref = std::min(ref, cov.min_lci);
  out.min_lci_reference = ref;
  for (WorkPoint& p : lci.points) p.error = std::fabs(p.value - ref);
  fit(lci, 1e-13, kAllPoints);

  WorkSeries cov_point{"coverage()", "h_mm", "mm", {}, {}, {}, ""};
  if (out.margin_quad_mm) {
    cov_point.points.push_back({0.0, t_cov, cov.margin_mm, std::fabs(cov.margin_mm - *out.margin_quad_mm), {}});
    cov_point.note = "margin by coverage() (fast path, exact test near tangency) against the quad margin";
  } else {
    cov_point.note = "joint limits: no quad margin; coverage() is the reference";
  }
  WorkSeries cov_lci{"coverage() min LCI", "h_mm", "1", {{0.0, t_cov, cov.min_lci, std::fabs(cov.min_lci - ref), {}}},
                     {}, {}, "min LCI by coverage() (sampling + compass search) against the refined minimum"};
  out.coverage.push_back(std::move(margin));
  out.coverage.push_back(std::move(lci));
  out.coverage.push_back(std::move(cov_point));
  out.coverage.push_back(std::move(cov_lci));
}

// --- restricted regions --------------------------------------------------------------------------

void restricted_study(const Mechanism& m, const Region& region, const AccuracyOptions& o, MechanismAccuracy& out) {
  const Timing tm = timing_for(o.quick);
  Mechanism ml = m;
  out.lci_threshold_from_design = m.min_lci > 0.0;
  out.lci_threshold = out.lci_threshold_from_design ? m.min_lci : kIllustrativeLci;
  ml.min_lci = out.lci_threshold;
  const auto b = region.bounds();
  const double extent = std::max(b[2] - b[0], b[3] - b[1]);
  const int k_lo = o.quick ? 4 : 3, k_hi = 6;
  const double h_ref = extent / double(1 << k_hi) / 16.0;
  out.reference_spacing_mm = h_ref;
  const Grid ref_grid = Grid::covering(b, h_ref, h_ref);
  for (Restriction r : {Restriction::assembly, Restriction::lci}) {
    const bool is_lci = r == Restriction::lci;
    const double ref = restricted_area(ml, r, ref_grid, 1).area_mm2;
    (is_lci ? out.lci_area_reference_mm2 : out.assembly_area_reference_mm2) = ref;
    WorkSeries s{is_lci ? "LCI-restricted area" : "assembly-restricted area", "h_mm", "mm2", {}, {}, {},
                 "restricted_area(" + std::string(is_lci ? "lci" : "assembly") +
                     ") against the same on a grid 16x finer than the finest; estimate = its own error estimate"};
    for (int k = k_lo; k <= k_hi; ++k) {
      const double h = extent / double(1 << k);
      const Grid grid = Grid::covering(b, h, h);
      SampledArea sa;
      const double t = median_time(tm, [&] { sa = restricted_area(ml, r, grid); });
      s.points.push_back({h, t, sa.area_mm2, std::fabs(sa.area_mm2 - ref), sa.error_mm2});
    }
    fit(s, kFitFloorRel * std::max(ref, 1e-300), kGridFitPoints);
    out.restricted.push_back(std::move(s));
  }
  // A thin region: LCI within 2 % of its largest value, a small island that slips between the
  // nodes of a coarse grid unless the cells that could hide it are refined.
  {
    const WorkspaceField field = sample_field(m, Grid::covering(b, extent / 256.0, 0.0));
    double top = 0.0;
    for (std::size_t k = 0; k < field.lci.size(); ++k) top = std::max(top, field.reach[k] ? field.lci[k] : 0.0);
    Mechanism thin = m;
    thin.min_lci = 0.98 * top;
    const double ref = restricted_area(thin, Restriction::lci, ref_grid, 1).area_mm2;
    WorkSeries s{"thin LCI-restricted area", "h_mm", "mm2", {}, {}, {},
                 "restricted_area(lci) with LCI >= " + format::fixed(thin.min_lci, 4) +
                     " (98 % of the largest LCI: a thin island) against the same on a grid 16x finer than the finest; "
                     "estimate = its own error estimate"};
    for (int k = k_lo; k <= k_hi; ++k) {
      const double h = extent / double(1 << k);
      const Grid grid = Grid::covering(b, h, h);
      SampledArea sa;
      const double t = median_time(tm, [&] { sa = restricted_area(thin, Restriction::lci, grid); });
      s.points.push_back({h, t, sa.area_mm2, std::fabs(sa.area_mm2 - ref), sa.error_mm2});
    }
    out.thin_lci_area_reference_mm2 = ref;
    out.thin_lci_threshold = thin.min_lci;
    out.restricted.push_back(std::move(s));
  }
}

// --- FK / IK precision ---------------------------------------------------------------------------

const std::vector<std::array<double, 2>> kStrata{{1e-1, 1.0 + 1e-9}, {1e-3, 1e-1}, {1e-6, 1e-3}, {1e-9, 1e-6}, {0.0, 1e-9}};
/// Targets of the last stratum (log-uniform); exactly singular inputs are the stability report's.
constexpr double kSmallestTarget = 1e-13;
/// Below this |sin| target a rounded input cannot carry the configuration (the distance to the
/// singularity is ~sin^2 of the length scale): the sample is built in a frame that puts the
/// sensitive input near zero, where doubles are dense (a rotated frame for FK, a translated one
/// for IK). The mechanism is the same up to the rounding of its base coordinates.
constexpr double kFrameShiftBelow = 3e-6;

int stratum_of(double s) {
  for (std::size_t i = 0; i < kStrata.size(); ++i)
    if (s >= kStrata[i][0] && s < kStrata[i][1]) return int(i);
  return 0;
}

QVec unitq(quad angle) {
  quad s, c;
  sincosq(angle, &s, &c);
  return {c, s};
}

/// Intersection of circles (c1, r1), (c2, r2) in quad, on side `side`; false if none.
bool intersect_q(QVec c1, quad r1, QVec c2, quad r2, int side, QVec& out) {
  const QVec v = c2 - c1;
  const quad dist = quadref::norm(v);
  if (dist == 0) return false;
  const quad K = (dist + r1 + r2) * (-dist + r1 + r2) * (dist - r1 + r2) * (dist + r1 - r2);
  if (K < 0) return false;
  const quad alpha = atan2q(sqrtq(K), dist * dist + r1 * r1 - r2 * r2);
  out = c1 + r1 * unitq(atan2q(v.y, v.x) + (side >= 0 ? alpha : -alpha));
  return true;
}

Vec2 round_vec(QVec v) { return {double(v.x), double(v.y)}; }

struct Sample {
  int base = 0;     ///< index of the design mechanism it comes from
  Mechanism m;      ///< the mechanism in the sample's frame
  int side = 1;     ///< FK branch
  double in1 = 0.0, in2 = 0.0;  ///< FK: theta1, theta2 (rad); IK: P (mm)
  double base1 = 0.0, base2 = 0.0;  ///< the same inputs in the design's frame (rounded), for batch timing
  quad out1 = 0, out2 = 0;      ///< reference: FK P (mm); IK theta1, theta2 (rad)
  double sin = 1.0;
  int stratum = 0;
};

double log_uniform(std::mt19937_64& rng, double lo, double hi) {
  std::uniform_real_distribution<double> u(std::log(lo), std::log(hi));
  return std::exp(u(rng));
}

std::optional<Sample> make_fk_sample(const Mechanism& base, int base_index, double s, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const quad L1 = base.L[0], L2 = base.L[1], L3 = base.L[2], L4 = base.L[3];
  const int side = base.assembly_mode == AssemblyMode::Minus ? -1 : 1;
  const bool stretched = U(rng) < 0.5;
  // |A1 - A2| for a tactor angle gamma with |sin gamma| = s, near pi (stretched) or 0 (folded).
  const quad half = asinq(quad(s)) / 2;  // (pi - gamma)/2 or gamma/2
  const quad D = stretched ? sqrtq((L3 + L4) * (L3 + L4) - 4 * L3 * L4 * sinq(half) * sinq(half))
                           : sqrtq((L3 - L4) * (L3 - L4) + 4 * L3 * L4 * sinq(half) * sinq(half));
  const int pick = U(rng) < 0.5 ? 1 : -1;
  double theta1 = -kPi + 2 * kPi * U(rng);
  Mechanism m = base;
  QVec A2;
  if (!intersect_q(quadref::q(m.O2), L2, quadref::q(m.O1) + L1 * unitq(theta1), D, pick, A2)) return std::nullopt;
  quad theta2 = atan2q(A2.y - quad(m.O2.y()), A2.x - quad(m.O2.x()));
  double phi_used = 0.0;
  if (s < kFrameShiftBelow) {
    // Rotate the frame so that theta2 becomes small: doubles near 0 resolve it finely enough.
    const double offset = (U(rng) < 0.5 ? -1 : 1) * (0.5 + 0.5 * U(rng)) * std::min(0.5, 4e11 * s * s);
    const double phi = double(theta2) - offset;
    phi_used = phi;
    quad sp, cp;
    sincosq(quad(phi), &sp, &cp);
    auto rot = [&](const Vec2& p) { return round_vec({cp * p.x() + sp * p.y(), -sp * p.x() + cp * p.y()}); };
    m.O1 = rot(base.O1);
    m.O2 = rot(base.O2);
    theta1 = double(quad(theta1) - quad(phi));
    if (!intersect_q(quadref::q(m.O2), L2, quadref::q(m.O1) + L1 * unitq(theta1), D, pick, A2)) return std::nullopt;
    theta2 = atan2q(A2.y - quad(m.O2.y()), A2.x - quad(m.O2.x()));
  }
  Sample out;
  out.base = base_index;
  out.m = m;
  out.m.assembly_mode = side > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
  out.side = side;
  out.in1 = theta1;
  out.in2 = double(theta2);
  out.base1 = theta1 + phi_used;
  out.base2 = out.in2 + phi_used;
  const quadref::QPose ref = quadref::fk(quadref::QMechanism(out.m), out.in1, out.in2, side);
  if (!ref.reachable || ref.continuum) return std::nullopt;
  out.out1 = ref.P.x;
  out.out2 = ref.P.y;
  out.sin = double(ref.type2_sin);
  out.stratum = stratum_of(out.sin);
  return out;
}

std::optional<Sample> make_ik_sample(const Mechanism& base, int base_index, double s, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const int leg = U(rng) < 0.5 ? 0 : 1;
  const int sigma = leg == 0 ? base.working_mode.sign1 : base.working_mode.sign2;
  const bool stretched = U(rng) < 0.5;
  const quad psi = sigma * (stretched ? asinq(quad(s)) : quadref::kQuadPi - asinq(quad(s)));
  const quad theta = -kPi + 2 * kPi * U(rng);
  Mechanism m = base;
  auto tactor = [&](const Mechanism& mm) {
    const Vec2& O = leg == 0 ? mm.O1 : mm.O2;
    return quadref::q(O) + quad(mm.L[leg]) * unitq(theta) + quad(mm.L[leg + 2]) * unitq(theta + psi);
  };
  QVec P = tactor(m);
  Vec2 shift_used(0.0, 0.0);
  if (s < kFrameShiftBelow) {
    // Translate the frame so that P lies near the origin, where doubles resolve it finely.
    const double r = (0.5 + 0.5 * U(rng)) * std::min(0.5, 4e11 * s * s) * base.length_scale();
    const double dir = 2 * kPi * U(rng);
    const Vec2 shift = round_vec(P) - r * Vec2(std::cos(dir), std::sin(dir));
    shift_used = shift;
    m.O1 = round_vec(quadref::q(base.O1) - quadref::q(shift));
    m.O2 = round_vec(quadref::q(base.O2) - quadref::q(shift));
    P = tactor(m);
  }
  Sample out;
  out.base = base_index;
  out.m = m;
  out.in1 = double(P.x);
  out.in2 = double(P.y);
  out.base1 = out.in1 + shift_used.x();
  out.base2 = out.in2 + shift_used.y();
  const quadref::QPose ref =
      quadref::ik(quadref::QMechanism(m), {out.in1, out.in2}, m.working_mode.sign1, m.working_mode.sign2);
  if (!ref.reachable || ref.continuum) return std::nullopt;
  out.out1 = ref.theta1;
  out.out2 = ref.theta2;
  out.sin = double(std::min(ref.type1_sin[0], ref.type1_sin[1]));
  out.stratum = stratum_of(out.sin);
  return out;
}

/// Error of one FK or IK answer against the sample's reference, in mm.
double error_mm(const Sample& s, bool is_ik, quad o1, quad o2) {
  if (!is_ik) return double(hypotq(o1 - s.out1, o2 - s.out2));
  const quad d1 = remainderq(o1 - s.out1, 2 * quadref::kQuadPi), d2 = remainderq(o2 - s.out2, 2 * quadref::kQuadPi);
  return double(std::max(quadref::qabs(d1) * quad(s.m.L[0]), quadref::qabs(d2) * quad(s.m.L[1])));
}

template <class T>
double ulp_of(double scale) {
  const T v = T(scale);
  return double(std::nextafter(v, std::numeric_limits<T>::infinity()) - v);
}

/// Runs one method over a stratum: errors sample by sample, and the median time per call of a
/// loop over all of them. `call(k, o1, o2)` returns false when the method finds no solution.
template <class Call>
PrecisionCell measure(const std::vector<const Sample*>& samples, bool is_ik, double ulp_rel, const Timing& tm,
                      Call&& call, std::function<void()> timed = {}) {
  PrecisionCell cell;
  double sum2 = 0.0, sum2_ulp = 0.0;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    ++cell.samples;
    quad o1 = 0, o2 = 0;
    if (!call(k, o1, o2)) {
      ++cell.failed;
      continue;
    }
    const double e = error_mm(*samples[k], is_ik, o1, o2);
    const double u = e / (ulp_rel * samples[k]->m.length_scale());
    cell.max_error_mm = std::max(cell.max_error_mm, e);
    cell.max_error_ulp = std::max(cell.max_error_ulp, u);
    sum2 += e * e;
    sum2_ulp += u * u;
  }
  const std::size_t ok = cell.samples - cell.failed;
  if (ok > 0) {
    cell.rms_error_mm = std::sqrt(sum2 / double(ok));
    cell.rms_error_ulp = std::sqrt(sum2_ulp / double(ok));
  }
  if (!samples.empty()) {
    if (!timed) {
      timed = [&] {
        quad o1, o2;
        for (std::size_t k = 0; k < samples.size(); ++k) call(k, o1, o2);
      };
    }
    cell.ns_per_call = 1e9 * median_time(tm, timed) / double(samples.size());
  }
  return cell;
}

/// ulp of the length scale relative to the scale itself (so ulp = this * scale, for this type).
template <class T>
double ulp_rel(const std::vector<const Sample*>& s) {
  if (s.empty()) return std::numeric_limits<T>::epsilon();
  const double scale = s.front()->m.length_scale();
  return ulp_of<T>(scale) / scale;
}

template <class T>
PrecisionCell templated_cell(const std::vector<const Sample*>& samples, bool is_ik, const Timing& tm) {
  std::vector<precision::MechanismT<T>> mech;
  std::vector<T> in1, in2;
  std::vector<int> side;
  for (const Sample* s : samples) {
    mech.emplace_back(s->m);
    in1.push_back(T(s->in1));
    in2.push_back(T(s->in2));
    side.push_back(s->side);
  }
  volatile double sink = 0.0;
  auto call = [&](std::size_t k, quad& o1, quad& o2) {
    T a = 0, b = 0;
    const bool ok = is_ik ? precision::ik(mech[k], in1[k], in2[k], a, b)
                          : precision::fk(mech[k], in1[k], in2[k], side[k], a, b);
    o1 = quad(a);
    o2 = quad(b);
    return ok;
  };
  auto timed = [&] {
    double acc = 0.0;
    for (std::size_t k = 0; k < mech.size(); ++k) {
      T a = 0, b = 0;
      const bool ok = is_ik ? precision::ik(mech[k], in1[k], in2[k], a, b)
                            : precision::fk(mech[k], in1[k], in2[k], side[k], a, b);
      acc += ok ? double(a + b) : 0.0;
    }
    sink = sink + acc;
  };
  return measure(samples, is_ik, ulp_rel<T>(samples), tm, call, timed);
}

/// The library's batch kernel over a stratum: errors from one call per sample (a sample near a
/// singularity has its own frame); the time from one batch call per design mechanism over the
/// same configurations expressed in the design's frame.
PrecisionCell batch_cell(const std::vector<const Sample*>& samples, bool is_ik,
                         const std::vector<const Mechanism*>& bases, const Timing& tm) {
  auto call = [&](std::size_t k, quad& o1, quad& o2) {
    const Sample& s = *samples[k];
    double a1 = s.in1, a2 = s.in2, r1 = 0.0, r2 = 0.0;
    Status st;
    if (is_ik) {
      ik_batch(s.m, {&a1, 1}, {&a2, 1}, {&r1, 1}, {&r2, 1}, {&st, 1});
    } else {
      fk_batch(s.m, {&a1, 1}, {&a2, 1}, {&r1, 1}, {&r2, 1}, {&st, 1});
    }
    o1 = r1;
    o2 = r2;
    return st != Status::unreachable;
  };
  std::map<int, std::vector<double>> in1, in2;
  for (const Sample* s : samples) {
    in1[s->base].push_back(s->base1);
    in2[s->base].push_back(s->base2);
  }
  std::vector<double> r1(samples.size()), r2(samples.size());
  std::vector<Status> st(samples.size());
  std::vector<Mechanism> ms;
  for (const Mechanism* b : bases) {
    ms.push_back(*b);
    if (ms.back().assembly_mode == AssemblyMode::Any) ms.back().assembly_mode = AssemblyMode::Plus;
  }
  volatile double sink = 0.0;
  auto timed = [&] {
    for (const auto& [base, x] : in1) {
      const std::size_t n = x.size();
      const std::vector<double>& y = in2.at(base);
      if (is_ik) {
        ik_batch(ms[base], x, y, {r1.data(), n}, {r2.data(), n}, {st.data(), n});
      } else {
        fk_batch(ms[base], x, y, {r1.data(), n}, {r2.data(), n}, {st.data(), n});
      }
      sink = sink + r1[0];
    }
  };
  return measure(samples, is_ik, ulp_rel<double>(samples), tm, call, timed);
}

}  // namespace

std::optional<double> fit_log_slope(const std::vector<double>& x, const std::vector<double>& y, double floor) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (std::size_t k = 0; k < x.size() && k < y.size(); ++k) {
    if (!(x[k] > 0.0) || !(y[k] > 0.0) || !(y[k] > floor) || !std::isfinite(x[k]) || !std::isfinite(y[k])) continue;
    const double lx = std::log(x[k]), ly = std::log(y[k]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
    ++n;
  }
  if (n < 2) return std::nullopt;
  const double den = n * sxx - sx * sx;
  if (!(std::fabs(den) > 1e-12 * std::max(1.0, n * sxx))) return std::nullopt;
  return (n * sxy - sx * sy) / den;
}

// --- tolerance estimates -------------------------------------------------------------------------

static void tolerance_study(const Mechanism& m, const Ellipse& target, const AccuracyOptions& o, MechanismAccuracy& out) {
  const Timing tm = timing_for(o.quick);
  // Illustrative tolerances: 0.05 mm on lengths and base positions, 0.5 deg on the joint angles;
  // 0.1 mm of play on each leg.
  ParameterSigmas sigma{};
  for (std::size_t j = 0; j < 8; ++j) sigma[j] = 0.05;
  sigma[8] = sigma[9] = 0.5 * format::kRadPerDeg;
  const std::array<double, 2> play{0.1, 0.1};
  const Vec2 P = target.center;
  if (ik(m, P).status != Status::ok) return;
  out.tolerance_reference_samples = o.quick ? 200000 : 1000000;
  out.tolerance_reference_3sigma_mm =
      major_3sigma_mm(tolerance_monte_carlo(m, std::vector<Vec2>{P}, sigma, out.tolerance_reference_samples, o.seed + 7)[0].covariance);
  const double ref = out.tolerance_reference_3sigma_mm;

  WorkSeries mc{"Monte Carlo 3-sigma", "samples", "mm", {}, {}, {},
                "tolerance_monte_carlo() of N printed devices; estimate = its standard error 3 sigma / sqrt(2 N)"};
  for (std::size_t n : {std::size_t(100), std::size_t(1000), std::size_t(10000), std::size_t(100000)}) {
    if (o.quick && n > 10000) break;
    MonteCarloTolerance r;
    const double t = median_time(tm, [&] { r = tolerance_monte_carlo(m, P, sigma, n, o.seed); });
    const double v = major_3sigma_mm(r.covariance);
    mc.points.push_back({double(n), t, v, std::abs(v - ref), v / std::sqrt(2.0 * double(n))});
  }
  // Order in N (about -1/2), above the reference's own standard error.
  fit(mc, 2.0 * ref / std::sqrt(2.0 * double(out.tolerance_reference_samples)), kAllPoints);
  out.tolerance.push_back(std::move(mc));
  ToleranceEstimate fo;
  const double t_fo = median_time(tm, [&] { fo = tolerance_first_order(m, P, sigma, 1e-4); });
  out.tolerance.push_back({"first-order 3-sigma", "samples", "mm",
                           {{0.0, t_fo, fo.ellipse_semi_axes.x(), std::abs(fo.ellipse_semi_axes.x() - ref), {}}},
                           {}, {}, "tolerance_first_order(): closed-form sensitivity, one evaluation"});

  // Play: the exact set's extent against devices with play drawn uniformly in their clearances
  // (sampling approaches the corners slowly) and against the first-order parallelogram.
  PlaySet exact;
  const double t_exact = median_time(tm, [&] { exact = tolerance_play(m, P, play); });
  out.play_extent_mm = exact.extent_mm;
  if (exact.status != Status::ok) return;
  const Pose q = ik(m, P);
  WorkSeries sampled{"play: sampled devices", "samples", "mm", {}, {}, {},
                     "largest |P' - P| over N devices whose legs start their distal links uniformly within the play "
                     "(the set's corners are reached only in the limit)"};
  for (std::size_t n : {std::size_t(100), std::size_t(1000), std::size_t(10000), std::size_t(100000)}) {
    if (o.quick && n > 10000) break;
    double far = 0.0;
    const double t = median_time(tm, [&] {
      std::mt19937_64 rng(o.seed + 11);
      std::uniform_real_distribution<double> u(0.0, 1.0);
      far = 0.0;
      for (std::size_t k = 0; k < n; ++k) {
        const auto disc = [&](double r) {
          const double rho = r * std::sqrt(u(rng)), phi = 2.0 * std::numbers::pi * u(rng);
          return Vec2(rho * std::cos(phi), rho * std::sin(phi));
        };
        const Vec2 a1 = q.A1 + disc(play[0]), a2 = q.A2 + disc(play[1]);
        const int side = (q.A2 - q.A1).x() * (q.P - q.A1).y() - (q.A2 - q.A1).y() * (q.P - q.A1).x() >= 0.0 ? 1 : -1;
        const CircleIntersection c = intersect_circles(a1, m.L[2], a2, m.L[3], side);
        if (c.status != Status::unreachable) far = std::max(far, (c.point - P).norm());
      }
    });
    sampled.points.push_back({double(n), t, far, std::abs(exact.extent_mm - far), {}});
  }
  fit(sampled, 0.0, kAllPoints);
  out.tolerance.push_back(std::move(sampled));
  out.tolerance.push_back({"play: first order", "samples", "mm",
                           {{0.0, t_exact, exact.linear_extent_mm, std::abs(exact.linear_extent_mm - exact.extent_mm), {}}},
                           {}, {}, "the parallelogram P + M^-1 [+-r1, +-r2] against the exact set (two thin annuli)"});
}

MechanismAccuracy mechanism_accuracy(const Mechanism& m, const Ellipse& target, const AccuracyOptions& o) {
  MechanismAccuracy out;
  out.mechanism = m.name;
  Region region;
  const double t_region = median_time(timing_for(o.quick), [&] { region = reachable_region(m); });
  say(o, "accuracy:   workspace area (cell counting, marching squares)");
  area_study(m, region, t_region, o, out);
  say(o, "accuracy:   coverage margin and min LCI");
  coverage_study(m, region, target, o, out);
  say(o, "accuracy:   restricted regions");
  restricted_study(m, region, o, out);
  say(o, "accuracy:   tolerance estimates");
  tolerance_study(m, target, o, out);
  return out;
}

PrecisionStudy precision_study(const std::vector<const Mechanism*>& mechanisms, std::string_view problem,
                               const AccuracyOptions& o) {
  const bool is_ik = problem == "ik";
  if (!is_ik && problem != "fk") throw std::invalid_argument("precision_study: problem must be \"fk\" or \"ik\"");
  PrecisionStudy study;
  study.problem = std::string(problem);
  study.stratified_by = is_ik ? "type I |sin| (smaller elbow angle)" : "type II |sin| (tactor angle)";
  study.strata = kStrata;
  const std::size_t per_stratum = o.quick ? 150 : 1000;
  std::mt19937_64 rng(o.seed + (is_ik ? 101 : 0));
  std::vector<std::vector<Sample>> by_stratum(kStrata.size());
  if (!mechanisms.empty()) {
    std::size_t attempts = 0, turn = 0;
    const std::size_t max_attempts = 40 * per_stratum * kStrata.size();
    while (attempts++ < max_attempts) {
      // Aim at the stratum furthest from full; the sample lands where its real |sin| says.
      std::size_t want = 0;
      for (std::size_t i = 1; i < kStrata.size(); ++i)
        if (by_stratum[i].size() < by_stratum[want].size()) want = i;
      if (by_stratum[want].size() >= per_stratum) break;
      const double lo = std::max(kStrata[want][0], kSmallestTarget), hi = std::min(kStrata[want][1], 1.0);
      const double s = log_uniform(rng, lo, hi);
      const int b = int(turn++ % mechanisms.size());
      auto sample = is_ik ? make_ik_sample(*mechanisms[b], b, s, rng) : make_fk_sample(*mechanisms[b], b, s, rng);
      if (!sample || by_stratum[sample->stratum].size() >= per_stratum) continue;
      by_stratum[sample->stratum].push_back(std::move(*sample));
    }
  }
  const Timing tm = timing_for(o.quick);
  const char* lib_full = is_ik ? "ik()" : "fk()";
  const char* lib_lean = is_ik ? "ik_angles()" : "fk_point()";
  const char* lib_batch = is_ik ? "ik_batch()" : "fk_batch()";
  study.methods = {{"float", std::numeric_limits<float>::epsilon(), false, {}},
                   {"double", std::numeric_limits<double>::epsilon(), false, {}},
                   {"long double", std::numeric_limits<long double>::epsilon(), false, {}},
                   {lib_full, std::numeric_limits<double>::epsilon(), true, {}},
                   {lib_lean, std::numeric_limits<double>::epsilon(), true, {}},
                   {lib_batch, std::numeric_limits<double>::epsilon(), true, {}}};
  for (std::size_t i = 0; i < kStrata.size(); ++i) {
    std::vector<const Sample*> samples;
    for (const Sample& s : by_stratum[i]) samples.push_back(&s);
    study.methods[0].cells.push_back(templated_cell<float>(samples, is_ik, tm));
    study.methods[1].cells.push_back(templated_cell<double>(samples, is_ik, tm));
    study.methods[2].cells.push_back(templated_cell<long double>(samples, is_ik, tm));
    study.methods[3].cells.push_back(measure(samples, is_ik, ulp_rel<double>(samples), tm,
                                             [&](std::size_t k, quad& o1, quad& o2) {
                                               const Sample& s = *samples[k];
                                               const Pose p = is_ik ? ik(s.m, {s.in1, s.in2})
                                                                    : fk(s.m, s.in1, s.in2, s.m.assembly_mode);
                                               o1 = is_ik ? p.theta1 : p.P.x();
                                               o2 = is_ik ? p.theta2 : p.P.y();
                                               return p.status != Status::unreachable;
                                             }));
    study.methods[4].cells.push_back(measure(samples, is_ik, ulp_rel<double>(samples), tm,
                                             [&](std::size_t k, quad& o1, quad& o2) {
                                               const Sample& s = *samples[k];
                                               if (is_ik) {
                                                 const AnglesResult r = ik_angles(s.m, {s.in1, s.in2});
                                                 o1 = r.theta1;
                                                 o2 = r.theta2;
                                                 return r.status != Status::unreachable;
                                               }
                                               const PointResult r = fk_point(s.m, s.in1, s.in2);
                                               o1 = r.P.x();
                                               o2 = r.P.y();
                                               return r.status != Status::unreachable;
                                             }));
    study.methods[5].cells.push_back(batch_cell(samples, is_ik, mechanisms, tm));
    // Order in eps over the three templated precisions.
    std::vector<double> eps, err;
    for (int k = 0; k < 3; ++k) {
      eps.push_back(study.methods[k].unit_roundoff);
      err.push_back(study.methods[k].cells.back().rms_error_mm);
    }
    study.order.push_back(samples.size() >= 2 ? fit_log_slope(eps, err) : std::nullopt);
  }
  return study;
}

std::optional<double> mirror_line(const Mechanism& a, const Ellipse& ta, const Mechanism& b, const Ellipse& tb) {
  // y -> 2c - y maps a onto b: the same x, the y coordinates summing to 2c, every sign of a
  // cross product (working and assembly modes) flipped, and theta -> -theta on the joint arcs.
  const double two_c = a.O1.y() + b.O1.y();
  const bool bases = a.O1.x() == b.O1.x() && a.O2.x() == b.O2.x() && a.O2.y() + b.O2.y() == two_c;
  const bool modes = a.working_mode.sign1 == -b.working_mode.sign1 && a.working_mode.sign2 == -b.working_mode.sign2 &&
                     int(a.assembly_mode) == -int(b.assembly_mode);
  bool limits = a.joint_limits.has_value() == b.joint_limits.has_value();
  if (limits && a.joint_limits) {
    for (std::size_t i = 0; i < 2; ++i) {
      limits = limits && (*b.joint_limits)[i].lo == -(*a.joint_limits)[i].hi && (*b.joint_limits)[i].hi == -(*a.joint_limits)[i].lo;
    }
  }
  const bool target = ta.center.x() == tb.center.x() && ta.center.y() + tb.center.y() == two_c && ta.axes == tb.axes &&
                      tb.angle == -ta.angle;
  if (!(bases && modes && limits && target && a.L == b.L && a.min_lci == b.min_lci)) return std::nullopt;
  return 0.5 * two_c;
}

AccuracyReport accuracy_report(const Design& design, const AccuracyOptions& o) {
  const auto t0 = Clock::now();
  AccuracyReport report;
  report.design = design.name;
  report.quick = o.quick;
  const std::vector<const Station*> stations = design.select_stations(o.station);
  std::vector<const Mechanism*> all;
  std::vector<const Ellipse*> targets;
  for (const Station* s : stations) {
    for (const Mechanism* m : s->mechanisms()) {
      // A mirror image of a mechanism already measured has the same figures (the regions, margins
      // and LCI are invariant under the reflection): they are that mechanism's, said so.
      std::optional<std::size_t> twin;
      std::optional<double> line;
      for (std::size_t k = 0; k < all.size() && !twin; ++k) {
        if (!report.mechanisms[k].mirror_of.empty()) continue;
        if ((line = mirror_line(*all[k], *targets[k], *m, s->target))) twin = k;
      }
      MechanismAccuracy ma;
      if (twin) {
        say(o, "accuracy: " + s->name + "/" + m->name + ": the mirror image of " + report.mechanisms[*twin].station + "/" +
                   report.mechanisms[*twin].mechanism);
        ma = report.mechanisms[*twin];
        ma.mirror_of = report.mechanisms[*twin].station + "/" + report.mechanisms[*twin].mechanism;
        ma.mirror_line_y_mm = *line;
        ma.mechanism = m->name;
      } else {
        say(o, "accuracy: " + s->name + "/" + m->name);
        ma = mechanism_accuracy(*m, s->target, o);
      }
      ma.station = s->name;
      report.mechanisms.push_back(std::move(ma));
      all.push_back(m);
      targets.push_back(&s->target);
    }
  }
  say(o, "accuracy: FK precision study");
  report.fk = precision_study(all, "fk", o);
  say(o, "accuracy: IK precision study");
  report.ik = precision_study(all, "ik", o);
  say(o, "accuracy: dynamics work-precision (BDF and explicit RK)");
  report.dynamics = dynamics_accuracy(design, o);
  report.seconds = seconds_since(t0);
  return report;
}

}  // namespace fivebar
