// A second formulation of the five-bar's dynamics (fivebar/dynamics.hpp), written here
// independently of the library's: the open chain of all four links in absolute angles
// q = (theta1, theta2, phi3, phi4) closed by the loop constraint with Lagrange multipliers,
//   c(q) = O1 + L1 e(theta1) + L3 e(phi3) - O2 - L2 e(theta2) - L4 e(phi4) = 0,
//   M(q) dv/dt + h(q, v) = Q(v) + C(q)^T lambda,   C = dc/dq,
// reduced to index 1 by differentiating c twice, C dv/dt + (dC/dt) v = 0, and integrated by
// SUNDIALS IDA (BDF on the residual F(t, y, y') = 0, y = (q, v, lambda), lambda algebraic). The
// library integrates the 2-DOF projection M(theta) dw/dt + h = tau (Kane's method) with CVODE; an
// unpowered, contact-free release with the joints' friction must give the same joint trajectories.
// SUNDIALS is included by this test only (the library keeps it in lib/src/dynamics/).

#include <gtest/gtest.h>

#include <ida/ida.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include <Eigen/Dense>

#include <array>
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "fivebar/dynamics.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/motor.hpp"
#include "fivebar/sections/print.hpp"

namespace fivebar {
namespace {

using V2 = Eigen::Vector2d;
using V4 = Eigen::Vector4d;
using M4 = Eigen::Matrix4d;

V2 e(double a) { return {std::cos(a), std::sin(a)}; }
V2 rot(double a, const V2& p) { return {std::cos(a) * p.x() - std::sin(a) * p.y(), std::sin(a) * p.x() + std::cos(a) * p.y()}; }
V2 perp(const V2& p) { return {-p.y(), p.x()}; }

/// A point of a body as a sum of vectors fixed in the rotating frames q[index] (plus a constant):
/// its velocity Jacobian column for q_i is perp(R(q_i) p), its acceleration at dv/dt = 0 is
/// -sum R(q_i) p q_i'^2.
struct Point {
  std::vector<std::pair<int, V2>> terms;
  void jacobian(const V4& q, Eigen::Matrix<double, 2, 4>& J) const {
    J.setZero();
    for (const auto& [i, p] : terms) J.col(i) += perp(rot(q[i], p));
  }
  V2 accel0(const V4& q, const V4& v) const {
    V2 a = V2::Zero();
    for (const auto& [i, p] : terms) a -= rot(q[i], p) * v[i] * v[i];
    return a;
  }
};

struct Body {
  double m = 0.0;      ///< kg
  double izz = 0.0;    ///< kg m^2 about the centre of mass
  int angle = 0;       ///< index of q that is this body's angle
  Point com;
};

struct Chain {
  Mechanism mech;
  std::vector<Body> bodies;
  std::array<MotorParams, 2> motors;

  /// M(q) and h(q, v) of the free chain (rotors on theta1, theta2).
  void terms(const V4& q, const V4& v, M4& M, V4& h) const {
    M.setZero();
    h.setZero();
    Eigen::Matrix<double, 2, 4> J;
    for (const Body& b : bodies) {
      b.com.jacobian(q, J);
      M += b.m * J.transpose() * J;
      M(b.angle, b.angle) += b.izz;
      h += b.m * J.transpose() * b.com.accel0(q, v);
    }
    for (int j = 0; j < 2; ++j) M(j, j) += motors[j].gear_ratio * motors[j].gear_ratio * motors[j].rotor_inertia();
  }
  /// Generalised forces: the joints' viscous and (smoothed) Coulomb friction, as the library's.
  V4 forces(const V4& v) const {
    V4 Q = V4::Zero();
    for (int j = 0; j < 2; ++j) {
      Q[j] = -(motors[j].viscous_friction() * v[j] + motors[j].coulomb_friction() * std::tanh(v[j] / kCoulombSmoothingSpeed));
    }
    return Q;
  }
  Eigen::Matrix<double, 2, 4> C(const V4& q) const {
    Eigen::Matrix<double, 2, 4> c;
    c.col(0) = mech.L[0] * 1e-3 * perp(e(q[0]));
    c.col(1) = -mech.L[1] * 1e-3 * perp(e(q[1]));
    c.col(2) = mech.L[2] * 1e-3 * perp(e(q[2]));
    c.col(3) = -mech.L[3] * 1e-3 * perp(e(q[3]));
    return c;
  }
  V2 Cdot_v(const V4& q, const V4& v) const {
    return 1e-3 * (-mech.L[0] * e(q[0]) * v[0] * v[0] + mech.L[1] * e(q[1]) * v[1] * v[1] -
                   mech.L[2] * e(q[2]) * v[2] * v[2] + mech.L[3] * e(q[3]) * v[3] * v[3]);
  }
  V2 constraint(const V4& q) const {
    const V2 O1(mech.O1.x(), mech.O1.y()), O2(mech.O2.x(), mech.O2.y());
    return 1e-3 * (O1 + mech.L[0] * e(q[0]) + mech.L[2] * e(q[2]) - O2 - mech.L[1] * e(q[1]) - mech.L[3] * e(q[3]));
  }
};

Chain make_chain(const MechanismModel& model) {
  Chain c;
  c.mech = model.mechanism;
  c.motors = model.motors;
  const MechanismInertia& in = model.inertia;
  const auto mm = [](const Vec2& p) { return V2(p.x() * 1e-3, p.y() * 1e-3); };
  const double L1 = model.mechanism.L[0] * 1e-3, L2 = model.mechanism.L[1] * 1e-3, L3 = model.mechanism.L[2] * 1e-3;
  // Link frames: x from the first joint towards the second (fivebar/dynamics.hpp LinkInertia).
  c.bodies.push_back({in.links[0].mass_kg, in.links[0].izz_kg_mm2 * 1e-6, 0, {{{0, mm(in.links[0].com_mm)}}}});
  c.bodies.push_back({in.links[1].mass_kg, in.links[1].izz_kg_mm2 * 1e-6, 1, {{{1, mm(in.links[1].com_mm)}}}});
  c.bodies.push_back({in.links[2].mass_kg, in.links[2].izz_kg_mm2 * 1e-6, 2, {{{0, V2(L1, 0)}, {2, mm(in.links[2].com_mm)}}}});
  c.bodies.push_back({in.links[3].mass_kg, in.links[3].izz_kg_mm2 * 1e-6, 3, {{{1, V2(L2, 0)}, {3, mm(in.links[3].com_mm)}}}});
  // The tip: a point mass at P (via link 3), its own inertia turning with the carrying link.
  c.bodies.push_back({in.tip_mass_kg, in.tip_izz_kg_mm2 * 1e-6, in.carrier, {{{0, V2(L1, 0)}, {2, V2(L3, 0)}}}});
  return c;
}

/// y = (q[4], v[4], lambda[2]).
int residual(realtype, N_Vector yy, N_Vector yp, N_Vector rr, void* data) {
  const Chain& c = *static_cast<const Chain*>(data);
  const double* y = N_VGetArrayPointer(yy);
  const double* d = N_VGetArrayPointer(yp);
  double* r = N_VGetArrayPointer(rr);
  const V4 q(y[0], y[1], y[2], y[3]), v(y[4], y[5], y[6], y[7]), vd(d[4], d[5], d[6], d[7]);
  const V2 lambda(y[8], y[9]);
  M4 M;
  V4 h;
  c.terms(q, v, M, h);
  const auto C = c.C(q);
  const V4 f = M * vd + h - c.forces(v) - C.transpose() * lambda;
  const V2 g = C * vd + c.Cdot_v(q, v);
  for (int i = 0; i < 4; ++i) {
    r[i] = d[i] - y[4 + i];
    r[4 + i] = f[i];
  }
  r[8] = g[0];
  r[9] = g[1];
  return 0;
}

struct Ida {
  SUNContext ctx = nullptr;
  N_Vector yy = nullptr, yp = nullptr, id = nullptr;
  SUNMatrix A = nullptr;
  SUNLinearSolver LS = nullptr;
  void* mem = nullptr;
  ~Ida() {
    if (mem) IDAFree(&mem);
    if (LS) SUNLinSolFree(LS);
    if (A) SUNMatDestroy(A);
    for (N_Vector* v : {&yy, &yp, &id})
      if (*v) N_VDestroy(*v);
    if (ctx) SUNContext_Free(&ctx);
  }
};

TEST(DynamicsDae, LagrangeMultiplierChainAgreesWithTheProjectionOnAnUnpoweredRelease) {
  const Design d = load_design(std::string(FIVEBAR_SOURCE_DIR) + "/designs/iros2022.yaml");
  const Station& s = d.require_station("index");
  const Mechanism& m = *s.lower;
  MechanismModel model;
  model.mechanism = m;
  model.inertia = closed_form_inertia(m, *d.get<Geometry>(), *d.get<PrintSettings>());
  for (int j = 0; j < 2; ++j) model.motors[static_cast<std::size_t>(j)] = d.get<MotorSettings>()->joint("index", "lower", j + 1);
  // Released off-centre with the joints moving (no gravity: the design gives no orientation),
  // windings open, no skin; the joints' friction stops it.
  const AnglesResult start = ik_angles(m, s.target.center + Vec2(2.0, -1.5));
  ASSERT_EQ(start.status, Status::ok);
  const V2 w0(0.4, -0.3);  // rad/s
  const double duration = 2.5, rtol = 1e-12;

  // The library: CVODE on the projection.
  SimulationInput in;
  in.station = "index";
  in.reference_name = "release";
  in.controller = *d.get<ControllerSettings>();
  SimulatedMechanism sm;
  sm.name = "lower";
  sm.model = model;
  sm.reference = {{start.theta1, start.theta2}};
  sm.reference_point_mm = {s.target.center};
  sm.theta0 = {start.theta1, start.theta2};
  sm.w0 = {w0[0], w0[1]};
  for (auto& c : sm.control) c = in.controller.joint("index", "lower", 1);
  in.mechanisms.push_back(sm);
  SimulationOptions o;
  o.drive = Drive::open_circuit;
  o.contact = false;
  o.duration_s = duration;
  o.rtol = rtol;
  o.rate_scale = 1e-2;
  const SimulationResult lib = simulate(in, o);
  ASSERT_TRUE(lib.ok()) << lib.reason;

  // IDA on the chain. Consistent initial values: phi from FK, their rates from C v = 0, the
  // accelerations and multipliers from [M -C^T; C 0] [v'; lambda] = [Q - h; -C' v].
  const Chain chain = make_chain(model);
  const Pose p0 = fk(m, start.theta1, start.theta2, m.assembly_mode);
  ASSERT_EQ(p0.status, Status::ok);
  const Vec2 A1 = m.O1 + m.L[0] * Vec2(std::cos(start.theta1), std::sin(start.theta1));
  const Vec2 A2 = m.O2 + m.L[1] * Vec2(std::cos(start.theta2), std::sin(start.theta2));
  V4 q(start.theta1, start.theta2, std::atan2(p0.P.y() - A1.y(), p0.P.x() - A1.x()),
       std::atan2(p0.P.y() - A2.y(), p0.P.x() - A2.x()));
  ASSERT_LT(chain.constraint(q).norm(), 1e-15);
  const auto C0 = chain.C(q);
  const V2 phi_dot = C0.rightCols<2>().fullPivLu().solve(-C0.leftCols<2>() * w0);
  const V4 v(w0[0], w0[1], phi_dot[0], phi_dot[1]);
  M4 M;
  V4 h;
  chain.terms(q, v, M, h);
  Eigen::Matrix<double, 6, 6> K = Eigen::Matrix<double, 6, 6>::Zero();
  K.topLeftCorner<4, 4>() = M;
  K.topRightCorner<4, 2>() = -C0.transpose();
  K.bottomLeftCorner<2, 4>() = C0;
  Eigen::Matrix<double, 6, 1> rhs;
  rhs << chain.forces(v) - h, -chain.Cdot_v(q, v);
  const Eigen::Matrix<double, 6, 1> sol = K.fullPivLu().solve(rhs);

  Ida ida;
  ASSERT_EQ(SUNContext_Create(nullptr, &ida.ctx), 0);
  ida.yy = N_VNew_Serial(10, ida.ctx);
  ida.yp = N_VNew_Serial(10, ida.ctx);
  ida.id = N_VNew_Serial(10, ida.ctx);
  double* y = N_VGetArrayPointer(ida.yy);
  double* yp = N_VGetArrayPointer(ida.yp);
  double* id = N_VGetArrayPointer(ida.id);
  for (int i = 0; i < 4; ++i) {
    y[i] = q[i];
    y[4 + i] = v[i];
    yp[i] = v[i];
    yp[4 + i] = sol[i];
    id[i] = id[4 + i] = 1.0;  // differential
  }
  y[8] = sol[4];
  y[9] = sol[5];
  yp[8] = yp[9] = 0.0;
  id[8] = id[9] = 0.0;  // algebraic: the multipliers
  ida.mem = IDACreate(ida.ctx);
  ASSERT_NE(ida.mem, nullptr);
  ASSERT_EQ(IDAInit(ida.mem, &residual, 0.0, ida.yy, ida.yp), IDA_SUCCESS);
  ASSERT_EQ(IDASStolerances(ida.mem, rtol, rtol * 1e-2), IDA_SUCCESS);
  IDASetUserData(ida.mem, const_cast<Chain*>(&chain));
  IDASetId(ida.mem, ida.id);
  IDASetSuppressAlg(ida.mem, SUNTRUE);  // the multipliers out of the error test (index 1 in them)
  IDASetMaxNumSteps(ida.mem, 100000);
  ida.A = SUNDenseMatrix(10, 10, ida.ctx);
  ida.LS = SUNLinSol_Dense(ida.yy, ida.A, ida.ctx);
  ASSERT_EQ(IDASetLinearSolver(ida.mem, ida.LS, ida.A), IDA_SUCCESS);

  double worst = 0.0, drift = 0.0, travel = 0.0;
  for (const TimeSample& t : lib.samples) {
    if (t.t > 0.0) {
      realtype reached = 0.0;
      ASSERT_GE(IDASolve(ida.mem, t.t, &reached, ida.yy, ida.yp, IDA_NORMAL), 0) << "t = " << t.t;
    }
    const V4 qt(y[0], y[1], y[2], y[3]);
    for (std::size_t j = 0; j < 2; ++j) {
      worst = std::max(worst, std::abs(y[j] - t.mechanisms[0].theta[j]));
      travel = std::max(travel, std::abs(y[j] - (j == 0 ? start.theta1 : start.theta2)));
    }
    drift = std::max(drift, chain.constraint(qt).norm());
  }
  std::ostringstream figures;
  figures << "max |theta_IDA - theta_CVODE| " << worst << " rad over " << lib.samples.size() << " samples, travel "
          << travel << " rad, loop drift " << drift << " m";
  RecordProperty("dae", figures.str());
  EXPECT_GT(travel, 0.05);            // it moved
  // The two formulations agree to the integrators' accuracy: 3.9e-10 rad at rtol 1e-12 each
  // (1.2e-7 rad at 1e-10: the difference falls with the tolerance, it is not a modelling one).
  EXPECT_LT(worst, 1e-8);
  EXPECT_LT(drift, 1e-9);             // the index-1 form keeps the loop closed to the tolerance
  // And both came to rest (friction): the last rates are small against the first.
  EXPECT_LT(std::abs(lib.samples.back().mechanisms[0].w[0]), 0.1 * std::abs(w0[0]));
}

}  // namespace
}  // namespace fivebar
