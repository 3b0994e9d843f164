// VTK XML documents of a station's workspace (fivebar/workspace/io.hpp): the only translation
// unit that speaks VTK. Documents are produced in memory (vtkXMLWriter's output string) so that
// the caller writes them atomically like every other file.
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkImageData.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkStringArray.h>
#include <vtkUnsignedCharArray.h>
#include <vtkXMLImageDataWriter.h>
#include <vtkXMLPolyDataWriter.h>

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include "fivebar/atlas.hpp"
#include "fivebar/error.hpp"
#include "fivebar/control.hpp"
#include "fivebar/io.hpp"
#include "fivebar/workspace/io.hpp"

namespace fivebar {

namespace {

/// Inline base64 with zlib: the document stays well-formed XML (appended raw data would not be)
/// and ParaView reads it as fast.
template <class Writer>
std::string write_document(Writer* writer, const char* what) {
  writer->SetDataModeToBinary();
  writer->SetCompressorTypeToZLib();
  writer->WriteToOutputStringOn();
  if (writer->Write() == 0) throw IoError(std::string("VTK could not produce the ") + what + " document");
  return writer->GetOutputString();
}

class CurveBuilder {
 public:
  CurveBuilder() {
    points_->SetDataTypeToDouble();  // the default float would cost 1e-7 mm at 10 mm
    kind_->SetName("kind");
    mechanism_->SetName("mechanism_id");
    loop_->SetName("loop_index");
    hole_->SetName("hole");
  }

  void add(const std::vector<Vec2>& points, bool closed, CurveKind kind, int mechanism_id, int loop_index,
           bool hole) {
    if (points.size() < 2) return;
    const vtkIdType first = points_->GetNumberOfPoints();
    for (const Vec2& p : points) points_->InsertNextPoint(p.x(), p.y(), 0.0);
    const vtkIdType n = vtkIdType(points.size());
    lines_->InsertNextCell(static_cast<int>(closed ? n + 1 : n));
    for (vtkIdType k = 0; k < n; ++k) lines_->InsertCellPoint(first + k);
    if (closed) lines_->InsertCellPoint(first);
    kind_->InsertNextValue(static_cast<int>(kind));
    mechanism_->InsertNextValue(mechanism_id);
    loop_->InsertNextValue(loop_index);
    hole_->InsertNextValue(hole ? 1 : 0);
  }

  void add_region(const Region& region, CurveKind kind, int mechanism_id) {
    int index = 0;
    for (const BoundaryLoop& loop : region.loops()) add(discretise(loop), true, kind, mechanism_id, index++, loop.hole);
  }

  void add_contours(const SampledArea& area, CurveKind kind, int mechanism_id, double spacing) {
    int index = 0;
    // Adjacent cells bisect a shared edge from opposite ends: the ends agree to ~1e-12 of a cell.
    for (const Polyline& c : chain_segments(area.contours, 1e-6 * spacing))
      add(c.points, c.closed, kind, mechanism_id, index++, false);
  }

  vtkNew<vtkPolyData> finish(const StationWorkspace& ws) {
    vtkNew<vtkPolyData> poly;
    poly->SetPoints(points_);
    poly->SetLines(lines_);
    poly->GetCellData()->AddArray(kind_);
    poly->GetCellData()->AddArray(mechanism_);
    poly->GetCellData()->AddArray(loop_);
    poly->GetCellData()->AddArray(hole_);
    poly->GetCellData()->SetActiveScalars("kind");
    vtkNew<vtkStringArray> kinds;
    kinds->SetName("kind_names");
    for (CurveKind k : {CurveKind::region, CurveKind::shared, CurveKind::target, CurveKind::assembly_contour,
                        CurveKind::lci_contour})
      kinds->InsertNextValue(to_string(k));
    vtkNew<vtkStringArray> mechanisms;
    mechanisms->SetName("mechanism_names");  // index = mechanism_id
    mechanisms->InsertNextValue("lower");
    mechanisms->InsertNextValue("upper");
    vtkNew<vtkStringArray> station;
    station->SetName("station");
    station->InsertNextValue(ws.station);
    poly->GetFieldData()->AddArray(kinds);
    poly->GetFieldData()->AddArray(mechanisms);
    poly->GetFieldData()->AddArray(station);
    return poly;
  }

 private:
  vtkNew<vtkPoints> points_;
  vtkNew<vtkCellArray> lines_;
  vtkNew<vtkIntArray> kind_;
  vtkNew<vtkIntArray> mechanism_;
  vtkNew<vtkIntArray> loop_;
  vtkNew<vtkUnsignedCharArray> hole_;
};

int mechanism_id(const Mechanism& m) { return m.name == "upper" ? 1 : 0; }

template <class Array, class T>
void add_point_array(vtkImageData* image, const char* name, const std::vector<T>& values) {
  vtkNew<Array> a;
  a->SetName(name);
  a->SetNumberOfComponents(1);
  a->SetNumberOfTuples(vtkIdType(values.size()));
  for (std::size_t k = 0; k < values.size(); ++k) a->SetValue(vtkIdType(k), values[k]);
  image->GetPointData()->AddArray(a);
}

/// Image data of nx x ny points from (x0, y0) at `spacing` mm (z = 0).
void shape_image(vtkImageData* image, double x0, double y0, double spacing, int nx, int ny) {
  image->SetDimensions(nx, ny, 1);
  image->SetOrigin(x0, y0, 0.0);
  image->SetSpacing(spacing, spacing, spacing);
}

/// The field data array `status_names`: index = Status value.
void add_status_names(vtkImageData* image) {
  vtkNew<vtkStringArray> status_names;
  status_names->SetName("status_names");
  for (Status s : {Status::ok, Status::unreachable, Status::singular_type1, Status::singular_type2})
    status_names->InsertNextValue(std::string(to_string(s)));
  image->GetFieldData()->AddArray(status_names);
}

/// The `.vti` document of `image`.
std::string image_document(vtkImageData* image) {
  vtkNew<vtkXMLImageDataWriter> writer;
  writer->SetInputData(image);
  return write_document(writer.Get(), ".vti");
}

}  // namespace

std::string regions_vtp(const StationWorkspace& ws) {
  CurveBuilder b;
  for (const MechanismWorkspace& w : ws.mechanisms) b.add_region(w.region, CurveKind::region, mechanism_id(w.mechanism));
  if (ws.shared) b.add_region(*ws.shared, CurveKind::shared, -1);
  b.add(ellipse_polyline(ws.target), true, CurveKind::target, -1, 0, false);
  for (const MechanismWorkspace& w : ws.mechanisms) {
    b.add_contours(w.assembly, CurveKind::assembly_contour, mechanism_id(w.mechanism), ws.grid.spacing);
    b.add_contours(w.lci, CurveKind::lci_contour, mechanism_id(w.mechanism), ws.grid.spacing);
  }
  vtkNew<vtkPolyData> poly = b.finish(ws);
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetInputData(poly);
  return write_document(writer.Get(), ".vtp");
}

std::string field_vti(const WorkspaceField& f) {
  const Grid& g = f.grid;
  vtkNew<vtkImageData> image;
  shape_image(image, g.x0, g.y0, g.spacing, g.nx, g.ny);
  // VTK's point order (x fastest, then y) is WorkspaceField's row-major j * nx + i.
  add_point_array<vtkUnsignedCharArray>(image, "reach", f.reach);
  add_point_array<vtkUnsignedCharArray>(image, "status", f.status);
  add_point_array<vtkUnsignedCharArray>(image, "assembly_ok", f.assembly_ok);
  add_point_array<vtkDoubleArray>(image, "lci", f.lci);
  add_point_array<vtkDoubleArray>(image, "type1_distance_mm", f.type1_distance_mm);
  add_point_array<vtkDoubleArray>(image, "type1_sin", f.type1_sin);
  add_point_array<vtkDoubleArray>(image, "type2_sin", f.type2_sin);
  add_point_array<vtkDoubleArray>(image, "transmission_deg", f.transmission_deg);
  add_point_array<vtkDoubleArray>(image, "force_capability", f.force_capability);
  image->GetPointData()->SetActiveScalars("lci");
  add_status_names(image);
  return image_document(image);
}

std::string image_vti(const ImageField& f) {
  const std::size_t n = static_cast<std::size_t>(std::max(f.nx, 0)) * static_cast<std::size_t>(std::max(f.ny, 0));
  for (const auto& [name, values] : f.arrays) {
    if (values.size() != n) {
      throw InputError("image field '" + name + "': " + std::to_string(values.size()) + " values for a " +
                       std::to_string(f.nx) + " x " + std::to_string(f.ny) + " grid");
    }
  }
  vtkNew<vtkImageData> image;
  shape_image(image, f.x0, f.y0, f.spacing, f.nx, f.ny);
  for (const auto& [name, values] : f.arrays) add_point_array<vtkDoubleArray>(image, name.c_str(), values);
  if (!f.arrays.empty()) image->GetPointData()->SetActiveScalars(f.arrays.front().first.c_str());
  return image_document(image);
}

// The stability field of fivebar/control.hpp (declared there; VTK stays in this file).
std::string rho_field_vti(const RhoField& f) {
  const Grid& g = f.grid;
  vtkNew<vtkImageData> image;
  shape_image(image, g.x0, g.y0, g.spacing, g.nx, g.ny);
  add_point_array<vtkDoubleArray>(image, "rho", f.rho);
  add_point_array<vtkUnsignedCharArray>(image, "status", f.status);  // 255: outside the joint limits
  image->GetPointData()->SetActiveScalars("rho");
  add_status_names(image);
  return image_document(image);
}

// The performance atlas of fivebar/atlas.hpp (declared there; VTK stays in this file): chart
// coordinates as x, y; figures NaN where the status is not ok.
std::string atlas_vti(const Atlas& a) {
  const std::size_t n = a.cells.size();
  std::vector<double> scale(n), height(n), lci(n), transmission(n);
  std::vector<unsigned char> status(n);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t k = 0; k < n; ++k) {
    const InscribedTarget& f = a.cells[k].figures;
    const bool ok = f.status == AtlasStatus::ok;
    scale[k] = ok ? f.scale : nan;
    height[k] = ok ? f.height : nan;
    lci[k] = ok ? f.min_lci : nan;
    transmission[k] = ok ? f.min_transmission_sin : nan;
    status[k] = static_cast<unsigned char>(f.status);
  }
  vtkNew<vtkImageData> image;
  shape_image(image, a.x0, a.y0, a.spacing, a.nx, a.ny);
  add_point_array<vtkDoubleArray>(image, "scale_D", scale);
  add_point_array<vtkDoubleArray>(image, "min_lci", lci);
  add_point_array<vtkDoubleArray>(image, "min_transmission_sin", transmission);
  add_point_array<vtkDoubleArray>(image, "height_D", height);
  add_point_array<vtkUnsignedCharArray>(image, "status", status);
  image->GetPointData()->SetActiveScalars("scale_D");
  vtkNew<vtkStringArray> status_names;
  status_names->SetName("status_names");
  for (AtlasStatus s : {AtlasStatus::ok, AtlasStatus::no_workspace, AtlasStatus::outside})
    status_names->InsertNextValue(std::string(to_string(s)));
  image->GetFieldData()->AddArray(status_names);
  return image_document(image);
}

}  // namespace fivebar
