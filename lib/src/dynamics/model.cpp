// The equations of motion of one five-bar, the links' mass properties and the discrete controller
// (fivebar/dynamics.hpp, where every formula is given with its source).

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "fivebar/io.hpp"

#include "fivebar/dynamics.hpp"
#include "fivebar/parts.hpp"
#include "fivebar/tolerances.hpp"

namespace fivebar {

namespace {

constexpr double kPi = std::numbers::pi;

Vec2 e(double a) { return {std::cos(a), std::sin(a)}; }
Vec2 e_perp(double a) { return {-std::sin(a), std::cos(a)}; }
double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }
/// S v: v turned by +90 degrees.
Vec2 perp(const Vec2& v) { return {-v.y(), v.x()}; }
Eigen::Matrix2d rot(double a) {
  Eigen::Matrix2d R;
  R << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  return R;
}

/// A body of many pieces, accumulated in the link frame (mm, kg).
struct Accum {
  double m = 0.0;
  Vec2 first{0.0, 0.0};   ///< sum m_i c_i
  double second = 0.0;    ///< sum (I_i + m_i |c_i|^2): z inertia about the frame origin
  void add(double mass, const Vec2& com, double izz_own) {
    m += mass;
    first += mass * com;
    second += izz_own + mass * com.squaredNorm();
  }
  LinkInertia body() const {
    LinkInertia l;
    l.mass_kg = m;
    l.com_mm = m > 0.0 ? Vec2(first / m) : Vec2(0.0, 0.0);
    l.izz_kg_mm2 = second - m * l.com_mm.squaredNorm();
    return l;
  }
};

/// Adds a solid half disc of radius r, thickness t, density rho (kg/mm^3) centred at `c`, bulging
/// along `dir` (+1: +x, -1: -x): mass rho pi r^2 t / 2, centroid 4 r / (3 pi) from the centre,
/// z inertia about the centre m r^2 / 2.
void add_half_disc(Accum& a, double rho, double r, double t, const Vec2& c, double dir) {
  const double m = rho * 0.5 * kPi * r * r * t;
  const double d = 4.0 * r / (3.0 * kPi);
  const double about_centre = 0.5 * m * r * r;
  const Vec2 com = c + Vec2(dir * d, 0.0);
  a.add(m, com, about_centre - m * d * d);
}

void add_cylinder(Accum& a, double rho, double r, double h, const Vec2& c) {
  const double m = rho * kPi * r * r * h;
  a.add(m, c, 0.5 * m * r * r);
}

}  // namespace

std::string_view to_string(MassSource source) {
  switch (source) {
    case MassSource::stl: return "stl";
    case MassSource::closed_form: return "closed_form";
  }
  return "?";
}

MechanismInertia closed_form_inertia(const Mechanism& m, const Geometry& g, const PrintSettings& print) {
  const double rho = print.density_g_cm3 * 1e-6;  // kg/mm^3
  const PartsHardware hw;
  MechanismInertia out;
  out.source = MassSource::closed_form;
  out.carrier = g.layers[3] > g.layers[2] ? 3 : 2;
  const double t = g.link_thickness;
  const double rb = 0.5 * g.boss_diameter;
  const double tip_height = hw.tip_flange_height + hw.tip_dome_height;
  const double post_height = std::max(0.0, g.tactor_height - tip_height);
  const double hole = g.pin_diameter + 2.0 * print.pin_clearance;
  const double bore = g.motor_shaft_diameter + 2.0 * print.pin_clearance;
  for (std::size_t i = 0; i < 4; ++i) {
    Accum a;
    const double L = m.L[i];
    const double w = g.link_width[i];
    const double slab = rho * L * w * t;
    a.add(slab, {0.5 * L, 0.0}, slab * (L * L + w * w) / 12.0);
    add_half_disc(a, rho, rb, t, {0.0, 0.0}, -1.0);
    add_half_disc(a, rho, rb, t, {L, 0.0}, +1.0);
    const bool carrier = static_cast<int>(i) == out.carrier;
    if (i < 2) {
      add_cylinder(a, rho, rb, hw.hub_height, {0.0, 0.0});
      add_cylinder(a, -rho, 0.5 * bore, t + hw.hub_height, {0.0, 0.0});  // shaft bore
    } else {
      add_cylinder(a, -rho, 0.5 * hole, t, {0.0, 0.0});  // elbow pin hole
    }
    if (carrier) add_cylinder(a, rho, rb, post_height, {L, 0.0});
    add_cylinder(a, -rho, 0.5 * hole, t + (carrier ? post_height : 0.0), {L, 0.0});  // far pin hole
    out.links[i] = a.body();
  }
  // Tip: the flange, the dome as a cylinder of half its height (a low spherical cap holds about
  // half its cylinder), and the peg down the post.
  const double rt = 0.5 * g.tactor_diameter;
  Accum tip;
  add_cylinder(tip, rho, rt, hw.tip_flange_height + 0.5 * hw.tip_dome_height, {0.0, 0.0});
  add_cylinder(tip, rho, 0.5 * g.pin_diameter, post_height, {0.0, 0.0});
  out.tip_mass_kg = tip.m;
  out.tip_izz_kg_mm2 = tip.second;
  out.note = "closed form: slab with half-disc bosses less pin holes, hub and post (density " +
             std::to_string(print.density_g_cm3).substr(0, 5) + " g/cm^3)";
  return out;
}

MechanismInertia stl_inertia(const Mechanism& m, const Geometry& g,
                             const std::map<std::string, std::filesystem::path>& stl_by_use, double density_g_cm3) {
  MechanismInertia out;
  out.source = MassSource::stl;
  out.carrier = g.layers[3] > g.layers[2] ? 3 : 2;
  const auto load = [&](const std::string& use) {
    const auto it = stl_by_use.find(use);
    if (it == stl_by_use.end()) throw InputError("no STL render of " + m.name + "/" + use + " for its mass properties");
    try {
      return mass_properties(read_stl(it->second), density_g_cm3);
    } catch (const InputError& e) {
      throw InputError(it->second.string() + ": " + e.what());
    }
  };
  for (std::size_t i = 0; i < 4; ++i) {
    const MassProperties p = load("L" + std::to_string(i + 1));
    out.links[i].mass_kg = p.mass_kg;
    out.links[i].com_mm = Vec2(p.com_mm.x(), p.com_mm.y());
    out.links[i].izz_kg_mm2 = p.inertia_kg_mm2(2, 2);
  }
  const MassProperties tip = load("tactor");
  out.tip_mass_kg = tip.mass_kg;
  // The tip turns with its carrier about its own axis (the z axis of its frame).
  out.tip_izz_kg_mm2 = inertia_about(tip, Eigen::Vector3d(0.0, 0.0, tip.com_mm.z()))(2, 2);
  out.note = "STL renders of the parts (density " + std::to_string(density_g_cm3).substr(0, 5) + " g/cm^3)";
  return out;
}

std::map<std::string, MechanismInertia> station_inertia(const Design& design, const Station& station, const Json* parts,
                                                        const std::filesystem::path& parts_dir) {
  const Geometry* g = design.get<Geometry>();
  if (g == nullptr) throw InputError("the design has no `geometry:` section (the links' outlines, for their masses)");
  const PrintSettings print = design.get<PrintSettings>() ? *design.get<PrintSettings>() : PrintSettings{};
  std::map<std::string, MechanismInertia> out;
  for (const Mechanism* m : station.mechanisms()) {
    if (parts == nullptr) {
      out[m->name] = closed_form_inertia(*m, *g, print);
      continue;
    }
    std::map<std::string, std::filesystem::path> stl;
    const Json& list = parts->contains("parts") ? (*parts)["parts"] : *parts;
    for (const Json& p : list) {
      if (!p.is_object() || p.value("station", "") != station.name || !p.contains("uses") || !p["stl"].is_string()) continue;
      for (const Json& use : p["uses"]) {
        const std::string u = use.get<std::string>();
        const std::string prefix = m->name + "/";
        if (u.rfind(prefix, 0) == 0) stl[u.substr(prefix.size())] = parts_dir / p["stl"].get<std::string>();
      }
    }
    out[m->name] = stl_inertia(*m, *g, stl, print.density_g_cm3);
  }
  return out;
}

DynamicsTerms dynamics_terms(const MechanismModel& model, const Eigen::Vector2d& theta, const Eigen::Vector2d& w) {
  DynamicsTerms out;
  const Mechanism& mech = model.mechanism;
  // Positions: the elbows from the angles, the tactor by the library's stable circle intersection
  // (kinematics.hpp) on the pinned branch (side = sign of cross(A2 - A1, P - A1)); without a pinned
  // branch, the one fk() chooses.
  int side = static_cast<int>(model.branch);
  if (side == 0) {
    const Pose pose = fk(mech, theta[0], theta[1]);
    if (pose.status == Status::unreachable) return out;
    side = pose.assembly != 0 ? pose.assembly : 1;
  }
  const Vec2 A1mm = mech.O1 + mech.L[0] * e(theta[0]);
  const Vec2 A2mm = mech.O2 + mech.L[1] * e(theta[1]);
  const CircleIntersection x = intersect_circles(A1mm, mech.L[2], A2mm, mech.L[3], side);
  if (x.status == Status::unreachable) return out;
  out.status = Status::ok;
  constexpr double kM = 1e-3;  // mm -> m
  const double L1 = mech.L[0] * kM, L2 = mech.L[1] * kM, L3 = mech.L[2] * kM, L4 = mech.L[3] * kM;
  const Vec2 A1 = A1mm * kM, A2 = A2mm * kM, P = x.point * kM;
  const Vec2 r3 = P - A1, r4 = P - A2;
  const double det = cross(r3, r4);
  out.type2_sin = std::abs(det) / (L3 * L4);
  if (!(out.type2_sin >= tol::kSingularSin)) {
    out.status = Status::singular_type2;
    return out;
  }
  Eigen::Matrix2d G;
  G << r3.x(), r3.y(), r4.x(), r4.y();
  const Eigen::Matrix2d Ginv = G.inverse();  // 2x2: explicit inverse, conditioning checked above

  // First order: dA_i/dtheta_i, dP/dtheta (columns per joint), dphi/dtheta.
  const Vec2 dA1 = L1 * e_perp(theta[0]), dA2 = L2 * e_perp(theta[1]);
  Eigen::Matrix2d J;
  J.col(0) = Ginv * Eigen::Vector2d(r3.dot(dA1), 0.0);
  J.col(1) = Ginv * Eigen::Vector2d(0.0, r4.dot(dA2));
  Eigen::Matrix2d JA1 = Eigen::Matrix2d::Zero(), JA2 = Eigen::Matrix2d::Zero();  // dA_i/dtheta
  JA1.col(0) = dA1;
  JA2.col(1) = dA2;
  const Eigen::RowVector2d Jphi3 = (r3.x() * (J - JA1).row(1) - r3.y() * (J - JA1).row(0)) / (L3 * L3);
  const Eigen::RowVector2d Jphi4 = (r4.x() * (J - JA2).row(1) - r4.y() * (J - JA2).row(0)) / (L4 * L4);

  // Velocities and the accelerations at dw/dt = 0.
  const Vec2 A1d = dA1 * w[0], A2d = dA2 * w[1];
  const Vec2 Pd = J * w;
  const double phi3d = Jphi3 * w, phi4d = Jphi4 * w;
  const Vec2 A1dd = -L1 * w[0] * w[0] * e(theta[0]);
  const Vec2 A2dd = -L2 * w[1] * w[1] * e(theta[1]);
  const Vec2 Pdd = Ginv * Eigen::Vector2d(r3.dot(A1dd) - (Pd - A1d).squaredNorm(), r4.dot(A2dd) - (Pd - A2d).squaredNorm());
  const double phi3dd = cross(r3, Pdd - A1dd) / (L3 * L3);
  const double phi4dd = cross(r4, Pdd - A2dd) / (L4 * L4);
  const double phi3 = std::atan2(r3.y(), r3.x()), phi4 = std::atan2(r4.y(), r4.x());

  Eigen::Matrix2d M = Eigen::Matrix2d::Zero();
  Eigen::Vector2d h = Eigen::Vector2d::Zero();
  const MechanismInertia& in = model.inertia;
  const auto body = [&](double mass, double izz, const Eigen::Matrix2d& Jv, const Eigen::RowVector2d& Jw,
                        const Vec2& a0, double alpha0) {
    M += mass * Jv.transpose() * Jv + izz * Jw.transpose() * Jw;
    h += mass * Jv.transpose() * a0 + izz * Jw.transpose() * alpha0;
  };
  // Proximal links about O_i at angle theta_i.
  for (int i = 0; i < 2; ++i) {
    const LinkInertia& l = in.links[static_cast<std::size_t>(i)];
    const Eigen::Matrix2d R = rot(theta[i]);
    const Vec2 c = R * (l.com_mm * kM);
    Eigen::Matrix2d Jv = Eigen::Matrix2d::Zero();
    Jv.col(i) = perp(c);
    Eigen::RowVector2d Jw = Eigen::RowVector2d::Zero();
    Jw[i] = 1.0;
    body(l.mass_kg, l.izz_kg_mm2 * 1e-6, Jv, Jw, -w[i] * w[i] * c, 0.0);
  }
  // Distal links from A_i at angle phi.
  const auto distal = [&](std::size_t i, const Eigen::Matrix2d& JA, const Vec2& Add, double phi, const Eigen::RowVector2d& Jphi,
                          double phid, double phidd) {
    const LinkInertia& l = in.links[i];
    double izz = l.izz_kg_mm2 * 1e-6;
    if (static_cast<int>(i) == in.carrier) izz += in.tip_izz_kg_mm2 * 1e-6;
    const Vec2 c = rot(phi) * (l.com_mm * kM);
    const Eigen::Matrix2d Jv = JA + perp(c) * Jphi;
    const Vec2 a0 = Add + phidd * perp(c) - phid * phid * c;
    body(l.mass_kg, izz, Jv, Jphi, a0, phidd);
  };
  distal(2, JA1, A1dd, phi3, Jphi3, phi3d, phi3dd);
  distal(3, JA2, A2dd, phi4, Jphi4, phi4d, phi4dd);
  // The tactor tip, a point mass at P.
  body(in.tip_mass_kg, 0.0, J, Eigen::RowVector2d::Zero(), Pdd, 0.0);
  // Rotors through their gears.
  for (int i = 0; i < 2; ++i) {
    const MotorParams& mp = model.motors[static_cast<std::size_t>(i)];
    M(i, i) += mp.gear_ratio * mp.gear_ratio * mp.rotor_inertia();
  }
  out.M = M;
  out.h = h;
  out.J = J;
  out.P = P;
  out.P_dot = Pd;
  return out;
}

double kinetic_energy(const MechanismModel& model, const Eigen::Vector2d& theta, const Eigen::Vector2d& w) {
  const DynamicsTerms t = dynamics_terms(model, theta, w);
  return 0.5 * w.dot(t.M * w);
}

double DiscretePid::update(double e) {
  const double T = period_;
  sum_ += e * T;
  if (gains_.ki > 0.0) {
    const double bound = gains_.i_clamp / gains_.ki;
    sum_ = std::clamp(sum_, -bound, bound);
  }
  const double d = first_ ? 0.0 : (e - previous_) / T;
  first_ = false;
  previous_ = e;
  return std::clamp(gains_.kp * e + gains_.ki * sum_ + gains_.kd * d, -1.0, 1.0);
}

double adc_reading(double theta, const Potentiometer& pot, int bits, const std::array<double, 2>& range_v) {
  const double v = pot.volts_at_zero + theta / pot.rad_per_volt;
  // 2^bits codes over the input range, one count = range / 2^bits (the exported volts_per_count):
  // code k reads range_v[0] + k q, k = 0 ... 2^bits - 1.
  const double q = (range_v[1] - range_v[0]) / std::ldexp(1.0, bits);
  const double top = std::ldexp(1.0, bits) - 1.0;
  const double code = std::clamp(std::round((v - range_v[0]) / q), 0.0, top);
  return pot.rad_per_volt * (range_v[0] + code * q - pot.volts_at_zero);
}

}  // namespace fivebar
