// Stability of the sampled-data loop over the target: gain margins, stability maps, the rho field,
// the station's study, its files and summary (fivebar/control.hpp; the loop itself: control.cpp).

#include "fivebar/control.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <numbers>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/motor.hpp"

namespace fivebar {

namespace {

/// Largest factor f in [0, cap] on the gain picked by `scale` with max rho < 1 over `poses`.
template <class Scale>
double gain_margin(const std::vector<PoseLoop>& poses, const std::array<PidGains, 2>& gains, bool delay, double cap,
                   double rel_tol, Scale scale) {
  const auto stable = [&](double f) {
    std::array<PidGains, 2> g = gains;
    for (PidGains& x : g) scale(x, f);
    return max_spectral_radius(poses, g, delay, 1.0) < 1.0;
  };
  double lo = 0.0, hi = 0.0;
  if (stable(1.0)) {
    lo = 1.0;
    hi = 2.0;
    while (stable(hi)) {
      lo = hi;
      if (hi >= cap) return cap;
      hi = std::min(cap, 2.0 * hi);
    }
  } else {
    if (!stable(0.0)) return 0.0;
    hi = 1.0;
  }
  while (hi - lo > rel_tol * std::max(lo, 1e-3)) {
    const double mid = 0.5 * (lo + hi);
    (stable(mid) ? lo : hi) = mid;
  }
  return lo;
}

}  // namespace

namespace {

/// stability_map() once its poses are computed: worst pose, least damping, margins.
StabilityMap map_of_poses(const LoopModel& loop, std::vector<PoseLoop> poses, const StabilityOptions& options) {
  StabilityMap map;
  map.station = loop.station;
  map.mechanism = loop.model.mechanism.name;
  map.poses = std::move(poses);
  std::size_t ok = 0;
  for (std::size_t k = 0; k < map.poses.size(); ++k) {
    const PoseLoop& pl = map.poses[k];
    if (pl.status != Status::ok) {
      ++map.not_ok;
      continue;
    }
    if (ok == 0 || pl.poles.oscillatory_damping < map.oscillatory_damping) {
      map.oscillatory_damping = pl.poles.oscillatory_damping;
      map.oscillatory_frequency_hz = pl.poles.oscillatory_frequency_hz;
      map.oscillatory_P_mm = pl.P_mm;
    }
    if (ok == 0 || pl.poles.rho > map.max_rho) {
      map.max_rho = pl.poles.rho;
      map.worst = k;
    }
    ++ok;
  }
  map.stable = ok > 0 && map.max_rho < 1.0;
  if (ok > 0) {
    map.damping = map.poses[map.worst].poles.damping;
    map.frequency_hz = map.poses[map.worst].poles.frequency_hz;
  }
  if (options.margins && ok > 0) {
    // The worst pose first: an unstable factor is then found at the first pose tried.
    std::vector<PoseLoop> ordered = map.poses;
    std::sort(ordered.begin(), ordered.end(), [](const PoseLoop& a, const PoseLoop& b) { return a.poles.rho > b.poles.rho; });
    map.kp_margin = gain_margin(ordered, loop.gains, loop.delay, options.margin_cap, options.margin_rel_tol,
                                [](PidGains& g, double f) { g.kp *= f; });
    map.kd_margin = gain_margin(ordered, loop.gains, loop.delay, options.margin_cap, options.margin_rel_tol,
                                [](PidGains& g, double f) { g.kd *= f; });
  }
  return map;
}

}  // namespace

StabilityMap stability_map(const LoopModel& loop, const std::vector<Vec2>& points, const StabilityOptions& options) {
  std::vector<PoseLoop> poses;
  poses.reserve(points.size());
  for (const Vec2& p : points) poses.push_back(pose_loop(loop, p));
  return map_of_poses(loop, std::move(poses), options);
}

StabilityMap stability_map(const LoopModel& loop, const std::vector<PoseLoop>& linearised, const StabilityOptions& options) {
  std::vector<PoseLoop> poses = linearised;
  for (PoseLoop& p : poses) {
    if (p.status == Status::ok) p.poles = loop_poles(closed_loop(p.plant, loop.gains, loop.delay), loop.period_s);
  }
  return map_of_poses(loop, std::move(poses), options);
}

RhoField rho_field(const LoopModel& loop, int cells_per_axis) {
  const Mechanism& m = loop.model.mechanism;
  // Bounding box of the intersection of the two legs' outer discs.
  const double r1 = m.L[0] + m.L[2];
  const double r2 = m.L[1] + m.L[3];
  const double xmin = std::max(m.O1.x() - r1, m.O2.x() - r2);
  const double xmax = std::min(m.O1.x() + r1, m.O2.x() + r2);
  const double ymin = std::max(m.O1.y() - r1, m.O2.y() - r2);
  const double ymax = std::min(m.O1.y() + r1, m.O2.y() + r2);
  const int n = std::max(cells_per_axis, 2);
  RhoField f;
  if (!(xmax > xmin) || !(ymax > ymin)) return f;  // the legs' discs do not meet: nothing reachable
  const double spacing = std::max(xmax - xmin, ymax - ymin) / (n - 1);
  f.grid = Grid::covering({xmin, ymin, xmax, ymax}, spacing, spacing);
  f.rho.assign(f.grid.size(), std::numeric_limits<double>::quiet_NaN());
  f.status.assign(f.grid.size(), static_cast<std::uint8_t>(Status::unreachable));
  for (int j = 0; j < f.grid.ny; ++j) {
    for (int i = 0; i < f.grid.nx; ++i) {
      const std::size_t k = std::size_t(j) * std::size_t(f.grid.nx) + std::size_t(i);
      const Vec2 P = f.grid.point(i, j);
      if (m.joint_limits) {
        const AnglesResult a = ik_angles(m, P);
        if (a.status == Status::ok &&
            !((*m.joint_limits)[0].contains(a.theta1) && (*m.joint_limits)[1].contains(a.theta2))) {
          f.status[k] = 255;
          continue;
        }
      }
      const PoseLoop pl = pose_loop(loop, P);
      f.status[k] = static_cast<std::uint8_t>(pl.status);
      if (pl.status == Status::ok) f.rho[k] = pl.poles.rho;
    }
  }
  return f;
}

Json to_json(const StabilityMap& map) {
  Json j;
  j["station"] = map.station;
  j["mechanism"] = map.mechanism;
  j["poses"] = map.poses.size();
  j["not_ok"] = map.not_ok;
  j["stable"] = map.stable;
  j["max_rho"] = map.max_rho;
  const Vec2 w = map.worst_P_mm();
  j["worst_pose_mm"] = Json::array({w.x(), w.y()});
  j["dominant_damping"] = map.damping;
  j["dominant_frequency_hz"] = map.frequency_hz;
  j["oscillatory_damping"] = map.oscillatory_damping;
  j["oscillatory_frequency_hz"] = map.oscillatory_frequency_hz;
  j["oscillatory_pose_mm"] = Json::array({map.oscillatory_P_mm.x(), map.oscillatory_P_mm.y()});
  j["kp_margin"] = map.kp_margin;
  j["kd_margin"] = map.kd_margin;
  if (map.not_ok >= map.poses.size()) {
    // No pose of the target is reachable and regular: no verdict, and null for every figure
    // that does not exist (docs/conventions.md; docs/reliability.md), never a 0 that reads as a value.
    for (const char* key : {"max_rho", "worst_pose_mm", "dominant_damping", "dominant_frequency_hz", "oscillatory_damping",
                            "oscillatory_frequency_hz", "oscillatory_pose_mm", "kp_margin", "kd_margin"}) {
      j[key] = nullptr;
    }
  }
  return j;
}

bool StationControl::stable() const {
  return !maps.empty() && std::all_of(maps.begin(), maps.end(), [](const StabilityMap& m) { return m.stable; });
}

StationControl station_control(const Design& design, const Station& station,
                               const std::map<std::string, MechanismInertia>& inertia, const ControlOptions& options) {
  StationControl out;
  out.station = station.name;
  const std::vector<Vec2> points = ellipse_lattice(station.target, options.stability.grid);
  for (const LoopModel& loop : loop_models(design, station, inertia)) {
    out.maps.push_back(stability_map(loop, points, options.stability));
    out.fields.push_back(rho_field(loop, options.field_cells));
    out.performance.push_back(performance_map(design, loop, ellipse_lattice(station.target, options.performance_grid)));
  }
  return out;
}

namespace {

std::string num(double v) {
  if (!std::isfinite(v)) return "";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// Fixed point without a sign on zero ("-0.00" never appears in a message): fivebar/format.hpp.
using format::fixed;

std::string margin_text(double f, double cap) { return f >= cap ? ">" + fixed(cap, 0) : fixed(f, 2); }

}  // namespace

std::vector<std::pair<std::string, std::string>> control_files(const StationControl& study, const Station& station,
                                                               const std::string& subtitle) {
  std::vector<std::pair<std::string, std::string>> files;
  const RenderedPlot plot = stability_plot(station, study.maps, study.fields, subtitle);
  files.emplace_back(study.station + "-stability.svg", plot.svg);
  files.emplace_back(study.station + "-stability.png", plot.png);
  for (std::size_t k = 0; k < study.maps.size(); ++k) {
    files.emplace_back(study.station + "-" + study.maps[k].mechanism + "-rho.vti", rho_field_vti(study.fields[k]));
  }
  std::string csv = "station,mechanism,x_mm,y_mm,status,rho,damping,frequency_hz\n";
  for (const StabilityMap& m : study.maps) {
    for (const PoseLoop& p : m.poses) {
      const bool ok = p.status == Status::ok;
      csv += study.station + "," + m.mechanism + "," + num(p.P_mm.x()) + "," + num(p.P_mm.y()) + "," +
             std::string(to_string(p.status)) + "," + (ok ? num(p.poles.rho) : "") + "," +
             (ok ? num(p.poles.damping) : "") + "," + (ok ? num(p.poles.frequency_hz) : "") + "\n";
    }
  }
  files.emplace_back(study.station + "-stability.csv", csv);
  std::string perf =
      "station,mechanism,x_mm,y_mm,status,bandwidth_hz,resolution_um_per_count,force_every_direction_N,"
      "tactor_damping_N_s_per_mm,zwidth_N_per_mm,coulomb_friction_N,position_quantum_um,zwidth_quantisation_N_per_mm,"
      "zwidth_abbott_okamura_N_per_mm,loop_rate_for_target_hz\n";
  for (const PerformanceMap& m : study.performance) {
    for (const PoseFigures& f : m.poses) {
      const bool ok = f.status == Status::ok;
      const auto v = [&](double x) { return ok ? num(x) : std::string(); };
      perf += study.station + "," + m.mechanism + "," + num(f.P_mm.x()) + "," + num(f.P_mm.y()) + "," +
              std::string(to_string(f.status)) + "," + v(f.bandwidth_hz) + "," + v(f.resolution_um) + "," +
              v(f.force_N) + "," + v(f.damping_N_s_per_mm) + "," + v(f.zwidth_N_per_mm) + "," + v(f.coulomb_N) + "," +
              v(f.quantum_um) + "," + v(f.zwidth_quantisation_N_per_mm) + "," + v(f.zwidth_abbott_okamura_N_per_mm) +
              "," + v(f.rate_for_target_hz) + "\n";
    }
  }
  files.emplace_back(study.station + "-performance.csv", perf);
  return files;
}

Json to_json(const StationControl& study) {
  Json j;
  j["station"] = study.station;
  j["stable"] = study.stable();
  Json mechs = Json::array();
  for (const StabilityMap& m : study.maps) mechs.push_back(to_json(m));
  j["mechanisms"] = mechs;
  Json perf = Json::array();
  for (const PerformanceMap& m : study.performance) perf.push_back(to_json(m));
  j["performance"] = perf;
  return j;
}

std::vector<std::string> summary_lines(const StationControl& study) {
  std::vector<std::string> out;
  const double cap = StabilityOptions{}.margin_cap;
  for (const StabilityMap& m : study.maps) {
    const std::size_t ok = m.poses.size() - m.not_ok;
    std::string line = study.station + " " + m.mechanism + ": ";
    if (ok == 0) {
      out.push_back(line + "no pose of the target is reachable and regular: no verdict");
      continue;
    }
    line += std::string(m.stable ? "stable" : "UNSTABLE") + " over the target, max rho " + fixed(m.max_rho, 4) +
            " at (" + fixed(m.worst_P_mm().x(), 2) + ", " + fixed(m.worst_P_mm().y(), 2) + ") mm (" +
            std::to_string(ok) + " poses";
    if (m.not_ok) line += ", " + std::to_string(m.not_ok) + " unreachable or singular";
    line += "); dominant pole damping " + fixed(m.damping, 3) + " at " + fixed(m.frequency_hz, 2) +
            " Hz, least-damped oscillation " + fixed(m.oscillatory_damping, 3) + " at " +
            fixed(m.oscillatory_frequency_hz, 2) + " Hz; margins kp x" + margin_text(m.kp_margin, cap) + ", kd x" + margin_text(m.kd_margin, cap);
    out.push_back(line);
  }
  for (const PerformanceMap& m : study.performance) out.push_back(performance_line(m));
  return out;
}

}  // namespace fivebar
