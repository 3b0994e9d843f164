// The studio's state and figures (fivebar/studio.hpp, docs/studio.md): the same library calls as
// `fivebar coverage`, `fivebar collision` and `fivebar workspace`, on a design loaded from the
// edited text of its file.
#include "fivebar/studio.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>

#include "fivebar/collision.hpp"
#include "fivebar/coverage/report.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sha256.hpp"
#include "fivebar/workspace/polyline.hpp"
#include "fivebar/workspace/region.hpp"

namespace fivebar {

namespace {

constexpr const char* kNotCertified = "not certified yet";

Json xy(const Vec2& p) { return Json::array({p.x(), p.y()}); }

Json polyline_json(const std::vector<Vec2>& points) {
  Json out = Json::array();
  for (const Vec2& p : points) out.push_back(xy(p));
  return out;
}

Json region_json(const Region& r) {
  Json loops = Json::array();
  for (const BoundaryLoop& loop : r.loops()) loops.push_back(polyline_json(discretise(loop)));
  return {{"area_mm2", r.area_mm2()}, {"components", r.components()}, {"holes", r.holes()}, {"loops_mm", loops}};
}

Json pose_json(const Mechanism& m, const Pose& pose) {
  Json j = {{"status", std::string(to_string(pose.status))}};
  if (pose.status == Status::unreachable) {
    j["points_mm"] = nullptr;
    j["lci"] = nullptr;
    return j;
  }
  j["points_mm"] = Json::array({xy(m.O1), xy(pose.A1), xy(pose.P), xy(pose.A2), xy(m.O2)});
  j["theta_deg"] = Json::array({pose.theta1 * 180.0 / M_PI, pose.theta2 * 180.0 / M_PI});
  j["lci"] = pose.lci;
  return j;
}

Json outline_json(const Mechanism& m, const Pose& pose, const Geometry* g) {
  if (g == nullptr || pose.status == Status::unreachable) return nullptr;
  Json parts = Json::array();
  for (const OutlinePart& part : link_outline(m, pose, *g)) {
    Json caps = Json::array();
    for (int i = 0; i < part.count; ++i) {
      const Capsule& c = part.shapes[std::size_t(i)];
      caps.push_back({{"a_mm", xy(c.a)}, {"b_mm", xy(c.b)}, {"radius_mm", c.radius}});
    }
    parts.push_back({{"part", std::string(part.name)}, {"plane", part.plane}, {"capsules", caps}});
  }
  return parts;
}

/// The LCI field of one mechanism over the target's bounding box (sampled, 48 cells across).
Json lci_field_json(const Mechanism& m, const Ellipse& e) {
  const double r = 0.5 * std::max(e.axes.x(), e.axes.y());
  const std::array<double, 4> box{e.center.x() - r, e.center.y() - r, e.center.x() + r, e.center.y() + r};
  const double spacing = 2.0 * r / 48.0;
  const WorkspaceField f = sample_field(m, Grid::covering(box, spacing, spacing));
  Json lci = Json::array();
  for (std::size_t k = 0; k < f.lci.size(); ++k) lci.push_back(f.reach[k] != 0 ? Json(f.lci[k]) : Json(nullptr));
  return {{"mechanism", m.name},
          {"origin_mm", Json::array({f.grid.x0, f.grid.y0})},
          {"spacing_mm", f.grid.spacing},
          {"nx", f.grid.nx},
          {"ny", f.grid.ny},
          {"lci_sampled", lci}};
}

/// `fivebar collision --json`'s map summary (the per-point arrays left out but the collision-free
/// positions of the lower tactor against the upper one at the centre).
Json collision_map_json(const Station& s, const Geometry& g) {
  const CollisionMap map = collision_map(s, g, {});
  Json j = to_json(map);
  j.erase("by_separation");
  Json free_points = Json::array(), blocked_points = Json::array();
  for (std::size_t k = 0; k < map.points.size(); ++k) {
    if (k < map.centre_collides.size() && map.centre_collides[k] == 0) free_points.push_back(xy(map.points[k]));
    if (k < map.centre_collides.size() && map.centre_collides[k] == 1) blocked_points.push_back(xy(map.points[k]));
  }
  j["lower_free_against_centre_mm"] = free_points;
  j["lower_colliding_against_centre_mm"] = blocked_points;
  return j;
}

Json mechanism_json(const Mechanism& m, const Vec2& at, const Geometry* g) {
  Json j = to_json(m);
  j["mechanism"] = m.name;
  j.erase("name");
  j["region"] = region_json(reachable_region(m));
  const Pose pose = ik(m, at);
  j["cursor_mm"] = xy(at);
  j["pose"] = pose_json(m, pose);
  j["outline"] = outline_json(m, pose, g);
  return j;
}

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file.string() + ": cannot be read");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> split_lines(std::string_view text) {
  std::vector<std::string> lines;
  std::size_t from = 0;
  while (from < text.size()) {
    std::size_t end = text.find('\n', from);
    if (end == std::string_view::npos) end = text.size();
    lines.emplace_back(text.substr(from, end - from));
    from = end + 1;
  }
  return lines;
}

}  // namespace

Json studio_figures(const Design& design, std::string_view station, const StudioCursor& cursor, StudioFigures which) {
  const Station* s = design.station(station);
  if (s == nullptr) throw InputError("design '" + design.name + "' has no station '" + std::string(station) + "'");
  const Geometry* g = design.get<Geometry>();
  Json names = Json::array();
  for (const Station& st : design.stations) names.push_back(st.name);
  const Vec2 lower_at = cursor.lower.value_or(s->target.center);
  const Vec2 upper_at = cursor.upper.value_or(s->target.center);
  Json j = {{"design", design.name}, {"station", s->name}, {"stations", names}};
  j["target"] = to_json(s->target);
  j["target"]["outline_mm"] = polyline_json(ellipse_polyline(s->target, 120));
  j["mechanisms"] = Json::array();
  for (const Mechanism* m : s->mechanisms()) {
    j["mechanisms"].push_back(mechanism_json(*m, m->name == "lower" ? lower_at : upper_at, g));
  }
  j["shared_region"] = s->lower && s->upper ? region_json(reachable_region(*s->lower).intersection(reachable_region(*s->upper)))
                                            : Json(nullptr);
  j["coverage"] = to_json(station_coverage(*s), s->name);
  // The paper's priority rule at the two tactor points, as `fivebar collision --upper --lower`.
  if (g != nullptr && s->lower && s->upper) {
    j["priority"] = to_json(apply_priority(*s->upper, *s->lower, *g, upper_at, lower_at));
  } else {
    j["priority"] = nullptr;
  }
  const bool full = which == StudioFigures::full;
  j["collision_map"] = !full ? Json(kNotCertified) : g != nullptr && s->lower && s->upper ? collision_map_json(*s, *g) : Json(nullptr);
  if (full) {
    j["lci_field"] = Json::array();
    for (const Mechanism* m : s->mechanisms()) j["lci_field"].push_back(lci_field_json(*m, s->target));
  } else {
    j["lci_field"] = kNotCertified;
  }
  j["figures"] = full ? "full" : "live";
  return j;
}

Json studio_controls(const Design& design) {
  Json stations = Json::array();
  for (const Station& s : design.stations) {
    double scale = std::max(s.target.axes.x(), s.target.axes.y());
    for (const Mechanism* m : s.mechanisms()) scale = std::max(scale, m->length_scale());
    const std::string at = "stations." + s.name;  // names are plain words in every shipped design
    Json keys = Json::array();
    auto length = [&](const std::string& key, double v) { keys.push_back({{"key", key}, {"value", v}, {"unit", "mm"}, {"min", 0.5 * v}, {"max", 1.5 * v}}); };
    auto coord = [&](const std::string& key, double v) { keys.push_back({{"key", key}, {"value", v}, {"unit", "mm"}, {"min", v - scale}, {"max", v + scale}}); };
    coord(at + ".target.center[0]", s.target.center.x());
    coord(at + ".target.center[1]", s.target.center.y());
    length(at + ".target.axes[0]", s.target.axes.x());
    length(at + ".target.axes[1]", s.target.axes.y());
    keys.push_back({{"key", at + ".target.angle"}, {"value", s.target.angle * 180.0 / M_PI}, {"unit", "deg"}, {"min", -180.0}, {"max", 180.0}});
    for (const Mechanism* m : s.mechanisms()) {
      const std::string mk = at + ".mechanisms." + m->name;
      for (int i = 0; i < 2; ++i) {
        const Vec2& o = i == 0 ? m->O1 : m->O2;
        coord(mk + ".bases[" + std::to_string(i) + "][0]", o.x());
        coord(mk + ".bases[" + std::to_string(i) + "][1]", o.y());
      }
      for (int i = 0; i < 4; ++i) length(mk + ".links[" + std::to_string(i) + "]", m->L[std::size_t(i)]);
      const Json mj = to_json(*m);
      keys.push_back({{"key", mk + ".working_mode"}, {"value", mj["working_mode"]}, {"choices", {"++", "+-", "-+", "--"}}});
      keys.push_back({{"key", mk + ".assembly_mode"}, {"value", mj["assembly_mode"]}, {"choices", {"+", "-", "any"}}});
      if (m->joint_limits) {
        for (int i = 0; i < 2; ++i) {
          for (int k = 0; k < 2; ++k) {
            const double v = mj["joint_limits_deg"][std::size_t(i)][std::size_t(k)].get<double>();
            keys.push_back({{"key", mk + ".joint_limits[" + std::to_string(i) + "][" + std::to_string(k) + "]"},
                            {"value", v}, {"unit", "deg"}, {"min", v - 180.0}, {"max", v + 180.0}});
          }
        }
      }
    }
    stations.push_back({{"station", s.name}, {"keys", keys}});
  }
  return {{"design", design.name}, {"stations", stations}};
}

Json line_diff(std::string_view before, std::string_view after) {
  const std::vector<std::string> a = split_lines(before), b = split_lines(after);
  Json out = Json::array();
  const std::size_t n = std::max(a.size(), b.size());
  bool rest = false;
  for (std::size_t i = 0; i < n; ++i) {
    const bool has_a = i < a.size(), has_b = i < b.size();
    if (!rest && has_a && has_b && a[i] == b[i]) continue;
    if (a.size() != b.size()) rest = true;  // not an in-place edit: every line from here
    out.push_back({{"line", i + 1}, {"before", has_a ? Json(a[i]) : Json(nullptr)}, {"after", has_b ? Json(b[i]) : Json(nullptr)}});
  }
  return out;
}

Studio::Studio(std::filesystem::path file, DesignRule rule) : file_(std::move(file)), rule_(std::move(rule)) { reload(); }

void Studio::reload() {
  std::string text = read_text(file_);
  (void)load_design_from_string(text, file_.string(), rule_);  // every rule of the command line
  text_ = std::move(text);
  sha_ = sha256_hex(text_);
}

std::string Studio::edited_text(const std::vector<FileEdit>& edits) const { return edit_design_text(text_, file_.string(), edits); }

Design Studio::design(const std::vector<FileEdit>& edits) const {
  Design d = load_design_from_string(edited_text(edits), file_.string(), rule_);
  d.source = file_;
  return d;
}

Json Studio::preview(const std::vector<FileEdit>& edits) const {
  const std::string after = edited_text(edits);
  (void)load_design_from_string(after, file_.string(), rule_);
  return {{"file", file_.filename().string()}, {"sha256", sha_}, {"changes", line_diff(text_, after)}, {"valid", true}};
}

Studio::SaveStatus Studio::save(const std::vector<FileEdit>& edits, std::string_view expected_sha256) {
  const std::string after = edited_text(edits);
  (void)load_design_from_string(after, file_.string(), rule_);  // refused before anything is written
  if (sha256_hex(read_text(file_)) != expected_sha256 || expected_sha256 != sha_) return SaveStatus::changed_on_disk;
  write_file_atomic(file_, after);
  text_ = after;
  sha_ = sha256_hex(text_);
  return SaveStatus::saved;
}

}  // namespace fivebar
