// Animated pattern pictures (fivebar/animation.hpp): an SVG document written as text (cairo's SVG
// surface cannot carry a script), with the frames as JSON and a small player script.

#include "fivebar/animation.hpp"
#include "fivebar/ranges.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "fivebar/csv_reader.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/json.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/workspace/polyline.hpp"
#include "fivebar/workspace/region.hpp"
#include "plot/style.hpp"

namespace fivebar {

namespace {

// The house colours (plot/style.hpp), as every other picture of a run.
const std::string kUpper = style::hex(style::kUpper);
const std::string kLower = style::hex(style::kLower);
const std::string kInk = style::hex(style::kInk);
const std::string kGrey = style::hex(style::kGrey);
const std::string kSimColour = style::hex(style::kSimulated);
constexpr double kSide = 16.0;     // px left and right of the panel
constexpr double kHeader = 58.0;   // title lines
constexpr double kFooter = 92.0;   // controls and legend

std::string num(double v, int digits = 2) { return format::fixed(v, digits); }

/// Millimetres rounded to 0.1 um for the JSON (shortest text of the rounded value).
double r4(double v) { return std::round(v * 1e4) / 1e4; }

/// JSON text that is also safe as XML character data and inside an HTML page: '<', '>' and '&'
/// occur only in strings, where \u escapes mean the same.
std::string safe_json(const Json& j) {
  const std::string text = j.dump();
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    if (c == '<') {
      out += "\\u003c";
    } else if (c == '>') {
      out += "\\u003e";
    } else if (c == '&') {
      out += "\\u0026";
    } else {
      out += c;
    }
  }
  return out;
}

std::string sanitise_id(std::string_view s) {
  std::string out;
  for (const char c : s) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '-' || c == '_';
    out += ok ? c : '_';
  }
  return out;
}

/// One panel: where it sits on the page and how it maps station millimetres to its own pixels
/// (y up to y down).
struct View {
  double x_px = 0.0, y_px = 0.0, width_px = 0.0, height_px = 0.0;  ///< on the page
  double xmin = 0.0, ymax = 0.0, scale = 1.0;
  double u(double x) const { return (x - xmin) * scale; }
  double v(double y) const { return (ymax - y) * scale; }
  std::string pt(const Vec2& p) const { return num(u(p.x())) + "," + num(v(p.y())); }
  /// The bounds [x0, x1] x [y0, y1] (mm) fitted into the panel with equal aspect, centred.
  static View fit(double x_px, double y_px, double w, double h, double x0, double x1, double y0, double y1) {
    View view{x_px, y_px, w, h, 0.0, 0.0, 1.0};
    view.scale = std::min(w / (x1 - x0), h / (y1 - y0));
    view.xmin = 0.5 * (x0 + x1) - 0.5 * w / view.scale;
    view.ymax = 0.5 * (y0 + y1) + 0.5 * h / view.scale;
    return view;
  }
  Json to_json() const {
    return {{"x_px", x_px},       {"y_px", y_px},        {"width_px", width_px}, {"height_px", height_px},
            {"xmin_mm", xmin},    {"ymax_mm", ymax},     {"px_per_mm", scale}};
  }
};

// The player: reads the frames, draws frame k, runs at true speed, seeks from the slider and the
// URL fragment. Written for XML (inside CDATA) and for an HTML page's inline SVG alike.
constexpr const char* kScript = R"JS(
(function () {
  var root = document.getElementById(ROOT_ID);
  if (!root || root.getAttribute('data-fivebar-ready')) return;
  root.setAttribute('data-fivebar-ready', '1');
  var D = JSON.parse(root.querySelector('.fivebar-animation-data').textContent);
  var T = D.t_s, n = T.length, dur = T[n - 1];
  var layers = [];
  var panels = root.querySelectorAll('.fivebar-panel');
  for (var p = 0; p < panels.length && p < D.views.length; ++p) {
    (function (panel, V) {
      function u(x) { return ((x - V.xmin_mm) * V.px_per_mm).toFixed(2); }
      function v(y) { return ((V.ymax_mm - y) * V.px_per_mm).toFixed(2); }
      D.mechanisms.forEach(function (m) {
        var g = panel.querySelector('.fivebar-mechanism-' + m.name);
        layers.push({ d: m, g: g, u: u, v: v,
                      pts: m.frames.map(function (f) { return f ? u(f[2]) + ',' + v(f[3]) : null; }),
                      sim: m.simulated ? m.simulated.map(function (q) { return q ? u(q[0]) + ',' + v(q[1]) : null; }) : null,
                      link: g.querySelector('.fivebar-link'), e1: g.querySelector('.fivebar-elbow1'),
                      e2: g.querySelector('.fivebar-elbow2'), tactor: g.querySelector('.fivebar-tactor'),
                      target: g.querySelector('.fivebar-target'), trail: g.querySelector('.fivebar-trail'),
                      simDot: g.querySelector('.fivebar-sim'), simTrail: g.querySelector('.fivebar-sim-trail') });
      });
    })(panels[p], D.views[p]);
  }
  var knob = root.querySelector('.fivebar-knob'), fill = root.querySelector('.fivebar-progress');
  var track = root.querySelector('.fivebar-track'), label = root.querySelector('.fivebar-time');
  var playIcon = root.querySelector('.fivebar-play-icon'), pauseIcon = root.querySelector('.fivebar-pause-icon');
  var x0 = parseFloat(track.getAttribute('x1')), x1 = parseFloat(track.getAttribute('x2'));
  var t = 0, playing = true, last = null, shown = -1, shownT = -1;
  function frameAt(time) {
    var lo = 0, hi = n - 1;
    while (lo < hi) { var mid = (lo + hi + 1) >> 1; if (T[mid] <= time + 1e-9) lo = mid; else hi = mid - 1; }
    return lo;
  }
  function upTo(list, k) { var out = []; for (var i = 0; i <= k; ++i) if (list[i] !== null) out.push(list[i]); return out.join(' '); }
  function draw(k) {
    layers.forEach(function (L) {
      function at(c, x, y) { if (c) { c.setAttribute('cx', L.u(x)); c.setAttribute('cy', L.v(y)); } }
      var f = L.d.frames[k], m = L.d;
      L.g.setAttribute('data-frame', k);
      var vis = f ? 'visible' : 'hidden';
      [L.link, L.e1, L.e2, L.tactor].forEach(function (el) { el.setAttribute('visibility', vis); });
      if (f) {
        L.link.setAttribute('points', [L.u(m.O1[0]) + ',' + L.v(m.O1[1]), L.u(f[0]) + ',' + L.v(f[1]), L.u(f[2]) + ',' + L.v(f[3]),
                                       L.u(f[4]) + ',' + L.v(f[5]), L.u(m.O2[0]) + ',' + L.v(m.O2[1])].join(' '));
        at(L.e1, f[0], f[1]); at(L.e2, f[4], f[5]); at(L.tactor, f[2], f[3]);
      }
      at(L.target, m.targets[k][0], m.targets[k][1]);
      L.trail.setAttribute('points', upTo(L.pts, k));
      if (L.sim && L.simDot) {
        var q = m.simulated[k];
        L.simDot.setAttribute('visibility', q ? 'visible' : 'hidden');
        if (q) at(L.simDot, q[0], q[1]);
        L.simTrail.setAttribute('points', upTo(L.sim, k));
      }
    });
  }
  function render() {
    var k = frameAt(t);
    if (k !== shown) { draw(k); shown = k; }
    if (t !== shownT) {
      var tc = Math.min(t, dur), x = x0 + (dur > 0 ? (x1 - x0) * tc / dur : 0);
      knob.setAttribute('cx', x.toFixed(2)); fill.setAttribute('x2', x.toFixed(2));
      label.textContent = 't = ' + tc.toFixed(2) + ' / ' + dur.toFixed(2) + ' s';
      shownT = t;
    }
    playIcon.setAttribute('visibility', playing ? 'hidden' : 'visible');
    pauseIcon.setAttribute('visibility', playing ? 'visible' : 'hidden');
  }
  function seekFromHash() {
    var m = /(?:^#|&)t=([0-9]*\.?[0-9]+)/.exec(window.location.hash || '');
    if (!m) return false;
    t = Math.max(0, Math.min(parseFloat(m[1]), dur)); playing = false; last = null; render();
    return true;
  }
  function step(now) {
    if (playing) {
      if (last !== null) t += (now - last) / 1000;
      last = now;
      if (t > dur + 0.75) t = 0;
    } else {
      last = null;
    }
    render();
    window.requestAnimationFrame(step);
  }
  function toSvgX(evt) {
    var q = root.createSVGPoint(); q.x = evt.clientX; q.y = evt.clientY;
    var m = root.getScreenCTM();
    return m ? q.matrixTransform(m.inverse()).x : q.x;
  }
  var dragging = false;
  function seekTo(evt) {
    var x = Math.max(x0, Math.min(x1, toSvgX(evt)));
    t = dur * (x - x0) / (x1 - x0); playing = false; render();
  }
  var hit = root.querySelector('.fivebar-slider');
  hit.addEventListener('pointerdown', function (evt) { dragging = true; if (hit.setPointerCapture) hit.setPointerCapture(evt.pointerId); seekTo(evt); evt.preventDefault(); });
  hit.addEventListener('pointermove', function (evt) { if (dragging) seekTo(evt); });
  hit.addEventListener('pointerup', function () { dragging = false; });
  root.querySelector('.fivebar-button').addEventListener('click', function () {
    playing = !playing; if (playing && t >= dur) t = 0; last = null; render();
  });
  window.addEventListener('hashchange', seekFromHash);
  seekFromHash();
  draw(frameAt(t)); shown = frameAt(t); render();
  window.requestAnimationFrame(step);
})();
)JS";

std::string region_path_d(const Region& region, const View& view) {
  std::string d;
  for (const BoundaryLoop& loop : region.loops()) {
    const std::vector<Vec2> pts = discretise(loop);
    for (std::size_t i = 0; i < pts.size(); ++i) d += (i == 0 ? "M" : "L") + view.pt(pts[i]);
    if (!pts.empty()) d += "Z";
  }
  return d;
}

}  // namespace

std::vector<SimulatedTrack> read_simulated_tracks(std::istream& in, std::string_view name) {
  // The one bounded reader of fivebar/csv_reader.hpp (docs/reliability.md "Resource bounds"):
  // lines of kMaxSimulatedLine bytes (a `fivebar simulate` row is about 250), kMaxSimulatedBytes
  // in all and kMaxSimulatedRows rows (24 bytes of tracks a row: 240 MB at most), each checked
  // while reading; strict decimal cells, no duplicated column.
  csv::Limits limits;
  limits.max_line = kMaxSimulatedLine;
  limits.max_bytes = kMaxSimulatedBytes;
  limits.max_rows = kMaxSimulatedRows;
  csv::Reader reader(in, std::string(name), limits);
  const std::size_t ct = reader.require("t_s"), cm = reader.require("mechanism"), cx = reader.require("x_mm"),
                    cy = reader.require("y_mm");
  std::vector<SimulatedTrack> tracks;
  std::map<std::string, std::size_t> index;
  while (reader.next()) {
    const double t = reader.number(ct, std::numeric_limits<double>::max(), "s");
    const Vec2 p(reader.number(cx, std::numeric_limits<double>::max(), "mm"),
                 reader.number(cy, std::numeric_limits<double>::max(), "mm"));
    // A tactor point is a coordinate (docs/reliability.md "Numeric ranges"): |x| <= 1e12 mm.
    for (const auto& [v, key] : {std::pair{p.x(), "x_mm"}, std::pair{p.y(), "y_mm"}}) {
      if (const auto why = ranges::coordinate_rule(v)) {
        throw InputError(reader.where() + std::string(key) + " = " + format::shortest(v) + " mm: " + *why);
      }
    }
    // Two tracks at most: a file of a million mechanism names would hold a million tracks.
    if (reader.cell(cm) != "lower" && reader.cell(cm) != "upper") throw InputError(reader.at(cm) + "not lower or upper");
    auto [it, added] = index.emplace(reader.cell(cm), tracks.size());
    if (added) tracks.push_back(SimulatedTrack{reader.cell(cm), {}, {}});
    SimulatedTrack& track = tracks[it->second];
    if (!track.time_s.empty() && t < track.time_s.back()) throw InputError(reader.at(ct) + "t_s goes back in time");
    track.time_s.push_back(t);
    track.point_mm.push_back(p);
  }
  return tracks;
}

std::vector<AnimationFrame> animation_frames(const Station& station, const PatternResult& result, std::size_t max_frames) {
  if (!station.upper || !station.lower) {
    throw InputError("station " + station.name + ": the animation needs both mechanisms");
  }
  const std::size_t n = result.samples.size();
  if (n == 0) throw InputError("station " + station.name + ": the pattern has no sample to animate");
  const std::size_t cap = std::max<std::size_t>(max_frames, 2);
  const std::size_t stride = n <= cap ? 1 : (n - 1 + cap - 2) / (cap - 1);
  std::vector<std::size_t> picks;
  for (std::size_t k = 0; k < n; k += stride) picks.push_back(k);
  if (picks.back() != n - 1) picks.push_back(n - 1);
  std::vector<AnimationFrame> frames;
  frames.reserve(picks.size());
  for (const std::size_t k : picks) {
    const PatternSample& s = result.samples[k];
    AnimationFrame f;
    f.time_s = s.time_s;
    f.sample = k;
    const std::array<std::pair<const Mechanism*, const TactorSample*>, 2> mechs{
        {{&*station.upper, &s.upper}, {&*station.lower, &s.lower}}};
    for (std::size_t i = 0; i < 2; ++i) {
      const auto [m, ts] = mechs[i];
      if (ts->pose.status == Status::unreachable) continue;
      const Pose pose = fk(*m, ts->theta[0], ts->theta[1]);
      if (pose.status == Status::unreachable) continue;
      f.linkage[i] = {true, pose.A1, pose.P, pose.A2};
    }
    frames.push_back(f);
  }
  return frames;
}

std::string animate_pattern_svg(const Station& station, const PatternResult& result, const AnimationOptions& options) {
  const std::vector<AnimationFrame> frames = animation_frames(station, result, options.max_frames);
  const std::array<const Mechanism*, 2> mechs{&*station.upper, &*station.lower};
  const std::array<std::string, 2> colours{kUpper, kLower};
  const std::string pattern(to_string(result.spec.kind));

  // Simulated points per frame and mechanism: the last simulated sample at or before the frame.
  std::array<std::vector<std::optional<Vec2>>, 2> simulated;
  std::array<bool, 2> has_sim{false, false};
  for (std::size_t i = 0; i < 2; ++i) {
    for (const SimulatedTrack& track : options.simulated) {
      if (track.mechanism != mechs[i]->name || track.time_s.empty()) continue;
      has_sim[i] = true;
      for (const AnimationFrame& f : frames) {
        const auto it = std::upper_bound(track.time_s.begin(), track.time_s.end(), f.time_s + 1e-9);
        if (it == track.time_s.begin()) {
          simulated[i].emplace_back();
        } else {
          simulated[i].emplace_back(track.point_mm[static_cast<std::size_t>(it - track.time_s.begin()) - 1]);
        }
      }
      break;
    }
  }

  // The view: bases, every drawn joint, the target ellipse and the simulated points.
  double xmin = std::numeric_limits<double>::infinity(), ymin = xmin, xmax = -xmin, ymax = -xmin;
  const auto grow = [&](const Vec2& p) {
    xmin = std::min(xmin, p.x());
    xmax = std::max(xmax, p.x());
    ymin = std::min(ymin, p.y());
    ymax = std::max(ymax, p.y());
  };
  for (const Mechanism* m : mechs) {
    grow(m->O1);
    grow(m->O2);
  }
  for (const AnimationFrame& f : frames) {
    for (const auto& l : f.linkage) {
      if (!l.drawn) continue;
      grow(l.A1);
      grow(l.A2);
      grow(l.P);
    }
  }
  for (const auto& list : simulated) {
    for (const auto& p : list) {
      if (p) grow(*p);
    }
  }
  for (const Vec2& p : ellipse_polyline(station.target, 72)) grow(p);
  const double pad = 0.06 * std::max(xmax - xmin, ymax - ymin) + 0.5 * options.tactor_diameter_mm + 1.0;
  xmin -= pad;
  xmax += pad;
  ymin -= pad;
  ymax += pad;
  // The detail: every tactor point, target and simulated point, enlarged (at least 4 mm across).
  double dx0 = std::numeric_limits<double>::infinity(), dy0 = dx0, dx1 = -dx0, dy1 = -dx0;
  const auto grow_detail = [&](const Vec2& p) {
    dx0 = std::min(dx0, p.x());
    dx1 = std::max(dx1, p.x());
    dy0 = std::min(dy0, p.y());
    dy1 = std::max(dy1, p.y());
  };
  for (const AnimationFrame& f : frames) {
    for (const auto& l : f.linkage) {
      if (l.drawn) grow_detail(l.P);
    }
    grow_detail(result.samples[f.sample].upper.target);
    grow_detail(result.samples[f.sample].lower.target);
  }
  for (const auto& list : simulated) {
    for (const auto& p : list) {
      if (p) grow_detail(*p);
    }
  }
  for (double* lo_hi : {&dx0, &dy0}) {
    double& lo = *lo_hi;
    double& hi = lo_hi == &dx0 ? dx1 : dy1;
    const double grow_by = std::max(0.0, 4.0 - (hi - lo));
    lo -= 0.5 * grow_by;
    hi += 0.5 * grow_by;
  }
  const double dpad = 0.1 * std::max(dx1 - dx0, dy1 - dy0) + 0.5 * options.tactor_diameter_mm + 0.5;
  const double width = std::max(options.width_px, 360.0);
  const double inner = width - 3.0 * kSide;
  const double main_w = std::round(0.52 * inner);
  const double detail_w = inner - main_w;
  const double panel_h = std::round(std::min((ymax - ymin) * main_w / (xmax - xmin), 1.3 * main_w));
  const std::array<View, 2> views{
      View::fit(kSide, kHeader, main_w, panel_h, xmin, xmax, ymin, ymax),
      View::fit(2.0 * kSide + main_w, kHeader, detail_w, panel_h, dx0 - dpad, dx1 + dpad, dy0 - dpad, dy1 + dpad)};
  const double height = kHeader + panel_h + kFooter;
  const std::string id = options.id.empty() ? sanitise_id("fivebar-animation-" + station.name + "-" + pattern)
                                            : sanitise_id(options.id);

  // The frames as JSON (mm, s).
  Json data;
  data["station"] = station.name;
  data["pattern"] = pattern;
  data["rate_hz"] = result.spec.rate_hz;
  data["tactor_diameter_mm"] = options.tactor_diameter_mm;
  data["views"] = Json::array({views[0].to_json(), views[1].to_json()});
  Json times = Json::array();
  for (const AnimationFrame& f : frames) times.push_back(f.time_s);
  data["t_s"] = times;
  data["sample"] = Json::array();
  for (const AnimationFrame& f : frames) data["sample"].push_back(f.sample);
  data["mechanisms"] = Json::array();
  for (std::size_t i = 0; i < 2; ++i) {
    const Mechanism& m = *mechs[i];
    Json jm;
    jm["name"] = m.name;
    jm["O1"] = {r4(m.O1.x()), r4(m.O1.y())};
    jm["O2"] = {r4(m.O2.x()), r4(m.O2.y())};
    jm["links_mm"] = {m.L[0], m.L[1], m.L[2], m.L[3]};
    Json fs = Json::array(), targets = Json::array();
    for (const AnimationFrame& f : frames) {
      const auto& l = f.linkage[i];
      if (l.drawn) {
        fs.push_back({r4(l.A1.x()), r4(l.A1.y()), r4(l.P.x()), r4(l.P.y()), r4(l.A2.x()), r4(l.A2.y())});
      } else {
        fs.push_back(nullptr);
      }
      const TactorSample& ts = i == 0 ? result.samples[f.sample].upper : result.samples[f.sample].lower;
      targets.push_back({r4(ts.target.x()), r4(ts.target.y())});
    }
    jm["frames"] = fs;
    jm["targets"] = targets;
    if (has_sim[i]) {
      Json sim = Json::array();
      for (const auto& p : simulated[i]) {
        if (p) {
          sim.push_back({r4(p->x()), r4(p->y())});
        } else {
          sim.push_back(nullptr);
        }
      }
      jm["simulated"] = sim;
    }
    data["mechanisms"].push_back(jm);
  }

  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" id=\"" << id << "\" class=\"fivebar-animation\" width=\"" << num(width, 0)
    << "\" height=\"" << num(height, 0) << "\" viewBox=\"0 0 " << num(width, 0) << " " << num(height, 0)
    << "\" font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\">\n";
  o << "<title>" << format::xml_escape(pattern + " on station " + station.name) << "</title>\n";
  o << "<metadata class=\"fivebar-animation-data\">" << safe_json(data) << "</metadata>\n";
  o << "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n";
  // Header.
  const double duration = frames.back().time_s;
  o << "<text x=\"" << kSide << "\" y=\"24\" font-size=\"17\" font-weight=\"bold\" fill=\"" << kInk << "\">"
    << format::xml_escape(pattern + " — " + station.name) << "</text>\n";
  std::string verdict = result.passed ? "renderable" : "NOT renderable";
  if (result.first_failure) {
    verdict += ": " + std::string(to_string(result.first_failure->status)) + " at t = " +
               num(result.first_failure->time_s) + " s (" + result.first_failure->mechanism + ")";
  }
  o << "<text x=\"" << kSide << "\" y=\"44\" font-size=\"12\" fill=\"" << (result.passed ? "#1a8033" : "#bf1a1a") << "\">"
    << format::xml_escape(std::to_string(result.samples.size()) + " samples at " + format::shortest(result.spec.rate_hz) +
                  " Hz over " + num(duration) + " s at true speed; left the station, right the tactors' region; " + verdict)
    << "</text>\n";

  // The panels: nested viewports, so that whatever lies outside a view is clipped.
  const std::array<Region, 2> regions{reachable_region(*mechs[0]), reachable_region(*mechs[1])};
  const AnimationFrame& first = frames.front();
  for (std::size_t panel = 0; panel < 2; ++panel) {
    const View& view = views[panel];
    o << "<svg class=\"fivebar-panel\" x=\"" << num(view.x_px) << "\" y=\"" << num(view.y_px) << "\" width=\""
      << num(view.width_px) << "\" height=\"" << num(view.height_px) << "\" viewBox=\"0 0 " << num(view.width_px) << " "
      << num(view.height_px) << "\" overflow=\"hidden\">\n";
    o << "<rect width=\"100%\" height=\"100%\" fill=\"#fbfbfb\" stroke=\"#d9d9d9\"/>\n";
    for (std::size_t i = 0; i < 2; ++i) {
      o << "<path class=\"fivebar-region\" d=\"" << region_path_d(regions[i], view) << "\" fill=\"" << colours[i]
        << "\" fill-opacity=\"0.07\" fill-rule=\"evenodd\" stroke=\"" << colours[i]
        << "\" stroke-opacity=\"0.45\" stroke-width=\"1\"/>\n";
    }
    {
      std::string d;
      const std::vector<Vec2> e = ellipse_polyline(station.target, 180);
      for (std::size_t k = 0; k < e.size(); ++k) d += (k == 0 ? "M" : "L") + view.pt(e[k]);
      o << "<path class=\"fivebar-target-ellipse\" d=\"" << d << "Z\" fill=\"none\" stroke=\"" << kInk
        << "\" stroke-opacity=\"0.8\" stroke-width=\"1.3\" stroke-dasharray=\"6 4\"/>\n";
    }
    // The whole target path, faint, so that one sees where the tactors are going.
    for (std::size_t i = 0; i < 2; ++i) {
      std::string pts;
      for (const AnimationFrame& f : frames) {
        const TactorSample& ts = i == 0 ? result.samples[f.sample].upper : result.samples[f.sample].lower;
        pts += (pts.empty() ? "" : " ") + view.pt(ts.target);
      }
      o << "<polyline class=\"fivebar-target-path\" points=\"" << pts << "\" fill=\"none\" stroke=\"" << colours[i]
        << "\" stroke-opacity=\"0.3\" stroke-width=\"1.5\" stroke-dasharray=\"2 3\"/>\n";
    }
    const double tactor_r = options.tactor_diameter_mm > 0.0 ? 0.5 * options.tactor_diameter_mm * view.scale : 6.0;
    for (std::size_t i = 0; i < 2; ++i) {
      const Mechanism& m = *mechs[i];
      const auto& l = first.linkage[i];
      const std::string vis = l.drawn ? "visible" : "hidden";
      const std::string c = colours[i];
      o << "<g class=\"fivebar-mechanism fivebar-mechanism-" << m.name << "\" data-frame=\"0\">\n";
      if (has_sim[i]) {
        o << "<polyline class=\"fivebar-sim-trail\" points=\"\" fill=\"none\" stroke=\"" << kSimColour
          << "\" stroke-width=\"1.6\" stroke-dasharray=\"4 2\"/>\n";
      }
      o << "<polyline class=\"fivebar-link\" visibility=\"" << vis << "\" points=\""
        << (l.drawn ? view.pt(m.O1) + " " + view.pt(l.A1) + " " + view.pt(l.P) + " " + view.pt(l.A2) + " " + view.pt(m.O2) : "")
        << "\" fill=\"none\" stroke=\"" << c << "\" stroke-opacity=\"0.85\" stroke-width=\"4\" stroke-linejoin=\"round\" "
        << "stroke-linecap=\"round\"/>\n";
      for (const Vec2& base : {m.O1, m.O2}) {
        o << "<rect class=\"fivebar-base\" x=\"" << num(view.u(base.x()) - 6.0) << "\" y=\"" << num(view.v(base.y()) - 6.0)
          << "\" width=\"12\" height=\"12\" fill=\"" << kInk << "\" fill-opacity=\"0.8\"/>\n";
      }
      const auto joint = [&](const char* cls, const Vec2& p) {
        o << "<circle class=\"" << cls << "\" visibility=\"" << vis << "\" cx=\"" << num(view.u(p.x())) << "\" cy=\""
          << num(view.v(p.y())) << "\" r=\"4\" fill=\"#ffffff\" stroke=\"" << c << "\" stroke-width=\"1.5\"/>\n";
      };
      joint("fivebar-elbow1", l.A1);
      joint("fivebar-elbow2", l.A2);
      o << "<circle class=\"fivebar-tactor\" visibility=\"" << vis << "\" cx=\"" << num(view.u(l.P.x())) << "\" cy=\""
        << num(view.v(l.P.y())) << "\" r=\"" << num(tactor_r) << "\" fill=\"" << c << "\" fill-opacity=\"0.15\" stroke=\"" << c
        << "\" stroke-width=\"1.5\"/>\n";
      o << "<polyline class=\"fivebar-trail\" points=\"" << (l.drawn ? view.pt(l.P) : "") << "\" fill=\"none\" stroke=\"" << c
        << "\" stroke-width=\"3\" stroke-linejoin=\"round\" stroke-linecap=\"round\"/>\n";
      const TactorSample& ts0 = i == 0 ? result.samples[first.sample].upper : result.samples[first.sample].lower;
      o << "<circle class=\"fivebar-target\" cx=\"" << num(view.u(ts0.target.x())) << "\" cy=\"" << num(view.v(ts0.target.y()))
        << "\" r=\"2.2\" fill=\"" << kInk << "\"/>\n";
      if (has_sim[i]) {
        const auto& p = simulated[i].front();
        o << "<circle class=\"fivebar-sim\" visibility=\"" << (p ? "visible" : "hidden") << "\" cx=\""
          << (p ? num(view.u(p->x())) : "0") << "\" cy=\"" << (p ? num(view.v(p->y())) : "0") << "\" r=\""
          << num(std::max(3.5, 0.6 * tactor_r)) << "\" fill=\"none\" stroke=\"" << kSimColour << "\" stroke-width=\"2\"/>\n";
      }
      o << "</g>\n";
    }
    // A scale bar of a round length near 80 px, and what the panel shows.
    double bar_mm = 0.1;
    for (const double len : {0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0}) {
      if (std::abs(len * view.scale - 80.0) < std::abs(bar_mm * view.scale - 80.0)) bar_mm = len;
    }
    const double by = view.height_px - 12.0;
    o << "<line x1=\"10\" y1=\"" << num(by) << "\" x2=\"" << num(10.0 + bar_mm * view.scale) << "\" y2=\"" << num(by)
      << "\" stroke=\"" << kInk << "\" stroke-width=\"2\"/><text x=\"10\" y=\"" << num(by - 6.0)
      << "\" font-size=\"11\" fill=\"" << kInk << "\">" << format::shortest(bar_mm) << " mm</text>\n";
    const double zoom = views[1].scale / views[0].scale;
    const std::string what = panel == 0   ? "the station"
                             : zoom >= 1.0 ? "the tactors' region, " + num(zoom, 1) + "× enlarged"
                                           : "the tactors' region, at " + num(zoom, 1) + "× the station's scale";
    o << "<text x=\"10\" y=\"18\" font-size=\"11\" fill=\"" << kGrey << "\">" << format::xml_escape(what) << "</text>\n";
    o << "</svg>\n";
  }

  // Controls: play/pause, the slider, the time.
  const double cy = kHeader + panel_h + 24.0;
  const double sx0 = kSide + 46.0, sx1 = width - kSide - 150.0;
  o << "<g class=\"fivebar-button\" cursor=\"pointer\" role=\"button\" aria-label=\"play or pause\">\n"
    << "<rect x=\"" << kSide << "\" y=\"" << num(cy - 14.0) << "\" width=\"32\" height=\"28\" rx=\"5\" fill=\"#eef1f6\" stroke=\"#9aa5b8\"/>\n"
    << "<path class=\"fivebar-play-icon\" visibility=\"hidden\" d=\"M" << num(kSide + 12.0) << "," << num(cy - 8.0) << " L"
    << num(kSide + 23.0) << "," << num(cy) << " L" << num(kSide + 12.0) << "," << num(cy + 8.0) << "Z\" fill=\"" << kInk << "\"/>\n"
    << "<g class=\"fivebar-pause-icon\"><rect x=\"" << num(kSide + 10.0) << "\" y=\"" << num(cy - 8.0)
    << "\" width=\"4\" height=\"16\" fill=\"" << kInk << "\"/><rect x=\"" << num(kSide + 18.0) << "\" y=\"" << num(cy - 8.0)
    << "\" width=\"4\" height=\"16\" fill=\"" << kInk << "\"/></g>\n</g>\n";
  o << "<g class=\"fivebar-slider\" cursor=\"pointer\">\n"
    << "<rect x=\"" << num(sx0 - 8.0) << "\" y=\"" << num(cy - 14.0) << "\" width=\"" << num(sx1 - sx0 + 16.0)
    << "\" height=\"28\" fill=\"#ffffff\" fill-opacity=\"0\"/>\n"
    << "<line class=\"fivebar-track\" x1=\"" << num(sx0) << "\" y1=\"" << num(cy) << "\" x2=\"" << num(sx1) << "\" y2=\""
    << num(cy) << "\" stroke=\"#c8ced8\" stroke-width=\"6\" stroke-linecap=\"round\"/>\n"
    << "<line class=\"fivebar-progress\" x1=\"" << num(sx0) << "\" y1=\"" << num(cy) << "\" x2=\"" << num(sx0) << "\" y2=\""
    << num(cy) << "\" stroke=\"#5b7bb5\" stroke-width=\"6\" stroke-linecap=\"round\"/>\n"
    << "<circle class=\"fivebar-knob\" cx=\"" << num(sx0) << "\" cy=\"" << num(cy) << "\" r=\"8\" fill=\"#ffffff\" stroke=\"#3d5a8f\" stroke-width=\"2\"/>\n"
    << "</g>\n";
  o << "<text class=\"fivebar-time\" x=\"" << num(width - kSide) << "\" y=\"" << num(cy + 4.0)
    << "\" font-size=\"12\" text-anchor=\"end\" fill=\"" << kInk << "\">t = 0.00 / " << num(duration) << " s</text>\n";
  // Legend.
  const double ly = cy + 38.0;
  double lx = kSide;
  const auto swatch = [&](const std::string& colour, const char* dash, const std::string& label) {
    o << "<line x1=\"" << num(lx) << "\" y1=\"" << num(ly - 4.0) << "\" x2=\"" << num(lx + 24.0) << "\" y2=\"" << num(ly - 4.0)
      << "\" stroke=\"" << colour << "\" stroke-width=\"3\"" << (dash[0] ? std::string(" stroke-dasharray=\"") + dash + "\"" : "")
      << "/><text x=\"" << num(lx + 30.0) << "\" y=\"" << num(ly) << "\" font-size=\"11\" fill=\"" << kInk << "\">"
      << format::xml_escape(label) << "</text>\n";
    lx += 30.0 + 6.2 * static_cast<double>(label.size()) + 18.0;
  };
  swatch(kUpper, "", "upper linkage and tactor path");
  swatch(kLower, "", "lower linkage and tactor path");
  if (has_sim[0] || has_sim[1]) swatch(kSimColour, "4 2", "simulated tactor (dynamics)");
  o << "<text x=\"" << kSide << "\" y=\"" << num(ly + 17.0) << "\" font-size=\"11\" fill=\"" << kGrey
    << "\">shaded: reachable regions; dashed ellipse: fingertip target; dots: pattern targets; squares: motors</text>\n";

  std::string script = kScript;
  const std::string marker = "ROOT_ID";
  script.replace(script.find(marker), marker.size(), "'" + id + "'");
  o << "<script type=\"text/javascript\"><![CDATA[" << script << "]]></script>\n";
  o << "</svg>\n";
  return o.str();
}

}  // namespace fivebar
