// fivebar collision: interference of a station's upper and lower mechanisms for a pair of tactor
// points, with the paper's priority rule; without points, the collision map over the target ellipse.

#include <unistd.h>

#include <cstdio>
#include <iostream>
#include <memory>

#include "common.hpp"
#include "fivebar/collision.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "tactors.hpp"

namespace fivebar::cli {

namespace {

struct CollisionOptions {
  std::string design;
  std::string station;
  std::string upper;  ///< "X,Y" mm
  std::string lower;
  double spacing_mm = 0.75;
  std::string out;
  bool json = false;
};

std::string xy_text(const Vec2& p) { return "(" + fixed(p.x()) + ", " + fixed(p.y()) + ")"; }

std::string pose_line(const Mechanism& m, const Pose& pose) {
  if (pose.status == Status::unreachable) return "unreachable in working mode " + to_string(m.working_mode);
  std::string s = std::string(to_string(pose.status)) + ", theta (" + fixed(angle_deg(pose.theta1), 3) + ", " +
                  fixed(angle_deg(pose.theta2), 3) + ") deg, LCI " + fixed(pose.lci);
  if (!pose.within_joint_limits) s += ", OUTSIDE the joint limits";
  if (!usable(m, pose)) s += "  (cannot be held)";
  return s;
}

void row(const std::string& key, const std::string& value) {
  std::string k = key;
  k.resize(std::max<std::size_t>(k.size() + 2, 28), ' ');
  std::cout << "  " << k << value << "\n";
}

std::string plane_name(const Geometry& g, int plane) {
  return plane == tactor_plane(g) ? "tactor (" + std::to_string(plane) + ")" : "plane " + std::to_string(plane);
}

void print_interference(const Geometry& g, const Interference& in) {
  row("min clearance", fixed(in.min_clearance_mm) + " mm (" + in.closest.name() + ", " +
                           plane_name(g, in.closest.plane) + "); required " + fixed(g.min_clearance, 3) + " mm");
  std::cout << "  per plane:\n";
  for (const PlaneClearance& p : in.planes) {
    std::printf("    %-12s %10s mm  %s\n", plane_name(g, p.plane).c_str(), fixed(p.closest.clearance_mm).c_str(),
                p.closest.name().c_str());
  }
  std::fflush(stdout);
  if (in.collides) {
    std::cout << "  colliding pairs (clearance below " << fixed(g.min_clearance, 3) << " mm):\n";
    for (const PairClearance& p : in.colliding) {
      std::printf("    %-28s %-12s %10s mm\n", p.name().c_str(), plane_name(g, p.plane).c_str(),
                  fixed(p.clearance_mm).c_str());
    }
    std::fflush(stdout);
  }
}

int run_pair(const CollisionOptions& opt, const Design& design, const Station& s, const Geometry& g) {
  const auto u = parse_point_mm(opt.upper, "--upper");
  const auto l = parse_point_mm(opt.lower, "--lower");
  const PriorityResult r = apply_priority(*s.upper, *s.lower, g, Vec2(u[0], u[1]), Vec2(l[0], l[1]));
  const bool collides = r.before && r.before->collides;
  const bool unusable = r.status == PriorityStatus::upper_unusable || r.status == PriorityStatus::lower_unusable;
  if (opt.json) {
    Json doc = {{"command", "collision"}, {"design", design.name}, {"station", s.name}};
    doc["collides"] = collides;
    doc.update(to_json(r));
    print_json(doc);
  } else {
    std::cout << s.name << "  collision check: upper tactor at " << xy_text(r.upper_target) << " mm, lower at "
              << xy_text(r.lower_target) << " mm\n";
    row("upper pose", pose_line(*s.upper, r.upper));
    row("lower pose", pose_line(*s.lower, ik(*s.lower, r.lower_target)));
    if (r.before) {
      print_interference(g, *r.before);
      row("verdict", r.before->collides ? "COLLISION (" + std::to_string(r.before->colliding.size()) + " pairs)"
                                        : "no collision");
    } else {
      row("verdict", "not checked: a target is unreachable");
    }
    row("priority rule", std::string(to_string(r.status)) + ": " + r.reason);
    if (r.status == PriorityStatus::moved) {
      row("lower target moved to", xy_text(r.lower_point) + " mm, " + fixed(r.moved_mm) + " mm away");
      row("lower pose (moved)", pose_line(*s.lower, r.lower));
      row("clearance after", fixed(r.after->min_clearance_mm) + " mm (" + r.after->closest.name() + ")");
    }
  }
  if (unusable) std::cerr << "fivebar collision: " << r.reason << "\n";
  if (collides) std::cerr << "fivebar collision: the targets collide (" << r.before->closest.name() << ")\n";
  return collides || unusable ? kCheckFailed : kOk;
}

int run_map(const CollisionOptions& opt, const Design& design, const Station& s, const Geometry& g) {
  CollisionMapOptions options;
  options.spacing_mm = opt.spacing_mm;
  if (::isatty(STDERR_FILENO) != 0) {  // progress only for a person watching
    options.progress = [](std::size_t done, std::size_t total) {
      std::fprintf(stderr, "\rfivebar collision: map %3zu %%", total > 0 ? 100 * done / total : 100);
      if (done == total) std::fprintf(stderr, "\r%*s\r", 30, "");
      std::fflush(stderr);
    };
  }
  const CollisionMap map = collision_map(s, g, options);
  const std::filesystem::path dir = output_dir(design, opt.out, "collision");
  const WriteFence fence(dir);  // nothing of this command lands outside it (fivebar/io.hpp)
  const RenderedPlot pic = plot_collision_map(s, g, map);
  const std::filesystem::path svg = dir / (s.name + ".svg");
  const std::filesystem::path png = dir / (s.name + ".png");
  write_file_atomic(svg, pic.svg);
  write_file_atomic(png, pic.png);
  if (opt.json) {
    Json doc = {{"command", "collision"}, {"design", design.name}};
    doc.update(to_json(map));
    doc["files"] = Json::array({svg.generic_string(), png.generic_string()});
    print_json(doc);
  } else {
    std::cout << s.name << "  collision map: " << map.points.size() << " tactor positions in the target ellipse (grid "
              << fixed(map.spacing_mm, 3) << " mm), " << map.pairs << " usable pairs\n";
    row("colliding pairs", fixed(100.0 * map.colliding_fraction, 1) + " %  (" + std::to_string(map.colliding) +
                               " of " + std::to_string(map.pairs) + ", clearance < " + fixed(g.min_clearance, 3) +
                               " mm)");
    if (map.any_free) {
      row("closest free pair", fixed(map.min_free_separation_mm, 3) + " mm: upper " + xy_text(map.min_free_pair[0]) +
                                   ", lower " + xy_text(map.min_free_pair[1]));
    } else {
      row("closest free pair", "none: every sampled pair collides");
    }
    if (map.any_colliding) {
      row("farthest colliding pair", fixed(map.max_colliding_separation_mm, 3) + " mm: upper " +
                                         xy_text(map.max_colliding_pair[0]) + ", lower " +
                                         xy_text(map.max_colliding_pair[1]));
    }
    std::string rule = std::string(to_string(map.centre_rule.status));
    if (map.centre_rule.status == PriorityStatus::moved) {
      rule += ": lower moved " + fixed(map.centre_rule.moved_mm) + " mm to " + xy_text(map.centre_rule.lower_point);
    }
    row("priority, both at centre", rule);
    std::cout << "  colliding share by tactor separation:\n";
    for (const SeparationBin& b : map.bins) {
      if (b.pairs == 0) continue;
      const double f = double(b.colliding) / double(b.pairs);
      std::printf("    %5.1f - %5.1f mm  %6.1f %%  %s\n", b.lo_mm, b.hi_mm, 100.0 * f,
                  std::string(static_cast<std::size_t>(f * 40.0 + 0.5), '#').c_str());
    }
    std::fflush(stdout);
    row("picture", svg.generic_string() + ", " + png.generic_string());
  }
  if (!map.any_free) {
    std::cerr << "fivebar collision: no pair of tactor positions in the target ellipse is collision-free\n";
    return kCheckFailed;
  }
  return kOk;
}

int run_collision(const CollisionOptions& opt) {
  if (opt.upper.empty() != opt.lower.empty()) {
    throw InputError("give both --upper X,Y and --lower X,Y for a pair check, or neither for the collision map");
  }
  if (!(opt.spacing_mm > 0.0)) throw InputError("--spacing must be a positive number of mm");
  const Design design = load(opt.design);
  const Station& s = select_pair_station(design, opt.station);
  const Geometry& g = require_geometry(design);
  return opt.upper.empty() ? run_map(opt, design, s, g) : run_pair(opt, design, s, g);
}

}  // namespace

void setup_collision(CLI::App& app) {
  auto [sub, opt] = add_command<CollisionOptions>(
      app, "collision",
      "Interference of a station's upper and lower mechanisms: a pair of tactor points with the priority rule "
      "(--upper, --lower), or the collision map over the target ellipse",
      run_collision);
  add_design_argument(*sub, opt->design);
  add_station_option(*sub, opt->station, "the only one in the design");
  sub->add_option("--upper", opt->upper, "Upper tactor point X,Y (mm)")->type_name("X,Y");
  sub->add_option("--lower", opt->lower, "Lower tactor point X,Y (mm)")->type_name("X,Y");
  sub->add_option("--spacing", opt->spacing_mm, "Grid spacing of the collision map (mm)")
      ->capture_default_str()
      ->type_name("MM");
  add_out_option(*sub, opt->out, "the map's picture", "collision");
  add_json_flag(*sub, opt->json);
  sub->footer(exit_status({.ok = "the pair does not collide (the map: a collision-free pair exists)",
                           .failed = "the pair collides or the priority rule finds a tactor unusable (the map: no "
                                     "pair in the target ellipse is collision-free)",
                           .writes = true}));
}

}  // namespace fivebar::cli
