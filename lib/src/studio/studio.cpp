// The studio's state and figures (fivebar/studio.hpp, docs/studio.md): the same library calls as
// `fivebar coverage`, `fivebar collision` and `fivebar workspace`, on a design loaded from the
// edited text of its file.
#include "fivebar/csv_reader.hpp"
#include "fivebar/studio.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <list>
#include <map>
#include <variant>
#include <memory>
#include <mutex>
#include <sstream>

#include "fivebar/collision.hpp"
#include "fivebar/coverage/coverage.hpp"
#include "fivebar/coverage/report.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/design/edit.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/io.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/pattern.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sha256.hpp"
#include "fivebar/tolerance.hpp"
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

/// A drawing coordinate to 0.1 um, far below the polyline's own step (kArcStepRad of an arc): a
/// third of the bytes of the shortest exact decimal.
double drawn(double v) { return std::round(v * 1e4) / 1e4; }

/// `id`: a name of the numbers the region is computed from (128 bits of the SHA-256 of `key`: two
/// states sharing one is out of reach), so that a page holding that region's loops can be sent the
/// region without them (docs/studio.md "Speed").
Json region_json(const Region& r, const std::string& key) {
  Json loops = Json::array();
  for (const BoundaryLoop& loop : r.loops()) {
    Json points = Json::array();
    for (const Vec2& p : discretise(loop)) points.push_back(Json::array({drawn(p.x()), drawn(p.y())}));
    loops.push_back(std::move(points));
  }
  return {{"id", sha256_hex(key).substr(0, 32)}, {"area_mm2", r.area_mm2()}, {"components", r.components()}, {"holes", r.holes()}, {"loops_mm", loops}};
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

Json mechanism_json(const Mechanism& m, const Json& region, const Vec2& at, const Geometry* g) {
  Json j = to_json(m);
  j["mechanism"] = m.name;
  j.erase("name");
  j["region"] = region;
  const Pose pose = ik(m, at);
  j["cursor_mm"] = xy(at);
  j["pose"] = pose_json(m, pose);
  j["outline"] = outline_json(m, pose, g);
  return j;
}

// --- The cache of studio_figures() ----------------------------------------------------------------

/// Appends the bytes of each number: equal keys mean equal numbers, bit for bit.
template <class... T>
void put(std::string& key, const T&... v) {
  (key.append(reinterpret_cast<const char*>(&v), sizeof(v)), ...);
}

/// Every number and mode a mechanism's region, coverage, poses and outlines are computed from.
std::string key_of(const Mechanism& m) {
  std::string k = m.name + '\0';
  put(k, m.O1.x(), m.O1.y(), m.O2.x(), m.O2.y(), m.L, m.working_mode.sign1, m.working_mode.sign2, m.assembly_mode, m.min_lci);
  const bool limits = m.joint_limits.has_value();
  put(k, limits);
  if (limits) {
    for (const JointRange& r : *m.joint_limits) put(k, r.lo, r.hi);
  }
  return k;
}

std::string key_of(const Ellipse& e) {
  std::string k;
  put(k, e.center.x(), e.center.y(), e.axes.x(), e.axes.y(), e.angle);
  return k;
}

std::string key_of(const Geometry& g) {
  std::string k;
  put(k, g.link_width, g.link_thickness, g.pin_diameter, g.boss_diameter, g.tactor_diameter, g.tactor_height, g.layers,
      g.layer_gap, g.motor_shaft_diameter, g.motor_shaft_flat, g.min_clearance);
  return k;
}

/// A region and its JSON, computed once.
struct RegionFigure {
  Region region;
  Json json;
};

/// The newest few values of one kind, by key (a drag edits one mechanism: the other's entry and
/// the previous state's stay).
template <class T>
class Recent {
 public:
  template <class Make>
  std::shared_ptr<const T> get(const std::string& key, Make&& make) {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      for (auto it = items_.begin(); it != items_.end(); ++it) {
        if (it->first != key) continue;
        items_.splice(items_.begin(), items_, it);
        return items_.front().second;
      }
    }
    auto value = std::make_shared<const T>(make());  // outside the lock: other requests go on
    put_value(key, value);
    return value;
  }

  /// The entry of `key`, or null: nothing computed.
  std::shared_ptr<const T> find(const std::string& key) {
    const std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& item : items_) {
      if (item.first == key) return item.second;
    }
    return nullptr;
  }

 private:
  void put_value(const std::string& key, const std::shared_ptr<const T>& value) {
    const std::lock_guard<std::mutex> lock(mutex_);
    for (auto it = items_.begin(); it != items_.end(); ++it) {
      if (it->first == key) {  // computed meanwhile by another request: keep one entry
        items_.erase(it);
        break;
      }
    }
    items_.emplace_front(key, value);
    if (items_.size() > kSize) items_.pop_back();
  }

  static constexpr std::size_t kSize = 8;
  std::mutex mutex_;
  std::list<std::pair<std::string, std::shared_ptr<const T>>> items_;
};

}  // namespace

struct StudioCache::Impl {
  Recent<RegionFigure> regions;      ///< key_of(mechanism)
  Recent<CoverageResult> coverages;  ///< key_of(mechanism) + key_of(target)
  Recent<RegionFigure> shared;       ///< key_of(lower) + key_of(upper)
  Recent<Json> priorities;           ///< both mechanisms, the geometry and the two points
};

StudioCache::StudioCache() : impl_(std::make_unique<Impl>()) {}
StudioCache::~StudioCache() = default;

namespace {

/// `make()` through `cache` when there is one.
template <class T, class Make>
std::shared_ptr<const T> cached(Recent<T>* recent, const std::string& key, Make&& make) {
  if (recent == nullptr) return std::make_shared<const T>(make());
  return recent->get(key, std::forward<Make>(make));
}

RegionFigure region_figure(Region r, const std::string& key) {
  Json j = region_json(r, key);
  return {std::move(r), std::move(j)};
}

/// The design file's text, bounded as the loader bounds it (kMaxDesignFileBytes, fivebar/design.hpp).
std::string read_text(const std::filesystem::path& file) {
  return csv::read_bounded(file, kMaxDesignFileBytes, "design file");
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

namespace {

/// The 3-sigma ellipse and worst case of `fivebar tolerance` (first order, its `centre_*` figures)
/// at the tactor point `at`.
Json tolerance_json(const Design& design, const Station& s, const Mechanism& m, const Vec2& at) {
  const ToleranceSources src = tolerance_sources(design, s, m);
  const ToleranceEstimate e = tolerance_first_order(m, at, src.spread(), std::max(src.rad_per_count[0], src.rad_per_count[1]));
  Json j = {{"at_mm", xy(at)}, {"status", std::string(to_string(e.status))}};
  if (e.status != Status::ok) return j;
  j["three_sigma_first_order_mm"] = e.ellipse_semi_axes.x();
  j["three_sigma_minor_first_order_mm"] = e.ellipse_semi_axes.y();
  j["three_sigma_angle_first_order_deg"] = e.ellipse_angle * 180.0 / M_PI;
  j["worst_case_first_order_mm"] = e.worst_case_mm;
  j["near_singular"] = e.near_singular;
  return j;
}

/// The paper's priority rule at the two tactor points, as `fivebar collision --upper --lower`
/// (null without both mechanisms and a geometry). Without `compute`: the cached record of these
/// numbers, else "not certified yet" (StudioFigures::quick).
Json priority_figure(const Station& s, const Geometry* g, const Vec2& lower_at, const Vec2& upper_at, StudioCache::Impl* cache,
                     bool compute) {
  if (g == nullptr || !s.lower || !s.upper) return nullptr;
  std::string pk = key_of(*s.upper) + key_of(*s.lower) + key_of(*g);
  put(pk, upper_at.x(), upper_at.y(), lower_at.x(), lower_at.y());
  if (!compute) {
    const auto known = cache ? cache->priorities.find(pk) : nullptr;
    return known ? *known : Json(kNotCertified);
  }
  return *cached(cache ? &cache->priorities : nullptr, pk,
                 [&] { return to_json(apply_priority(*s.upper, *s.lower, *g, upper_at, lower_at)); });
}

/// The station's regions, coverage and priority rule (studio_figures()'s live part), each computed
/// once per request and through the cache when there is one; the tolerance band at each cursor.
/// Without `priority_now`, the priority rule only when the cache holds it (priority_figure()).
void live_figures(Json& j, const Design& design, const Station& s, const Geometry* g, const Vec2& lower_at, const Vec2& upper_at,
                  StudioCache::Impl* cache, bool priority_now) {
  std::vector<std::shared_ptr<const RegionFigure>> regions;
  std::vector<CoverageResult> coverages;
  j["mechanisms"] = Json::array();
  for (const Mechanism* m : s.mechanisms()) {
    const std::string mk = key_of(*m);
    regions.push_back(cached(cache ? &cache->regions : nullptr, mk, [&] { return region_figure(reachable_region(*m), mk); }));
    coverages.push_back(*cached(cache ? &cache->coverages : nullptr, mk + key_of(s.target),
                                [&] { return coverage(*m, regions.back()->region, s.target); }));
    const Vec2& at = m->name == "lower" ? lower_at : upper_at;
    j["mechanisms"].push_back(mechanism_json(*m, regions.back()->json, at, g));
    j["mechanisms"].back()["tolerance"] = tolerance_json(design, s, *m, at);
  }
  // `fivebar coverage`'s record (station_coverage()), from the regions above.
  StationCoverage sc;
  sc.station = s.name;
  std::size_t next = 0;
  if (s.lower) sc.lower = coverages[next++];
  if (s.upper) sc.upper = coverages[next++];
  j["shared_region"] = nullptr;
  if (s.lower && s.upper) {
    const std::string sk = key_of(*s.lower) + key_of(*s.upper);
    const auto shared = cached(cache ? &cache->shared : nullptr, sk,
                               [&] { return region_figure(regions[0]->region.intersection(regions[1]->region), "shared" + sk); });
    j["shared_region"] = shared->json;
    sc.shared = coverage_shared(*sc.lower, *sc.upper, shared->region, s.target);
  }
  j["coverage"] = to_json(sc, s.name);
  j["priority"] = priority_figure(s, g, lower_at, upper_at, cache, priority_now);
}

}  // namespace

Json studio_figures(const Design& design, std::string_view station, const StudioCursor& cursor, StudioFigures which,
                    StudioCache* cache) {
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
  live_figures(j, design, *s, g, lower_at, upper_at, cache ? &cache->impl() : nullptr, which != StudioFigures::quick);
  const bool full = which == StudioFigures::full;
  j["collision_map"] = !full ? Json(kNotCertified) : g != nullptr && s->lower && s->upper ? collision_map_json(*s, *g) : Json(nullptr);
  if (full) {
    j["lci_field"] = Json::array();
    for (const Mechanism* m : s->mechanisms()) j["lci_field"].push_back(lci_field_json(*m, s->target));
  } else {
    j["lci_field"] = kNotCertified;
  }
  j["figures"] = full ? "full" : which == StudioFigures::quick ? "quick" : "live";
  return j;
}

Json studio_pattern(const Design& design, std::string_view station, std::string_view kind) {
  const Station* s = design.station(station);
  if (s == nullptr) throw InputError("design '" + design.name + "' has no station '" + std::string(station) + "'");
  const auto k = parse_pattern_kind(kind);
  if (!k) throw InputError("pattern '" + std::string(kind) + "': expected stretch, slip, twist or pivot");
  const Geometry* g = design.get<Geometry>();
  if (!s->lower || !s->upper || g == nullptr) {
    throw InputError("station '" + s->name + "': a pattern needs both mechanisms and a geometry: section");
  }
  const PatternResult r = check_pattern(*s, *g, pattern_spec(design, *s, *k), pattern_joint_speed_limit(design, *s));
  Json j = to_json(r, true);
  const auto joints = [](const Mechanism& m, const Pose& p) {
    return p.status == Status::unreachable ? Json(nullptr) : Json::array({xy(m.O1), xy(p.A1), xy(p.P), xy(p.A2), xy(m.O2)});
  };
  Json frames = Json::array();
  for (const PatternSample& x : r.samples) {
    frames.push_back({{"lower", joints(*s->lower, x.lower.pose)}, {"upper", joints(*s->upper, x.upper.pose)}});
  }
  j["frames"] = std::move(frames);
  return j;
}

Json studio_priority(const Design& design, std::string_view station, const StudioCursor& cursor, StudioCache* cache) {
  const Station* s = design.station(station);
  if (s == nullptr) throw InputError("design '" + design.name + "' has no station '" + std::string(station) + "'");
  return priority_figure(*s, design.get<Geometry>(), cursor.lower.value_or(s->target.center), cursor.upper.value_or(s->target.center),
                         cache ? &cache->impl() : nullptr, true);
}

namespace {

/// One number or mode of a station that the page edits: its key path, its control (value, unit,
/// slider range or choices) and where live_design() sets it.
struct StationKey {
  enum class Kind : std::uint8_t { number, joint_limit, working_mode, assembly_mode };
  Kind kind = Kind::number;
  DesignKey at;  ///< path; for a number, field / upper / i / j as set_station_number() takes them
  Json control;
};

/// The keys of one station, in the order the page lists them (studio_controls()).
std::vector<StationKey> station_keys(const Station& s) {
  double scale = std::max(s.target.axes.x(), s.target.axes.y());
  for (const Mechanism* m : s.mechanisms()) scale = std::max(scale, m->length_scale());
  const std::string at = "stations." + s.name;  // names are plain words in every shipped design
  std::vector<StationKey> keys;
  auto add = [&](StationKey::Kind kind, const std::string& key, DesignKey::Field field, bool upper, int i, int j, Json control) {
    StationKey k;
    k.kind = kind;
    k.at.path = key;
    k.at.field = field;
    k.at.station = s.name;
    k.at.upper = upper;
    k.at.i = i;
    k.at.j = j;
    k.control = {{"key", key}};  // first, then the rest in the order given
    for (auto& [name, value] : control.items()) k.control[name] = std::move(value);
    keys.push_back(std::move(k));
  };
  using F = DesignKey::Field;
  using K = StationKey::Kind;
  auto length = [&](const std::string& key, F field, bool upper, int i, double v) {
    add(K::number, key, field, upper, i, 0, {{"value", v}, {"unit", "mm"}, {"min", 0.5 * v}, {"max", 1.5 * v}});
  };
  auto coord = [&](const std::string& key, F field, bool upper, int i, int j, double v) {
    add(K::number, key, field, upper, i, j, {{"value", v}, {"unit", "mm"}, {"min", v - scale}, {"max", v + scale}});
  };
  coord(at + ".target.center[0]", F::center, false, 0, 0, s.target.center.x());
  coord(at + ".target.center[1]", F::center, false, 1, 0, s.target.center.y());
  length(at + ".target.axes[0]", F::axes, false, 0, s.target.axes.x());
  length(at + ".target.axes[1]", F::axes, false, 1, s.target.axes.y());
  add(K::number, at + ".target.angle", F::angle, false, 0, 0,
      {{"value", s.target.angle * 180.0 / M_PI}, {"unit", "deg"}, {"min", -180.0}, {"max", 180.0}});
  for (const Mechanism* m : s.mechanisms()) {
    const std::string mk = at + ".mechanisms." + m->name;
    const bool up = m->name == "upper";
    for (int i = 0; i < 2; ++i) {
      const Vec2& o = i == 0 ? m->O1 : m->O2;
      coord(mk + ".bases[" + std::to_string(i) + "][0]", F::base, up, i, 0, o.x());
      coord(mk + ".bases[" + std::to_string(i) + "][1]", F::base, up, i, 1, o.y());
    }
    for (int i = 0; i < 4; ++i) length(mk + ".links[" + std::to_string(i) + "]", F::link, up, i, m->L[std::size_t(i)]);
    const Json mj = to_json(*m);
    add(K::working_mode, mk + ".working_mode", F::other, up, 0, 0, {{"value", mj["working_mode"]}, {"choices", {"++", "+-", "-+", "--"}}});
    add(K::assembly_mode, mk + ".assembly_mode", F::other, up, 0, 0, {{"value", mj["assembly_mode"]}, {"choices", {"+", "-", "any"}}});
    if (m->joint_limits) {
      for (int i = 0; i < 2; ++i) {
        for (int k = 0; k < 2; ++k) {
          const double v = mj["joint_limits_deg"][std::size_t(i)][std::size_t(k)].get<double>();
          add(K::joint_limit, mk + ".joint_limits[" + std::to_string(i) + "][" + std::to_string(k) + "]", F::other, up, i, k,
              {{"value", v}, {"unit", "deg"}, {"min", v - 180.0}, {"max", v + 180.0}});
        }
      }
    }
  }
  return keys;
}

}  // namespace

Json studio_controls(const Design& design) {
  Json stations = Json::array();
  for (const Station& s : design.stations) {
    Json keys = Json::array();
    for (StationKey& k : station_keys(s)) keys.push_back(std::move(k.control));
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

/// The design as read and, by key path, the numbers and modes live_design() sets in memory.
struct Studio::Live {
  Design base;
  std::map<std::string, StationKey, std::less<>> keys;
  std::map<std::string, std::size_t, std::less<>> station_index;
};

namespace {

/// Sets `value` at `k` in `d` as the loader would read it from the edited text; false for a value
/// of the wrong kind (the loader then says what is wrong).
bool set_live(Design& d, std::size_t station, const StationKey& k, const std::variant<double, std::string>& value) {
  Station& st = d.stations[station];
  const double* number = std::get_if<double>(&value);
  const std::string* text = std::get_if<std::string>(&value);
  if (k.kind == StationKey::Kind::number) {
    if (number == nullptr || !std::isfinite(*number)) return false;
    set_station_number(st, k.at, *number);
    return true;
  }
  std::optional<Mechanism>& m = k.at.upper ? st.upper : st.lower;
  if (!m) return false;
  if (k.kind == StationKey::Kind::joint_limit) {
    if (number == nullptr || !std::isfinite(*number) || !m->joint_limits) return false;
    JointRange& r = (*m->joint_limits)[std::size_t(k.at.i)];
    (k.at.j == 0 ? r.lo : r.hi) = format::kRadPerDeg * *number;  // as the loader converts
    return true;
  }
  if (text == nullptr) return false;
  if (k.kind == StationKey::Kind::working_mode) {
    const auto mode = parse_working_mode(*text);
    if (!mode) return false;
    m->working_mode = *mode;
  } else {
    const auto mode = parse_assembly_mode(*text);
    if (!mode) return false;
    m->assembly_mode = *mode;
  }
  return true;
}

/// Each listed number moved a little, each by another amount (so that two numbers one text holds
/// come out unequal by one way and equal by the other), a mode kept: the edits prepare_live()
/// checks both ways.
std::vector<FileEdit> nudged(const std::vector<StationKey>& keys) {
  std::vector<FileEdit> edits;
  for (const StationKey& k : keys) {
    const Json& v = k.control["value"];
    if (v.is_number()) edits.push_back({k.at.path, v.get<double>() * (1.0 + 1e-7) + 1e-7 * double(edits.size() + 1)});
    else edits.push_back({k.at.path, v.get<std::string>()});
  }
  return edits;
}

}  // namespace

Studio::Studio(std::filesystem::path file, DesignRule rule) : file_(std::move(file)), rule_(std::move(rule)) { reload(); }

void Studio::reload() {
  std::string text = read_text(file_);
  Design base = load_design_from_string(text, file_.string(), rule_);  // every rule of the command line
  text_ = std::move(text);
  sha_ = sha256_hex(text_);
  prepare_live(std::move(base));
}

void Studio::prepare_live(Design base) {
  base.source = file_;
  auto live = std::make_shared<Live>();
  std::vector<StationKey> all;
  for (std::size_t i = 0; i < base.stations.size(); ++i) {
    live->station_index[base.stations[i].name] = i;
    for (StationKey& k : station_keys(base.stations[i])) all.push_back(std::move(k));
  }
  live->base = std::move(base);
  // Only keys the file's text holds (an angle the file leaves out has no line to edit) ...
  std::vector<StationKey> in_file;
  const auto holds = [&](const std::vector<StationKey>& keys) {
    try {
      (void)edit_design_text(text_, file_.string(), nudged(keys));
      return true;
    } catch (const InputError&) {
      return false;  // left to design(): the loader's message
    }
  };
  if (holds(all)) {
    in_file = std::move(all);
  } else {
    for (StationKey& k : all) {
      if (holds({k})) in_file.push_back(std::move(k));
    }
  }
  // ... and only when setting them in memory gives the design the loader reads from the edited
  // text (an anchor shared by two numbers would not).
  live_.reset();
  for (StationKey& k : in_file) live->keys[k.at.path] = k;
  const std::vector<FileEdit> probe = nudged(in_file);
  try {
    const Design by_text = design(probe);
    live_ = live;
    if (to_yaml(live_design(probe)) != to_yaml(by_text)) live_.reset();
  } catch (const std::exception&) {
    live_.reset();  // the nudged design is refused or differs: every edit through the loader
  }
}

std::string Studio::edited_text(const std::vector<FileEdit>& edits) const { return edit_design_text(text_, file_.string(), edits); }

Design Studio::design(const std::vector<FileEdit>& edits) const {
  Design d = load_design_from_string(edited_text(edits), file_.string(), rule_);
  d.source = file_;
  return d;
}

Design Studio::live_design(const std::vector<FileEdit>& edits) const {
  const std::shared_ptr<const Live> live = live_;
  if (!live) return design(edits);
  Design d = live->base;
  std::vector<std::size_t> touched;
  for (const FileEdit& e : edits) {
    const auto k = live->keys.find(e.key);
    if (k == live->keys.end()) return design(edits);
    const std::size_t station = live->station_index.find(k->second.at.station)->second;
    if (!set_live(d, station, k->second, e.value)) return design(edits);
    touched.push_back(station);
  }
  try {
    for (const std::size_t i : touched) check_station_edit(d.stations[i], d.get<Geometry>());
  } catch (const ValidationError&) {
    return design(edits);  // refused: the loader's FILE:LINE: key message
  }
  return d;
}

Json Studio::preview(const std::vector<FileEdit>& edits) const {
  const std::string after = edited_text(edits);
  (void)load_design_from_string(after, file_.string(), rule_);
  return {{"file", file_.filename().string()}, {"sha256", sha_}, {"changes", line_diff(text_, after)}, {"valid", true}};
}

Studio::SaveStatus Studio::save(const std::vector<FileEdit>& edits, std::string_view expected_sha256) {
  const std::string after = edited_text(edits);
  Design saved = load_design_from_string(after, file_.string(), rule_);  // refused before anything is written
  if (sha256_hex(read_text(file_)) != expected_sha256 || expected_sha256 != sha_) return SaveStatus::changed_on_disk;
  write_file_atomic(file_, after);
  text_ = after;
  sha_ = sha256_hex(text_);
  prepare_live(std::move(saved));
  return SaveStatus::saved;
}

}  // namespace fivebar
