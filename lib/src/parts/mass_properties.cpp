// Mass properties of closed triangle meshes (fivebar/parts.hpp): volume, centre of mass and inertia
// tensor by the divergence theorem, after D. Eberly, "Polyhedral Mass Properties (Revisited)",
// Geometric Tools (2002, rev. 2009), itself a simplification of B. Mirtich, "Fast and Accurate
// Computation of Polyhedral Mass Properties", J. Graphics Tools 1(2), 1996.

#include <Eigen/Geometry>

#include <array>
#include <cmath>
#include <sstream>

#include "fivebar/parts.hpp"

namespace fivebar {

namespace {

/// Eberly's per-coordinate subexpressions of one triangle (w0, w1, w2 = one coordinate of its
/// three vertices): f1 = sum w, f2 = sum of the degree-2 monomials, f3 = of degree 3, and g_i.
struct Sub {
  double f1, f2, f3, g0, g1, g2;
};

Sub subexpressions(double w0, double w1, double w2) {
  const double temp0 = w0 + w1;
  const double temp1 = w0 * w0;
  const double temp2 = temp1 + w1 * temp0;
  Sub s{};
  s.f1 = temp0 + w2;
  s.f2 = temp2 + w2 * s.f1;
  s.f3 = w0 * temp1 + w1 * temp2 + w2 * s.f2;
  s.g0 = s.f2 + w0 * (s.f1 + w0);
  s.g1 = s.f2 + w1 * (s.f1 + w1);
  s.g2 = s.f2 + w2 * (s.f1 + w2);
  return s;
}

}  // namespace

MassProperties mass_properties(const TriangleMesh& mesh, double density_g_cm3) {
  if (!(density_g_cm3 > 0.0) || !std::isfinite(density_g_cm3)) {
    throw InputError("density " + std::to_string(density_g_cm3) + " g/cm^3: must be > 0");
  }
  // Integrals of 1, x, y, z, x^2, y^2, z^2, xy, yz, zx over the solid (unit density), in a frame
  // centred on the bounding box.
  const Eigen::Vector3d origin = mesh.triangles.empty() ? Eigen::Vector3d::Zero()
                                                        : Eigen::Vector3d(0.5 * (mesh.bbox_min() + mesh.bbox_max()));
  std::array<double, 10> in{};
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3d p0 = mesh.vertices[t[0]] - origin;
    const Eigen::Vector3d p1 = mesh.vertices[t[1]] - origin;
    const Eigen::Vector3d p2 = mesh.vertices[t[2]] - origin;
    const Eigen::Vector3d a = p1 - p0;
    const Eigen::Vector3d b = p2 - p0;
    const Eigen::Vector3d d = a.cross(b);  // twice the area times the outward normal
    const Sub x = subexpressions(p0.x(), p1.x(), p2.x());
    const Sub y = subexpressions(p0.y(), p1.y(), p2.y());
    const Sub z = subexpressions(p0.z(), p1.z(), p2.z());
    in[0] += d.x() * x.f1;
    in[1] += d.x() * x.f2;
    in[2] += d.y() * y.f2;
    in[3] += d.z() * z.f2;
    in[4] += d.x() * x.f3;
    in[5] += d.y() * y.f3;
    in[6] += d.z() * z.f3;
    in[7] += d.x() * (p0.y() * x.g0 + p1.y() * x.g1 + p2.y() * x.g2);
    in[8] += d.y() * (p0.z() * y.g0 + p1.z() * y.g1 + p2.z() * y.g2);
    in[9] += d.z() * (p0.x() * z.g0 + p1.x() * z.g1 + p2.x() * z.g2);
  }
  constexpr std::array<double, 10> kMult{1.0 / 6,  1.0 / 24, 1.0 / 24, 1.0 / 24,  1.0 / 60,
                                         1.0 / 60, 1.0 / 60, 1.0 / 120, 1.0 / 120, 1.0 / 120};
  for (std::size_t i = 0; i < in.size(); ++i) in[i] *= kMult[i];

  const double volume = in[0];
  if (!(volume > 0.0)) {
    std::ostringstream s;
    s << "mesh of " << mesh.triangles.size() << " triangles encloses a volume of " << volume
      << " mm^3: mass properties need a closed, outward-oriented mesh";
    throw InputError(s.str());
  }
  const Eigen::Vector3d c(in[1] / volume, in[2] / volume, in[3] / volume);
  // Second moments about the centre of mass (unit density), then inertia.
  const double xx = in[4] - volume * c.x() * c.x();
  const double yy = in[5] - volume * c.y() * c.y();
  const double zz = in[6] - volume * c.z() * c.z();
  const double xy = in[7] - volume * c.x() * c.y();
  const double yz = in[8] - volume * c.y() * c.z();
  const double zx = in[9] - volume * c.z() * c.x();
  const double rho = density_g_cm3 * 1e-6;  // kg/mm^3
  MassProperties m;
  m.volume_mm3 = volume;
  m.mass_kg = rho * volume;
  m.com_mm = c + origin;
  m.inertia_kg_mm2 << rho * (yy + zz), -rho * xy, -rho * zx,  //
      -rho * xy, rho * (xx + zz), -rho * yz,                  //
      -rho * zx, -rho * yz, rho * (xx + yy);
  return m;
}

MassProperties transformed(const MassProperties& m, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  MassProperties out = m;
  out.com_mm = R * m.com_mm + t;
  out.inertia_kg_mm2 = R * m.inertia_kg_mm2 * R.transpose();
  return out;
}

Eigen::Matrix3d inertia_about(const MassProperties& m, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = m.com_mm - p;
  return m.inertia_kg_mm2 + m.mass_kg * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
}

}  // namespace fivebar
