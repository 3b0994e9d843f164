// The `collision` product: for every station with both mechanisms, the sampled collision map of
// the two tactors over the target ellipse (fraction colliding, closest collision-free separation),
// the priority rule with both targets at the centre, and the map's picture.

#include <algorithm>
#include <string>

#include "fivebar/collision.hpp"
#include "fivebar/json.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {

namespace {

constexpr const char* kPreamble =
    "Both tactors of a station share the fingertip. Every pair of tactor positions on a grid over the "
    "target ellipse (upper anywhere, lower anywhere) is checked for interference of the two mechanisms' "
    "link outlines (capsules of the link width, pin bosses, tactor disks; plane by plane as in "
    "`geometry.layers`, exact distances): a pair collides when two parts in one plane are closer than "
    "`geometry.min_clearance`. The *closest free pair* is the smallest tactor separation seen without "
    "collision; every sampled pair farther apart than the *farthest colliding pair* is free. The priority "
    "rule (paper Sec. II-D) is shown with both targets at the ellipse centre: the upper keeps its target "
    "and the lower moves to the closest collision-free point.\n\n";

}  // namespace

Product collision_product() {
  Product p;
  p.name = "collision";
  p.checks_designs = true;  // re-run on a proposed design (check_design())
  p.title = "Collision of the two tactors";
  p.unavailable = [](const Design& d) { return without_pairs(d, "link widths and planes are needed"); };
  p.build = [](Context& ctx) {
    const Design& d = ctx.design;
    const Geometry& g = *d.get<Geometry>();
    Built b;
    Json stations = Json::array();
    std::string markdown = kPreamble;
    md::Table table({"station", "positions", "usable pairs", "colliding", "closest free pair (mm)",
                     "farthest colliding pair (mm)", "priority rule at the centre", "picture"},
                    "lrrrrrll");
    std::vector<std::string> notes, problems, checks, images;
    for (const Station& s : d.stations) {
      if (!has_pair(s)) {
        notes.push_back("station " + md::code(s.name) + " left out: it does not have both mechanisms");
        continue;
      }
      ctx.say("collision: station " + s.name + " (map of tactor pairs)");
      const CollisionMap map = collision_map(s, g);
      const RenderedPlot pic = plot_collision_map(s, g, map);
      const std::string stem = "collision/" + s.name;
      ctx.write_file(stem + ".svg", pic.svg);
      ctx.write_file(stem + ".png", pic.png);
      Json js = to_json(map);
      js["files"] = Json::array({stem + ".svg", stem + ".png"});
      stations.push_back(js);

      std::string rule = std::string(to_string(map.centre_rule.status));
      if (map.centre_rule.status == PriorityStatus::moved) {
        rule += ": lower moved " + md::fixed(map.centre_rule.moved_mm, 2) + " mm to " +
                md::pair(map.centre_rule.lower_point.x(), map.centre_rule.lower_point.y(), 2);
      }
      table.row({md::code(s.name), std::to_string(map.points.size()), std::to_string(map.pairs),
                 md::fixed(100.0 * map.colliding_fraction, 1) + " %",
                 map.any_free ? md::fixed(map.min_free_separation_mm, 2) : "none",
                 map.any_colliding ? md::fixed(map.max_colliding_separation_mm, 2) : "none", rule,
                 "[" + stem + ".png](" + stem + ".png)"});
      images.push_back("![collision map of station " + s.name + "](" + stem + ".png)");
      if (!map.any_free) problems.push_back(s.name + ": no sampled pair of tactor positions is collision-free");
      if (map.centre_rule.status == PriorityStatus::no_free_point) {
        problems.push_back(s.name + ": with both targets at the centre the priority rule finds no free point");
      }
      checks.push_back(s.name + " " + md::fixed(100.0 * map.colliding_fraction, 1) + " % of pairs collide, free from " +
                       (map.any_free ? md::fixed(map.min_free_separation_mm, 2) + " mm" : std::string("nowhere")));
    }
    markdown += table.str() + "\n";
    for (const auto& n : notes) markdown += "- " + n + "\n";
    for (const auto& pr : problems) markdown += "- ✗ " + pr + "\n";
    if (!notes.empty() || !problems.empty()) markdown += "\n";
    for (const auto& image : images) markdown += image + "\n\n";
    b.result = {{"min_clearance_mm", g.min_clearance}, {"stations", stations}};
    b.markdown = markdown;
    b.passed = problems.empty();
    std::string check;
    for (const auto& c : checks) check += (check.empty() ? "" : "; ") + c;
    b.check = b.passed ? check : problems.front();
    return b;
  };
  return p;
}

}  // namespace fivebar::products
