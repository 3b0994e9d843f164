// A station's workspace analysed once for writing and reporting (fivebar/workspace/station.hpp).
#include "fivebar/workspace/station.hpp"

#include "fivebar/format.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "fivebar/error.hpp"

namespace fivebar {

namespace {

/// More samples than this per field is a mistake (a spacing typed in metres, say), not a request:
/// 4 million samples of every field take ~0.3 GB.
constexpr double kMaxSamples = 4.0e6;

std::array<double, 4> ellipse_bounds(const Ellipse& e) {
  // Axis-aligned half extents of a rotated ellipse with semi-axes a, b.
  const double a = 0.5 * e.axes.x(), b = 0.5 * e.axes.y();
  const double c = std::cos(e.angle), s = std::sin(e.angle);
  const double hx = std::hypot(a * c, b * s), hy = std::hypot(a * s, b * c);
  return {e.center.x() - hx, e.center.y() - hy, e.center.x() + hx, e.center.y() + hy};
}

void unite(std::array<double, 4>& into, const std::array<double, 4>& b) {
  into[0] = std::min(into[0], b[0]);
  into[1] = std::min(into[1], b[1]);
  into[2] = std::max(into[2], b[2]);
  into[3] = std::max(into[3], b[3]);
}

Json region_json(const Region& r) {
  return {{"area_mm2", r.area_mm2()},
          {"perimeter_mm", r.perimeter_mm()},
          {"components", r.components()},
          {"holes", r.holes()}};
}

}  // namespace

void WorkspaceOptions::validate() const {
  if (!(std::isfinite(spacing_mm) && spacing_mm > 0.0)) {
    std::ostringstream msg;
    msg << "spacing_mm = " << spacing_mm << " mm: must be a finite number > 0";
    throw InputError(msg.str());
  }
  if (!mechanism.empty() && mechanism != "lower" && mechanism != "upper") {
    throw InputError("mechanism '" + mechanism + "': expected lower or upper");
  }
}

const MechanismWorkspace* StationWorkspace::find(std::string_view mechanism) const {
  for (const auto& m : mechanisms)
    if (m.mechanism.name == mechanism) return &m;
  return nullptr;
}

StationWorkspace analyse_workspace(const Station& station, const WorkspaceOptions& options,
                                   const std::function<void(std::string_view)>& progress) {
  options.validate();
  auto say = [&](const std::string& message) {
    if (progress) progress(message);
  };
  StationWorkspace out;
  out.station = station.name;
  out.target = station.target;

  std::vector<const Mechanism*> chosen;
  for (const Mechanism* m : station.mechanisms())
    if (options.mechanism.empty() || m->name == options.mechanism) chosen.push_back(m);
  if (!options.mechanism.empty() && chosen.empty()) {
    throw InputError("station '" + station.name + "' has no " + options.mechanism + " mechanism");
  }

  std::array<double, 4> bounds = ellipse_bounds(station.target);
  for (const Mechanism* m : chosen) {
    say(station.name + "/" + m->name + ": exact region");
    MechanismWorkspace w{*m, reachable_region(*m), {}, {}, {}, ik(*m, station.target.center)};
    if (!w.region.empty()) unite(bounds, w.region.bounds());
    out.mechanisms.push_back(std::move(w));
  }
  const double h = options.spacing_mm;
  const double width = bounds[2] - bounds[0], height = bounds[3] - bounds[1];
  // Coarser than the workspace itself samples nothing (and a margin of 2h would dwarf it).
  if (h > std::max(width, height)) {
    std::ostringstream msg;
    msg << "spacing " << h << " mm is larger than the " << width << " x " << height << " mm workspace of station '"
        << station.name << "': use a finer spacing";
    throw InputError(msg.str());
  }
  const double samples = (width / h + 5.0) * (height / h + 5.0);
  if (samples > kMaxSamples) {
    const std::string count = format::general(samples, 3);  // a double: it may exceed every integer type
    std::ostringstream msg;
    msg << "spacing " << h << " mm needs about " << count << " samples per field over the "
        << (bounds[2] - bounds[0]) << " x " << (bounds[3] - bounds[1]) << " mm workspace of station '" << station.name
        << "' (at most " << std::llround(kMaxSamples) << "): use a coarser spacing";
    throw InputError(msg.str());
  }
  out.grid = Grid::covering(bounds, h, 2.0 * h);

  for (MechanismWorkspace& w : out.mechanisms) {
    const std::string label = station.name + "/" + w.mechanism.name;
    say(label + ": fields on " + std::to_string(out.grid.nx) + " x " + std::to_string(out.grid.ny) + " samples");
    w.field = sample_field(w.mechanism, out.grid);
    say(label + ": assembly-restricted region");
    w.assembly = restricted_area(w.mechanism, Restriction::assembly, out.grid);
    say(label + ": LCI-restricted region");
    w.lci = restricted_area(w.mechanism, Restriction::lci, out.grid);
  }
  if (out.mechanisms.size() == 2) {
    say(station.name + ": shared region");
    out.shared = out.mechanisms[0].region.intersection(out.mechanisms[1].region);
  }
  return out;
}

Json to_json(const StationWorkspace& ws) {
  Json j;
  j["station"] = ws.station;
  j["target"] = to_json(ws.target);
  j["grid"] = {{"origin_mm", {ws.grid.x0, ws.grid.y0}},
               {"spacing_mm", ws.grid.spacing},
               {"nx", ws.grid.nx},
               {"ny", ws.grid.ny}};
  Json mechanisms = Json::array();
  for (const MechanismWorkspace& w : ws.mechanisms) {
    Json m = {{"mechanism", w.mechanism.name}};
    m.update(region_json(w.region));
    if (w.region.empty()) {
      m["bounds_mm"] = nullptr;
    } else {
      const auto b = w.region.bounds();
      m["bounds_mm"] = {{b[0], b[1]}, {b[2], b[3]}};
    }
    m["assembly_area_mm2"] = w.assembly.area_mm2;
    m["assembly_error_mm2"] = w.assembly.error_mm2;
    m["lci_area_mm2"] = w.lci.area_mm2;
    m["lci_error_mm2"] = w.lci.error_mm2;
    m["min_lci"] = w.mechanism.min_lci;
    double best = 0.0;
    for (std::size_t k = 0; k < w.field.lci.size(); ++k)
      if (w.field.reach[k] != 0) best = std::max(best, w.field.lci[k]);
    m["max_lci_sampled"] = best;
    mechanisms.push_back(std::move(m));
  }
  j["mechanisms"] = mechanisms;
  j["shared"] = ws.shared ? region_json(*ws.shared) : Json(nullptr);
  return j;
}

std::vector<std::string> WorkspaceFileNames::all() const {
  std::vector<std::string> out{vtp};
  out.insert(out.end(), vti.begin(), vti.end());
  out.push_back(svg);
  out.push_back(png);
  return out;
}

WorkspaceFileNames workspace_file_names(const StationWorkspace& ws) {
  WorkspaceFileNames n;
  n.vtp = ws.station + "-regions.vtp";
  for (const auto& m : ws.mechanisms) n.vti.push_back(ws.station + "-" + m.mechanism.name + "-field.vti");
  n.svg = ws.station + "-workspace.svg";
  n.png = ws.station + "-workspace.png";
  return n;
}

}  // namespace fivebar
