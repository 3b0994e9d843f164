// Workspace files: polylines of boundary pieces, VTK XML documents read back with VTK's own
// readers, the picture as well-formed SVG and a decodable PNG, and the station analysis behind
// them. Geometric expectations come from the paper's Table 1 (annuli radii |L_i -+ L_{i+2}|),
// not from the library.

#include <cairo.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkIdList.h>
#include <vtkImageData.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkObject.h>
#include <vtkPointData.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkXMLDataElement.h>
#include <vtkXMLImageDataReader.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLUtilities.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "fivebar/workspace/station.hpp"
#include "fivebar/workspace/files.hpp"
#include "fivebar/workspace/io.hpp"
#include "fivebar/workspace/plot.hpp"
#include "process.hpp"

namespace fs = std::filesystem;
using namespace fivebar;
using ::testing::HasSubstr;

namespace {

const fs::path kSource = FIVEBAR_SOURCE_DIR;
constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

/// Paper Table 1: index station, bases (0,0), (12.5,0) and (0,31), (12.5,31); L = 9, 9, 15, 15:
/// every leg's annulus has radii 15 - 9 = 6 and 15 + 9 = 24.
constexpr double kInner = 6.0, kOuter = 24.0;

const Design& paper() {
  static const Design d = load_design(kSource / "designs" / "iros2022.yaml");
  return d;
}
const Station& index_station() { return *paper().station("index"); }

/// One analysis of the index station shared by the tests (coarse spacing keeps them fast).
const StationWorkspace& index_workspace() {
  static const StationWorkspace ws = [] {
    WorkspaceOptions o;
    o.spacing_mm = 0.5;
    return analyse_workspace(index_station(), o);
  }();
  return ws;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

class TempDir : public ::testing::Test {
 protected:
  void SetUp() override {
    std::random_device rd;
    dir_ = fs::temp_directory_path() / ("fivebar_test_workspace_io_" + std::to_string(::getpid()) + "_" + std::to_string(rd()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

CurvePiece arc(Vec2 c, double r, double a0, double a1, bool ccw) {
  CurvePiece p;
  p.is_arc = true;
  p.center = c;
  p.radius = r;
  p.ccw = ccw;
  p.source = c + r * Vec2(std::cos(a0), std::sin(a0));
  p.target = c + r * Vec2(std::cos(a1), std::sin(a1));
  return p;
}

double angle_between(const Vec2& a, const Vec2& b) { return std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b)); }

// --- discretise / chain_segments ----------------------------------------------------------------

TEST(Discretise, ArcsStepAtMostOneDegreeOnTheCircleFromSourceToTarget) {
  struct Case {
    double a0, a1;
    bool ccw;
    int steps;  // ceil(|sweep| / 1 deg)
  };
  // 90 deg ccw; 90 deg cw (the long way round is 270 deg); 0.5 deg; 100.5 deg.
  for (const Case& c : {Case{0.0, kPi / 2, true, 90}, Case{0.0, kPi / 2, false, 270}, Case{0.2, 0.2 + 0.5 * kDeg, true, 1},
                        Case{1.0, 1.0 - 100.5 * kDeg, false, 101}}) {
    SCOPED_TRACE(::testing::Message() << "a0 " << c.a0 << " a1 " << c.a1 << " ccw " << c.ccw);
    const Vec2 centre(3.0, -2.0);
    const double r = 7.5;
    const CurvePiece p = arc(centre, r, c.a0, c.a1, c.ccw);
    const auto pts = discretise(p);
    ASSERT_EQ(pts.size(), std::size_t(c.steps) + 1);
    EXPECT_EQ(pts.front(), p.source);
    EXPECT_EQ(pts.back(), p.target);
    double total = 0.0;
    for (std::size_t k = 0; k < pts.size(); ++k) {
      EXPECT_NEAR((pts[k] - centre).norm(), r, 1e-12 * r);
      if (k == 0) continue;
      const double step = angle_between(pts[k - 1] - centre, pts[k] - centre);
      EXPECT_LE(std::fabs(step), 1.0 * kDeg * (1 + 1e-12));
      EXPECT_EQ(step > 0, c.ccw) << "step " << k << " goes the wrong way round";
      total += step;
    }
    EXPECT_NEAR(std::fabs(total), c.steps == 1 ? 0.5 * kDeg : c.steps == 101 ? 100.5 * kDeg : c.steps * kDeg, 1e-12);
  }
}

TEST(Discretise, SegmentsAreTheirEndsAndLoopsShareEndsOnce) {
  CurvePiece s;
  s.source = {1, 2};
  s.target = {4, 6};
  EXPECT_EQ(discretise(s), (std::vector<Vec2>{{1, 2}, {4, 6}}));
  // A disk of radius 2 as two half circles: 180 + 180 points, closed, first point not repeated.
  BoundaryLoop loop;
  loop.pieces = {arc({0, 0}, 2.0, 0.0, kPi, true), arc({0, 0}, 2.0, kPi, 2 * kPi, true)};
  const auto pts = discretise(loop);
  ASSERT_EQ(pts.size(), 360u);
  std::set<std::pair<long, long>> distinct;
  for (const Vec2& p : pts) distinct.insert({std::lround(p.x() * 1e6), std::lround(p.y() * 1e6)});
  EXPECT_EQ(distinct.size(), 360u);
  // Shoelace area of the 360-gon inscribed in the circle: (n/2) r^2 sin(2 pi / n).
  double area = 0.0;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    const Vec2& a = pts[k];
    const Vec2& b = pts[(k + 1) % pts.size()];
    area += 0.5 * (a.x() * b.y() - a.y() * b.x());
  }
  EXPECT_NEAR(area, 180.0 * 4.0 * std::sin(2 * kPi / 360), 1e-10);
  EXPECT_THROW((void)discretise(loop.pieces[0], 0.0), std::invalid_argument);
}

TEST(ChainSegments, JoinsShuffledReversedSegmentsIntoClosedAndOpenChains) {
  // A unit square split into 8 segments (shuffled, some reversed, ends off by 1e-10), plus an
  // open three-segment zigzag far away.
  const std::vector<Vec2> square{{0, 0}, {0.5, 0}, {1, 0}, {1, 0.5}, {1, 1}, {0.5, 1}, {0, 1}, {0, 0.5}};
  std::vector<std::vector<Vec2>> pieces;
  for (std::size_t k = 0; k < square.size(); ++k) {
    const Vec2 a = square[k], b = square[(k + 1) % square.size()] + Vec2(1e-10, -1e-10);
    pieces.push_back(k % 3 == 0 ? std::vector<Vec2>{b, a} : std::vector<Vec2>{a, b});
  }
  pieces.push_back({{10, 10}, {11, 10}});
  pieces.push_back({{12, 11}, {11, 10}});
  pieces.push_back({{12, 11}, {13, 10}});
  std::mt19937 rng(7);
  std::shuffle(pieces.begin(), pieces.end(), rng);

  const auto chains = chain_segments(pieces, 1e-8);
  ASSERT_EQ(chains.size(), 2u);
  const Polyline& closed = chains[0].closed ? chains[0] : chains[1];
  const Polyline& open = chains[0].closed ? chains[1] : chains[0];
  EXPECT_TRUE(closed.closed);
  EXPECT_FALSE(open.closed);
  EXPECT_EQ(closed.points.size(), 8u);
  ASSERT_EQ(open.points.size(), 4u);
  // The open chain runs end to end: from (10,10) to (13,10) or back.
  const bool forward = open.points.front().isApprox(Vec2(10, 10));
  EXPECT_TRUE(forward || open.points.back().isApprox(Vec2(10, 10)));
  EXPECT_TRUE((forward ? open.points.back() : open.points.front()).isApprox(Vec2(13, 10)));
  // Consecutive points of the closed chain are 0.5 apart (neighbours on the square).
  for (std::size_t k = 0; k < 8; ++k) EXPECT_NEAR((closed.points[k] - closed.points[(k + 1) % 8]).norm(), 0.5, 1e-9);

  // Below the 1e-10 gaps the square falls apart into its 8 segments; the zigzag, whose ends
  // coincide exactly, still joins.
  EXPECT_EQ(chain_segments(pieces, 1e-12).size(), 8u + 1u);
}

// --- station analysis -------------------------------------------------------------------------

TEST(StationWorkspace, CommonGridCoversEveryRegionAndTheSharedRegionIsTheLens) {
  const StationWorkspace& ws = index_workspace();
  ASSERT_EQ(ws.mechanisms.size(), 2u);
  EXPECT_EQ(ws.mechanisms[0].mechanism.name, "lower");
  EXPECT_EQ(ws.mechanisms[1].mechanism.name, "upper");
  ASSERT_TRUE(ws.shared.has_value());
  // Lower region: inside both circles of radius 24 about (0,0) and (12.5,0): x in [12.5 - 24, 24],
  // y within +-c, c = sqrt(24^2 - 6.25^2) (where the circles cross); the upper one is shifted by
  // 31. The grid covers both with (at least) one sample of margin.
  const double c = std::sqrt(kOuter * kOuter - 6.25 * 6.25);
  const double h = ws.grid.spacing;
  EXPECT_LE(ws.grid.x0, 12.5 - kOuter - h);
  EXPECT_LE(ws.grid.y0, -c - h);
  EXPECT_GE(ws.grid.x0 + (ws.grid.nx - 1) * h, kOuter + h);
  EXPECT_GE(ws.grid.y0 + (ws.grid.ny - 1) * h, 31 + c + h);
  for (const auto& w : ws.mechanisms) EXPECT_EQ(w.field.reach.size(), ws.grid.size());
  // The shared region runs from the upper region's lower cusp (y = 31 - c) to the lower region's
  // upper cusp (y = c), both at x = 6.25.
  const auto b = ws.shared->bounds();
  EXPECT_NEAR(b[3], c, 1e-9);
  EXPECT_NEAR(b[1], 31 - c, 1e-9);
  // Pose at the target centre for drawing: the tactor is there.
  for (const auto& w : ws.mechanisms) EXPECT_LT((w.centre.P - ws.target.center).norm(), 1e-12);
}

TEST(StationWorkspace, OneMechanismAndBadOptions) {
  WorkspaceOptions o;
  o.spacing_mm = 1.0;
  o.mechanism = "upper";
  const StationWorkspace ws = analyse_workspace(index_station(), o);
  ASSERT_EQ(ws.mechanisms.size(), 1u);
  EXPECT_EQ(ws.mechanisms[0].mechanism.name, "upper");
  EXPECT_FALSE(ws.shared.has_value());
  EXPECT_EQ(workspace_file_names(ws).vti, std::vector<std::string>{"index-upper-field.vti"});

  for (double bad : {0.0, -0.2, std::nan("")}) {
    o.spacing_mm = bad;
    EXPECT_THAT([&] { (void)analyse_workspace(index_station(), o); },
                ::testing::ThrowsMessage<InputError>(HasSubstr("spacing_mm")));
  }
  o.spacing_mm = 1e-4;  // ~1e11 samples: refused before any allocation
  EXPECT_THAT([&] { (void)analyse_workspace(index_station(), o); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("coarser spacing")));
  o.spacing_mm = 1.0;
  o.mechanism = "middle";
  EXPECT_THROW((void)analyse_workspace(index_station(), o), InputError);
}

TEST(StationWorkspace, JsonMirrorsTheResults) {
  const StationWorkspace& ws = index_workspace();
  const Json j = to_json(ws);
  EXPECT_EQ(j["station"], "index");
  EXPECT_EQ(j["grid"]["nx"], ws.grid.nx);
  ASSERT_EQ(j["mechanisms"][0]["mechanism"], "lower");  // mechanisms are records (docs/conventions.md)
  const auto& lower = j["mechanisms"][0];
  EXPECT_EQ(lower["area_mm2"].get<double>(), ws.mechanisms[0].region.area_mm2());
  EXPECT_EQ(lower["holes"], 2);  // the two inner disks (radius 6, centres 12.5 apart) are disjoint
  EXPECT_EQ(lower["components"], 1);
  EXPECT_EQ(lower["assembly_area_mm2"].get<double>(), ws.mechanisms[0].assembly.area_mm2);
  EXPECT_GT(lower["assembly_error_mm2"].get<double>(), 0.0);
  EXPECT_GT(lower["max_lci_sampled"].get<double>(), 0.5);
  EXPECT_LE(lower["max_lci_sampled"].get<double>(), 1.0);
  EXPECT_EQ(j["shared"]["components"], 1);
  EXPECT_EQ(j["shared"]["holes"], 0);
}

// --- VTK documents read back ------------------------------------------------------------------

TEST_F(TempDir, FieldVtiReadsBackWithVtkAndEqualsTheField) {
  const StationWorkspace& ws = index_workspace();
  const MechanismWorkspace& lower = ws.mechanisms[0];
  const fs::path path = dir_ / "lower.vti";
  write_field_vti(path, lower.field);

  vtkNew<vtkXMLImageDataReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  ASSERT_NE(image, nullptr);
  int dims[3];
  image->GetDimensions(dims);
  EXPECT_EQ(dims[0], ws.grid.nx);
  EXPECT_EQ(dims[1], ws.grid.ny);
  EXPECT_EQ(dims[2], 1);
  double origin[3], spacing[3];
  image->GetOrigin(origin);
  image->GetSpacing(spacing);
  EXPECT_EQ(origin[0], ws.grid.x0);
  EXPECT_EQ(origin[1], ws.grid.y0);
  EXPECT_EQ(spacing[0], 0.5);
  EXPECT_EQ(spacing[1], 0.5);

  const WorkspaceField& f = lower.field;
  const std::map<std::string, const std::vector<double>*> doubles{
      {"lci", &f.lci},
      {"type1_distance_mm", &f.type1_distance_mm},
      {"type1_sin", &f.type1_sin},
      {"type2_sin", &f.type2_sin},
      {"transmission_deg", &f.transmission_deg},
      {"force_capability", &f.force_capability}};
  const std::map<std::string, const std::vector<std::uint8_t>*> bytes{
      {"reach", &f.reach}, {"status", &f.status}, {"assembly_ok", &f.assembly_ok}};
  vtkPointData* pd = image->GetPointData();
  EXPECT_EQ(pd->GetNumberOfArrays(), 9);
  const vtkIdType n = vtkIdType(ws.grid.size());
  for (const auto& [name, values] : doubles) {
    vtkDataArray* a = pd->GetArray(name.c_str());
    ASSERT_NE(a, nullptr) << name;
    ASSERT_EQ(a->GetNumberOfTuples(), n) << name;
    for (vtkIdType k = 0; k < n; ++k) ASSERT_EQ(a->GetTuple1(k), (*values)[std::size_t(k)]) << name << " at " << k;
  }
  for (const auto& [name, values] : bytes) {
    vtkDataArray* a = pd->GetArray(name.c_str());
    ASSERT_NE(a, nullptr) << name;
    ASSERT_EQ(a->GetNumberOfTuples(), n) << name;
    for (vtkIdType k = 0; k < n; ++k) ASSERT_EQ(a->GetTuple1(k), double((*values)[std::size_t(k)])) << name << " at " << k;
  }

  // The point at VTK index i + nx*j is grid point (i, j): its reach must agree with the annuli
  // of Table 1 wherever the point is clearly inside or outside both.
  vtkDataArray* reach = pd->GetArray("reach");
  std::size_t checked = 0;
  for (vtkIdType k = 0; k < n; k += 7) {
    double p[3];
    image->GetPoint(k, p);
    const double d1 = std::hypot(p[0], p[1]), d2 = std::hypot(p[0] - 12.5, p[1]);
    const double margin = std::min({kOuter - d1, kOuter - d2, d1 - kInner, d2 - kInner});
    if (std::fabs(margin) < 1e-6) continue;
    ASSERT_EQ(reach->GetTuple1(k), margin > 0 ? 1.0 : 0.0) << "at (" << p[0] << ", " << p[1] << ")";
    ++checked;
  }
  EXPECT_GT(checked, 1000u);
  auto* status_names = vtkStringArray::SafeDownCast(image->GetFieldData()->GetAbstractArray("status_names"));
  ASSERT_NE(status_names, nullptr);
  EXPECT_EQ(status_names->GetValue(1), "unreachable");
}

struct Cells {
  std::vector<std::vector<Vec2>> points;  // per cell, closing point included
  std::vector<int> kind, mechanism, loop, hole;
};

Cells read_vtp(const fs::path& path) {
  vtkNew<vtkXMLPolyDataReader> reader;
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkPolyData* poly = reader->GetOutput();
  Cells c;
  vtkCellData* cd = poly->GetCellData();
  vtkDataArray* kind = cd->GetArray("kind");
  vtkDataArray* mech = cd->GetArray("mechanism_id");
  vtkDataArray* loop = cd->GetArray("loop_index");
  vtkDataArray* hole = cd->GetArray("hole");
  if (!kind || !mech || !loop || !hole) {
    ADD_FAILURE() << "missing cell data arrays";
    return c;
  }
  vtkCellArray* lines = poly->GetLines();
  EXPECT_EQ(lines->GetNumberOfCells(), poly->GetNumberOfCells());
  vtkNew<vtkIdList> ids;
  lines->InitTraversal();
  vtkIdType cell = 0;
  while (lines->GetNextCell(ids)) {
    std::vector<Vec2> pts;
    for (vtkIdType k = 0; k < ids->GetNumberOfIds(); ++k) {
      double p[3];
      poly->GetPoint(ids->GetId(k), p);
      EXPECT_EQ(p[2], 0.0);
      pts.emplace_back(p[0], p[1]);
    }
    c.points.push_back(pts);
    c.kind.push_back(int(kind->GetTuple1(cell)));
    c.mechanism.push_back(int(mech->GetTuple1(cell)));
    c.loop.push_back(int(loop->GetTuple1(cell)));
    c.hole.push_back(int(hole->GetTuple1(cell)));
    ++cell;
  }
  return c;
}

TEST_F(TempDir, RegionsVtpReadsBackWithVtkAndLiesOnTheAnnuli) {
  const StationWorkspace& ws = index_workspace();
  const fs::path path = dir_ / "index.vtp";
  write_regions_vtp(path, ws);
  const Cells c = read_vtp(path);
  ASSERT_FALSE(c.points.empty());

  const Vec2 bases[2][2] = {{{0, 0}, {12.5, 0}}, {{0, 31}, {12.5, 31}}};
  std::map<int, int> region_cells, region_holes;
  int shared = 0, target = 0, assembly = 0;
  for (std::size_t k = 0; k < c.points.size(); ++k) {
    const auto& pts = c.points[k];
    SCOPED_TRACE(::testing::Message() << "cell " << k << " kind " << c.kind[k] << " mechanism " << c.mechanism[k]);
    switch (c.kind[k]) {
      case int(CurveKind::region): {
        ASSERT_TRUE(c.mechanism[k] == 0 || c.mechanism[k] == 1);
        ++region_cells[c.mechanism[k]];
        region_holes[c.mechanism[k]] += c.hole[k];
        EXPECT_EQ(pts.front(), pts.back()) << "a boundary loop is a closed polyline";
        // Every point is on one of the mechanism's four circles (radii 6 and 24 about its bases)
        // and no chord spans more than 1 degree of the largest circle.
        for (std::size_t m = 0; m < pts.size(); ++m) {
          double off = 1e9;
          for (const Vec2& o : bases[c.mechanism[k]])
            for (double r : {kInner, kOuter}) off = std::min(off, std::fabs((pts[m] - o).norm() - r));
          ASSERT_LT(off, 1e-9) << "point " << m << " (" << pts[m].x() << ", " << pts[m].y() << ")";
          if (m > 0) EXPECT_LE((pts[m] - pts[m - 1]).norm(), 2 * kOuter * std::sin(0.5 * kDeg) * (1 + 1e-9));
        }
        break;
      }
      case int(CurveKind::shared):
        ++shared;
        EXPECT_EQ(c.mechanism[k], -1);
        for (const Vec2& p : pts) {  // inside all four outer circles, to rounding
          for (const auto& pair : bases)
            for (const Vec2& o : pair) EXPECT_LE((p - o).norm(), kOuter + 1e-9);
        }
        break;
      case int(CurveKind::target): {
        ++target;
        EXPECT_EQ(c.mechanism[k], -1);
        for (const Vec2& p : pts) {  // (x - 6.25)^2 / 7.5^2 + (y - 15.5)^2 / 6^2 = 1
          const double u = (p.x() - 6.25) / 7.5, v = (p.y() - 15.5) / 6.0;
          EXPECT_NEAR(u * u + v * v, 1.0, 1e-12);
        }
        break;
      }
      case int(CurveKind::assembly_contour): {
        ++assembly;
        const Mechanism& m = ws.mechanisms[std::size_t(c.mechanism[k])].mechanism;
        // Refined crossings lie on the zero set of the assembly margin (bisected to ~1e-12 of a cell).
        for (const Vec2& p : pts) ASSERT_LT(std::fabs(restriction_margin(m, Restriction::assembly, p)), 1e-6);
        break;
      }
      case int(CurveKind::lci_contour):
        EXPECT_GE(c.mechanism[k], 0);
        break;
      default:
        ADD_FAILURE() << "unknown kind";
    }
  }
  // Each region: one outer loop and two holes (the inner disks are disjoint: 6 + 6 < 12.5).
  EXPECT_EQ(region_cells[0], 3);
  EXPECT_EQ(region_cells[1], 3);
  EXPECT_EQ(region_holes[0], 2);
  EXPECT_EQ(region_holes[1], 2);
  EXPECT_EQ(shared, 1);
  EXPECT_EQ(target, 1);
  EXPECT_GT(assembly, 0);
}

TEST_F(TempDir, WritersAreAtomicAndWriteExactlyTheNamedFiles) {
  const StationWorkspace& ws = index_workspace();
  // A directory that does not exist: IoError, nothing written anywhere.
  EXPECT_THROW(write_regions_vtp(dir_ / "missing" / "x.vtp", ws), IoError);
  EXPECT_THROW(write_field_vti(dir_ / "missing" / "x.vti", ws.mechanisms[0].field), IoError);
  EXPECT_TRUE(fs::is_empty(dir_));

  PlotOptions plot;
  plot.width_px = 800;
  plot.height_px = 500;
  const auto written = write_workspace_files(dir_ / "out", ws, plot);
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir_ / "out")) names.insert(e.path().filename().string());
  EXPECT_EQ(names, (std::set<std::string>{"index-regions.vtp", "index-lower-field.vti", "index-upper-field.vti",
                                          "index-workspace.svg", "index-workspace.png"}));
  EXPECT_EQ(written.size(), 5u);
  for (const auto& p : written) EXPECT_GT(fs::file_size(p), 1000u) << p;

  plot.width_px = 10;  // refused before anything is drawn or written
  EXPECT_THROW((void)write_workspace_files(dir_ / "none", ws, plot), InputError);
  EXPECT_FALSE(fs::exists(dir_ / "none"));
}

// --- pictures -----------------------------------------------------------------------------------

TEST(Picture, SvgIsWellFormedXmlWithTheRequestedSize) {
  const StationWorkspace& ws = index_workspace();
  PlotOptions plot;
  plot.width_px = 900;
  plot.height_px = 560;
  const std::string svg = station_svg(ws, plot);
  vtkSmartPointer<vtkXMLDataElement> root;
  root.TakeReference(vtkXMLUtilities::ReadElementFromString(svg.c_str()));
  ASSERT_NE(root, nullptr) << "the SVG does not parse as XML";
  EXPECT_STREQ(root->GetName(), "svg");
  ASSERT_NE(root->GetAttribute("width"), nullptr);
  EXPECT_THAT(std::string(root->GetAttribute("width")), ::testing::StartsWith("900"));
  EXPECT_THAT(std::string(root->GetAttribute("height")), ::testing::StartsWith("560"));
  // Vector paths for the regions and an embedded image for the LCI heat map.
  EXPECT_NE(root->LookupElementWithName("path"), nullptr);
  EXPECT_NE(root->LookupElementWithName("image"), nullptr);

  // The check can fail: a truncated document is refused.
  const bool warn = vtkObject::GetGlobalWarningDisplay();
  vtkObject::GlobalWarningDisplayOff();
  vtkSmartPointer<vtkXMLDataElement> broken;
  broken.TakeReference(vtkXMLUtilities::ReadElementFromString(svg.substr(0, svg.size() / 2).c_str()));
  vtkObject::SetGlobalWarningDisplay(warn);
  EXPECT_EQ(broken, nullptr);
}

struct Png {
  cairo_surface_t* surface = nullptr;
  ~Png() {
    if (surface) cairo_surface_destroy(surface);
  }
};

cairo_status_t read_from(void* closure, unsigned char* data, unsigned int length) {
  auto* in = static_cast<std::pair<const std::string*, std::size_t>*>(closure);
  if (in->second + length > in->first->size()) return CAIRO_STATUS_READ_ERROR;
  std::copy_n(in->first->data() + in->second, length, data);
  in->second += length;
  return CAIRO_STATUS_SUCCESS;
}

TEST(Picture, PngDecodesWithTheRequestedSizeAndShowsBothMechanismColours) {
  const StationWorkspace& ws = index_workspace();
  PlotOptions plot;
  plot.width_px = 1200;
  plot.height_px = 750;
  const std::string png = station_png(ws, plot);
  ASSERT_GT(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  std::pair<const std::string*, std::size_t> in{&png, 0};
  Png image;
  image.surface = cairo_image_surface_create_from_png_stream(read_from, &in);
  ASSERT_EQ(cairo_surface_status(image.surface), CAIRO_STATUS_SUCCESS);
  EXPECT_EQ(cairo_image_surface_get_width(image.surface), 1200);
  EXPECT_EQ(cairo_image_surface_get_height(image.surface), 750);

  // The lower region is red and the upper blue (paper Fig. 4): both hues cover many pixels (the
  // translucent fills over white are about (245, 206, 204) and (204, 217, 245)); the corner is
  // the white background.
  cairo_surface_flush(image.surface);
  const unsigned char* data = cairo_image_surface_get_data(image.surface);
  const int stride = cairo_image_surface_get_stride(image.surface);
  std::size_t reddish = 0, bluish = 0;
  for (int y = 0; y < 750; ++y) {
    for (int x = 0; x < 1200; ++x) {
      const auto px = *reinterpret_cast<const std::uint32_t*>(data + y * stride + 4 * x);
      const int r = (px >> 16) & 0xFF, g = (px >> 8) & 0xFF, b = px & 0xFF;
      if (r > g + 25 && r > b + 25) ++reddish;
      if (b > r + 25 && b > g + 20) ++bluish;
    }
  }
  EXPECT_GT(reddish, 10000u);
  EXPECT_GT(bluish, 10000u);
  EXPECT_EQ(*reinterpret_cast<const std::uint32_t*>(data), 0xFFFFFFFFu);

  plot.height_px = 100;
  EXPECT_THROW((void)station_png(ws, plot), InputError);
}

TEST(Picture, ViridisIsMatplotlibsMap) {
  // matplotlib.cm.viridis (matplotlib 3.6, Debian 12), independent of the table in the code:
  // 0 = (0.267004, 0.004874, 0.329415), 0.5 = (0.127568, 0.566949, 0.550556),
  // 1 = (0.993248, 0.906157, 0.143936); between the table's stops (every 0.1) the map is linear, so
  // 0.25 and 0.75 are matplotlib's (0.229739, 0.322361, 0.545706) and (0.369214, 0.788888, 0.382914)
  // to within the interpolation error (< 0.02).
  const Rgb lo = viridis(0.0), hi = viridis(1.0), mid = viridis(0.5);
  EXPECT_NEAR(lo.r, 0.267004, 1e-6);
  EXPECT_NEAR(lo.b, 0.329415, 1e-6);
  EXPECT_NEAR(mid.r, 0.127568, 1e-6);
  EXPECT_NEAR(mid.g, 0.566949, 1e-6);
  EXPECT_NEAR(mid.b, 0.550556, 1e-6);
  EXPECT_NEAR(hi.g, 0.906157, 1e-6);
  const Rgb q1 = viridis(0.25), q3 = viridis(0.75);
  EXPECT_NEAR(q1.r, 0.229739, 0.02);
  EXPECT_NEAR(q1.g, 0.322361, 0.02);
  EXPECT_NEAR(q1.b, 0.545706, 0.02);
  EXPECT_NEAR(q3.r, 0.369214, 0.02);
  EXPECT_NEAR(q3.g, 0.788888, 0.02);
  EXPECT_NEAR(q3.b, 0.382914, 0.02);
  EXPECT_EQ(viridis(-3).r, lo.r);
  EXPECT_EQ(viridis(7).b, hi.b);
  EXPECT_EQ(viridis(std::nan("")).r, lo.r);
}

}  // namespace

namespace {

/// Pixels of a decoded PNG that differ from its corner's colour (the background) in the band of
/// `band` pixels along its four edges: text or a plot that runs off the canvas leaves ink there.
std::size_t ink_in_outer_band(cairo_surface_t* s, int band) {
  cairo_surface_flush(s);
  const int w = cairo_image_surface_get_width(s), h = cairo_image_surface_get_height(s);
  const int stride = cairo_image_surface_get_stride(s);
  const unsigned char* data = cairo_image_surface_get_data(s);
  const auto pixel = [&](int x, int y) {
    std::uint32_t p = 0;
    std::memcpy(&p, data + std::size_t(y) * std::size_t(stride) + std::size_t(x) * 4, 4);
    return p;
  };
  const std::uint32_t background = pixel(0, 0);
  std::size_t ink = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const bool in_band = x < band || y < band || x >= w - band || y >= h - band;
      if (in_band && pixel(x, y) != background) ++ink;
    }
  }
  return ink;
}

}  // namespace

TEST(Picture, EveryPngOfTheSceneKeepsItsOuterMarginClear) {
  // The products that draw PNGs with text and fields near their edges (report's work-precision
  // plots with their footnotes, tolerance and control heat maps, workspace, collision and pattern
  // pictures), as `fivebar run` writes them; each decoded, and its outer 3-pixel band must be all
  // background: nothing is cut at the canvas edge.
  const fs::path dir = fs::temp_directory_path() / ("fivebar_png_margin_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const fivebar::testing::Outcome r = fivebar::testing::run(
      FIVEBAR_BINARY,
      {"run", (fs::path(FIVEBAR_SOURCE_DIR) / "designs" / "iros2022.yaml").string(), "--products",
       "workspace,collision,pattern,tolerance,control,report", "--out", (dir / "out").string(), "-q"},
      dir, dir, 900.0);
  ASSERT_TRUE(r.code == 0 || r.code == 1) << r.err;
  std::size_t pngs = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir / "out")) {
    if (!e.is_regular_file() || e.path().extension() != ".png") continue;
    ++pngs;
    Png image;
    image.surface = cairo_image_surface_create_from_png(e.path().c_str());
    ASSERT_EQ(cairo_surface_status(image.surface), CAIRO_STATUS_SUCCESS) << e.path();
    EXPECT_EQ(ink_in_outer_band(image.surface, 3), 0u) << fs::relative(e.path(), dir).string() << " has ink in its outer margin";
  }
  EXPECT_GE(pngs, 20u);
  fs::remove_all(dir);
}
