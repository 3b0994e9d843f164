// Tolerance studies of a five-bar (fivebar/tolerance.hpp): the sources from a design, the play
// set, robust coverage with its Monte Carlo reference, and the maps over the reachable region.
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <ostream>
#include <random>

#include "fivebar/coverage/coverage.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/io.hpp"
#include "fivebar/workspace/io.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/print.hpp"
#include "fivebar/sections/tolerance.hpp"
#include "fivebar/tolerance.hpp"
#include "fivebar/provenance.hpp"

namespace fivebar {
namespace {

constexpr double kDeg = format::kRadPerDeg;
/// Grid points per axis of the target ellipse's bounding box (those inside are the target's).
constexpr int kTargetGrid = 21;
/// Cap of the map's grid per axis.
constexpr int kMaxGrid = 1000;
/// Points of the ellipse's boundary at which robust coverage linearises the signed distance.
constexpr std::size_t kRobustBoundaryPoints = 72;
/// Tolerance of the certified robust margin, relative to the mechanism's longest link.
constexpr double kRobustTolRel = 1e-6;

double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }

/// Points of a kTargetGrid x kTargetGrid grid over the filled ellipse, centre included.
std::vector<Vec2> ellipse_grid(const Ellipse& e) {
  std::vector<Vec2> out;
  const double c = std::cos(e.angle);
  const double s = std::sin(e.angle);
  for (int i = 0; i < kTargetGrid; ++i) {
    for (int j = 0; j < kTargetGrid; ++j) {
      const double u = -1.0 + 2.0 * i / (kTargetGrid - 1);
      const double v = -1.0 + 2.0 * j / (kTargetGrid - 1);
      if (u * u + v * v > 1.0) continue;
      const double x = 0.5 * e.axes.x() * u;
      const double y = 0.5 * e.axes.y() * v;
      out.push_back(e.center + Vec2(c * x - s * y, s * x + c * y));
    }
  }
  return out;
}

/// The mechanism of a printed device: lengths and base positions moved by dq.
Mechanism perturbed(const Mechanism& m, const std::array<double, kToleranceParameters>& dq) {
  Mechanism p = m;
  for (std::size_t i = 0; i < 4; ++i) p.L[i] = m.L[i] + dq[i];
  p.O1 = m.O1 + Vec2(dq[4], dq[5]);
  p.O2 = m.O2 + Vec2(dq[6], dq[7]);
  return p;
}

bool lengths_positive(const Mechanism& m) {
  return std::all_of(m.L.begin(), m.L.end(), [](double l) { return l > 0.0; });
}

void monte_carlo_margins(const Mechanism& m, const Ellipse& target, const ParameterSpread& sigma, double fraction,
                         std::size_t samples, std::uint64_t seed, RobustCoverage& out);

}  // namespace

// --- Sources ------------------------------------------------------------------------------------

ToleranceSources tolerance_sources(const Design& design, const Station& station, const Mechanism& m) {
  const ToleranceSettings* given = design.get<ToleranceSettings>();
  const ToleranceSettings t = given ? *given : ToleranceSettings{};
  ToleranceSources out;
  out.sigma = parameter_sigmas(t);
  out.robust_fraction = t.robust_fraction;
  out.samples = t.samples;
  out.seed = t.seed;

  const ControllerSettings* controller = design.get<ControllerSettings>();
  if (t.adc_bits) {
    out.rad_per_count = {angle_per_count(*t.adc_bits), angle_per_count(*t.adc_bits)};
    out.resolution_source = "tolerance.adc_bits: 2^" + std::to_string(*t.adc_bits) + " counts per turn";
  } else if (controller != nullptr) {
    const double volts = (controller->adc_range_v[1] - controller->adc_range_v[0]) / std::ldexp(1.0, controller->adc_bits);
    for (int j = 0; j < 2; ++j) {
      const Potentiometer pot = controller->joint(station.name, m.name, j + 1).potentiometer;
      out.rad_per_count[static_cast<std::size_t>(j)] = volts * std::abs(pot.rad_per_volt);
    }
    out.resolution_source = "controller: " + std::to_string(controller->adc_bits) + "-bit ADC over its range, "
                            "times each joint's potentiometer scale";
  } else {
    out.rad_per_count = {angle_per_count(16), angle_per_count(16)};
    out.resolution_source = "default: 2^16 counts per turn (no controller: section)";
  }

  // The potentiometer's linearity joins the calibration offset in quadrature (a uniform band of
  // half-width a has sigma a / sqrt(3)); the ADC's quantisation is the resolution, reported apart.
  const double linearity = t.linearity_percent / 100.0 * t.pot_travel_deg * kDeg;  // half band
  for (std::size_t j = 0; j < 2; ++j) {
    const double offset = out.sigma[8 + j];
    out.sigma[8 + j] = std::sqrt(offset * offset + linearity * linearity / 3.0);
  }

  // A calibration's posterior covariance replaces the sigmas it covers (docs/calibrate.md
  // "Posterior covariance in the design"): the provenance entries' sigmas and correlations of this
  // mechanism's twelve calibration keys.
  out.spread_source = given ? "tolerance: section" : "tolerance: defaults (assumptions)";
  const std::array<std::string, 12> keys = calibration_keys(design, station.name, m.name);
  const ProvenanceCovariance pc = provenance_covariance(design, std::vector<std::string>(keys.begin(), keys.end()));
  if (std::find(pc.measured.begin(), pc.measured.end(), true) != pc.measured.end()) {
    CalibratedUncertainty cu;
    const auto& names = tolerance_parameter_names();
    std::vector<std::string> covered, rest;
    for (int a = 0; a < 12; ++a) {
      const auto ua = static_cast<std::size_t>(a);
      cu.measured[ua] = pc.measured[ua];
      if (pc.measured[ua]) cu.keys.push_back(keys[ua]);
      for (int b = 0; b < 12; ++b) {
        if (pc.measured[ua] && pc.measured[static_cast<std::size_t>(b)]) cu.covariance(a, b) = pc.covariance(a, b);
      }
      if (a < 8) {
        if (!pc.measured[ua]) cu.covariance(a, a) = out.sigma[ua] * out.sigma[ua];
        (pc.measured[ua] ? covered : rest).emplace_back(names[ua]);
      }
    }
    for (int j = 0; j < 2; ++j) {
      const auto uj = static_cast<std::size_t>(j);
      cu.rad_per_volt[uj] = controller ? controller->joint(station.name, m.name, j + 1).potentiometer.rad_per_volt
                                       : ControllerSettings{}.potentiometer.rad_per_volt;
      // A joint whose volts_at_zero and rad_per_volt are both calibrated keeps only the linearity;
      // otherwise the whole tolerance angle sigma (the calibration offset and the linearity) stays:
      // a V0 measured at a held slope (one hard stop) does not replace it.
      const bool pot = pc.measured[static_cast<std::size_t>(8 + 2 * j)] && pc.measured[static_cast<std::size_t>(9 + 2 * j)];
      cu.angle_variance[uj] = pot ? linearity * linearity / 3.0 : out.sigma[8 + uj] * out.sigma[8 + uj];
      (pot ? covered : rest).emplace_back(names[8 + uj]);
    }
    cu.sources = pc.sources;
    out.calibrated = cu;
    out.spread_source = "calibration posterior covariance (" + format::join(pc.sources) + ") for " + format::join(covered) +
                        (rest.empty() ? std::string() : "; " + out.spread_source + " for " + format::join(rest)) +
                        (std::find(covered.begin(), covered.end(), "theta1") != covered.end() ||
                                 std::find(covered.begin(), covered.end(), "theta2") != covered.end()
                             ? "; potentiometer linearity kept"
                             : "");
  }

  const PrintSettings* print = design.get<PrintSettings>();
  const double pin = t.pin_play_mm ? *t.pin_play_mm : (print ? print->pin_clearance : PrintSettings{}.pin_clearance);
  const double half_backlash = 0.5 * t.backlash_deg * kDeg;
  out.leg_play_mm = {t.shaft_play_mm + pin + 2.0 * m.L[0] * std::sin(0.5 * half_backlash),
                     t.shaft_play_mm + 2.0 * pin + 2.0 * m.L[1] * std::sin(0.5 * half_backlash)};
  return out;
}

// --- Play set -------------------------------------------------------------------------------------

PlaySet tolerance_play(const Mechanism& m, const Vec2& P, const std::array<double, 2>& r) {
  PlaySet out;
  const Pose pose = ik(m, P);
  out.status = pose.status;
  if (pose.status != Status::ok) return out;
  if (r[0] < 0.0 || r[1] < 0.0) throw InputError("leg play must be >= 0 mm");
  if (r[0] == 0.0 && r[1] == 0.0) {  // no play: the set is the point itself
    out.corners.assign(4, P);
    return out;
  }
  // First-order parallelogram: P + M^{-1} [s1 r1, s2 r2], M = [u1^T; u2^T].
  const Vec2 u1 = (pose.P - pose.A1).normalized();
  const Vec2 u2 = (pose.P - pose.A2).normalized();
  const double det = cross(u1, u2);
  Eigen::Matrix2d inv;
  inv << u2.y(), -u1.y(), -u2.x(), u1.x();
  inv /= det;
  for (const double s1 : {-1.0, 1.0})
    for (const double s2 : {-1.0, 1.0})
      out.linear_extent_mm = std::max(out.linear_extent_mm, (inv * Eigen::Vector2d(s1 * r[0], s2 * r[1])).norm());
  // Exact set: corners of the two annuli on P's side of the line A1 -> A2.
  const int side = cross(pose.A2 - pose.A1, pose.P - pose.A1) >= 0.0 ? 1 : -1;
  bool all = true;
  for (const double s1 : {-1.0, 1.0}) {
    for (const double s2 : {-1.0, 1.0}) {
      const double R1 = m.L[2] + s1 * r[0];
      const double R2 = m.L[3] + s2 * r[1];
      const CircleIntersection c =
          (R1 > 0.0 && R2 > 0.0) ? intersect_circles(pose.A1, R1, pose.A2, R2, side) : CircleIntersection{};
      if (c.status == Status::unreachable) {
        all = false;
        continue;
      }
      out.corners.push_back(c.point);
      out.extent_mm = std::max(out.extent_mm, (c.point - P).norm());
    }
  }
  if (!all || !std::isfinite(out.linear_extent_mm)) out.status = Status::singular_type2;
  if (!std::isfinite(out.linear_extent_mm)) out.linear_extent_mm = 0.0;
  return out;
}

bool in_play_set(const Mechanism& m, const Vec2& P, const std::array<double, 2>& r, const Vec2& X, double slack) {
  const Pose pose = ik(m, P);
  if (pose.status != Status::ok) return false;
  const double d1 = (X - pose.A1).norm();
  const double d2 = (X - pose.A2).norm();
  const int side = cross(pose.A2 - pose.A1, pose.P - pose.A1) >= 0.0 ? 1 : -1;
  const bool same_side = side * cross(pose.A2 - pose.A1, X - pose.A1) >= -slack * (pose.A2 - pose.A1).norm();
  return std::abs(d1 - m.L[2]) <= r[0] + slack && std::abs(d2 - m.L[3]) <= r[1] + slack && same_side;
}

// --- Robust coverage ------------------------------------------------------------------------------

double normal_quantile(double p) {
  if (!(p > 0.0 && p < 1.0)) throw InputError("normal_quantile: p must be in (0, 1)");
  // Phi(x) = erfc(-x / sqrt 2) / 2; Newton from a logistic start (|x| < 9 for any double p).
  double x = std::log(p / (1.0 - p)) / 1.702;
  for (int k = 0; k < 60; ++k) {
    const double f = 0.5 * std::erfc(-x / std::numbers::sqrt2) - p;
    const double d = std::exp(-0.5 * x * x) / std::sqrt(2.0 * std::numbers::pi);
    if (d == 0.0) break;
    const double step = std::clamp(f / d, -2.0, 2.0);
    x -= step;
    if (std::abs(step) <= 1e-15 * std::max(1.0, std::abs(x))) break;
  }
  return x;
}

RobustCoverage robust_coverage(const Mechanism& m, const Ellipse& target, const ParameterSpread& spread,
                               double fraction, std::size_t samples, std::uint64_t seed) {
  RobustCoverage out;
  out.fraction = fraction;
  out.calibrated = spread.calibrated();
  const ParameterSigmas& sigma = spread.sigma();
  const Containment nominal = containment(m, target);
  out.margin_mm = nominal.margin_mm;
  out.decided = nominal.decided;
  out.worst_point = nominal.worst_point;
  out.z = normal_quantile(fraction);
  // The signed distance d(b) of each boundary point b of the ellipse to the region's boundary, as
  // the certified margin of a circle of radius eps at b plus eps (exact for the annuli), for the
  // design and for each parameter moved by +-1 % of its sigma (central differences).
  const double scale = std::max({m.L[0], m.L[1], m.L[2], m.L[3]});
  const double eps = 1e-6 * scale;
  std::vector<Vec2> boundary(kRobustBoundaryPoints);
  for (std::size_t k = 0; k < boundary.size(); ++k)
    boundary[k] = target.boundary_point(2.0 * std::numbers::pi * static_cast<double>(k) / static_cast<double>(boundary.size()));
  const auto distances = [&](const Mechanism& mech) {
    std::vector<double> d(boundary.size());
    for (std::size_t k = 0; k < boundary.size(); ++k) {
      Ellipse dot;
      dot.center = boundary[k];
      dot.axes = {2.0 * eps, 2.0 * eps};
      d[k] = containment(mech, dot).margin_mm + eps;
    }
    return d;
  };
  // Inside: the certified minimum over the whole boundary (lib/src/tolerance/tolerance_robust.cpp). Outside
  // (or undecided) the first-order distances do not hold across the boundary: the sampled estimate
  // below, reported as not certified.
  if (nominal.decided && nominal.margin_mm > 0.0) {
    const RobustMarginBound b = robust_margin_min(m, target, spread, out.z, kRobustTolRel * scale);
    out.robust_margin_mm = b.value_mm;
    out.robust_margin_lower_mm = b.lower_mm;
    out.robust_certified = b.certified;
    out.sigma_mm = b.at.sigma_mm;
    out.gradient = b.at.gradient;
    out.robust_point = b.point;
    out.fraction_first_order = b.fraction_first_order;
    out.robust_margin_mm = std::min(out.robust_margin_mm, out.margin_mm);
    out.robust_margin_lower_mm = std::min(out.robust_margin_lower_mm, out.robust_margin_mm);
    out.covered = out.robust_margin_mm >= 0.0;
    monte_carlo_margins(m, target, spread, fraction, samples, seed, out);
    return out;
  }
  const std::vector<double> d0 = distances(m);
  // The signed distance of a point to a leg's set moves at most 1 mm per mm of any length or base
  // coordinate (its boundary arcs' radii and centres do), so sigma(b) <= S = sqrt(sum_j sigma_j^2)
  // over the eight and d(b) - z S bounds the robust margin at b from below: the gradients are
  // needed only at the points, taken by increasing d(b), until that bound passes the best robust
  // margin found (5 % slack for the central differences at a kink).
  // Correlated errors: g^T C g <= (sum_j |g_j| sigma_j)^2 <= (sum_j sigma_j)^2 (|C_jk| <= sigma_j sigma_k).
  double bound_var = 0.0, bound_sum = 0.0;
  for (std::size_t j = 0; j < 8; ++j) bound_var += sigma[j] * sigma[j], bound_sum += sigma[j];
  const double S = 1.05 * (spread.correlated() ? bound_sum : std::sqrt(bound_var));
  std::vector<std::size_t> order(boundary.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return d0[a] < d0[b]; });
  const auto point_distance = [&](const Mechanism& mech, const Vec2& at) {
    Ellipse dot;
    dot.center = at;
    dot.axes = {2.0 * eps, 2.0 * eps};
    return containment(mech, dot).margin_mm + eps;
  };
  std::array<Mechanism, 16> moved;
  std::array<bool, 8> usable{};
  for (std::size_t j = 0; j < 8; ++j) {  // the angle offsets do not move the region
    std::array<double, kToleranceParameters> dq{};
    dq[j] = 0.01 * sigma[j];
    moved[2 * j] = perturbed(m, dq);
    dq[j] = -0.01 * sigma[j];
    moved[2 * j + 1] = perturbed(m, dq);
    usable[j] = sigma[j] > 0.0 && lengths_positive(moved[2 * j]) && lengths_positive(moved[2 * j + 1]);
  }
  out.robust_margin_mm = std::numeric_limits<double>::infinity();
  out.fraction_first_order = 1.0;
  for (const std::size_t k : order) {
    if (d0[k] - out.z * S >= out.robust_margin_mm) break;  // no later point can do worse
    std::array<double, kToleranceParameters> g{};
    for (std::size_t j = 0; j < 8; ++j) {
      if (!usable[j]) continue;
      g[j] = (point_distance(moved[2 * j], boundary[k]) - point_distance(moved[2 * j + 1], boundary[k])) /
             (0.02 * sigma[j]);
    }
    const double s = std::sqrt(spread.variance(g));
    const double robust = d0[k] - out.z * s;
    if (robust < out.robust_margin_mm) {
      out.robust_margin_mm = robust;
      out.sigma_mm = s;
      out.gradient = g;
      out.robust_point = boundary[k];
    }
    const double covering = s > 0.0 ? 0.5 * std::erfc(-d0[k] / (s * std::numbers::sqrt2)) : (d0[k] >= 0.0 ? 1.0 : 0.0);
    out.fraction_first_order = std::min(out.fraction_first_order, covering);
  }
  // The nominal margin also sees what the boundary points cannot (a hole inside the ellipse).
  out.robust_margin_mm = std::min(out.robust_margin_mm, out.margin_mm);
  out.robust_margin_lower_mm = out.robust_margin_mm;
  out.covered = out.robust_margin_mm >= 0.0;
  monte_carlo_margins(m, target, spread, fraction, samples, seed, out);
  return out;
}

namespace {

void monte_carlo_margins(const Mechanism& m, const Ellipse& target, const ParameterSpread& sigma, double fraction,
                         std::size_t samples, std::uint64_t seed, RobustCoverage& out) {
  if (samples == 0) return;

  // Draws first, in order, so that the answer does not depend on the threads.
  std::vector<std::array<double, kToleranceParameters>> draws(samples);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (auto& dq : draws) {
    std::array<double, kToleranceParameters> z{};
    for (std::size_t j = 0; j < kToleranceParameters; ++j) z[j] = normal(rng);
    dq = sigma.draw(z);
  }
  std::vector<double> margins(samples);
  const auto n = static_cast<std::ptrdiff_t>(samples);
#pragma omp parallel for schedule(dynamic, 64)
  for (std::ptrdiff_t k = 0; k < n; ++k) {
    const Mechanism p = perturbed(m, draws[static_cast<std::size_t>(k)]);
    margins[static_cast<std::size_t>(k)] =
        lengths_positive(p) ? containment(p, target).margin_mm : -std::numeric_limits<double>::infinity();
  }
  out.samples = samples;
  out.samples_covering = static_cast<std::size_t>(std::count_if(margins.begin(), margins.end(), [](double v) { return v >= 0.0; }));
  out.fraction_monte_carlo = static_cast<double>(out.samples_covering) / static_cast<double>(samples);
  out.monte_carlo_stderr =
      std::sqrt(out.fraction_monte_carlo * (1.0 - out.fraction_monte_carlo) / static_cast<double>(samples));
  const auto q = static_cast<std::size_t>(std::floor((1.0 - fraction) * static_cast<double>(samples - 1)));
  std::nth_element(margins.begin(), margins.begin() + static_cast<std::ptrdiff_t>(q), margins.end());
  const double quantile = margins[q];
  out.quantile_margin_mm = std::isfinite(quantile) ? quantile : -std::numeric_limits<double>::max();
  const QuantileBound bound = quantile_lower_bound_rank(samples, 1.0 - fraction, out.quantile_confidence);
  out.quantile_lower_rank = bound.rank;
  if (bound.rank == 0) {
    out.quantile_lower_mm = -std::numeric_limits<double>::infinity();
  } else {
    std::nth_element(margins.begin(), margins.begin() + static_cast<std::ptrdiff_t>(bound.rank - 1), margins.end());
    const double lower = margins[bound.rank - 1];
    out.quantile_lower_mm = std::isfinite(lower) ? lower : -std::numeric_limits<double>::max();
  }
}

}  // namespace

std::vector<DeviceSample> tolerance_devices(const Mechanism& m, const Ellipse& target, const ParameterSpread& spread,
                                            std::size_t samples, std::uint64_t seed) {
  std::vector<DeviceSample> out(samples);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const Pose nominal = ik(m, target.center);
  const ParameterSpread sigma = nominal.status == Status::ok ? spread.at(nominal.theta1, nominal.theta2) : spread;
  for (DeviceSample& d : out) {
    std::array<double, kToleranceParameters> z{};
    for (std::size_t j = 0; j < kToleranceParameters; ++j) z[j] = normal(rng);
    d.dq = sigma.draw(z);
  }
  Mechanism free = m;
  free.joint_limits.reset();
  if (nominal.status == Status::ok) free.assembly_mode = nominal.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
  const auto n = static_cast<std::ptrdiff_t>(samples);
#pragma omp parallel for schedule(dynamic, 64)
  for (std::ptrdiff_t k = 0; k < n; ++k) {
    DeviceSample& d = out[static_cast<std::size_t>(k)];
    const Mechanism p = perturbed(m, d.dq);
    if (!lengths_positive(p)) {
      d.margin_mm = -std::numeric_limits<double>::max();
      continue;
    }
    d.margin_mm = containment(p, target).margin_mm;
    if (nominal.status != Status::ok) continue;
    const PointResult r = fk_point(perturbed(free, d.dq), nominal.theta1 + d.dq[8], nominal.theta2 + d.dq[9]);
    d.status = r.status;
    if (r.status == Status::ok) d.error_mm = r.P - target.center;
  }
  return out;
}

void write_devices_csv(std::ostream& out, const std::vector<DeviceSample>& devices) {
  out << "device,dL1_mm,dL2_mm,dL3_mm,dL4_mm,dO1x_mm,dO1y_mm,dO2x_mm,dO2y_mm,dtheta1_deg,dtheta2_deg,status,"
         "error_x_mm,error_y_mm,margin_mm,covers\n";
  for (std::size_t k = 0; k < devices.size(); ++k) {
    const DeviceSample& d = devices[k];
    out << k;
    for (std::size_t j = 0; j < kToleranceParameters; ++j) out << ',' << format::shortest(j >= 8 ? d.dq[j] / kDeg : d.dq[j]);
    out << ',' << to_string(d.status) << ',' << format::shortest(d.error_mm.x()) << ',' << format::shortest(d.error_mm.y()) << ','
        << format::shortest(d.margin_mm) << ',' << (d.margin_mm >= 0.0 ? 1 : 0) << '\n';
  }
}

// --- Maps -----------------------------------------------------------------------------------------

ToleranceMap tolerance_map(const Mechanism& m, const std::string& station, const Ellipse& target,
                           const ToleranceSources& src, double spacing_mm) {
  if (!(spacing_mm > 0.0) || !std::isfinite(spacing_mm)) throw InputError("spacing_mm must be > 0");
  ToleranceMap map;
  map.station = station;
  map.mechanism = m.name;
  map.target = target;
  const double per_count = std::max(src.rad_per_count[0], src.rad_per_count[1]);
  const ParameterSpread spread = src.spread();
  // Bounding box of the intersection of the two outer disks (the reachable region's superset).
  const double R1 = m.L[0] + m.L[2], R2 = m.L[1] + m.L[3];
  const double xlo = std::max(m.O1.x() - R1, m.O2.x() - R2), xhi = std::min(m.O1.x() + R1, m.O2.x() + R2);
  const double ylo = std::max(m.O1.y() - R1, m.O2.y() - R2), yhi = std::min(m.O1.y() + R1, m.O2.y() + R2);
  double h = spacing_mm;
  while ((xhi - xlo) / h + 1.0 > kMaxGrid || (yhi - ylo) / h + 1.0 > kMaxGrid) h *= 2.0;
  map.spacing_mm = h;
  map.x0 = xlo;
  map.y0 = ylo;
  map.nx = std::max(1, static_cast<int>(std::floor((xhi - xlo) / h)) + 1);
  map.ny = std::max(1, static_cast<int>(std::floor((yhi - ylo) / h)) + 1);
  const std::size_t n = static_cast<std::size_t>(map.nx) * static_cast<std::size_t>(map.ny);
  map.field_status.assign(n, static_cast<std::uint8_t>(Status::unreachable));
  map.field_3sigma_mm.assign(n, 0.0);
  map.field_worst_case_mm.assign(n, 0.0);
  map.field_resolution_um.assign(n, 0.0);
  map.field_play_mm.assign(n, 0.0);
  map.field_near_singular.assign(n, 0);
  const auto count = static_cast<std::ptrdiff_t>(n);
#pragma omp parallel for schedule(static)
  for (std::ptrdiff_t k = 0; k < count; ++k) {
    const auto idx = static_cast<std::size_t>(k);
    const Vec2 p(map.x0 + h * static_cast<double>(k % map.nx), map.y0 + h * static_cast<double>(k / map.nx));
    const ToleranceEstimate e = tolerance_first_order(m, p, spread, per_count);
    map.field_status[idx] = static_cast<std::uint8_t>(e.status);
    if (e.status != Status::ok) continue;
    map.field_3sigma_mm[idx] = e.ellipse_semi_axes.x();
    map.field_worst_case_mm[idx] = e.worst_case_mm;
    map.field_near_singular[idx] = e.near_singular ? 1 : 0;
    map.field_resolution_um[idx] = e.resolution_um;
    map.field_play_mm[idx] = tolerance_play(m, p, src.leg_play_mm).extent_mm;
  }

  map.centre = tolerance_first_order(m, target.center, spread, per_count);
  map.centre_monte_carlo = tolerance_monte_carlo(m, target.center, spread, src.samples, src.seed);
  map.centre_monte_carlo_3sigma_mm = major_3sigma_mm(map.centre_monte_carlo.covariance);
  map.centre_play = tolerance_play(m, target.center, src.leg_play_mm);
  map.centre_corners = tolerance_corners(m, target.center, spread);
  map.target_points_mm = ellipse_grid(target);
  // Where a figure is the same everywhere (every sigma 0: all zero), its worst point is the
  // target's centre, a point of the target, not the origin (docs/reliability.md "JSON and exported files").
  map.worst_case_at = map.worst_3sigma_at = map.worst_case_first_order_at = map.worst_resolution_at = map.worst_play_at =
      target.center;
  for (const Vec2& p : map.target_points_mm) {
    ++map.target_points;
    const ToleranceEstimate e = tolerance_first_order(m, p, spread, per_count);
    map.target_estimates.push_back(e);
    const PlaySet play = tolerance_play(m, p, src.leg_play_mm);
    if (e.status != Status::ok || play.status != Status::ok) {
      ++map.target_not_ok;
      continue;
    }
    const CornerEnumeration corners = tolerance_corners(m, p, spread);
    if (e.near_singular) {
      ToleranceMap::Flagged f;
      f.at = p;
      f.first_order = e;
      f.corners = corners;
      map.near_singular.push_back(f);
    } else if (corners.worst_mm > 1.1 * e.worst_case_mm) {
      ++map.first_order_low_by_10_percent;
    }
    if (corners.status == Status::ok && corners.worst_mm > map.worst_case_mm) {
      map.worst_case_mm = corners.worst_mm;
      map.worst_case_at = p;
      map.worst_case_flagged = e.near_singular;
    }
    if (e.ellipse_semi_axes.x() > map.worst_3sigma_mm) {
      map.worst_3sigma_mm = e.ellipse_semi_axes.x();
      map.worst_3sigma_at = p;
      map.worst_3sigma_flagged = e.near_singular;
    }
    if (e.worst_case_mm > map.worst_case_first_order_mm) {
      map.worst_case_first_order_mm = e.worst_case_mm;
      map.worst_case_first_order_at = p;
      map.worst_case_first_order_flagged = e.near_singular;
    }
    if (e.resolution_um > map.worst_resolution_um) {
      map.worst_resolution_um = e.resolution_um;
      map.worst_resolution_at = p;
    }
    if (play.extent_mm > map.worst_play_mm) {
      map.worst_play_mm = play.extent_mm;
      map.worst_play_at = p;
    }
  }
  if (!map.near_singular.empty()) {  // the Monte Carlo where the first order is not to be trusted
    std::vector<Vec2> at;
    for (const auto& f : map.near_singular) at.push_back(f.at);
    const auto mc = tolerance_monte_carlo(m, at, spread, src.samples, src.seed);
    for (std::size_t k = 0; k < at.size(); ++k) {
      map.near_singular[k].monte_carlo = mc[k];
      map.near_singular[k].monte_carlo_3sigma_mm = major_3sigma_mm(mc[k].covariance);
    }
  }
  map.robust = robust_coverage(m, target, spread, src.robust_fraction, src.samples, src.seed);
  map.spread_source = src.spread_source;
  map.calibrated = spread.calibrated();
  return map;
}

// --- Outputs ----------------------------------------------------------------------------------

Json to_json(const RobustCoverage& r) {
  const auto xy = [](const Vec2& p) { return Json::array({p.x(), p.y()}); };
  Json robust;
  robust["fraction"] = r.fraction;
  robust["margin_mm"] = r.margin_mm;
  robust["decided"] = r.decided;
  robust["margin_sigma_first_order_mm"] = r.sigma_mm;
  robust["calibrated"] = r.calibrated;
  robust["z"] = r.z;
  robust["robust_margin_first_order_mm"] = r.robust_margin_mm;
  robust["robust_margin_first_order_lower_mm"] = r.robust_margin_lower_mm;
  robust["robust_margin_first_order_certified"] = r.robust_certified;
  robust["covered"] = r.covered;
  robust["fraction_first_order_at_most"] = r.fraction_first_order;
  robust["robust_point_mm"] = xy(r.robust_point);
  robust["worst_point_mm"] = xy(r.worst_point);
  robust["monte_carlo_samples"] = r.samples;
  robust["monte_carlo_covering"] = r.samples_covering;
  robust["fraction_monte_carlo"] = r.fraction_monte_carlo;
  robust["fraction_monte_carlo_stderr"] = r.monte_carlo_stderr;
  robust["monte_carlo_quantile_margin_mm"] = r.quantile_margin_mm;
  // -inf (too few samples for the confidence) is written as null.
  robust["monte_carlo_quantile_lower_mm"] =
      std::isfinite(r.quantile_lower_mm) ? Json(r.quantile_lower_mm) : Json(nullptr);
  robust["monte_carlo_quantile_confidence"] = r.quantile_confidence;
  return robust;
}

Json to_json(const ToleranceMap& map) {
  const auto xy = [](const Vec2& p) { return Json::array({p.x(), p.y()}); };
  Json j;
  j["mechanism"] = map.mechanism;
  j["sigmas_from"] = map.spread_source;
  j["calibrated"] = map.calibrated;
  j["centre_status"] = std::string(to_string(map.centre.status));
  j["centre_3sigma_first_order_mm"] = map.centre.ellipse_semi_axes.x();
  j["centre_3sigma_minor_first_order_mm"] = map.centre.ellipse_semi_axes.y();
  j["centre_3sigma_angle_first_order_deg"] = angle_deg(map.centre.ellipse_angle);
  // The +-3 sigma corners on the real kinematics; the first-order corner beside it.
  j["centre_worst_case_mm"] = map.centre_corners.worst_mm;
  j["centre_worst_case_corners"] = map.centre_corners.corners;
  j["centre_worst_case_corners_failed"] = map.centre_corners.failed;
  j["centre_worst_case_first_order_mm"] = map.centre.worst_case_mm;
  j["centre_sum_of_effects_first_order_mm"] = map.centre.sum_of_effects_mm;
  j["centre_near_singular"] = map.centre.near_singular;
  j["centre_resolution_um"] = map.centre.resolution_um;
  j["centre_monte_carlo_3sigma_mm"] = map.centre_monte_carlo_3sigma_mm;
  j["monte_carlo_samples_used"] = map.centre_monte_carlo.used;
  j["monte_carlo_samples_failed"] = map.centre_monte_carlo.failed;
  j["centre_play_status"] = std::string(to_string(map.centre_play.status));
  j["centre_play_mm"] = map.centre_play.extent_mm;
  j["centre_play_first_order_mm"] = map.centre_play.linear_extent_mm;
  j["target_points"] = map.target_points;
  j["target_points_not_ok"] = map.target_not_ok;
  j["target_worst_3sigma_first_order_mm"] = map.worst_3sigma_mm;
  j["target_worst_3sigma_first_order_at_mm"] = xy(map.worst_3sigma_at);
  j["target_worst_case_mm"] = map.worst_case_mm;
  j["target_worst_case_at_mm"] = xy(map.worst_case_at);
  j["target_worst_case_first_order_mm"] = map.worst_case_first_order_mm;
  j["target_worst_case_first_order_at_mm"] = xy(map.worst_case_first_order_at);
  j["target_points_first_order_low_by_10_percent"] = map.first_order_low_by_10_percent;
  j["target_worst_3sigma_first_order_near_singular"] = map.worst_3sigma_flagged;
  j["target_worst_case_near_singular"] = map.worst_case_flagged;
  j["target_worst_case_first_order_near_singular"] = map.worst_case_first_order_flagged;
  Json flagged = Json::array();
  for (const auto& f : map.near_singular) {
    flagged.push_back({{"at_mm", xy(f.at)},
                       {"first_order_3sigma_mm", f.first_order.ellipse_semi_axes.x()},
                       {"first_order_worst_case_mm", f.first_order.worst_case_mm},
                       {"monte_carlo_3sigma_mm", f.monte_carlo_3sigma_mm},
                       {"monte_carlo_samples_used", f.monte_carlo.used},
                       {"monte_carlo_samples_failed", f.monte_carlo.failed},
                       {"corners_worst_case_mm", f.corners.worst_mm},
                       {"corners_failed", f.corners.failed}});
  }
  j["target_points_near_singular"] = map.near_singular.size();
  j["near_singular"] = std::move(flagged);
  j["target_worst_resolution_um"] = map.worst_resolution_um;
  j["target_worst_resolution_at_mm"] = xy(map.worst_resolution_at);
  j["target_worst_play_mm"] = map.worst_play_mm;
  j["target_worst_play_at_mm"] = xy(map.worst_play_at);
  j["robust_coverage"] = to_json(map.robust);
  j["grid"] = {{"origin_mm", xy(Vec2(map.x0, map.y0))}, {"spacing_mm", map.spacing_mm}, {"nx", map.nx}, {"ny", map.ny}};
  // Quantities that do not exist are null, never 0 mm at (0, 0) (docs/conventions.md; docs/reliability.md
  // family 5): no first-order estimate at the centre, no regular point of the target.
  if (map.centre.status != Status::ok) {
    for (const char* key : {"centre_3sigma_first_order_mm", "centre_3sigma_minor_first_order_mm", "centre_3sigma_angle_first_order_deg",
                            "centre_worst_case_first_order_mm", "centre_resolution_um"}) {
      j[key] = nullptr;
    }
  }
  if (map.centre_corners.status != Status::ok) j["centre_worst_case_mm"] = nullptr;
  if (map.centre_monte_carlo.used == 0) j["centre_monte_carlo_3sigma_mm"] = nullptr;
  if (map.centre_play.status != Status::ok) j["centre_play_mm"] = j["centre_play_first_order_mm"] = nullptr;
  if (map.target_not_ok >= map.target_points) {
    for (const char* key : {"target_worst_3sigma_first_order_mm", "target_worst_3sigma_first_order_at_mm", "target_worst_case_mm",
                            "target_worst_case_at_mm", "target_worst_case_first_order_mm", "target_worst_case_first_order_at_mm",
                            "target_worst_resolution_um", "target_worst_resolution_at_mm", "target_worst_play_mm",
                            "target_worst_play_at_mm"}) {
      j[key] = nullptr;
    }
  }
  return j;
}

std::vector<std::pair<std::string, std::string>> tolerance_files(const Station& station,
                                                                 const std::vector<ToleranceMap>& maps) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const ToleranceMap& map : maps) {
    ImageField f;
    f.x0 = map.x0;
    f.y0 = map.y0;
    f.spacing = map.spacing_mm;
    f.nx = map.nx;
    f.ny = map.ny;
    f.arrays.emplace_back("three_sigma_first_order_mm", map.field_3sigma_mm);
    f.arrays.emplace_back("worst_case_first_order_mm", map.field_worst_case_mm);
    f.arrays.emplace_back("resolution_um", map.field_resolution_um);
    f.arrays.emplace_back("play_mm", map.field_play_mm);
    f.arrays.emplace_back("near_singular",
                          std::vector<double>(map.field_near_singular.begin(), map.field_near_singular.end()));
    f.arrays.emplace_back("status", std::vector<double>(map.field_status.begin(), map.field_status.end()));
    out.emplace_back(station.name + "-" + map.mechanism + "-tolerance.vti", image_vti(f));
  }
  RenderedPlot plot = plot_tolerance(station, maps);
  out.emplace_back(station.name + "-tolerance.svg", std::move(plot.svg));
  out.emplace_back(station.name + "-tolerance.png", std::move(plot.png));
  return out;
}

std::vector<std::filesystem::path> write_tolerance_files(const std::filesystem::path& dir, const Station& station,
                                                         const std::vector<ToleranceMap>& maps) {
  std::vector<std::filesystem::path> out;
  for (const auto& [name, bytes] : tolerance_files(station, maps)) {
    write_file_atomic(dir / name, bytes);
    out.push_back(dir / name);
  }
  return out;
}

}  // namespace fivebar
