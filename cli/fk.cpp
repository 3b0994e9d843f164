// fivebar fk: motor angles (deg) -> tactor point, status, Jacobian, LCI.

#include <iostream>
#include <memory>
#include <numbers>

#include "fivebar/format.hpp"
#include "batch.hpp"
#include "common.hpp"
#include "fivebar/error.hpp"
#include "fivebar/json.hpp"

namespace fivebar::cli {

namespace {

struct FkOptions {
  Target target;
  std::string theta;       ///< "T1,T2" in degrees
  std::string theta_file;  ///< batch CSV, '-' = stdin
  std::string output;      ///< batch output file; empty = stdout
  std::string branch;      ///< "+", "-", "any"; empty = the design's assembly mode
  bool all = false;
  bool json = false;
};

AssemblyMode branch_of(const FkOptions& opt, const Mechanism& m) {
  if (opt.branch.empty()) return m.assembly_mode;
  const auto mode = parse_assembly_mode(opt.branch);
  if (!mode) throw InputError("--branch '" + opt.branch + "': expected +, - or any");
  return *mode;
}

Json context_json(const Design& design, const Selection& sel, const std::array<double, 2>& theta_deg) {
  return {{"command", "fk"},
          {"design", design.name},
          {"station", sel.station->name},
          {"mechanism", sel.mechanism->name},
          {"input_theta_deg", {theta_deg[0], theta_deg[1]}}};
}

int run_batch(const FkOptions& opt, const Mechanism& m, AssemblyMode branch) {
  const BatchTally tally = stream_batch(opt.theta_file, {"theta1_deg", "theta2_deg"}, opt.output,
                                        [&](const std::vector<double>& row, std::ostream& out) {
                                          const Pose pose =
                                              fk(m, format::rad_from_deg(row[0]), format::rad_from_deg(row[1]), branch);
                                          write_batch_row(out, pose, std::nullopt, std::array<double, 2>{row[0], row[1]});
                                          return pose.status != Status::unreachable;
                                        });
  if (tally.unsolved > 0) {
    std::cerr << "fivebar fk: " << tally.unsolved << " of " << tally.rows
              << " rows have no configuration (status unreachable)\n";
    return kCheckFailed;
  }
  return kOk;
}

int run_fk(const FkOptions& opt) {
  require_single_or_batch("fk", opt.theta, "--theta T1,T2", opt.theta_file, "--theta-file", opt.output);
  const Design design = load(opt.target.design);
  const Selection sel = select(design, opt.target);
  const Mechanism& m = *sel.mechanism;
  const AssemblyMode branch = branch_of(opt, m);
  if (!opt.theta_file.empty()) return run_batch(opt, m, branch);

  const auto theta_deg = parse_pair(opt.theta, "--theta", "T1,T2 in degrees");
  const double t1 = format::rad_from_deg(theta_deg[0]);
  const double t2 = format::rad_from_deg(theta_deg[1]);

  if (opt.all) {
    const auto poses = fk_all(m, t1, t2);
    const bool any = poses[0].status != Status::unreachable || poses[1].status != Status::unreachable;
    if (opt.json) {
      Json doc = context_json(design, sel, theta_deg);
      doc["branches"] = Json::array();
      const char* names[2] = {"+", "-"};
      for (int k = 0; k < 2; ++k) {
        Json p = to_json(poses[static_cast<std::size_t>(k)]);
        p["branch"] = names[k];
        doc["branches"].push_back(p);
      }
      print_json(doc);
    } else {
      std::cout << sel.label() << "  fk at theta = (" << fixed(theta_deg[0], 3) << ", " << fixed(theta_deg[1], 3)
                << ") deg, both assembly branches\n";
      for (int k = 0; k < 2; ++k) {
        std::cout << "\nbranch " << (k == 0 ? "+" : "-") << "\n";
        print_pose(std::cout, m, poses[static_cast<std::size_t>(k)]);
      }
    }
    return any ? kOk : kCheckFailed;
  }

  const Pose pose = fk(m, t1, t2, branch);
  if (opt.json) {
    Json doc = context_json(design, sel, theta_deg);
    doc["branch"] = to_string(branch);
    doc.update(to_json(pose));
    print_json(doc);
  } else {
    std::cout << sel.label() << "  fk at theta = (" << fixed(theta_deg[0], 3) << ", " << fixed(theta_deg[1], 3)
              << ") deg, assembly branch " << to_string(branch) << "\n";
    print_pose(std::cout, m, pose);
  }
  if (pose.status == Status::unreachable) {
    std::cerr << "fivebar fk: no configuration: the distal links cannot meet at these angles\n";
    return kCheckFailed;
  }
  return kOk;
}

}  // namespace

void setup_fk(CLI::App& app) {
  auto [sub, opt] = add_command<FkOptions>(
      app, "fk", "Forward kinematics: motor angles theta1,theta2 (deg) -> tactor point P (mm), status, Jacobian, LCI",
      run_fk);
  add_target_options(*sub, opt->target);
  auto* theta = sub->add_option("-t,--theta", opt->theta,
                                "Motor angles T1,T2 in degrees, counter-clockwise from +x (e.g. --theta 100,80)")
                    ->type_name("T1,T2");
  auto* file = add_batch_options(*sub, "theta", "theta1_deg,theta2_deg", theta, opt->theta_file, opt->output);
  auto* branch = sub->add_option("-b,--branch", opt->branch,
                                 "Assembly branch: + (tactor above the line A1A2), - (below) or any; default: the design's")
                     ->check(CLI::IsMember({"+", "-", "any"}))
                     ->type_name("SIGN");
  auto* all = sub->add_flag("-a,--all", opt->all, "Both assembly branches");
  auto* json = add_json_flag(*sub, opt->json, "one JSON document (mm, deg)");
  all->excludes(branch);
  file->excludes(all)->excludes(json);
  sub->footer(exit_status({.ok = "a configuration exists", .failed = "none (status says why)"}));
}

}  // namespace fivebar::cli
