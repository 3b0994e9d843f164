// The calibration model and its closed-form Jacobian (fivebar/calibrate/model.hpp).
#include "fivebar/calibrate/model.hpp"

#include <cmath>

namespace fivebar::calibrate {

namespace {
double cross(const Vec2& a, const Vec2& b) { return a.x() * b.y() - a.y() * b.x(); }
}  // namespace

const std::array<std::string, kMechanismParameters>& mechanism_parameter_names() {
  static const std::array<std::string, kMechanismParameters> names{
      "L1",  "L2",  "L3",  "L4",  "O1x", "O1y", "O2x", "O2y", "theta1.volts_at_zero", "theta1.rad_per_volt",
      "theta2.volts_at_zero", "theta2.rad_per_volt"};
  return names;
}

const std::array<std::string, kFrameParameters>& frame_parameter_names() {
  static const std::array<std::string, kFrameParameters> names{"frame.rotation", "frame.x", "frame.y"};
  return names;
}

MechanismVector mechanism_vector(const Mechanism& m, double v01, double k1, double v02, double k2) {
  MechanismVector q;
  q << m.L[0], m.L[1], m.L[2], m.L[3], m.O1.x(), m.O1.y(), m.O2.x() - m.O1.x(), m.O2.y() - m.O1.y(), v01, k1, v02, k2;
  return q;
}

Mechanism with_geometry(const Mechanism& m, const MechanismVector& q) {
  Mechanism out = m;
  out.L = {q[0], q[1], q[2], q[3]};
  out.O1 = Vec2(q[4], q[5]);
  out.O2 = out.O1 + Vec2(q[6], q[7]);
  return out;
}

std::array<double, 2> joint_angles(const MechanismVector& q, double volts1, double volts2) {
  return {q[9] * (volts1 - q[8]), q[11] * (volts2 - q[10])};
}

Prediction predict(const Mechanism& m, const MechanismVector& q, const FrameVector& frame, double volts1, double volts2) {
  Prediction out;
  const Mechanism g = with_geometry(m, q);
  const auto theta = joint_angles(q, volts1, volts2);
  const Pose pose = fk(g, theta[0], theta[1]);
  if (pose.status == Status::unreachable) {
    out.status = Status::unreachable;
    return out;
  }
  const Vec2 u1 = (pose.P - pose.A1) / q[2];
  const Vec2 u2 = (pose.P - pose.A2) / q[3];
  const double det = cross(u1, u2);
  const Vec2 e1(std::cos(theta[0]), std::sin(theta[0]));
  const Vec2 e2(std::cos(theta[1]), std::sin(theta[1]));
  Eigen::Matrix2d Minv;
  Minv << u2.y(), -u1.y(), -u2.x(), u1.x();
  Minv /= det;
  // Rows: leg 1, leg 2 (M dP = R dq); O1 moves the whole mechanism (dP/dO1 = I).
  Eigen::Matrix<double, 2, kMechanismParameters> R = Eigen::Matrix<double, 2, kMechanismParameters>::Zero();
  R(0, 0) = u1.dot(e1);
  R(1, 1) = u2.dot(e2);
  R(0, 2) = 1.0;
  R(1, 3) = 1.0;
  R(1, 6) = u2.x();
  R(1, 7) = u2.y();
  const double dP_dtheta1 = q[0] * cross(e1, u1);
  const double dP_dtheta2 = q[1] * cross(e2, u2);
  R(0, 8) = dP_dtheta1 * -q[9];
  R(0, 9) = dP_dtheta1 * (volts1 - q[8]);
  R(1, 10) = dP_dtheta2 * -q[11];
  R(1, 11) = dP_dtheta2 * (volts2 - q[10]);
  Eigen::Matrix<double, 2, kMechanismParameters> dP = Minv * R;
  dP.col(4) = Vec2(1.0, 0.0);
  dP.col(5) = Vec2(0.0, 1.0);
  const double c = std::cos(frame[0]), s = std::sin(frame[0]);
  Eigen::Matrix2d Rot;
  Rot << c, -s, s, c;
  Eigen::Matrix2d dRot;
  dRot << -s, -c, c, -s;
  out.y = Rot * pose.P + frame.tail<2>();
  if (pose.status == Status::singular_type2 || !dP.allFinite()) {
    out.status = Status::singular_type2;
    return out;
  }
  out.status = Status::ok;  // a type I pose is still a pose: its Jacobian is finite
  out.dq = Rot * dP;
  out.dframe.col(0) = dRot * pose.P;
  out.dframe.col(1) = Vec2(1.0, 0.0);
  out.dframe.col(2) = Vec2(0.0, 1.0);
  return out;
}

}  // namespace fivebar::calibrate
