// Dynamics of the device (fivebar/dynamics.hpp) and the mass properties of its parts
// (fivebar/parts.hpp). Every expected value is an independent closed form: the box and the regular
// prism (exact for a tessellated cylinder) from textbook integrals, the parallel-axis theorem, the
// stall current V/R of an Ohmic winding, a PID sequence worked by hand, and conservation of
// kinetic energy of an unforced, frictionless linkage.

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <array>
#include <cmath>
#include <complex>
#include <cstdint>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "fivebar/dynamics.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/parts.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/print.hpp"
#include "fivebar/sections/contact.hpp"
#include "fivebar/sections/motor.hpp"

namespace fivebar {
namespace {

// --- Meshes built here, independently of the library ---------------------------------------------

/// Axis-aligned box [0, a] x [0, b] x [0, c], outward oriented (12 triangles).
TriangleMesh box(double a, double b, double c) {
  TriangleMesh m;
  for (int k = 0; k < 8; ++k) m.vertices.emplace_back((k & 1) ? a : 0.0, (k & 2) ? b : 0.0, (k & 4) ? c : 0.0);
  // Faces as quads (outward, counter-clockwise seen from outside), split in two.
  const std::array<std::array<std::uint32_t, 4>, 6> quads{{
      {0, 2, 3, 1},  // z = 0, normal -z
      {4, 5, 7, 6},  // z = c, +z
      {0, 1, 5, 4},  // y = 0, -y
      {2, 6, 7, 3},  // y = b, +y
      {0, 4, 6, 2},  // x = 0, -x
      {1, 3, 7, 5},  // x = a, +x
  }};
  for (const auto& q : quads) {
    m.triangles.push_back({q[0], q[1], q[2]});
    m.triangles.push_back({q[0], q[2], q[3]});
  }
  return m;
}

/// Regular n-gon prism of circumradius r, height h, axis z from z = 0, outward oriented.
TriangleMesh prism(int n, double r, double h) {
  TriangleMesh m;
  for (int z = 0; z < 2; ++z) {
    for (int k = 0; k < n; ++k) {
      const double a = 2.0 * std::numbers::pi * k / n;
      m.vertices.emplace_back(r * std::cos(a), r * std::sin(a), z * h);
    }
  }
  const auto N = static_cast<std::uint32_t>(n);
  m.vertices.emplace_back(0.0, 0.0, 0.0);
  m.vertices.emplace_back(0.0, 0.0, h);
  const std::uint32_t c0 = 2 * N;
  const std::uint32_t c1 = 2 * N + 1;
  for (std::uint32_t k = 0; k < N; ++k) {
    const std::uint32_t k1 = (k + 1) % N;
    m.triangles.push_back({c0, k1, k});          // bottom, normal -z
    m.triangles.push_back({c1, N + k, N + k1});  // top, +z
    m.triangles.push_back({k, k1, N + k1});      // side
    m.triangles.push_back({k, N + k1, N + k});
  }
  return m;
}

Eigen::Matrix3d box_inertia(double mass, double a, double b, double c) {
  return Eigen::Vector3d(mass * (b * b + c * c) / 12.0, mass * (a * a + c * c) / 12.0, mass * (a * a + b * b) / 12.0)
      .asDiagonal();
}

double rel_diff(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) { return (a - b).norm() / b.norm(); }

TEST(MassProperties, BoxMatchesItsClosedForm) {
  const double a = 12.0, b = 4.0, c = 2.5, rho = 1.15;
  const MassProperties m = mass_properties(box(a, b, c), rho);
  const double volume = a * b * c;
  const double mass = rho * 1e-6 * volume;
  EXPECT_NEAR(m.volume_mm3, volume, 1e-12 * volume);
  EXPECT_NEAR(m.mass_kg, mass, 1e-12 * mass);
  EXPECT_LT((m.com_mm - Eigen::Vector3d(a / 2, b / 2, c / 2)).norm(), 1e-12 * a);
  EXPECT_LT(rel_diff(m.inertia_kg_mm2, box_inertia(mass, a, b, c)), 1e-12);
}

TEST(MassProperties, RegularPrismIsExactAndConvergesToTheCylinder) {
  const double r = 2.5, h = 6.0, rho = 1.0;
  for (int n : {8, 96, 1024}) {
    SCOPED_TRACE(n);
    const MassProperties m = mass_properties(prism(n, r, h), rho);
    // The regular n-gon of circumradius r: area A = n r^2 sin(a) / 2 with a = 2 pi / n; its polar
    // second moment about the centre is A r^2 (2 + cos a) / 6 (n triangles from the centre, each
    // (A_t / 6)(|v1|^2 + v1.v2 + |v2|^2)), and I_x = I_y = J / 2 for n >= 3.
    const double alpha = 2.0 * std::numbers::pi / n;
    const double area = 0.5 * n * r * r * std::sin(alpha);
    const double polar = area * r * r * (2.0 + std::cos(alpha)) / 6.0;
    const double mass = rho * 1e-6 * area * h;
    const double izz = rho * 1e-6 * h * polar;
    const double ixx = 0.5 * izz + mass * h * h / 12.0;
    EXPECT_NEAR(m.volume_mm3, area * h, 1e-12 * area * h);
    EXPECT_LT((m.com_mm - Eigen::Vector3d(0, 0, h / 2)).norm(), 1e-12 * r);
    EXPECT_LT(rel_diff(m.inertia_kg_mm2, Eigen::Vector3d(ixx, ixx, izz).asDiagonal()), 1e-12);
    // The cylinder: m r^2 / 2 and m (3 r^2 + h^2) / 12, which the prism approaches as
    // 1 - (2 pi / n)^2 / 6 (area) and faster for the moments: within 2 (2 pi/n)^2 relative.
    const double cyl_mass = rho * 1e-6 * std::numbers::pi * r * r * h;
    const double bound = 2.0 * alpha * alpha;
    EXPECT_NEAR(m.mass_kg, cyl_mass, bound * cyl_mass);
    EXPECT_NEAR(m.inertia_kg_mm2(2, 2), 0.5 * cyl_mass * r * r, bound * 0.5 * cyl_mass * r * r);
    EXPECT_NEAR(m.inertia_kg_mm2(0, 0), cyl_mass * (3 * r * r + h * h) / 12.0,
                bound * cyl_mass * (3 * r * r + h * h) / 12.0);
  }
}

TEST(MassProperties, MovedBoxFollowsRotationAndTheParallelAxisTheorem) {
  const double a = 9.0, b = 4.0, c = 2.5, rho = 1.15;
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-0.4, Eigen::Vector3d(1, 2, 0).normalized()))
          .toRotationMatrix();
  const Eigen::Vector3d t(31.0, -12.5, 4.0);
  TriangleMesh mesh = box(a, b, c);
  for (auto& v : mesh.vertices) v = R * v + t;
  const MassProperties m = mass_properties(mesh, rho);
  const double mass = rho * 1e-6 * a * b * c;
  const Eigen::Vector3d com = R * Eigen::Vector3d(a / 2, b / 2, c / 2) + t;
  const Eigen::Matrix3d i_com = R * box_inertia(mass, a, b, c) * R.transpose();
  EXPECT_NEAR(m.mass_kg, mass, 1e-12 * mass);
  EXPECT_LT((m.com_mm - com).norm(), 1e-12 * t.norm());
  EXPECT_LT(rel_diff(m.inertia_kg_mm2, i_com), 1e-10);
  // About the origin: I_o = I_com + m (|d|^2 1 - d d^T), written out here.
  Eigen::Matrix3d steiner;
  const Eigen::Vector3d& d = com;
  steiner << d.y() * d.y() + d.z() * d.z(), -d.x() * d.y(), -d.x() * d.z(),  //
      -d.x() * d.y(), d.x() * d.x() + d.z() * d.z(), -d.y() * d.z(),          //
      -d.x() * d.z(), -d.y() * d.z(), d.x() * d.x() + d.y() * d.y();
  EXPECT_LT(rel_diff(inertia_about(m, Eigen::Vector3d::Zero()), i_com + mass * steiner), 1e-10);
  // transformed() of the unmoved box gives the same body.
  const MassProperties moved = transformed(mass_properties(box(a, b, c), rho), R, t);
  EXPECT_LT((moved.com_mm - com).norm(), 1e-12 * t.norm());
  EXPECT_LT(rel_diff(moved.inertia_kg_mm2, i_com), 1e-12);
}

TEST(MassProperties, InwardOrOpenMeshIsRefused) {
  TriangleMesh inward = box(1.0, 2.0, 3.0);
  for (auto& t : inward.triangles) std::swap(t[1], t[2]);
  EXPECT_THROW(mass_properties(inward, 1.0), InputError);
  EXPECT_THROW(mass_properties(TriangleMesh{}, 1.0), InputError);
  EXPECT_THROW(mass_properties(box(1, 1, 1), 0.0), InputError);
}

// --- motor: and contact: sections ----------------------------------------------------------------

const std::string kStations = R"(name: t
stations:
  index:
    target: {center: [6.25, 15.5], axes: [15, 12]}
    mechanisms:
      lower: {bases: [[0, 0], [12.5, 0]], links: [9, 9, 15, 15], working_mode: "-+"}
      upper: {bases: [[0, 31], [12.5, 31]], links: [9, 9, 15, 15], working_mode: "+-"}
)";

TEST(MotorSection, NarrowerScopesWinAndTheFileReadsBack) {
  const std::string text = kStations + R"(motor:
  gear_ratio: 40
  mechanisms:
    upper: {gear_ratio: 50, theta2: {supply_voltage_V: 12}}
  stations:
    index:
      current_limit_A: 2
      upper: {gear_ratio: 60}
contact: {shear_stiffness_N_per_mm: 2.5}
)";
  const Design d = load_design_from_string(text, "m.yaml");
  const MotorSettings& m = *d.get<MotorSettings>();
  EXPECT_EQ(m.joint("index", "lower", 1).gear_ratio, 40.0);
  EXPECT_EQ(m.joint("index", "upper", 1).gear_ratio, 60.0);  // station scope beats every station's
  EXPECT_EQ(m.joint("other", "upper", 1).gear_ratio, 50.0);
  EXPECT_EQ(m.joint("index", "upper", 2).supply_voltage_V, 12.0);
  EXPECT_EQ(m.joint("index", "upper", 1).supply_voltage_V, 6.0);
  EXPECT_EQ(m.joint("index", "lower", 2).current_limit_A, 2.0);
  EXPECT_EQ(d.get<ContactSettings>()->shear_stiffness_N_per_mm, 2.5);
  // SI accessors: 1 mV/rpm = 60 / (2 pi) mV s/rad.
  MotorParams p;
  p.back_emf_mV_per_rpm = 2.0 * std::numbers::pi / 60.0;
  EXPECT_NEAR(p.back_emf_constant(), 1e-3, 1e-18);
  const Design back = load_design_from_string(to_yaml(d), "back.yaml");
  for (const char* mech : {"lower", "upper"}) {
    for (int j : {1, 2}) {
      const MotorParams a = m.joint("index", mech, j);
      const MotorParams b = back.get<MotorSettings>()->joint("index", mech, j);
      for (const MotorField& f : motor_fields()) EXPECT_EQ(a.*f.member, b.*f.member) << mech << j << f.key;
    }
  }
}

TEST(MotorSection, BadValuesNameFileLineAndKey) {
  const auto message = [&](const std::string& section) {
    try {
      (void)load_design_from_string(kStations + section, "bad.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message("motor: {gearbox_efficiency: 1.5}\n"),
            "bad.yaml:8: motor.gearbox_efficiency = 1.5: must be > 0 and <= 1");
  EXPECT_NE(message("motor:\n  stations: {index: {upper: {theta2: {inductance_mH: 0}}}}\n")
                .find("bad.yaml:9: motor.stations.index.upper.theta2.inductance_mH = 0"),
            std::string::npos);
  EXPECT_NE(message("motor:\n  stations: {nowhere: {gear_ratio: 2}}\n").find("motor.stations.nowhere: no such station"),
            std::string::npos);
  EXPECT_NE(message("contact: {friction_coefficient: -1}\n").find("bad.yaml:8: contact.friction_coefficient = -1"),
            std::string::npos);
}

// --- Dynamics ---------------------------------------------------------------------------------------

/// `text` contains `part`.
#define EXPECT_THAT_REASON(text, part) EXPECT_NE((text).find(part), std::string::npos) << (text)

const Design& paper() {
  static const Design d = load_design(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  return d;
}

MechanismModel paper_model(const std::string& station, const std::string& which) {
  const Design& d = paper();
  const Mechanism& m = *d.require_station(station).mechanism(which);
  MechanismModel model;
  model.mechanism = m;
  model.inertia = closed_form_inertia(m, *d.get<Geometry>(), *d.get<PrintSettings>());
  for (int j = 0; j < 2; ++j) model.motors[static_cast<std::size_t>(j)] = d.get<MotorSettings>()->joint(station, which, j + 1);
  return model;
}

/// Joint angles on a grid over the station's target ellipse (IK in the working mode).
std::vector<Eigen::Vector2d> workspace_grid(const Station& s, const Mechanism& m) {
  std::vector<Eigen::Vector2d> out;
  for (int a = 0; a < 5; ++a) {
    for (int r = 0; r <= 4; ++r) {
      const double rho = r / 4.0, phi = 2.0 * std::numbers::pi * a / 5.0 + 0.3 * r;
      const Vec2 p = s.target.center + Vec2(0.5 * s.target.axes.x() * rho * std::cos(phi),
                                            0.5 * s.target.axes.y() * rho * std::sin(phi));
      const AnglesResult ik = ik_angles(m, p);
      if (ik.status == Status::ok) out.emplace_back(ik.theta1, ik.theta2);
    }
  }
  return out;
}

/// Kinetic energy by a second route: each body's centre of mass and angle from FK alone
/// (fivebar/kinematics.hpp), differentiated by central differences along w.
double kinetic_energy_by_differences(const MechanismModel& model, const Eigen::Vector2d& theta, const Eigen::Vector2d& w) {
  const Mechanism& m = model.mechanism;
  const MechanismInertia& in = model.inertia;
  struct Bodies {
    std::array<Vec2, 5> c;     // L1..L4 centres of mass, tip (m)
    std::array<double, 4> phi; // link angles
  };
  const auto bodies = [&](const Eigen::Vector2d& th) {
    const Pose p = fk(m, th[0], th[1]);
    Bodies b;
    const std::array<Vec2, 4> from{m.O1, m.O2, p.A1, p.A2};
    const std::array<Vec2, 4> to{p.A1, p.A2, p.P, p.P};
    for (std::size_t i = 0; i < 4; ++i) {
      const Vec2 axis = (to[i] - from[i]).normalized();
      b.phi[i] = std::atan2(axis.y(), axis.x());
      const Vec2 c = in.links[i].com_mm;
      b.c[i] = 1e-3 * (from[i] + c.x() * axis + c.y() * Vec2(-axis.y(), axis.x()));
    }
    b.c[4] = 1e-3 * p.P;
    return b;
  };
  const double h = 1e-6;
  const Bodies plus = bodies(theta + h * w), minus = bodies(theta - h * w);
  double T = 0.0;
  for (std::size_t i = 0; i < 4; ++i) {
    const Vec2 v = (plus.c[i] - minus.c[i]) / (2 * h);
    double dphi = plus.phi[i] - minus.phi[i];
    dphi = std::remainder(dphi, 2.0 * std::numbers::pi) / (2 * h);
    double izz = in.links[i].izz_kg_mm2 * 1e-6;
    if (static_cast<int>(i) == in.carrier) izz += in.tip_izz_kg_mm2 * 1e-6;
    T += 0.5 * in.links[i].mass_kg * v.squaredNorm() + 0.5 * izz * dphi * dphi;
  }
  const Vec2 vp = (plus.c[4] - minus.c[4]) / (2 * h);
  T += 0.5 * in.tip_mass_kg * vp.squaredNorm();
  for (int j = 0; j < 2; ++j) {
    const MotorParams& mp = model.motors[static_cast<std::size_t>(j)];
    T += 0.5 * mp.gear_ratio * mp.gear_ratio * mp.rotor_inertia() * w[j] * w[j];
  }
  return T;
}

TEST(Dynamics, LinkMassesFromTheRenderedPartsAgreeWithTheClosedForm) {
  // Two routes to each body: volume integrals over the STL renders of the index parts (openscad,
  // $fn 24) and the slab-with-bosses formula; they share only the design's numbers.
  Design d = paper();
  d.get<PrintSettings>()->fn = 24;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("fivebar_test_dynamics_" + std::to_string(::getpid()));
  PartsOptions o;
  o.out_dir = dir;
  o.station = "index";
  const PartsReport report = build_parts(d, o);
  ASSERT_TRUE(report.passed());
  const Json parts = to_json(report);
  const Station& s = d.require_station("index");
  const auto stl = station_inertia(d, s, &parts, dir);
  const auto closed = station_inertia(d, s, nullptr, dir);
  std::filesystem::remove_all(dir);
  ASSERT_EQ(stl.size(), 2u);
  for (const auto& [name, a] : stl) {
    const MechanismInertia& b = closed.at(name);
    EXPECT_EQ(a.source, MassSource::stl);
    EXPECT_EQ(b.source, MassSource::closed_form);
    for (std::size_t i = 0; i < 4; ++i) {
      SCOPED_TRACE(name + " L" + std::to_string(i + 1));
      EXPECT_NEAR(a.links[i].mass_kg, b.links[i].mass_kg, 0.1 * a.links[i].mass_kg);
      EXPECT_NEAR(a.links[i].izz_kg_mm2, b.links[i].izz_kg_mm2, 0.1 * a.links[i].izz_kg_mm2);
      EXPECT_NEAR(a.links[i].com_mm.x(), b.links[i].com_mm.x(), 0.05 * d.stations[0].lower->L[i]);
      EXPECT_LT(std::abs(a.links[i].com_mm.y()), 0.01 * d.stations[0].lower->L[i]);
    }
    EXPECT_NEAR(a.tip_mass_kg, b.tip_mass_kg, 0.1 * a.tip_mass_kg);
  }
}

TEST(Dynamics, MassMatrixIsSymmetricPositiveDefiniteAndMatchesTheEnergyOfTheBodies) {
  int checked = 0;
  for (const Station& s : paper().stations) {
    for (const Mechanism* m : s.mechanisms()) {
      MechanismModel model = paper_model(s.name, m->name);
      model.motors[0].rotor_inertia_g_cm2 = model.motors[1].rotor_inertia_g_cm2 = 0.0;  // the linkage alone
      for (const Eigen::Vector2d& th : workspace_grid(s, *m)) {
        SCOPED_TRACE(s.name + " " + m->name + " theta = " + std::to_string(th[0]) + ", " + std::to_string(th[1]));
        const DynamicsTerms t = dynamics_terms(model, th, Eigen::Vector2d::Zero());
        ASSERT_EQ(t.status, Status::ok);
        EXPECT_LE(std::abs(t.M(0, 1) - t.M(1, 0)), 1e-14 * t.M.norm());
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(t.M);
        EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
        // The quadratic form against the bodies' energy from FK alone, for three directions.
        for (const Eigen::Vector2d w : {Eigen::Vector2d(1.0, 0.0), Eigen::Vector2d(0.0, 1.0), Eigen::Vector2d(0.7, -1.3)}) {
          const double reference = kinetic_energy_by_differences(model, th, w);
          EXPECT_NEAR(0.5 * w.dot(t.M * w), reference, 1e-7 * reference);
        }
        // J against the library's kinematic Jacobian (mm/rad).
        EXPECT_LT((1e3 * t.J - fk(*m, th[0], th[1]).J).norm(), 1e-9 * t.J.norm() * 1e3);
        ++checked;
      }
    }
  }
  EXPECT_GE(checked, 60);
}

TEST(Dynamics, CoriolisTermEqualsTheChristoffelSymbolsOfM) {
  // h_k = sum_ij (dM_kj/dtheta_i - 1/2 dM_ij/dtheta_k) w_i w_j (Lagrange), with dM by central
  // differences of the library's M: an independent route to the projected accelerations.
  MechanismModel model = paper_model("index", "lower");
  // The linkage alone: the rotors' constant inertia would only add rounding to the differences.
  model.motors[0].rotor_inertia_g_cm2 = model.motors[1].rotor_inertia_g_cm2 = 0.0;
  const Station& s = paper().stations.front();
  const double d = 1e-6;
  for (const Eigen::Vector2d& th : workspace_grid(s, *s.lower)) {
    const Eigen::Vector2d w(2.3, -1.1);
    std::array<Eigen::Matrix2d, 2> dM;
    for (int i = 0; i < 2; ++i) {
      Eigen::Vector2d e = Eigen::Vector2d::Zero();
      e[i] = d;
      dM[static_cast<std::size_t>(i)] = (dynamics_terms(model, th + e, w).M - dynamics_terms(model, th - e, w).M) / (2 * d);
    }
    Eigen::Vector2d h = Eigen::Vector2d::Zero();
    for (int k = 0; k < 2; ++k)
      for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j)
          h[k] += (dM[static_cast<std::size_t>(i)](k, j) - 0.5 * dM[static_cast<std::size_t>(k)](i, j)) * w[i] * w[j];
    const Eigen::Vector2d lib = dynamics_terms(model, th, w).h;
    SCOPED_TRACE(std::to_string(th[0]) + ", " + std::to_string(th[1]));
    EXPECT_LT((lib - h).norm(), 1e-6 * h.norm() + 1e-15);
  }
}

SimulationInput single(const MechanismModel& model, const Eigen::Vector2d& theta0) {
  SimulationInput in;
  in.station = "index";
  in.reference_name = "test";
  in.controller = *paper().get<ControllerSettings>();
  SimulatedMechanism sm;
  sm.name = model.mechanism.name;
  sm.model = model;
  sm.reference = {{theta0[0], theta0[1]}};
  sm.reference_point_mm = {fk_point(model.mechanism, theta0[0], theta0[1]).P};
  sm.theta0 = {theta0[0], theta0[1]};
  for (auto& c : sm.control) c = in.controller.joint("index", model.mechanism.name, 1);
  in.mechanisms.push_back(sm);
  return in;
}

TEST(Dynamics, UnpoweredFrictionlessLinkageConservesEnergy) {
  // No gravity (the design gives no orientation), so the linkage is set moving instead of being
  // released: open windings, no friction, no skin, no rotor inertia (the linkage's own terms).
  MechanismModel model = paper_model("index", "lower");
  for (MotorParams& mp : model.motors) {
    mp.viscous_friction_mNm_s_per_rad = mp.coulomb_friction_mNm = mp.rotor_inertia_g_cm2 = 0.0;
  }
  const Station& s = paper().stations.front();
  const AnglesResult start = ik_angles(*s.lower, s.target.center + Vec2(2.0, -1.5));  // off-centre
  ASSERT_EQ(start.status, Status::ok);
  SimulationInput in = single(model, {start.theta1, start.theta2});
  in.mechanisms[0].w0 = {0.05, -0.03};
  SimulationOptions o;
  o.drive = Drive::open_circuit;
  o.contact = false;
  o.duration_s = 10.0;
  o.rtol = 1e-13;
  o.rate_scale = 1e-2;
  const SimulationResult r = simulate(in, o);
  ASSERT_TRUE(r.ok()) << r.reason;
  ASSERT_EQ(r.samples.size(), 1001u);
  const double e0 = r.samples.front().mechanisms[0].energy_J;
  ASSERT_GT(e0, 0.0);
  double worst = 0.0, travel = 0.0;
  for (const TimeSample& t : r.samples) {
    worst = std::max(worst, std::abs(t.mechanisms[0].energy_J - e0) / e0);
    travel = std::max(travel, std::abs(t.mechanisms[0].theta[0] - start.theta1));
  }
  EXPECT_LT(worst, 1e-8);
  EXPECT_GT(travel, 0.1);  // it really moved (and the speeds changed: a closed chain)
  std::ostringstream figures;
  figures << "drift " << worst << ", travel " << travel << " rad, " << r.steps << " steps";
  RecordProperty("energy", figures.str());
}

TEST(Dynamics, LockedRotorDrawsTheStallCurrentVOverR) {
  const MechanismModel model = paper_model("index", "lower");
  const Station& s = paper().stations.front();
  const AnglesResult start = ik_angles(*s.lower, s.target.center);
  for (const double duty : {0.5, -0.8}) {
    SimulationInput in = single(model, {start.theta1, start.theta2});
    SimulationOptions o;
    o.drive = Drive::constant_duty;
    o.duty = duty;
    o.lock_joints = true;
    o.contact = false;
    o.duration_s = 0.05;  // 500 L/R
    o.rtol = 1e-10;
    const SimulationResult r = simulate(in, o);
    ASSERT_TRUE(r.ok()) << r.reason;
    const MotorParams& mp = model.motors[0];
    const double stall = duty * mp.supply_voltage_V / mp.terminal_resistance_ohm;  // 0.6 A, -0.96 A
    SCOPED_TRACE(duty);
    ASSERT_LT(std::abs(stall), mp.current_limit_A);
    for (std::size_t j = 0; j < 2; ++j) EXPECT_NEAR(r.samples.back().mechanisms[0].current[j], stall, 1e-8);
    EXPECT_NEAR(r.summary[0].peak_current_A, std::abs(stall), 1e-8);
  }
  // Above the driver's limit the current settles at the limit.
  SimulationInput in = single(model, {start.theta1, start.theta2});
  in.mechanisms[0].model.motors[0].current_limit_A = 0.25;
  SimulationOptions o;
  o.drive = Drive::constant_duty;
  o.duty = 1.0;
  o.lock_joints = true;
  o.contact = false;
  o.duration_s = 0.05;
  o.rtol = 1e-10;
  const SimulationResult r = simulate(in, o);
  ASSERT_TRUE(r.ok()) << r.reason;
  EXPECT_NEAR(r.samples.back().mechanisms[0].current[0], 0.25, 1e-8);
  // Joint 2 keeps the 1 A limit: 6 V / 5 ohm = 1.2 A would exceed it.
  EXPECT_NEAR(r.samples.back().mechanisms[0].current[1], 1.0, 1e-8);
}

TEST(Dynamics, ASingularStartOrAnExhaustedBudgetIsAStatusWithTheStateNeverANaN) {
  const MechanismModel model = paper_model("index", "lower");
  // Distal links aligned (type II): theta1 = 180 deg puts A1 at (-9, 0); |A2 - A1| = L3 + L4 = 30
  // when 21.5^2 + 2 21.5 9 cos(theta2) + 81 = 900, i.e. cos(theta2) = 356.75 / 387.
  const double theta2 = std::acos(356.75 / 387.0);
  SimulationInput in = single(model, {std::numbers::pi, theta2});
  SimulationResult r = simulate(in);
  EXPECT_EQ(r.status, SimStatus::singular);
  EXPECT_THAT_REASON(r.reason, "t = 0 s");

  const Station& s = paper().stations.front();
  const AnglesResult start = ik_angles(*s.lower, s.target.center);
  in = single(model, {start.theta1, start.theta2});
  in.mechanisms[0].reference.push_back({start.theta1 + 0.3, start.theta2 + 0.3});  // a step to chase
  in.mechanisms[0].reference_point_mm.push_back(s.target.center);
  SimulationOptions o;
  o.max_steps = 50;
  r = simulate(in, o);
  EXPECT_EQ(r.status, SimStatus::step_limit);
  EXPECT_THAT_REASON(r.reason, "more than 50 integrator steps");
  EXPECT_THAT_REASON(r.reason, "lower theta = (");
  EXPECT_LE(r.steps, 51u);
  EXPECT_TRUE(std::isfinite(r.t_end));
  o = SimulationOptions{};
  o.max_wall_s = 0.0;
  r = simulate(in, o);
  EXPECT_EQ(r.status, SimStatus::wall_time_limit);
  EXPECT_THAT_REASON(r.reason, "of wall time");
  for (const TimeSample& t : r.samples) {
    for (double v : {t.mechanisms[0].theta[0], t.mechanisms[0].current[0], t.mechanisms[0].P_mm.x()}) EXPECT_TRUE(std::isfinite(v));
  }
}

TEST(Dynamics, DiscretePidFollowsAHandComputedSequence) {
  // kp 0.1, ki 10, kd 0.02, i_clamp 0.05, T = 10 ms (the accumulator's bound is 0.05/10 = 0.005):
  //   e = 0.2:  s = 0.002,                 duty = 0.02 + 0.02          = 0.04
  //   e = 0.3:  s = 0.005, d = 10,         duty = 0.03 + 0.05 + 0.2    = 0.28
  //   e = 0.3:  s = 0.008 -> 0.005, d = 0, duty = 0.03 + 0.05          = 0.08
  //   e = -0.4: s = 0.001, d = -70,        duty = -0.04 + 0.01 - 1.4   -> -1 (clamped)
  //   e = -0.4: s = -0.003, d = 0,         duty = -0.04 - 0.03         = -0.07
  PidGains g;
  g.kp = 0.1;
  g.ki = 10.0;
  g.kd = 0.02;
  g.i_clamp = 0.05;
  DiscretePid pid(g, 0.01);
  const std::array<double, 5> e{0.2, 0.3, 0.3, -0.4, -0.4};
  const std::array<double, 5> expected{0.04, 0.28, 0.08, -1.0, -0.07};
  for (std::size_t k = 0; k < e.size(); ++k) {
    SCOPED_TRACE(k);
    EXPECT_NEAR(pid.update(e[k]), expected[k], 1e-12);
  }
}

TEST(Dynamics, AdcQuantisesToTheNearestLevelAndClamps) {
  // The export's ADC model (fivebar/export/export.hpp adc.volts_per_count): 2^bits codes range / 2^bits
  // apart from the range's low end, the top code one step below its high end.
  Potentiometer pot;  // 2.5 V at 0, pi/3 rad per V
  const std::array<double, 2> range{-10.0, 10.0};
  // One count is range / 2^bits, the exported adc.volts_per_count (a 16-bit converter over 20 V:
  // 20/65536 V; codes 0 ... 65535 read -10 V ... 10 V - one count).
  const double q = 20.0 / 65536.0;  // V per count
  for (double theta : {0.0, 0.1234567, -1.0, 2.0}) {
    const double read = adc_reading(theta, pot, 16, range);
    EXPECT_LE(std::abs(read - theta), 0.5 * q * pot.rad_per_volt * (1 + 1e-9)) << theta;
    // The reading is a whole number of counts above the range's bottom.
    const double counts = (read / pot.rad_per_volt + pot.volts_at_zero - range[0]) / q;
    EXPECT_NEAR(counts, std::round(counts), 1e-6) << theta;
  }
  // Two angles one count apart (in volts) read one count apart.
  const double a = adc_reading(0.3, pot, 16, range);
  const double b = adc_reading(0.3 + q * pot.rad_per_volt, pot, 16, range);
  EXPECT_NEAR((b - a) / pot.rad_per_volt, q, 1e-12);
  // 8 bits: counts 20/256 V apart; 40 rad is 40.7 V, beyond the range: reads the top code 255,
  // 10 V - 20/256 V (was 10 V when the step was range / (2^bits - 1)).
  EXPECT_NEAR(adc_reading(40.0, pot, 8, range), pot.rad_per_volt * (10.0 - 20.0 / 256 - 2.5), 1e-12);
  EXPECT_NEAR(adc_reading(-40.0, pot, 8, range), pot.rad_per_volt * (-10.0 - 2.5), 1e-12);
  EXPECT_NEAR(adc_reading(0.0, pot, 8, range), pot.rad_per_volt * (-10.0 + std::round(12.5 / (20.0 / 256)) * (20.0 / 256) - 2.5),
              1e-12);
}

TEST(Dynamics, ThePaperStationTracksItsStretchWithinTheDriverLimits) {
  const Design& d = paper();
  std::map<std::string, MechanismInertia> inertia;
  for (const Mechanism* m : d.require_station("index").mechanisms()) {
    inertia[m->name] = closed_form_inertia(*m, *d.get<Geometry>(), *d.get<PrintSettings>());
  }
  SimulationRequest request;
  request.station = "index";
  request.pattern = PatternKind::stretch;
  const std::vector<SimulationInput> inputs = simulation_inputs(d, request, inertia);
  ASSERT_EQ(inputs.size(), 1u);
  const SimulationResult r = simulate(inputs[0]);
  ASSERT_TRUE(r.ok()) << r.reason;
  ASSERT_EQ(r.summary.size(), 2u);
  for (const MechanismSummary& s : r.summary) {
    SCOPED_TRACE(s.name);
    EXPECT_TRUE(std::isfinite(s.max_error_mm));
    EXPECT_LT(s.rms_error_mm, s.max_error_mm + 1e-12);
    // The clamp of the driver keeps the current within its limit (di/dt <= R (I - i) / L).
    EXPECT_LE(s.peak_current_A, d.get<MotorSettings>()->defaults.current_limit_A * (1 + 1e-5));
    EXPECT_LE(s.peak_duty, 1.0);
  }
  // The last sample has settled on the pattern's end point within a tenth of a millimetre.
  for (const MechanismSample& m : r.samples.back().mechanisms) EXPECT_LT((m.P_mm - m.P_ref_mm).norm(), 0.1);
}

TEST(Dynamics, TheTrajectoryConvergesAsTheToleranceTightens) {
  // Against a run at rtol 1e-11 (ADC quantisation off: a rounding level flipped by a tiny
  // difference would change the next duty, a discontinuity no tolerance removes), the tactor
  // error falls with the tolerance: BDF's local error control is proportional.
  const Design& d = paper();
  SimulationRequest request;
  request.station = "index";
  request.pattern = PatternKind::twist;
  const SimulationInput in = simulation_inputs(d, request, station_inertia(d, d.require_station("index"), nullptr, {})).front();
  SimulationOptions o;
  o.quantise = false;
  o.rtol = 1e-11;
  const SimulationResult reference = simulate(in, o);
  ASSERT_TRUE(reference.ok()) << reference.reason;
  const auto error_at = [&](double rtol) {
    o.rtol = rtol;
    const SimulationResult r = simulate(in, o);
    EXPECT_TRUE(r.ok()) << r.reason;
    EXPECT_EQ(r.samples.size(), reference.samples.size());
    double e = 0.0;
    for (std::size_t s = 0; s < std::min(r.samples.size(), reference.samples.size()); ++s) {
      for (std::size_t k = 0; k < 2; ++k) {
        e = std::max(e, (r.samples[s].mechanisms[k].P_mm - reference.samples[s].mechanisms[k].P_mm).norm());
      }
    }
    return e;
  };
  const double e5 = error_at(1e-5), e7 = error_at(1e-7), e9 = error_at(1e-9);
  SCOPED_TRACE(std::to_string(e5) + " " + std::to_string(e7) + " " + std::to_string(e9));
  EXPECT_LT(e5, 1e-4);  // mm, for a 6 mm twist
  EXPECT_LT(e7, e5 / 10.0);
  EXPECT_LT(e9, e7 / 10.0);
}

TEST(Dynamics, LowFrictionMakesTheTactorSlipAndHighFrictionDoesNot) {
  const Design& d = paper();
  std::map<std::string, MechanismInertia> inertia;
  for (const Mechanism* m : d.require_station("index").mechanisms()) {
    inertia[m->name] = closed_form_inertia(*m, *d.get<Geometry>(), *d.get<PrintSettings>());
  }
  SimulationRequest request;
  request.station = "index";
  request.pattern = PatternKind::stretch;
  SimulationInput in = simulation_inputs(d, request, inertia).front();
  // Stretch by 3 mm on a 1 N/mm skin: a spring force of ~3 N against mu N.
  in.contact.friction_coefficient = 10.0;
  const SimulationResult stick = simulate(in);
  ASSERT_TRUE(stick.ok()) << stick.reason;
  in.contact.friction_coefficient = 0.5;
  const SimulationResult slip = simulate(in);
  ASSERT_TRUE(slip.ok()) << slip.reason;
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_FALSE(stick.summary[k].slipped);
    EXPECT_TRUE(slip.summary[k].slipped);
    // Sliding caps the spring at mu N = 0.25 N (plus the damper's share while sticking).
    EXPECT_GT(stick.summary[k].peak_shear_N, 1.0);
    EXPECT_LT(slip.summary[k].peak_shear_N, 0.25 + 0.1);
  }
  // While sliding the skin force is exactly mu N (the anchor keeps the stretch at mu N / k).
  std::size_t sliding = 0;
  for (const TimeSample& t : slip.samples) {
    for (const MechanismSample& m : t.mechanisms) {
      if (!m.slipping) continue;
      ++sliding;
      EXPECT_NEAR(m.force_N.norm(), 0.25, 1e-5) << "t = " << t.t;
    }
  }
  EXPECT_GT(sliding, 10u);
}


// --- The explicit comparison integrator and the switched PWM -------------------------------------

SimulationInput paper_pattern(PatternKind kind) {
  const Design& d = paper();
  SimulationRequest request;
  request.station = "index";
  request.pattern = kind;
  return simulation_inputs(d, request, station_inertia(d, d.require_station("index"), nullptr, {})).front();
}

double max_path_difference_mm(const SimulationResult& a, const SimulationResult& b) {
  double e = 0.0;
  EXPECT_EQ(a.samples.size(), b.samples.size());
  for (std::size_t s = 0; s < std::min(a.samples.size(), b.samples.size()); ++s) {
    for (std::size_t k = 0; k < a.samples[s].mechanisms.size(); ++k) {
      e = std::max(e, (a.samples[s].mechanisms[k].P_mm - b.samples[s].mechanisms[k].P_mm).norm());
    }
  }
  return e;
}

TEST(Dynamics, ExplicitRungeKuttaAndBdfAgreeOnAPattern) {
  // Two integrators of different families (ARKODE's Dormand-Prince 5(4), CVODE's BDF) on the same
  // model, the twist with slip roots and restarts at every sample (ADC off, as in the convergence
  // test: a flipped quantisation level is not an integration error). Each is within ~1e-7 mm of
  // the exact path at rtol 1e-8 (the BDF convergence test above), so they agree within 1e-5 mm.
  const SimulationInput in = paper_pattern(PatternKind::twist);
  SimulationOptions o;
  o.quantise = false;
  o.rtol = 1e-8;
  const SimulationResult bdf = simulate(in, o);
  o.integrator = Integrator::erk;
  const SimulationResult erk = simulate(in, o);
  ASSERT_TRUE(bdf.ok()) << bdf.reason;
  ASSERT_TRUE(erk.ok()) << erk.reason;
  const double diff = max_path_difference_mm(bdf, erk);
  RecordProperty("bdf_erk", format::shortest(diff) + " mm; steps " + std::to_string(bdf.steps) + " / " +
                                std::to_string(erk.steps));
  EXPECT_LT(diff, 1e-5);
  for (std::size_t k = 0; k < 2; ++k) EXPECT_EQ(bdf.summary[k].slips, erk.summary[k].slips);
  // Stiffer: the motors' L/R from 100 us to 0.1 us. The explicit method's steps are bounded by its
  // stability region (h < ~3.3 L/R for Dormand-Prince on the decay of the current), so its step
  // count grows ~1000-fold; BDF's (A(alpha)-stable) barely moves.
  // Started 1 deg off its reference, so that the motors work from the first sample on.
  SimulationInput stiff = in;
  for (SimulatedMechanism& m : stiff.mechanisms) {
    for (MotorParams& mp : m.model.motors) mp.inductance_mH *= 1e-3;
    m.theta0[0] += 1.0 / format::kDegPerRad;
  }
  o.duration_s = 0.02;
  o.rtol = 1e-6;
  o.integrator = Integrator::bdf;
  const SimulationResult stiff_bdf = simulate(stiff, o);
  o.integrator = Integrator::erk;
  const SimulationResult stiff_erk = simulate(stiff, o);
  ASSERT_TRUE(stiff_bdf.ok()) << stiff_bdf.reason;
  ASSERT_TRUE(stiff_erk.ok()) << stiff_erk.reason;
  const double tau = stiff.mechanisms[0].model.motors[0].inductance() / stiff.mechanisms[0].model.motors[0].resistance();
  // At least one explicit step per ~10 L/R (quiet stretches at zero duty, where nothing excites
  // the current, let it stride further than its stability bound of ~3.3 L/R).
  EXPECT_GT(double(stiff_erk.steps), 0.02 / (10.0 * tau));
  EXPECT_GT(stiff_erk.steps, 20 * stiff_bdf.steps);
  EXPECT_LT(max_path_difference_mm(stiff_bdf, stiff_erk), 1e-3);
}

TEST(Dynamics, SwitchedPwmRipplesAsAnRlCircuitUnderASquareWave) {
  // Locked rotor, constant duty D: each PWM period applies V for D T_pwm, then 0 V. The periodic
  // solution of L di/dt = V - R i (closed form in fivebar/dynamics.hpp) peaks at the end of the
  // on-phase and bottoms at the period start. Both instants are stop times of the integrator;
  // stepping over them would round the corners.
  MechanismModel model = paper_model("index", "lower");
  for (MotorParams& mp : model.motors) mp.current_limit_A = 2.0;  // V/R = 1.2 A: no clamp
  const Station& s = paper().stations.front();
  const AnglesResult start = ik_angles(*s.lower, s.target.center);
  for (const Integrator integrator : {Integrator::bdf, Integrator::erk}) {
    for (const double duty : {0.3, -0.65}) {
      SCOPED_TRACE(std::string(to_string(integrator)) + " duty " + std::to_string(duty));
      const SimulationInput in = single(model, {start.theta1, start.theta2});
      SimulationOptions o;
      o.drive = Drive::constant_duty;
      o.duty = duty;
      o.lock_joints = true;
      o.contact = false;
      o.pwm = PwmModel::switched;
      o.integrator = integrator;
      o.duration_s = 0.02;  // 200 L/R: periodic to 1e-80
      o.rtol = 1e-10;
      o.dense_dt_s = 5e-6;  // the on-phase ends (0.3 ms, 0.65 ms) are on this grid
      const SimulationResult r = simulate(in, o);
      ASSERT_TRUE(r.ok()) << r.reason;
      const MotorParams& mp = model.motors[0];
      const double tau = mp.inductance() / mp.resistance(), T = 1e-3, D = std::abs(duty);
      const double v_over_r = (duty > 0 ? 1.0 : -1.0) * mp.supply_voltage_V / mp.resistance();
      const double i_max = v_over_r * (1.0 - std::exp(-D * T / tau)) / (1.0 - std::exp(-T / tau));
      const double i_min = i_max * std::exp(-(1.0 - D) * T / tau);
      // The last full period [19 ms, 20 ms].
      double hi = -1e9, lo = 1e9;
      std::size_t n = 0;
      for (const TimeSample& t : r.dense) {
        if (t.t < 0.019 - 1e-12) continue;
        ++n;
        hi = std::max(hi, t.mechanisms[0].current[0]);
        lo = std::min(lo, t.mechanisms[0].current[0]);
      }
      ASSERT_GE(n, 200u);
      EXPECT_NEAR(duty > 0 ? hi : lo, i_max, 1e-6 * std::abs(v_over_r));
      EXPECT_NEAR(duty > 0 ? lo : hi, i_min, 1e-6 * std::abs(v_over_r));
      // The controller's samples (period starts) see the trough; its mean is the averaged D V / R.
      EXPECT_NEAR(r.samples.back().mechanisms[0].current[1], i_min, 1e-6 * std::abs(v_over_r));
      double mean = 0.0;  // trapezoid over the last period on the 5 us grid
      std::vector<double> last;
      for (const TimeSample& t : r.dense)
        if (t.t >= 0.019 - 1e-12) last.push_back(t.mechanisms[0].current[0]);
      for (std::size_t i = 0; i + 1 < last.size(); ++i) mean += 0.5 * (last[i] + last[i + 1]) / double(last.size() - 1);
      EXPECT_NEAR(mean, duty * mp.supply_voltage_V / mp.resistance(), 2e-3 * std::abs(v_over_r));
    }
  }
}

TEST(Dynamics, SwitchedAndAveragedPwmAgreeOnTheSlowMotion) {
  // The switched waveform adds a 1 kHz torque ripple of at most eta N k_t V / R peak to peak; on the
  // joints' inertia (smallest eigenvalue of M) a zero-mean square wave of that swing moves them by
  // at most a T^2 / 8 (twice integrated), and the tactor by |J| times that. The tactor paths agree
  // within a few times this bound; the mean current is the same (linear winding). The drivers'
  // current limit is raised out of the way: a cycle-by-cycle limiter cuts the ripple's peaks (1.2 A
  // at 6 V / 5 ohm against 1 A) where the average is far below the limit, a real difference of
  // the two models, not an integration error.
  SimulationInput in = paper_pattern(PatternKind::stretch);
  for (SimulatedMechanism& m : in.mechanisms)
    for (MotorParams& mp : m.model.motors) mp.current_limit_A = 3.0;
  SimulationOptions o;
  o.quantise = false;
  o.rtol = 1e-7;
  o.duration_s = 0.4;  // the stretch's first 3 mm
  const SimulationResult averaged = simulate(in, o);
  o.pwm = PwmModel::switched;
  const SimulationResult switched = simulate(in, o);
  ASSERT_TRUE(averaged.ok()) << averaged.reason;
  ASSERT_TRUE(switched.ok()) << switched.reason;
  double bound = 0.0;
  for (const SimulatedMechanism& m : in.mechanisms) {
    const MotorParams& mp = m.model.motors[0];
    const DynamicsTerms t = dynamics_terms(m.model, Eigen::Vector2d(m.theta0[0], m.theta0[1]), Eigen::Vector2d::Zero());
    const double lambda = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(t.M).eigenvalues().minCoeff();
    const double torque = mp.gearbox_efficiency * mp.gear_ratio * mp.torque_constant() * mp.supply_voltage_V / mp.resistance();
    const double sigma = Eigen::JacobiSVD<Eigen::Matrix2d>(t.J).singularValues()[0];
    bound = std::max(bound, 1e3 * sigma * torque / lambda * 1e-6 / 8.0);  // mm
  }
  const double diff = max_path_difference_mm(averaged, switched);
  RecordProperty("averaged_switched", format::shortest(diff) + " mm against the ripple bound " + format::shortest(bound) +
                                          " mm; steps " + std::to_string(averaged.steps) + " / " +
                                          std::to_string(switched.steps));
  EXPECT_LT(diff, 4.0 * bound);
  EXPECT_GT(switched.restarts, 10 * averaged.restarts);  // every edge a restart
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_NEAR(switched.summary[k].max_error_mm, averaged.summary[k].max_error_mm, 4.0 * bound);
    EXPECT_GT(switched.summary[k].peak_current_A, averaged.summary[k].peak_current_A);  // the ripple's peaks
  }
}

TEST(Dynamics, ChirpBodeRecoversAFirstOrderLowPass) {
  // The estimator alone, on a record made here: the commanded chirp through a first-order low-pass
  // discretised exactly with the controller's zero-order hold, y_k+1 = e y_k + (1 - e) u_k with
  // e = exp(-T / tau), whose magnitude is |(1 - e) / (z - e)| at z = exp(i 2 pi f T). The estimate
  // follows it within 10 % over the band and its -3 dB frequency within 5 %.
  SimulationRequest request;
  request.chirp = true;
  const double rate = 100.0, T = 1.0 / rate, fc = 6.0, tau = 1.0 / (2.0 * std::numbers::pi * fc);
  const double e = std::exp(-T / tau);
  SimulationInput in;
  in.controller.loop_rate_hz = rate;
  SimulatedMechanism sm;
  sm.name = "lower";
  in.mechanisms.push_back(sm);
  SimulationResult r;
  const double f0 = request.chirp_f0_hz, f1 = 0.25 * rate, D = request.chirp_duration_s, k = f1 / f0;
  double y = 0.0;
  for (std::size_t n = 0; n <= static_cast<std::size_t>(D * rate) + 50; ++n) {
    const double t = double(n) * T;
    const double tt = std::min(t, D);
    const double u = 0.2 * std::sin(2.0 * std::numbers::pi * f0 * D * (std::pow(k, tt / D) - 1.0) / std::log(k));
    TimeSample ts;
    ts.t = t;
    MechanismSample ms;
    ms.P_ref_mm = Vec2(u, 0.0);
    ms.P_mm = Vec2(y, 0.0);
    ts.mechanisms.push_back(ms);
    r.samples.push_back(ts);
    y = e * y + (1.0 - e) * u;
  }
  const BodeResult bode = chirp_bode(in, r, request);
  ASSERT_EQ(bode.magnitude.size(), 1u);
  const auto exact = [&](double f) {
    const std::complex<double> z = std::polar(1.0, 2.0 * std::numbers::pi * f * T);
    return std::abs((1.0 - e) / (z - e));
  };
  for (std::size_t i = 0; i < bode.f_hz.size(); ++i) {
    EXPECT_NEAR(bode.magnitude[0][i], exact(bode.f_hz[i]), 0.1 * exact(bode.f_hz[i])) << bode.f_hz[i] << " Hz";
  }
  // The exact -3 dB point relative to the lowest frequency's magnitude, by bisection.
  const double level = exact(bode.f_hz.front()) * std::pow(10.0, -3.0 / 20.0);
  double lo = bode.f_hz.front(), hi = bode.f_hz.back();
  for (int n = 0; n < 60; ++n) (exact(0.5 * (lo + hi)) > level ? lo : hi) = 0.5 * (lo + hi);
  ASSERT_TRUE(bode.bandwidth_hz[0]);
  EXPECT_NEAR(*bode.bandwidth_hz[0], lo, 0.05 * lo);
}

}  // namespace
}  // namespace fivebar
