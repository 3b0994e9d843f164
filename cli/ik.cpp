// fivebar ik: tactor point (mm) -> motor angles (deg) in the design's working mode, or all four.

#include <iostream>
#include <memory>

#include "batch.hpp"
#include "common.hpp"
#include "fivebar/error.hpp"
#include "fivebar/json.hpp"

namespace fivebar::cli {

namespace {

struct IkOptions {
  Target target;
  std::string point;       ///< "X,Y" in mm
  std::string point_file;  ///< batch CSV, '-' = stdin
  std::string output;      ///< batch output file; empty = stdout
  std::string mode;        ///< "+-" etc.; empty = the design's working mode
  bool all = false;
  bool json = false;
};

/// A configuration the device can take: it exists and respects the joint limits.
bool usable(const Pose& pose) { return pose.status != Status::unreachable && pose.within_joint_limits; }

WorkingMode mode_of(const IkOptions& opt, const Mechanism& m) {
  if (opt.mode.empty()) return m.working_mode;
  const auto mode = parse_working_mode(opt.mode);
  if (!mode) throw InputError("--mode '" + opt.mode + "': expected two signs such as -+ (leg 1, leg 2)");
  return *mode;
}

Json context_json(const Design& design, const Selection& sel, const Vec2& p) {
  return {{"command", "ik"},
          {"design", design.name},
          {"station", sel.station->name},
          {"mechanism", sel.mechanism->name},
          {"target_mm", {p.x(), p.y()}}};
}

int run_batch(const IkOptions& opt, const Mechanism& m, WorkingMode mode) {
  const BatchTally tally = stream_batch(opt.point_file, {"x_mm", "y_mm"}, opt.output,
                                        [&](const std::vector<double>& row, std::ostream& out) {
                                          const Vec2 p(row[0], row[1]);
                                          const Pose pose = ik(m, p, mode);
                                          write_batch_row(out, pose, p, std::nullopt);
                                          return usable(pose);
                                        });
  if (tally.unsolved > 0) {
    std::cerr << "fivebar ik: " << tally.unsolved << " of " << tally.rows
              << " rows have no usable solution (unreachable or outside the joint limits)\n";
    return kCheckFailed;
  }
  return kOk;
}

void print_all(const Selection& sel, const Vec2& p, const std::array<Pose, 4>& poses) {
  const Mechanism& m = *sel.mechanism;
  std::cout << sel.label() << "  ik at P = (" << fixed(p.x()) << ", " << fixed(p.y())
            << ") mm, all four working modes (* = the design's)\n\n";
  std::printf("  %-6s %-15s %12s %12s %8s %10s %9s %8s\n", "mode", "status", "theta1(deg)", "theta2(deg)", "LCI",
              "typeI(mm)", "typeIIsin", "limits");
  std::cout << std::flush;
  const auto modes = all_working_modes();
  for (std::size_t k = 0; k < 4; ++k) {
    const Pose& pose = poses[k];
    const std::string name = to_string(modes[k]) + (modes[k] == m.working_mode ? " *" : "");
    if (pose.status == Status::unreachable) {
      std::printf("  %-6s %-15s %12s %12s %8s %10s %9s %8s\n", name.c_str(), "unreachable", "-", "-", "-", "-", "-",
                  "-");
    } else {
      std::printf("  %-6s %-15s %12s %12s %8s %10s %9s %8s\n", name.c_str(),
                  std::string(to_string(pose.status)).c_str(), fixed(angle_deg(pose.theta1)).c_str(),
                  fixed(angle_deg(pose.theta2)).c_str(), fixed(pose.lci).c_str(),
                  fixed(pose.type1_distance_mm).c_str(), fixed(pose.type2_sin).c_str(),
                  limits_text(m, pose).c_str());
    }
  }
  std::fflush(stdout);
}

int run_ik(const IkOptions& opt) {
  require_single_or_batch("ik", opt.point, "--point X,Y", opt.point_file, "--point-file", opt.output);
  const Design design = load(opt.target.design);
  const Selection sel = select(design, opt.target);
  const Mechanism& m = *sel.mechanism;
  const WorkingMode mode = mode_of(opt, m);
  if (!opt.point_file.empty()) return run_batch(opt, m, mode);

  const auto xy = parse_point_mm(opt.point, "--point");
  const Vec2 p(xy[0], xy[1]);

  if (opt.all) {
    const auto poses = ik_all(m, p);
    bool any = false;
    for (const Pose& pose : poses) any = any || usable(pose);
    if (opt.json) {
      Json doc = context_json(design, sel, p);
      doc["design_working_mode"] = to_string(m.working_mode);
      doc["branches"] = Json::array();
      const auto modes = all_working_modes();
      for (std::size_t k = 0; k < 4; ++k) {
        Json b = to_json(poses[k]);
        b["working_mode"] = to_string(modes[k]);
        doc["branches"].push_back(b);
      }
      print_json(doc);
    } else {
      print_all(sel, p, poses);
    }
    if (!any) std::cerr << "fivebar ik: no working mode reaches this point within the joint limits\n";
    return any ? kOk : kCheckFailed;
  }

  const Pose pose = ik(m, p, mode);
  if (opt.json) {
    Json doc = context_json(design, sel, p);
    doc["working_mode"] = to_string(mode);
    doc.update(to_json(pose));
    print_json(doc);
  } else {
    std::cout << sel.label() << "  ik at P = (" << fixed(p.x()) << ", " << fixed(p.y()) << ") mm, working mode "
              << to_string(mode) << "\n";
    print_pose(std::cout, m, pose);
  }
  if (pose.status == Status::unreachable) {
    std::cerr << "fivebar ik: point unreachable: it lies outside the annulus of at least one leg\n";
    return kCheckFailed;
  }
  if (!pose.within_joint_limits) {
    std::cerr << "fivebar ik: the solution lies outside the joint limits\n";
    return kCheckFailed;
  }
  return kOk;
}

}  // namespace

void setup_ik(CLI::App& app) {
  auto [sub, opt] = add_command<IkOptions>(
      app, "ik", "Inverse kinematics: tactor point X,Y (mm) -> motor angles (deg) in the design's working mode", run_ik);
  add_target_options(*sub, opt->target);
  auto* point = sub->add_option("-p,--point", opt->point, "Tactor point X,Y in mm, station frame (e.g. --point 6.25,15.5)")
                    ->type_name("X,Y");
  auto* file = add_batch_options(*sub, "point", "x_mm,y_mm", point, opt->point_file, opt->output);
  auto* mode = sub->add_option("--mode", opt->mode,
                               "Working mode: signs of cross(A_i-O_i, P-A_i) for legs 1 and 2, e.g. -+ "
                               "(elbows out, lower) or +- (upper); default: the design's")
                   ->type_name("SIGNS");
  auto* all = sub->add_flag("-a,--all", opt->all, "All four working modes ++, +-, -+, --");
  auto* json = add_json_flag(*sub, opt->json, "one JSON document (mm, deg)");
  all->excludes(mode);
  file->excludes(all)->excludes(json);
  sub->footer(exit_status({.ok = "a solution within the joint limits",
                           .failed = "none (unreachable or outside the limits)"}));
}

}  // namespace fivebar::cli
