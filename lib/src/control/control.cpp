// The sampled-data loop of one mechanism: linearised plant, ZOH discretisation, the PID with one
// period of delay, spectral radius over the target (fivebar/control.hpp).

#include "fivebar/control.hpp"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <unsupported/Eigen/MatrixFunctions>

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

LinearPlant linear_plant(const MechanismModel& model, const Eigen::Vector2d& theta, const ContactSettings* contact) {
  LinearPlant p;
  p.theta = theta;
  const DynamicsTerms t = dynamics_terms(model, theta, Eigen::Vector2d::Zero());
  p.status = t.status;
  if (t.status == Status::unreachable || t.status == Status::singular_type2) {
    p.status = t.status == Status::unreachable ? Status::unreachable : Status::singular_type2;
    return p;
  }
  p.status = Status::ok;
  p.M = t.M;
  p.J = t.J;
  p.P_mm = 1e3 * t.P;
  Eigen::Matrix2d K = Eigen::Matrix2d::Zero();  // N m / rad
  Eigen::Matrix2d C = Eigen::Matrix2d::Zero();  // N m s / rad
  if (contact) {
    const Eigen::Matrix2d JtJ = t.J.transpose() * t.J;
    K = contact->shear_stiffness_N_per_mm * 1e3 * JtJ;
    C = contact->damping_N_s_per_mm * 1e3 * JtJ;
  }
  Eigen::Matrix2d Kt = Eigen::Matrix2d::Zero();
  for (int j = 0; j < 2; ++j) {
    const MotorParams& mp = model.motors[static_cast<std::size_t>(j)];
    C(j, j) += mp.viscous_friction();
    Kt(j, j) = mp.gearbox_efficiency * mp.gear_ratio * mp.torque_constant();
  }
  const Eigen::Matrix2d Minv = t.M.inverse();
  p.A.block<2, 2>(0, 2) = Eigen::Matrix2d::Identity();
  p.A.block<2, 2>(2, 0) = -Minv * K;
  p.A.block<2, 2>(2, 2) = -Minv * C;
  p.A.block<2, 2>(2, 4) = Minv * Kt;
  for (int j = 0; j < 2; ++j) {
    const MotorParams& mp = model.motors[static_cast<std::size_t>(j)];
    const double L = mp.inductance();
    p.A(4 + j, 2 + j) = -mp.back_emf_constant() * mp.gear_ratio / L;
    p.A(4 + j, 4 + j) = -mp.resistance() / L;
    p.B(4 + j, j) = mp.supply_voltage_V / L;
  }
  return p;
}

std::array<Eigen::MatrixXd, 2> zoh(const Eigen::MatrixXd& A, const Eigen::MatrixXd& B, double period_s) {
  const Eigen::Index n = A.rows();
  const Eigen::Index m = B.cols();
  Eigen::MatrixXd aug = Eigen::MatrixXd::Zero(n + m, n + m);
  aug.topLeftCorner(n, n) = A * period_s;
  aug.topRightCorner(n, m) = B * period_s;
  const Eigen::MatrixXd e = aug.exp();
  return {e.topLeftCorner(n, n), e.topRightCorner(n, m)};
}

DiscretePlant discretise(const LinearPlant& plant, double period_s) {
  constexpr int n = kPlantStates + 2;
  Eigen::Matrix<double, n, n> aug = Eigen::Matrix<double, n, n>::Zero();
  aug.topLeftCorner<kPlantStates, kPlantStates>() = plant.A * period_s;
  aug.topRightCorner<kPlantStates, 2>() = plant.B * period_s;
  const Eigen::Matrix<double, n, n> e = aug.exp();
  DiscretePlant d;
  d.Ad = e.topLeftCorner<kPlantStates, kPlantStates>();
  d.Bd = e.topRightCorner<kPlantStates, 2>();
  d.period_s = period_s;
  return d;
}

LoopMatrix closed_loop(const DiscretePlant& plant, const std::array<PidGains, 2>& gains, bool delay) {
  const double T = plant.period_s;
  LoopMatrix phi = LoopMatrix::Zero();
  // duty_k = -g theta_k + ki s_{k-1} - (kd / T) e_{k-1}, g = kp + ki T + kd / T (per joint).
  Eigen::Matrix<double, 2, kLoopStates> duty = Eigen::Matrix<double, 2, kLoopStates>::Zero();
  for (int j = 0; j < 2; ++j) {
    const PidGains& g = gains[static_cast<std::size_t>(j)];
    duty(j, j) = -(g.kp + g.ki * T + g.kd / T);
    duty(j, 8 + j) = g.ki;
    duty(j, 10 + j) = -g.kd / T;
  }
  phi.topLeftCorner<kPlantStates, kPlantStates>() = plant.Ad;
  if (delay) {
    phi.block<kPlantStates, 2>(0, 6) = plant.Bd;
  } else {
    phi.topRows<kPlantStates>() += plant.Bd * duty;
  }
  phi.middleRows<2>(6) = duty;
  for (int j = 0; j < 2; ++j) {
    phi(8 + j, 8 + j) = 1.0;   // s_k = s_{k-1} + T e_k, e_k = -theta_k
    phi(8 + j, j) = -T;
    phi(10 + j, j) = -1.0;     // e_prev <- e_k
  }
  return phi;
}

LoopPoles loop_poles(const LoopMatrix& phi, double period_s) {
  LoopPoles out;
  if (!phi.allFinite()) {
    out.rho = std::numeric_limits<double>::infinity();
    out.damping = -1.0;
    return out;
  }
  Eigen::EigenSolver<LoopMatrix> es(phi, false);
  const auto ev = es.eigenvalues();
  for (Eigen::Index i = 0; i < ev.size(); ++i) {
    const double r = std::abs(ev[i]);
    // Of a conjugate pair, the one with the positive imaginary part.
    if (r > out.rho || (r == out.rho && ev[i].imag() > out.dominant.imag())) {
      out.rho = r;
      out.dominant = ev[i];
    }
  }
  for (Eigen::Index i = 0; i < ev.size(); ++i) {
    if (!(ev[i].imag() > 1e-12 * std::max(1.0, std::abs(ev[i])))) continue;
    const std::complex<double> s = std::log(ev[i]) / period_s;
    const double zeta = -s.real() / std::abs(s);
    if (zeta < out.oscillatory_damping) {
      out.oscillatory_damping = zeta;
      out.oscillatory_frequency_hz = s.imag() / (2.0 * std::numbers::pi);
    }
  }
  if (out.rho > 0.0) {
    const std::complex<double> s = std::log(out.dominant) / period_s;
    const double mag = std::abs(s);
    out.damping = mag > 0.0 ? -s.real() / mag : 1.0;
    out.frequency_hz = std::abs(s.imag()) / (2.0 * std::numbers::pi);
  }
  return out;
}

std::vector<LoopModel> loop_models(const Design& design, const Station& station,
                                   const std::map<std::string, MechanismInertia>& inertia) {
  const std::string where = design.source.empty() ? std::string("control: ") : design.source.string() + ": control: ";
  if (!design.get<Geometry>()) throw InputError(where + "the design has no `geometry:` section (link outlines, masses)");
  if (!design.get<MotorSettings>()) {
    throw InputError(where + "the design has no `motor:` section (motor.terminal_resistance_ohm, ... : the motors' data)");
  }
  if (!design.get<ControllerSettings>()) {
    throw InputError(where + "the design has no `controller:` section (controller.pid, loop_rate_hz: the loop to check)");
  }
  const ControllerSettings& ctl = *design.get<ControllerSettings>();
  const MotorSettings& motor = *design.get<MotorSettings>();
  const ContactSettings skin = design.get<ContactSettings>() ? *design.get<ContactSettings>() : ContactSettings{};
  std::vector<LoopModel> out;
  for (const Mechanism* m : station.mechanisms()) {
    LoopModel l;
    l.station = station.name;
    l.model.mechanism = *m;
    const auto it = inertia.find(m->name);
    if (it == inertia.end()) throw InputError("control: no mass properties for the " + m->name + " mechanism");
    l.model.inertia = it->second;
    for (int j = 0; j < 2; ++j) {
      l.model.motors[static_cast<std::size_t>(j)] = motor.joint(station.name, m->name, j + 1);
      l.gains[static_cast<std::size_t>(j)] = ctl.joint(station.name, m->name, j + 1).pid;
    }
    l.period_s = 1.0 / ctl.loop_rate_hz;
    l.skin = skin;
    out.push_back(std::move(l));
  }
  return out;
}

PoseLoop pose_loop(const LoopModel& loop, const Vec2& P_mm) {
  PoseLoop out;
  out.P_mm = P_mm;
  const AnglesResult a = ik_angles(loop.model.mechanism, P_mm);
  if (a.status != Status::ok) {
    out.status = a.status;
    return out;
  }
  MechanismModel model = loop.model;
  if (model.branch == AssemblyMode::Any) {
    const Pose p = fk(model.mechanism, a.theta1, a.theta2);
    if (p.assembly != 0) model.branch = p.assembly > 0 ? AssemblyMode::Plus : AssemblyMode::Minus;
  }
  const LinearPlant plant =
      linear_plant(model, Eigen::Vector2d(a.theta1, a.theta2), loop.contact ? &loop.skin : nullptr);
  out.status = plant.status;
  if (plant.status != Status::ok) return out;
  out.plant = discretise(plant, loop.period_s);
  out.poles = loop_poles(closed_loop(out.plant, loop.gains, loop.delay), loop.period_s);
  return out;
}

std::vector<Vec2> ellipse_lattice(const Ellipse& e, int n) {
  std::vector<Vec2> out;
  if (n < 1) return out;
  const double c = std::cos(e.angle);
  const double s = std::sin(e.angle);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const double u = n == 1 ? 0.0 : -1.0 + 2.0 * i / (n - 1);
      const double v = n == 1 ? 0.0 : -1.0 + 2.0 * j / (n - 1);
      if (u * u + v * v > 1.0) continue;
      const double x = 0.5 * e.axes.x() * u;
      const double y = 0.5 * e.axes.y() * v;
      out.push_back(e.center + Vec2(c * x - s * y, s * x + c * y));
    }
  }
  return out;
}

double max_spectral_radius(const std::vector<PoseLoop>& poses, const std::array<PidGains, 2>& gains, bool delay,
                           double stop_at) {
  double worst = 0.0;
  for (const PoseLoop& p : poses) {
    if (p.status != Status::ok) continue;
    worst = std::max(worst, loop_poles(closed_loop(p.plant, gains, delay), p.plant.period_s).rho);
    if (worst >= stop_at) break;
  }
  return worst;
}

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

// --- Performance over the target ----------------------------------------------------------------

std::array<double, 2> tactor_gain(const DiscretePlant& plant, const std::array<PidGains, 2>& gains, bool delay,
                                  const Eigen::Matrix2d& J, double frequency_hz) {
  const double T = plant.period_s;
  const LoopMatrix phi = closed_loop(plant, gains, delay);
  Eigen::Matrix<double, kLoopStates, 2> G = Eigen::Matrix<double, kLoopStates, 2>::Zero();
  Eigen::Matrix2d Dr = Eigen::Matrix2d::Zero();
  for (int j = 0; j < 2; ++j) {
    const PidGains& g = gains[static_cast<std::size_t>(j)];
    Dr(j, j) = g.kp + g.ki * T + g.kd / T;
    G(8 + j, j) = T;
    G(10 + j, j) = 1.0;
  }
  G.middleRows<2>(6) = Dr;
  if (!delay) G.topRows<kPlantStates>() = plant.Bd * Dr;
  using Cmat = Eigen::Matrix<std::complex<double>, kLoopStates, kLoopStates>;
  const std::complex<double> z = std::polar(1.0, 2.0 * std::numbers::pi * frequency_hz * T);
  const Cmat A = z * Cmat::Identity() - phi.cast<std::complex<double>>();
  const Eigen::Matrix<std::complex<double>, kLoopStates, 2> X = A.partialPivLu().solve(G.cast<std::complex<double>>());
  const Eigen::Matrix2cd H = X.topRows<2>();
  const Eigen::Matrix2cd Ht = J.cast<std::complex<double>>() * H * J.inverse().cast<std::complex<double>>();
  const Eigen::JacobiSVD<Eigen::Matrix2cd> svd(Ht);
  const auto sv = svd.singularValues();
  return {sv[1], sv[0]};
}

void abbott_okamura(const Eigen::Matrix2d& J, const Eigen::Matrix2d& Bj, const std::array<double, 2>& coulomb_Nm,
                    const std::array<double, 2>& quantum_rad, double period_s, double target_N_per_mm, PoseFigures& f) {
  const Eigen::Matrix2d Jinv = J.inverse();
  const double target = 1e3 * target_N_per_mm;  // N/m
  double coulomb = std::numeric_limits<double>::infinity(), quantum = 0.0;
  double kq = std::numeric_limits<double>::infinity(), kao = std::numeric_limits<double>::infinity();
  double rate = 0.0;
  constexpr int kDirections = 360;  // over [0, pi): u and -u are the same direction
  for (int k = 0; k < kDirections; ++k) {
    const double a = std::numbers::pi * k / kDirections;
    const Eigen::Vector2d u(std::cos(a), std::sin(a));
    const Eigen::Vector2d w = Jinv * u;  // joint rates at unit tactor speed along u
    const double b = w.dot(Bj * w);      // N s/m
    const double fc = coulomb_Nm[0] * std::abs(w[0]) + coulomb_Nm[1] * std::abs(w[1]);  // N
    const double delta = std::max(std::abs(u.dot(J.col(0))) * quantum_rad[0], std::abs(u.dot(J.col(1))) * quantum_rad[1]);
    const double k_q = delta > 0.0 ? 2.0 * fc / delta : std::numeric_limits<double>::infinity();
    coulomb = std::min(coulomb, fc);
    quantum = std::max(quantum, delta);
    kq = std::min(kq, k_q);
    kao = std::min(kao, std::min(2.0 * b / period_s, k_q));
    rate = std::max(rate, k_q >= target ? target / (2.0 * b) : std::numeric_limits<double>::infinity());
  }
  f.coulomb_N = coulomb;
  f.quantum_um = 1e6 * quantum;
  f.zwidth_quantisation_N_per_mm = 1e-3 * kq;
  f.zwidth_abbott_okamura_N_per_mm = 1e-3 * kao;
  f.rate_for_target_hz = rate;
}

PoseFigures pose_figures(const LoopModel& loop, const Vec2& P_mm, int adc_bits, const std::array<double, 2>& adc_range_v,
                         const std::array<Potentiometer, 2>& pots, double target_N_per_mm) {
  PoseFigures f;
  f.P_mm = P_mm;
  const AnglesResult a = ik_angles(loop.model.mechanism, P_mm);
  if (a.status != Status::ok) {
    f.status = a.status;
    return f;
  }
  const LinearPlant plant = linear_plant(loop.model, Eigen::Vector2d(a.theta1, a.theta2), loop.contact ? &loop.skin : nullptr);
  f.status = plant.status;
  if (plant.status != Status::ok) return f;
  const DiscretePlant dp = discretise(plant, loop.period_s);
  const Eigen::Matrix2d& J = plant.J;
  // Bandwidth: a log scan to Nyquist, then bisection on the first crossing of 1/sqrt(2).
  const double nyquist = 0.5 / loop.period_s;
  const double level = 1.0 / std::sqrt(2.0);
  const auto low = [&](double hz) { return tactor_gain(dp, loop.gains, loop.delay, J, hz)[0] < level; };
  f.bandwidth_hz = nyquist;
  double previous = 0.0;
  constexpr int kScan = 80;
  for (int k = 0; k <= kScan; ++k) {
    const double hz = 0.01 * std::pow(nyquist / 0.01, double(k) / kScan);
    if (low(hz)) {
      double lo = previous, hi = hz;
      for (int it = 0; it < 40 && hi - lo > 1e-6 * hi; ++it) {
        const double mid = 0.5 * (lo + hi);
        (low(mid) ? hi : lo) = mid;
      }
      f.bandwidth_hz = 0.5 * (lo + hi);
      break;
    }
    previous = hz;
  }
  // Resolution, force, damping and Z-width.
  const double span = adc_range_v[1] - adc_range_v[0];
  double torque_min_ratio = std::numeric_limits<double>::infinity();
  Eigen::Matrix2d Bj = Eigen::Matrix2d::Zero();
  std::array<double, 2> coulomb{}, quantum{};
  for (int j = 0; j < 2; ++j) {
    const double dtheta = std::abs(pots[static_cast<std::size_t>(j)].rad_per_volt) * span / std::ldexp(1.0, adc_bits);
    quantum[static_cast<std::size_t>(j)] = dtheta;
    coulomb[static_cast<std::size_t>(j)] = loop.model.motors[static_cast<std::size_t>(j)].coulomb_friction();
    f.resolution_um = std::max(f.resolution_um, 1e6 * J.col(j).norm() * dtheta);
    const MotorParams& mp = loop.model.motors[static_cast<std::size_t>(j)];
    const double torque = mp.gearbox_efficiency * mp.gear_ratio * mp.torque_constant() * mp.current_limit_A;
    torque_min_ratio = std::min(torque_min_ratio, torque / J.col(j).norm());
    Bj(j, j) = mp.viscous_friction() + mp.gearbox_efficiency * mp.gear_ratio * mp.gear_ratio * mp.torque_constant() *
                                           mp.back_emf_constant() / mp.resistance();
  }
  f.force_N = torque_min_ratio;
  const Eigen::Matrix2d Jinv = J.inverse();
  const Eigen::Matrix2d Bx = Jinv.transpose() * Bj * Jinv;  // N s / m
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(0.5 * (Bx + Bx.transpose()), Eigen::EigenvaluesOnly);
  const double bmin = es.eigenvalues()[0];
  f.damping_N_s_per_mm = 1e-3 * bmin;
  f.zwidth_N_per_mm = 1e-3 * 2.0 * bmin / loop.period_s;
  abbott_okamura(J, Bj, coulomb, quantum, loop.period_s, target_N_per_mm, f);
  return f;
}

PerformanceMap performance_map(const Design& design, const LoopModel& loop, const std::vector<Vec2>& points) {
  PerformanceMap m;
  m.station = loop.station;
  m.mechanism = loop.model.mechanism.name;
  const ControllerSettings& c = *design.get<ControllerSettings>();
  const std::array<Potentiometer, 2> pots{c.joint(loop.station, m.mechanism, 1).potentiometer,
                                          c.joint(loop.station, m.mechanism, 2).potentiometer};
  m.target_N_per_mm = c.target_stiffness_N_per_mm;
  m.loop_rate_hz = c.loop_rate_hz;
  bool any = false;
  for (const Vec2& P : points) {
    m.poses.push_back(pose_figures(loop, P, c.adc_bits, c.adc_range_v, pots, c.target_stiffness_N_per_mm));
    const PoseFigures& f = m.poses.back();
    if (f.status != Status::ok) continue;
    if (!any || f.bandwidth_hz < m.worst_bandwidth.bandwidth_hz) m.worst_bandwidth = f;
    if (!any || f.resolution_um > m.worst_resolution.resolution_um) m.worst_resolution = f;
    if (!any || f.force_N < m.worst_force.force_N) m.worst_force = f;
    if (!any || f.zwidth_N_per_mm < m.worst_zwidth.zwidth_N_per_mm) m.worst_zwidth = f;
    if (!any || f.zwidth_abbott_okamura_N_per_mm < m.worst_zwidth_abbott_okamura.zwidth_abbott_okamura_N_per_mm) {
      m.worst_zwidth_abbott_okamura = f;
    }
    if (!any || f.rate_for_target_hz > m.worst_rate.rate_for_target_hz) m.worst_rate = f;
    any = true;
  }
  return m;
}

Json to_json(const PerformanceMap& m) {
  const auto at = [](const PoseFigures& f) { return Json::array({f.P_mm.x(), f.P_mm.y()}); };
  const bool any = std::any_of(m.poses.begin(), m.poses.end(), [](const PoseFigures& f) { return f.status == Status::ok; });
  if (!any) {
    // No pose reachable and regular: the worst figures do not exist (null), and no wall is renderable.
    Json j = {{"station", m.station}, {"mechanism", m.mechanism}, {"poses", m.poses.size()},
              {"target_stiffness_N_per_mm", m.target_N_per_mm}, {"loop_rate_hz", m.loop_rate_hz},
              {"target_renderable", false}};
    for (const char* key : {"min_bandwidth_hz", "min_bandwidth_pose_mm", "max_resolution_um_per_count", "max_resolution_pose_mm",
                            "min_force_every_direction_N", "min_force_pose_mm", "min_tactor_damping_N_s_per_mm",
                            "min_zwidth_N_per_mm", "min_zwidth_pose_mm", "min_coulomb_friction_N", "max_position_quantum_um",
                            "min_zwidth_quantisation_N_per_mm", "min_zwidth_abbott_okamura_N_per_mm",
                            "min_zwidth_abbott_okamura_pose_mm", "loop_rate_for_target_hz", "loop_rate_for_target_pose_mm"}) {
      j[key] = nullptr;
    }
    return j;
  }
  return {{"station", m.station},
          {"mechanism", m.mechanism},
          {"poses", m.poses.size()},
          {"min_bandwidth_hz", m.worst_bandwidth.bandwidth_hz},
          {"min_bandwidth_pose_mm", at(m.worst_bandwidth)},
          {"max_resolution_um_per_count", m.worst_resolution.resolution_um},
          {"max_resolution_pose_mm", at(m.worst_resolution)},
          {"min_force_every_direction_N", m.worst_force.force_N},
          {"min_force_pose_mm", at(m.worst_force)},
          {"min_tactor_damping_N_s_per_mm", m.worst_zwidth.damping_N_s_per_mm},
          {"min_zwidth_N_per_mm", m.worst_zwidth.zwidth_N_per_mm},
          {"min_zwidth_pose_mm", at(m.worst_zwidth)},
          {"min_coulomb_friction_N", m.worst_zwidth_abbott_okamura.coulomb_N},
          {"max_position_quantum_um", m.worst_zwidth_abbott_okamura.quantum_um},
          {"min_zwidth_quantisation_N_per_mm", m.worst_zwidth_abbott_okamura.zwidth_quantisation_N_per_mm},
          {"min_zwidth_abbott_okamura_N_per_mm", m.worst_zwidth_abbott_okamura.zwidth_abbott_okamura_N_per_mm},
          {"min_zwidth_abbott_okamura_pose_mm", at(m.worst_zwidth_abbott_okamura)},
          {"target_stiffness_N_per_mm", m.target_N_per_mm},
          {"loop_rate_hz", m.loop_rate_hz},
          // null when the quantisation forbids the target at some pose (no loop rate renders it)
          {"loop_rate_for_target_hz", std::isfinite(m.worst_rate.rate_for_target_hz) ? Json(m.worst_rate.rate_for_target_hz)
                                                                                      : Json(nullptr)},
          {"loop_rate_for_target_pose_mm", at(m.worst_rate)},
          {"target_renderable", m.worst_rate.rate_for_target_hz <= m.loop_rate_hz}};
}

std::string performance_line(const PerformanceMap& m) {
  const auto at = [](const PoseFigures& f) { return " at (" + fixed(f.P_mm.x(), 2) + ", " + fixed(f.P_mm.y(), 2) + ")"; };
  if (std::none_of(m.poses.begin(), m.poses.end(), [](const PoseFigures& f) { return f.status == Status::ok; })) {
    return m.station + " " + m.mechanism + ": no pose of the target is reachable and regular: no performance figures";
  }
  return m.station + " " + m.mechanism + ": bandwidth >= " + fixed(m.worst_bandwidth.bandwidth_hz, 2) + " Hz" +
         at(m.worst_bandwidth) + "; resolution <= " + fixed(m.worst_resolution.resolution_um, 3) + " um per count" +
         at(m.worst_resolution) + "; force >= " + fixed(m.worst_force.force_N, 2) + " N in every direction" +
         at(m.worst_force) + " (fingertip devices: >= 1.5 N); Z-width >= " + fixed(m.worst_zwidth.zwidth_N_per_mm, 1) +
         " N/mm" + at(m.worst_zwidth) + " (hard surface: 0.8-1.0 N/mm); with Coulomb friction and quantisation " +
         "(Abbott-Okamura) >= " + fixed(m.worst_zwidth_abbott_okamura.zwidth_abbott_okamura_N_per_mm, 2) + " N/mm" +
         at(m.worst_zwidth_abbott_okamura) + "; a " + format::shortest(m.target_N_per_mm) + " N/mm wall needs " +
         (std::isfinite(m.worst_rate.rate_for_target_hz)
              ? "a loop rate >= " + fixed(m.worst_rate.rate_for_target_hz, 2) + " Hz" + at(m.worst_rate) + " (here " +
                    format::shortest(m.loop_rate_hz) + " Hz: " +
                    (m.worst_rate.rate_for_target_hz <= m.loop_rate_hz ? "renderable" : "NOT renderable") + ")"
              : "a finer position sensor or more friction: the quantisation forbids it at any loop rate" +
                    at(m.worst_rate));
}

}  // namespace fivebar
