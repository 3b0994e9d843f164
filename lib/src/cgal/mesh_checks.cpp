// Mesh checks of printed parts with CGAL Polygon_mesh_processing: the only CGAL 3-D translation
// unit. The triangles go into a Surface_mesh as they are (no repair, no re-orientation), so every
// defect of the file is seen: a soup that is not an oriented 2-manifold, border edges, faces that
// intersect, inward normals, empty volume, extra shells.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <sstream>

#include "fivebar/parts.hpp"

namespace fivebar {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point3 = Kernel::Point_3;
using Mesh = CGAL::Surface_mesh<Point3>;
namespace PMP = CGAL::Polygon_mesh_processing;
}  // namespace

MeshCheck check_mesh(const TriangleMesh& input, std::size_t expected_components) {
  MeshCheck c;
  c.vertices = input.vertices.size();
  c.triangles = input.triangles.size();
  if (!input.vertices.empty()) {
    c.bbox_min_mm = input.bbox_min();
    c.bbox_max_mm = input.bbox_max();
  }
  if (input.triangles.empty()) {
    c.problems.push_back("the mesh has no triangles");
    return c;
  }

  std::vector<Point3> points;
  points.reserve(input.vertices.size());
  for (const auto& v : input.vertices) points.emplace_back(v.x(), v.y(), v.z());
  std::vector<std::vector<std::size_t>> polygons;
  polygons.reserve(input.triangles.size());
  for (const auto& t : input.triangles) polygons.push_back({t[0], t[1], t[2]});

  if (!PMP::is_polygon_soup_a_polygon_mesh(polygons)) {
    c.problems.push_back(
        "not an oriented 2-manifold: some edge is shared by more than two triangles, used twice in the "
        "same direction, or a vertex is non-manifold");
    return c;
  }
  c.manifold = true;
  Mesh mesh;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, mesh);

  c.closed = CGAL::is_closed(mesh);
  if (!c.closed) {
    std::size_t border = 0;
    for (auto h : mesh.halfedges()) {
      if (mesh.is_border(h)) ++border;
    }
    c.problems.push_back("not closed: " + std::to_string(border) + " border edges (the part has a gap)");
  }
  c.self_intersects = PMP::does_self_intersect(mesh);
  if (c.self_intersects) c.problems.push_back("self-intersecting (or degenerate) triangles");

  auto component = mesh.add_property_map<Mesh::Face_index, std::size_t>("f:component", 0).first;
  c.components = PMP::connected_components(mesh, component);
  if (c.components != expected_components) {
    c.problems.push_back(std::to_string(c.components) + " separate shells, expected " +
                         std::to_string(expected_components));
  }

  if (c.closed) {
    c.outward = PMP::is_outward_oriented(mesh);
    if (!c.outward) c.problems.push_back("normals point inward (inside-out part)");
    c.volume_mm3 = CGAL::to_double(PMP::volume(mesh));
    if (!(c.volume_mm3 > 0.0)) {
      std::ostringstream s;
      s << "enclosed volume " << c.volume_mm3 << " mm^3 is not positive";
      c.problems.push_back(s.str());
    }
  } else {
    c.problems.push_back("orientation and volume not checked: the mesh is not closed");
  }
  return c;
}

}  // namespace fivebar
