#include "fivebar/format.hpp"
#include "fivebar/json.hpp"

#include <cmath>
#include <numbers>

namespace fivebar {
using json = Json;

namespace {

json xy(const Vec2& v) { return json::array({v.x(), v.y()}); }

double rad_to_deg(double rad) { return rad * format::kDegPerRad; }

}  // namespace

double angle_deg(double angle_rad) {
  double deg = std::remainder(rad_to_deg(angle_rad), 360.0);  // [-180, 180]
  if (deg <= -180.0) deg += 360.0;
  return deg == 0.0 ? 0.0 : deg;  // no "-0"
}

char sign_char(int sign) { return sign > 0 ? '+' : (sign < 0 ? '-' : '0'); }

std::string mode_string(const WorkingMode& mode) {
  return {sign_char(mode.sign1), sign_char(mode.sign2)};
}

json to_json(const Pose& pose) {
  json j;
  j["status"] = std::string(to_string(pose.status));
  const bool exists = pose.status != Status::unreachable;
  if (!exists) {
    for (const char* key : {"point_mm", "theta_deg", "elbows_mm", "mode", "assembly", "jacobian"}) {
      j[key] = nullptr;
    }
  } else {
    j["point_mm"] = xy(pose.P);
    j["theta_deg"] = json::array({angle_deg(pose.theta1), angle_deg(pose.theta2)});
    j["elbows_mm"] = json::array({xy(pose.A1), xy(pose.A2)});
    j["mode"] = mode_string(pose.mode);
    j["assembly"] = std::string(1, sign_char(pose.assembly));
    if (pose.jacobian_valid) {
      j["jacobian"] = json::array({json::array({pose.J(0, 0), pose.J(0, 1)}),
                                   json::array({pose.J(1, 0), pose.J(1, 1)})});
    } else {
      j["jacobian"] = nullptr;
    }
  }
  j["lci"] = pose.lci;
  j["force_capability"] = pose.force_capability;
  if (!exists) {
    for (const char* key : {"transmission_deg", "singularity", "closure_error_mm", "within_joint_limits"}) {
      j[key] = nullptr;
    }
    return j;
  }
  // Transmission angles live in [0, pi]: plain conversion, no wrapping.
  j["transmission_deg"] = json::array({rad_to_deg(pose.transmission[0]), rad_to_deg(pose.transmission[1]),
                                       rad_to_deg(pose.transmission[2])});
  j["singularity"] = {{"type1_sin", json::array({pose.type1_sin[0], pose.type1_sin[1]})},
                      {"type2_sin", pose.type2_sin},
                      {"type1_distance_mm", pose.type1_distance_mm}};
  j["closure_error_mm"] = pose.closure_error_mm;
  j["within_joint_limits"] = pose.within_joint_limits;
  return j;
}

json to_json(const Mechanism& m) {
  json j;
  j["name"] = m.name;
  j["bases_mm"] = json::array({xy(m.O1), xy(m.O2)});
  j["links_mm"] = json::array({m.L[0], m.L[1], m.L[2], m.L[3]});
  j["working_mode"] = to_string(m.working_mode);
  j["assembly_mode"] = to_string(m.assembly_mode);
  if (m.joint_limits) {
    json limits = json::array();
    for (const JointRange& r : *m.joint_limits) {
      const double lo = angle_deg(r.lo);
      limits.push_back(json::array({lo, lo + rad_to_deg(r.span())}));
    }
    j["joint_limits_deg"] = limits;
  } else {
    j["joint_limits_deg"] = nullptr;
  }
  j["min_lci"] = m.min_lci;
  j["length_scale_mm"] = m.length_scale();
  return j;
}

json to_json(const Ellipse& e) {
  return {{"center_mm", xy(e.center)}, {"axes_mm", xy(e.axes)}, {"angle_deg", angle_deg(e.angle)}};
}

void to_json(json& j, const Pose& pose) { j = to_json(pose); }
void to_json(json& j, const Mechanism& mechanism) { j = to_json(mechanism); }
void to_json(json& j, const Ellipse& ellipse) { j = to_json(ellipse); }

}  // namespace fivebar
