// Dynamics of the device (fivebar/dynamics.hpp) and the mass properties of its parts
// (fivebar/parts.hpp). Every expected value is an independent closed form: the box and the regular
// prism (exact for a tessellated cylinder) from textbook integrals, the parallel-axis theorem, the
// stall current V/R of an Ohmic winding, a PID sequence worked by hand, and conservation of
// kinetic energy of an unforced, frictionless linkage.

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "fivebar/error.hpp"
#include "fivebar/parts.hpp"
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

}  // namespace
}  // namespace fivebar
