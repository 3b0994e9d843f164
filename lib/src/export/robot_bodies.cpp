// The rigid bodies of a station for the URDF and the MJCF (robot_bodies.hpp).

#include "export/robot_bodies.hpp"

#include <algorithm>
#include <map>

#include "fivebar/error.hpp"
#include "fivebar/parts.hpp"
#include "fivebar/sections/print.hpp"

namespace fivebar::detail {

namespace {

/// The plate approximation of the out-of-plane components (fivebar/export/urdf.hpp).
Body plate(const LinkInertia& l, double width, double thickness) {
  Body b;
  b.mass_kg = l.mass_kg;
  b.com_mm = Eigen::Vector3d(l.com_mm.x(), l.com_mm.y(), 0.5 * thickness);
  const double ixx = l.mass_kg * (width * width + thickness * thickness) / 12.0;
  const double iyy = l.izz_kg_mm2 - l.mass_kg * width * width / 12.0 + l.mass_kg * thickness * thickness / 12.0;
  b.inertia_kg_mm2.diagonal() << ixx, iyy, l.izz_kg_mm2;
  return b;
}

Body from_mesh(const std::filesystem::path& file, double density) {
  const MassProperties p = mass_properties(read_stl(file), density);
  Body b;
  b.mass_kg = p.mass_kg;
  b.com_mm = p.com_mm;
  b.inertia_kg_mm2 = p.inertia_kg_mm2;
  return b;
}

/// The STL of every piece of `mechanism` ("L1" ... "tactor") and of "base", from a parts report.
std::map<std::string, std::string> stl_by_use(const Json& parts, const Station& station, const std::string& mechanism) {
  std::map<std::string, std::string> out;
  const Json& list = parts.contains("parts") ? parts["parts"] : parts;
  for (const Json& p : list) {
    if (!p.is_object() || p.value("station", "") != station.name || !p.contains("uses") || !p.contains("stl") ||
        !p["stl"].is_string()) {
      continue;
    }
    for (const Json& use : p["uses"]) {
      const std::string u = use.get<std::string>();
      const std::string prefix = mechanism + "/";
      if (u.rfind(prefix, 0) == 0) out[u.substr(prefix.size())] = p["stl"].get<std::string>();
      if (u == "base") out["base"] = p["stl"].get<std::string>();
    }
  }
  return out;
}

/// The base plate's closed form (robot_bodies.hpp): a box of the printing density.
void plate_base(StationBodies& out, const Station& station, const PartsHardware& hw, double density_g_cm3) {
  Eigen::Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
  for (const Mechanism* m : station.mechanisms()) {
    for (const Vec2& O : {m->O1, m->O2}) {
      lo = lo.cwiseMin(Eigen::Vector2d(O.x(), O.y()));
      hi = hi.cwiseMax(Eigen::Vector2d(O.x(), O.y()));
    }
  }
  const double grow = 0.5 * hw.motor_diameter + hw.base_margin;
  const Eigen::Vector3d size(hi.x() - lo.x() + 2.0 * grow, hi.y() - lo.y() + 2.0 * grow, hw.base_plate_thickness);
  out.base_plate_size_mm = size;
  out.base_plate_centre_mm = Eigen::Vector3d(0.5 * (lo.x() + hi.x()), 0.5 * (lo.y() + hi.y()), -0.5 * size.z());
  Body& b = out.base;
  b.mass_kg = density_g_cm3 * 1e-6 * size.x() * size.y() * size.z();  // 1 g/cm^3 = 1e-6 kg/mm^3
  b.com_mm = out.base_plate_centre_mm;
  const double m = b.mass_kg;
  b.inertia_kg_mm2.diagonal() << m * (size.y() * size.y() + size.z() * size.z()) / 12.0,
      m * (size.x() * size.x() + size.z() * size.z()) / 12.0, m * (size.x() * size.x() + size.y() * size.y()) / 12.0;
}

}  // namespace

StationBodies station_bodies(const Design& design, const Station& station, const UrdfOptions& options) {
  const Geometry* gp = design.get<Geometry>();
  if (gp == nullptr) throw InputError("the URDF and the MJCF need the design's `geometry:` section (the links' outlines and masses)");
  const Geometry& g = *gp;
  const PrintSettings print = design.get<PrintSettings>() ? *design.get<PrintSettings>() : PrintSettings{};
  const PartsHardware hw;
  StationBodies out;
  out.hub_height_mm = hw.hub_height;
  out.link_thickness_mm = g.link_thickness;
  out.layer_gap_mm = g.layer_gap;
  // The renders when the report has every piece of the station; the closed form otherwise (say why).
  const Json* parts = options.parts;
  std::map<std::string, MechanismInertia> inertia;
  try {
    inertia = station_inertia(design, station, parts, options.parts_dir);
  } catch (const InputError& e) {
    if (parts == nullptr) throw;
    out.parts_problem = e.what();
    parts = nullptr;
    inertia = station_inertia(design, station, nullptr, options.parts_dir);
  }
  for (const Mechanism* mech : station.mechanisms()) {
    std::map<std::string, std::string> stl;
    if (parts != nullptr) {
      stl = stl_by_use(*parts, station, mech->name);
      if (auto it = stl.find("base"); it != stl.end()) {
        out.base_mesh = options.mesh_prefix + "/" + it->second;
        out.base_mesh_rel = it->second;
      }
    }
    MechanismBodies mb;
    mb.mechanism = mech;
    mb.inertia = inertia.at(mech->name);
    const MechanismInertia& in = mb.inertia;
    mb.from_stl = in.source == MassSource::stl;
    for (std::size_t i = 0; i < 4; ++i) {
      const std::string use = "L" + std::to_string(i + 1);
      if (mb.from_stl && stl.count(use) != 0) {
        mb.links[i] = from_mesh(options.parts_dir / stl.at(use), print.density_g_cm3);
        mb.links[i].mesh = options.mesh_prefix + "/" + stl.at(use);
        mb.links[i].mesh_rel = stl.at(use);
      } else {
        mb.links[i] = plate(in.links[i], g.link_width[i], g.link_thickness);
      }
    }
    const double tip_height = hw.tip_flange_height + hw.tip_dome_height;
    mb.post_height_mm = std::max(0.0, g.tactor_height - tip_height);
    mb.tip_height_mm = tip_height;
    if (mb.from_stl && stl.count("tactor") != 0) {
      mb.tip = from_mesh(options.parts_dir / stl.at("tactor"), print.density_g_cm3);
      mb.tip.mesh = options.mesh_prefix + "/" + stl.at("tactor");
      mb.tip.mesh_rel = stl.at("tactor");
    } else {
      // A disc of the tactor's diameter (closed_form_inertia(): flange, half the dome, the peg).
      const double r = 0.5 * g.tactor_diameter;
      const double h = tip_height;
      mb.tip.mass_kg = in.tip_mass_kg;
      mb.tip.com_mm = Eigen::Vector3d(0.0, 0.0, 0.25 * h);
      const double side = in.tip_mass_kg * (3.0 * r * r + h * h) / 12.0;
      mb.tip.inertia_kg_mm2.diagonal() << side, side, in.tip_izz_kg_mm2;
    }
    out.mechanisms.push_back(std::move(mb));
  }
  plate_base(out, station, hw, print.density_g_cm3);
  if (!out.base_mesh_rel.empty()) {
    const std::string mesh = out.base_mesh, rel = out.base_mesh_rel;
    out.base = from_mesh(options.parts_dir / rel, print.density_g_cm3);
    out.base.mesh = mesh;
    out.base.mesh_rel = rel;
    out.base_from_stl = true;
  }
  return out;
}

void add_station_meshes(const StationBodies& bodies, std::vector<std::string>& meshes) {
  const auto add = [&](const Body& b) {
    if (!b.mesh_rel.empty() && std::find(meshes.begin(), meshes.end(), b.mesh_rel) == meshes.end()) meshes.push_back(b.mesh_rel);
  };
  add(bodies.base);
  for (const MechanismBodies& mb : bodies.mechanisms) {
    for (const Body& b : mb.links) add(b);
    add(mb.tip);
  }
}

}  // namespace fivebar::detail
