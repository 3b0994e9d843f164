// The `kinematics` product: for every station and mechanism, the link data and modes, the pose at
// the centre of the target ellipse (IK in the working mode, verified by FK of its angles) and
// the status and LCI at the four ends of the ellipse's axes.

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "fivebar/format.hpp"
#include "fivebar/json.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/numerics.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {
using json = Json;

namespace {

constexpr double kRadToDeg = format::kDegPerRad;

struct AxisEnd {
  const char* label;
  double t;  ///< ellipse parameter, radians
};
constexpr std::array<AxisEnd, 4> kAxisEnds{{{"+a", 0.0},
                                            {"+b", std::numbers::pi / 2},
                                            {"-a", std::numbers::pi},
                                            {"-b", 3 * std::numbers::pi / 2}}};

std::string joint_limits_text(const Mechanism& m) {
  if (!m.joint_limits) return "none";
  std::string out;
  for (const JointRange& r : *m.joint_limits) {
    const double lo = angle_deg(r.lo);
    if (!out.empty()) out += ", ";
    out += "[" + md::fixed(lo, 1) + ", " + md::fixed(lo + r.span() * kRadToDeg, 1) + "]";
  }
  return out;
}

/// Results for one mechanism; `problems` collects what fails the product's check.
struct MechanismReport {
  const Mechanism* m;
  Pose centre;
  Pose back;  ///< FK of centre's angles in the design's assembly mode
  double closure_mm = 0.0;
  double closure_bound_mm = 0.0;
  std::array<Pose, 4> ends;
  std::vector<std::string> problems;
  std::vector<std::string> notes;
};

MechanismReport analyse(const Station& s, const Mechanism& m) {
  MechanismReport r{&m, {}, {}, 0.0, 0.0, {}, {}, {}};
  const Vec2 c = s.target.center;
  r.centre = ik(m, c);
  const std::string where = s.name + "/" + m.name;
  if (r.centre.status == Status::unreachable) {
    r.problems.push_back(where + ": target centre unreachable in working mode " + to_string(m.working_mode));
  } else {
    r.back = fk(m, r.centre.theta1, r.centre.theta2);
    r.closure_mm = (r.back.P - c).norm();
    // FK(IK(c)) returns to c up to rounding amplified by the conditioning of the pose.
    r.closure_bound_mm = tol::kClosureRel * m.length_scale() / std::max(r.centre.lci, tol::kSingularSin);
    if (r.centre.status != Status::ok) {
      r.problems.push_back(where + ": target centre is " + std::string(to_string(r.centre.status)));
    }
    if (r.back.status == Status::unreachable || !(r.closure_mm <= r.closure_bound_mm)) {
      r.problems.push_back(where + ": FK of the centre's angles does not return to the centre (assembly mode " +
                           to_string(m.assembly_mode) + ", error " + md::sci(r.closure_mm) + " mm)");
    }
    if (!r.centre.within_joint_limits) r.problems.push_back(where + ": centre angles outside the joint limits");
    if (r.centre.lci < m.min_lci) {
      r.problems.push_back(where + ": LCI " + md::fixed(r.centre.lci) + " at the centre is below min_lci " +
                           md::fixed(m.min_lci));
    }
  }
  for (std::size_t k = 0; k < kAxisEnds.size(); ++k) {
    r.ends[k] = ik(m, s.target.boundary_point(kAxisEnds[k].t));
    const Pose& p = r.ends[k];
    const std::string at = where + " at axis end " + kAxisEnds[k].label;
    if (p.status != Status::ok) {
      r.notes.push_back(at + " is " + std::string(to_string(p.status)));
    } else if (!p.within_joint_limits) {
      r.notes.push_back(at + " is outside the joint limits");
    } else if (p.lci < m.min_lci) {
      r.notes.push_back(at + ": LCI " + md::fixed(p.lci) + " < min_lci " + md::fixed(m.min_lci));
    }
  }
  return r;
}

json mechanism_json(const Station& s, const MechanismReport& r) {
  json j;
  j["mechanism"] = r.m->name;
  j["parameters"] = to_json(*r.m);
  json centre;
  centre["target_mm"] = json::array({s.target.center.x(), s.target.center.y()});
  centre["ik"] = to_json(r.centre);
  if (r.centre.status != Status::unreachable) {
    centre["fk_back"] = {{"status", std::string(to_string(r.back.status))},
                         {"point_mm", json::array({r.back.P.x(), r.back.P.y()})},
                         {"error_mm", r.closure_mm},
                         {"bound_mm", r.closure_bound_mm}};
  } else {
    centre["fk_back"] = nullptr;
  }
  j["centre"] = centre;
  json ends = json::array();
  for (std::size_t k = 0; k < kAxisEnds.size(); ++k) {
    const Vec2 p = s.target.boundary_point(kAxisEnds[k].t);
    const Pose& pose = r.ends[k];
    ends.push_back({{"label", kAxisEnds[k].label},
                    {"point_mm", json::array({p.x(), p.y()})},
                    {"status", std::string(to_string(pose.status))},
                    {"lci", pose.lci},
                    {"within_joint_limits", pose.status == Status::unreachable ? json(nullptr)
                                                                               : json(pose.within_joint_limits)}});
  }
  j["axis_ends"] = ends;
  j["passed"] = r.problems.empty();
  j["problems"] = r.problems;
  j["notes"] = r.notes;
  return j;
}

std::string station_markdown(const Station& s, const std::vector<MechanismReport>& reports) {
  std::string out;
  const Ellipse& e = s.target;
  out += "### Station " + md::code(s.name) + "\n\n";
  out += "Target ellipse: centre " + md::pair(e.center.x(), e.center.y(), 2) + " mm, full axes " +
         md::fixed(e.axes.x(), 2) + " × " + md::fixed(e.axes.y(), 2) + " mm, rotated " +
         md::fixed(angle_deg(e.angle), 1) + "°.\n\n";

  md::Table links({"mechanism", "O1 (mm)", "O2 (mm)", "L1 (mm)", "L2 (mm)", "L3 (mm)", "L4 (mm)", "working mode",
                   "assembly mode", "joint limits (deg)", "min LCI"},
                  "lllrrrrccll");
  for (const auto& r : reports) {
    const Mechanism& m = *r.m;
    links.row({m.name, md::pair(m.O1.x(), m.O1.y(), 2), md::pair(m.O2.x(), m.O2.y(), 2), md::fixed(m.L[0], 2),
               md::fixed(m.L[1], 2), md::fixed(m.L[2], 2), md::fixed(m.L[3], 2), md::code(to_string(m.working_mode)),
               md::code(to_string(m.assembly_mode)), joint_limits_text(m), md::fixed(m.min_lci, 2)});
  }
  out += "**Linkages**\n\n" + links.str() + "\n";

  md::Table centre({"mechanism", "status", "θ1 (deg)", "θ2 (deg)", "realised mode", "LCI", "force cap. (N/N·mm)",
                    "transmission elbow 1 / 2 / tactor (deg)", "type I distance (mm)", "type II sin", "FK closure (mm)",
                    "within limits"},
                   "llrrcrrcrrrc");
  md::Table jac({"mechanism", "∂x/∂θ1 (mm/rad)", "∂x/∂θ2 (mm/rad)", "∂y/∂θ1 (mm/rad)", "∂y/∂θ2 (mm/rad)"}, "lrrrr");
  for (const auto& r : reports) {
    const Pose& p = r.centre;
    if (p.status == Status::unreachable) {
      centre.row({r.m->name, "unreachable", "—", "—", "—", "0", "0", "—", "—", "—", "—", "—"});
      continue;
    }
    centre.row({r.m->name, std::string(to_string(p.status)), md::fixed(angle_deg(p.theta1), 3),
                md::fixed(angle_deg(p.theta2), 3), md::code(mode_string(p.mode)), md::fixed(p.lci, 4),
                md::fixed(p.force_capability, 4),
                md::fixed(p.transmission[0] * kRadToDeg, 1) + " / " + md::fixed(p.transmission[1] * kRadToDeg, 1) +
                    " / " + md::fixed(p.transmission[2] * kRadToDeg, 1),
                md::fixed(p.type1_distance_mm, 3), md::fixed(p.type2_sin, 4), md::sci(r.closure_mm),
                p.within_joint_limits ? "yes" : "**no**"});
    if (p.jacobian_valid) {
      jac.row({r.m->name, md::fixed(p.J(0, 0), 3), md::fixed(p.J(0, 1), 3), md::fixed(p.J(1, 0), 3),
               md::fixed(p.J(1, 1), 3)});
    } else {
      jac.row({r.m->name, "—", "—", "—", "—"});
    }
  }
  out += "**Pose at the target centre** (IK in the working mode, then FK of those angles back)\n\n" + centre.str() +
         "\n";
  out += "**Jacobian dP/dθ at the centre**\n\n" + jac.str() + "\n";

  std::vector<std::string> header{"axis end", "x (mm)", "y (mm)"};
  std::string align = "lrr";
  for (const auto& r : reports) {
    header.push_back(r.m->name + " status");
    header.push_back(r.m->name + " LCI");
    align += "lr";
  }
  md::Table ends(header, align);
  for (std::size_t k = 0; k < kAxisEnds.size(); ++k) {
    const Vec2 p = e.boundary_point(kAxisEnds[k].t);
    std::vector<std::string> row{kAxisEnds[k].label, md::fixed(p.x(), 3), md::fixed(p.y(), 3)};
    for (const auto& r : reports) {
      const Pose& pose = r.ends[k];
      std::string status(to_string(pose.status));
      if (pose.status != Status::unreachable && !pose.within_joint_limits) status += " (outside limits)";
      row.push_back(status);
      row.push_back(md::fixed(pose.lci, 4));
    }
    ends.row(std::move(row));
  }
  out += "**Ends of the ellipse axes** (`+a`/`-a` along the first axis, `+b`/`-b` along the second)\n\n" +
         ends.str() + "\n";

  std::vector<std::string> remarks;
  for (const auto& r : reports) {
    for (const auto& p : r.problems) remarks.push_back("✗ " + p);
    for (const auto& n : r.notes) remarks.push_back("⚠ " + n);
  }
  for (const auto& line : remarks) out += "- " + line + "\n";
  if (!remarks.empty()) out += "\n";
  return out;
}

constexpr const char* kPreamble =
    "For every station and mechanism: the link data, then the configuration that puts the tactor at "
    "the centre of the target ellipse. *LCI* is 1/cond(J) of the Jacobian J = dP/dθ (1 isotropic, 0 "
    "singular); *force cap.* is 1/σmax(J), the smallest tactor force per unit motor torque; transmission "
    "angles are best near 90° and singular at 0° or 180°; *type I distance* is how far the tactor is from "
    "a stretched or folded leg; *type II sin* is |sin| of the angle between the distal links (0 = parallel "
    "singularity). *FK closure* is the distance between the centre and FK of the IK angles in the "
    "design's assembly mode. The *realised mode* gives the signs of cross(A_i − O_i, P − A_i) for legs 1 "
    "and 2.\n\n"
    "The check passes when every mechanism reaches the centre in its working mode, non-singular, within "
    "its joint limits, with LCI ≥ min_lci and a closing FK. The axis ends are informative only; whether the "
    "whole ellipse is covered is the `coverage` product's question.\n\n";

}  // namespace

/// The usable range of every joint from the hardware (fivebar/device/joint_limits.hpp), when any joint
/// of the station has one.
std::string usable_ranges_markdown(const Design& d, const Station& s) {
  md::Table table({"joint", "usable range", "angle at the target centre (deg)"}, "llr");
  bool any = false;
  for (const Mechanism* m : s.mechanisms()) {
    for (const UsableRange& r : usable_ranges(d, s, *m)) {
      any = any || r.limited || !r.usable;
      table.row({md::code(r.joint), describe(r), r.usable ? md::fixed(angle_deg(r.reference), 2) : "-"});
    }
  }
  if (!any) return "";
  return "**Usable joint ranges** (the potentiometers' travel, the links' hard stops and the declared limits; "
         "docs/urdf.md)\n\n" + table.str() + "\n";
}

Product kinematics_product() {
  Product p;
  p.name = "kinematics";
  p.title = "Kinematics at the target";
  p.unavailable = without_mechanisms;
  p.build = [](Context& ctx) {
    Built b;
    json stations = json::array();
    std::string markdown = kPreamble;
    std::size_t failed = 0, total = 0;
    for (const Station& s : ctx.design.stations) {
      const auto mechanisms = s.mechanisms();
      if (mechanisms.empty()) continue;
      ctx.say("kinematics: station " + s.name);
      std::vector<MechanismReport> reports;
      json js;
      js["station"] = s.name;
      js["target"] = to_json(s.target);
      js["mechanisms"] = json::array();
      for (const Mechanism* m : mechanisms) {
        reports.push_back(analyse(s, *m));
        js["mechanisms"].push_back(mechanism_json(s, reports.back()));
        ++total;
        if (!reports.back().problems.empty()) ++failed;
      }
      stations.push_back(js);
      markdown += station_markdown(s, reports);
      markdown += usable_ranges_markdown(ctx.design, s);
    }
    b.result = {{"stations", stations}};
    b.markdown = markdown;
    b.passed = failed == 0;
    b.check = b.passed ? "all " + std::to_string(total) + " mechanisms reach their target centre cleanly"
                       : std::to_string(failed) + " of " + std::to_string(total) +
                             " mechanisms fail at their target centre (see the list in the section)";
    return b;
  };
  return p;
}

}  // namespace fivebar::products
