// Animated pattern pictures (fivebar/animation.hpp): an SVG document written as text (cairo's SVG
// surface cannot carry a script), with the frames as JSON and a small player script.

#include "fivebar/animation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <sstream>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/json.hpp"
#include "fivebar/kinematics.hpp"
#include "fivebar/polyline.hpp"
#include "fivebar/workspace.hpp"

namespace fivebar {

namespace {

constexpr const char* kUpperColour = "#2961c7";  // as the pattern pictures (lib/src/plot/tactor_canvas.hpp)
constexpr const char* kLowerColour = "#d12e29";
constexpr const char* kInk = "#1f1f1f";
constexpr const char* kGrey = "#8c8c8c";
constexpr const char* kSimColour = "#1a8a3a";
constexpr double kSide = 16.0;     // px left and right of the panel
constexpr double kHeader = 58.0;   // title lines
constexpr double kFooter = 92.0;   // controls and legend

std::string num(double v, int digits = 2) { return format::fixed(v, digits); }

/// Millimetres rounded to 0.1 um for the JSON (shortest text of the rounded value).
double r4(double v) { return std::round(v * 1e4) / 1e4; }

std::string xml_escape(std::string_view s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

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

/// Station millimetres to the panel's pixels (y up to y down).
struct View {
  double xmin = 0.0, ymax = 0.0, scale = 1.0;
  double u(double x) const { return (x - xmin) * scale; }
  double v(double y) const { return (ymax - y) * scale; }
  std::string pt(const Vec2& p) const { return num(u(p.x())) + "," + num(v(p.y())); }
};

// The player: reads the frames, draws frame k, runs at true speed, seeks from the slider and the
// URL fragment. Written for XML (inside CDATA) and for an HTML page's inline SVG alike.
constexpr const char* kScript = R"JS(
(function () {
  var root = document.getElementById(ROOT_ID);
  if (!root || root.getAttribute('data-fivebar-ready')) return;
  root.setAttribute('data-fivebar-ready', '1');
  var D = JSON.parse(root.querySelector('.fivebar-animation-data').textContent);
  var T = D.t_s, n = T.length, dur = T[n - 1], V = D.view;
  function u(x) { return ((x - V.xmin_mm) * V.px_per_mm).toFixed(2); }
  function v(y) { return ((V.ymax_mm - y) * V.px_per_mm).toFixed(2); }
  var mechs = D.mechanisms.map(function (m) {
    var g = root.querySelector('.fivebar-mechanism-' + m.name);
    var pts = m.frames.map(function (f) { return f ? u(f[2]) + ',' + v(f[3]) : null; });
    var sim = m.simulated ? m.simulated.map(function (p) { return p ? u(p[0]) + ',' + v(p[1]) : null; }) : null;
    return { d: m, g: g, pts: pts, sim: sim, link: g.querySelector('.fivebar-link'),
             e1: g.querySelector('.fivebar-elbow1'), e2: g.querySelector('.fivebar-elbow2'),
             tactor: g.querySelector('.fivebar-tactor'), target: g.querySelector('.fivebar-target'),
             trail: g.querySelector('.fivebar-trail'), simDot: g.querySelector('.fivebar-sim'),
             simTrail: g.querySelector('.fivebar-sim-trail') };
  });
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
  function setCircle(c, x, y) { if (c) { c.setAttribute('cx', u(x)); c.setAttribute('cy', v(y)); } }
  function upTo(list, k) { var out = []; for (var i = 0; i <= k; ++i) if (list[i] !== null) out.push(list[i]); return out.join(' '); }
  function draw(k) {
    mechs.forEach(function (m) {
      var f = m.d.frames[k];
      m.g.setAttribute('data-frame', k);
      var vis = f ? 'visible' : 'hidden';
      [m.link, m.e1, m.e2, m.tactor].forEach(function (el) { el.setAttribute('visibility', vis); });
      if (f) {
        m.link.setAttribute('points', [u(m.d.O1[0]) + ',' + v(m.d.O1[1]), u(f[0]) + ',' + v(f[1]), u(f[2]) + ',' + v(f[3]),
                                       u(f[4]) + ',' + v(f[5]), u(m.d.O2[0]) + ',' + v(m.d.O2[1])].join(' '));
        setCircle(m.e1, f[0], f[1]); setCircle(m.e2, f[4], f[5]); setCircle(m.tactor, f[2], f[3]);
      }
      setCircle(m.target, m.d.targets[k][0], m.d.targets[k][1]);
      m.trail.setAttribute('points', upTo(m.pts, k));
      if (m.sim && m.simDot) {
        var s = m.d.simulated[k];
        m.simDot.setAttribute('visibility', s ? 'visible' : 'hidden');
        if (s) setCircle(m.simDot, s[0], s[1]);
        m.simTrail.setAttribute('points', upTo(m.sim, k));
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
    var p = root.createSVGPoint(); p.x = evt.clientX; p.y = evt.clientY;
    var m = root.getScreenCTM();
    return m ? p.matrixTransform(m.inverse()).x : p.x;
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
  const auto fail = [&](std::size_t line, const std::string& what) {
    throw InputError(std::string(name) + ":" + std::to_string(line) + ": " + what);
  };
  const auto split = [](const std::string& line) {
    std::vector<std::string> out;
    std::string cell;
    std::istringstream s(line);
    while (std::getline(s, cell, ',')) out.push_back(cell);
    if (!line.empty() && line.back() == ',') out.emplace_back();
    return out;
  };
  std::string line;
  if (!std::getline(in, line)) fail(1, "empty file: expected the time series header");
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const std::vector<std::string> header = split(line);
  const auto column = [&](const char* key) {
    const auto it = std::find(header.begin(), header.end(), key);
    if (it == header.end()) fail(1, std::string("no column ") + key + " in the header");
    return static_cast<std::size_t>(it - header.begin());
  };
  const std::size_t ct = column("t_s"), cm = column("mechanism"), cx = column("x_mm"), cy = column("y_mm");
  const std::size_t need = std::max({ct, cm, cx, cy}) + 1;
  std::vector<SimulatedTrack> tracks;
  std::map<std::string, std::size_t> index;
  std::size_t line_no = 1;
  const auto number = [&](const std::string& text, const char* key) {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v)) {
      fail(line_no, std::string(key) + " = '" + text.substr(0, 40) + "' is not a finite number");
    }
    return v;
  };
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const std::vector<std::string> cells = split(line);
    if (cells.size() < need) fail(line_no, "expected " + std::to_string(header.size()) + " fields");
    const double t = number(cells[ct], "t_s");
    const Vec2 p(number(cells[cx], "x_mm"), number(cells[cy], "y_mm"));
    auto [it, added] = index.emplace(cells[cm], tracks.size());
    if (added) tracks.push_back(SimulatedTrack{cells[cm], {}, {}});
    SimulatedTrack& track = tracks[it->second];
    if (!track.time_s.empty() && t < track.time_s.back()) fail(line_no, "t_s goes back in time");
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
  const std::array<const char*, 2> colours{kUpperColour, kLowerColour};
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
  const double width = std::max(options.width_px, 360.0);
  const double panel_w = width - 2.0 * kSide;
  View view{xmin, ymax, panel_w / (xmax - xmin)};
  double panel_h = (ymax - ymin) * view.scale;
  if (panel_h > 1.2 * width) {  // a tall view: fit the height instead
    view.scale *= 1.2 * width / panel_h;
    panel_h = 1.2 * width;
  }
  const double height = kHeader + panel_h + kFooter;
  const std::string id = options.id.empty() ? sanitise_id("fivebar-animation-" + station.name + "-" + pattern)
                                            : sanitise_id(options.id);

  // The frames as JSON (mm, s).
  Json data;
  data["station"] = station.name;
  data["pattern"] = pattern;
  data["rate_hz"] = result.spec.rate_hz;
  data["view"] = {{"xmin_mm", r4(view.xmin)}, {"ymax_mm", r4(view.ymax)}, {"px_per_mm", view.scale}};
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
  o << "<title>" << xml_escape(pattern + " on station " + station.name) << "</title>\n";
  o << "<metadata class=\"fivebar-animation-data\">" << safe_json(data) << "</metadata>\n";
  o << "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n";
  // Header.
  const double duration = frames.back().time_s;
  o << "<text x=\"" << kSide << "\" y=\"24\" font-size=\"17\" font-weight=\"bold\" fill=\"" << kInk << "\">"
    << xml_escape(pattern + " — " + station.name) << "</text>\n";
  std::string verdict = result.passed ? "renderable" : "NOT renderable";
  if (result.first_failure) {
    verdict += ": " + std::string(to_string(result.first_failure->status)) + " at t = " +
               num(result.first_failure->time_s) + " s (" + result.first_failure->mechanism + ")";
  }
  o << "<text x=\"" << kSide << "\" y=\"44\" font-size=\"12\" fill=\"" << (result.passed ? "#1a8033" : "#bf1a1a") << "\">"
    << xml_escape(std::to_string(result.samples.size()) + " samples at " + format::shortest(result.spec.rate_hz) +
                  " Hz over " + num(duration) + " s, shown at true speed; " + verdict)
    << "</text>\n";

  // The panel: a nested viewport, so that whatever lies outside the view is clipped.
  o << "<svg class=\"fivebar-panel\" x=\"" << kSide << "\" y=\"" << kHeader << "\" width=\"" << num(panel_w) << "\" height=\""
    << num(panel_h) << "\" viewBox=\"0 0 " << num(panel_w) << " " << num(panel_h) << "\" overflow=\"hidden\">\n";
  o << "<rect width=\"100%\" height=\"100%\" fill=\"#fbfbfb\" stroke=\"#d9d9d9\"/>\n";
  for (std::size_t i = 0; i < 2; ++i) {
    o << "<path class=\"fivebar-region\" d=\"" << region_path_d(reachable_region(*mechs[i]), view) << "\" fill=\""
      << colours[i] << "\" fill-opacity=\"0.07\" fill-rule=\"evenodd\" stroke=\"" << colours[i]
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
      << "\" stroke-opacity=\"0.25\" stroke-width=\"1.5\" stroke-dasharray=\"2 3\"/>\n";
  }
  const double tactor_r = options.tactor_diameter_mm > 0.0 ? 0.5 * options.tactor_diameter_mm * view.scale : 6.0;
  const AnimationFrame& first = frames.front();
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
    const auto joint = [&](const char* cls, const Vec2& p, double r, const std::string& fill, const std::string& stroke) {
      o << "<circle class=\"" << cls << "\" visibility=\"" << vis << "\" cx=\"" << num(view.u(p.x())) << "\" cy=\""
        << num(view.v(p.y())) << "\" r=\"" << num(r) << "\" fill=\"" << fill << "\" stroke=\"" << stroke
        << "\" stroke-width=\"1.5\"/>\n";
    };
    joint("fivebar-elbow1", l.A1, 4.0, "#ffffff", c);
    joint("fivebar-elbow2", l.A2, 4.0, "#ffffff", c);
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
  o << "</svg>\n";

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
  const auto swatch = [&](const char* colour, const char* dash, const std::string& label) {
    o << "<line x1=\"" << num(lx) << "\" y1=\"" << num(ly - 4.0) << "\" x2=\"" << num(lx + 24.0) << "\" y2=\"" << num(ly - 4.0)
      << "\" stroke=\"" << colour << "\" stroke-width=\"3\"" << (dash[0] ? std::string(" stroke-dasharray=\"") + dash + "\"" : "")
      << "/><text x=\"" << num(lx + 30.0) << "\" y=\"" << num(ly) << "\" font-size=\"11\" fill=\"" << kInk << "\">"
      << xml_escape(label) << "</text>\n";
    lx += 30.0 + 6.2 * static_cast<double>(label.size()) + 18.0;
  };
  swatch(kUpperColour, "", "upper linkage and tactor path");
  swatch(kLowerColour, "", "lower linkage and tactor path");
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
