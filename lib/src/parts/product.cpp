// The `parts` product: OpenSCAD sources, STL renders, mesh and design-intent checks and the bill
// of materials of every station in the scene, into <scene>/parts/ (fivebar/parts.hpp).

#include "fivebar/parts.hpp"
#include "fivebar/numerics.hpp"
#include "products/markdown.hpp"
#include "products/product.hpp"

namespace fivebar::products {

namespace {

std::string holes_text(const PartResult& p) {
  std::string out;
  for (std::size_t i = 0; i < p.spec.holes.size(); ++i) {
    const HoleSpec& h = p.spec.holes[i];
    out += out.empty() ? "" : ", ";
    out += h.label + " Ø" + (i < p.holes.size() && p.holes[i].found ? md::fixed(p.holes[i].diameter_mm, 3) : "?") +
           "/" + md::fixed(h.diameter_mm, 3);
  }
  return out;
}

std::string markdown(const PartsReport& r) {
  std::string out =
      "Printable parts for resin, one OpenSCAD file each (`parts/<station>/<part>.scad`, using the library "
      "copy `parts/scad/fivebar.scad`), rendered to binary STL with `openscad --hardwarnings` and checked: the "
      "mesh is closed, free of self-intersections, outward oriented, of positive volume and one shell; on the "
      "mesh, each hole's axis and narrowest diameter (design: pin + 2 × clearance) and each link's pin-centre "
      "distance (design: its length) are measured by fitting circles to the hole walls and must agree within " +
      md::fixed(tol::kPartDimensionMm, 2) +
      " mm. Identical pieces are one part with a count. Bill of materials: `parts/bom.csv`.\n\n";
  md::Table t({"station", "part", "pieces", "count", "length (mm)", "measured centre distance (mm)",
               "holes Ø measured/design (mm)", "volume (mm³)", "resin (ml)", "bbox (mm)", "render", "checks"},
              "llllrrlrrlll");
  for (const PartResult& p : r.parts) {
    std::string render(to_string(p.render));
    if (p.render == RenderState::rendered) {
      render += p.copied_from.empty() ? " (" + md::fixed(p.render_seconds, 1) + " s)" : " (copy of " + p.copied_from + ")";
    }
    std::string bbox = "—";
    if (p.mesh) {
      const Eigen::Vector3d e = p.mesh->bbox_max_mm - p.mesh->bbox_min_mm;
      bbox = md::fixed(e.x(), 2) + " × " + md::fixed(e.y(), 2) + " × " + md::fixed(e.z(), 2);
    }
    std::string uses;
    for (const auto& u : p.spec.uses) uses += (uses.empty() ? "" : ", ") + u;
    const bool link = p.spec.kind == PartKind::proximal_link || p.spec.kind == PartKind::distal_link;
    t.row({p.spec.station, md::code(p.spec.name), uses, std::to_string(p.spec.count),
           link ? md::fixed(p.spec.length_mm, 3) : "—",
           p.centre_distance_mm ? md::fixed(*p.centre_distance_mm, 4) : "—", holes_text(p),
           p.mesh ? md::fixed(p.mesh->volume_mm3, 1) : "—",
           p.mesh ? md::fixed(p.spec.count * p.mesh->volume_mm3 / 1000.0, 3) : "—", bbox, render,
           p.passed() ? "✓" : "✗"});
  }
  out += t.str() + "\n";
  out += "Resin for one set of the parts above: " + md::fixed(r.resin_ml(), 2) + " ml (without supports). " +
         std::to_string(r.count(RenderState::rendered)) + " rendered, " +
         std::to_string(r.count(RenderState::up_to_date)) + " up to date (inputs unchanged), " +
         std::to_string(r.count(RenderState::failed)) + " failed; " + md::fixed(r.wall_seconds, 1) + " s in all.\n\n";
  for (const PartResult& p : r.parts) {
    for (const auto& problem : p.problems) out += "- ✗ " + p.spec.label() + ": " + problem + "\n";
  }
  return out;
}

}  // namespace

Product parts_product() {
  Product p;
  p.name = "parts";
  p.title = "Printable parts";
  p.cost_s = 2.2;  // the openscad renders (scheduler hint only, Product::cost_s)
  p.unavailable = [](const Design& d) -> std::optional<std::string> {
    if (!d.get<Geometry>()) return "no `geometry:` section (link widths, pins, bosses, tactor sizes)";
    bool any = false;
    for (const Station& s : d.stations) any = any || !s.mechanisms().empty();
    if (!any) return "no station has a mechanism";
    if (!find_openscad()) return "openscad is not installed (Debian: apt-get install openscad)";
    return std::nullopt;
  };
  p.build = [](Context& ctx) {
    PartsOptions options;
    options.out_dir = ctx.dir / "parts";
    options.progress = ctx.progress;
    const PartsReport report = build_parts(ctx.design, options);
    for (const auto& f : report.files) ctx.record(std::filesystem::path("parts") / f);
    Built b;
    b.result = to_json(report);
    b.result["out_dir"] = "parts";
    b.markdown = markdown(report);
    b.passed = report.passed();
    std::size_t failed = 0;
    for (const auto& part : report.parts) failed += part.passed() ? 0 : 1;
    b.check = b.passed ? std::to_string(report.parts.size()) + " parts: meshes watertight, pin centres and holes as " +
                             "designed; " + md::fixed(report.resin_ml(), 1) + " ml of resin"
                       : std::to_string(failed) + " of " + std::to_string(report.parts.size()) +
                             " parts fail their render, mesh or fit checks";
    return b;
  };
  return p;
}

}  // namespace fivebar::products
