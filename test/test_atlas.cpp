// Performance atlases (fivebar/atlas.hpp) against independent references: the closed form of the
// largest circle inside two overlapping annuli, the annulus of coincident bases, the invariance of
// the normalised figures under scaling and rigid motion, the mirror image, the tactor angle on the
// symmetry axis by hand, and the certified coverage of the inscribed target itself.

#include <gtest/gtest.h>
#include <vtkDataArray.h>
#include <vtkFieldData.h>
#include <vtkImageData.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkStringArray.h>
#include <vtkXMLImageDataReader.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "fivebar/atlas.hpp"
#include "fivebar/coverage/coverage.hpp"
#include "fivebar/error.hpp"
#include "paper.hpp"
#include "process.hpp"

namespace fivebar {
namespace {

using testing::paper_mechanism;

constexpr double kSqrt3 = 1.7320508075688772;

/// Small and quick options for the tests (ASan runs them ~10x slower).
AtlasOptions quick(int cells = 9) {
  AtlasOptions o;
  o.cells = cells;
  o.heights = 12;
  o.rel_tol = 1e-4;
  return o;
}

/// The largest circle inside both annuli |r2 - r1| <= |P - O_i| <= r1 + r2 (O_i = (-+r3/2, 0)),
/// centred on the axis x = 0, by hand: at height y the distance to both bases is d = sqrt(y^2 +
/// r3^2/4) and the radius min(d - |r2 - r1|, r1 + r2 - d), best at d = max(r1, r2) when that is
/// reachable (d >= r3/2), else at y = 0.
double largest_circle(double r1, double r2, double r3) {
  const double d = std::max(std::max(r1, r2), 0.5 * r3);
  return std::max(0.0, std::min(d - std::abs(r2 - r1), r1 + r2 - d));
}

/// The rules of docs/conventions.md "JSON documents" (docs/schemas/common.schema.json) that a
/// product's result must keep: "station" a name or null, "mechanism" lower, upper or null, no key
/// "lower" or "upper", "stations" and "mechanisms" arrays.
void expect_json_conventions(const Json& j, const std::string& at = "$") {
  if (j.is_array()) {
    for (std::size_t k = 0; k < j.size(); ++k) expect_json_conventions(j[k], at + "[" + std::to_string(k) + "]");
    return;
  }
  if (!j.is_object()) return;
  for (const auto& [key, value] : j.items()) {
    EXPECT_NE(key, "lower") << at;
    EXPECT_NE(key, "upper") << at;
    if (key == "station") EXPECT_TRUE(value.is_string() || value.is_null()) << at;
    if (key == "mechanism") EXPECT_TRUE(value.is_null() || value == "lower" || value == "upper") << at;
    if (key == "stations" || key == "mechanisms") EXPECT_TRUE(value.is_array()) << at;
    expect_json_conventions(value, at + "." + key);
  }
}

TEST(Atlas, ChartIsTheTriangleAndRoundTrips) {
  std::mt19937_64 rng(testing::test_seed());
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int k = 0; k < 200; ++k) {
    // A random point of the triangle (sorted uniforms give barycentric weights).
    double a = u(rng), b = u(rng);
    if (a > b) std::swap(a, b);
    DesignPoint p;
    p.r1 = 3.0 * a;
    p.r2 = 3.0 * (b - a);
    p.r3 = 3.0 * (1.0 - b);
    const Vec2 c = chart_of(p);
    const DesignPoint q = point_at_chart(c.x(), c.y());
    EXPECT_NEAR(q.r1, p.r1, 1e-12);
    EXPECT_NEAR(q.r2, p.r2, 1e-12);
    EXPECT_NEAR(q.r3, p.r3, 1e-12);
    EXPECT_NEAR(q.r1 + q.r2 + q.r3, 3.0, 1e-12);
  }
  // The vertices, and the equilateral triangle's side 2 sqrt(3).
  const Vec2 v1 = chart_of({3.0, 0.0, 0.0}), v2 = chart_of({0.0, 3.0, 0.0}), v3 = chart_of({0.0, 0.0, 3.0});
  EXPECT_NEAR((v1 - Vec2(-kSqrt3, 0.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((v2 - Vec2(kSqrt3, 0.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((v3 - Vec2(0.0, 3.0)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((v1 - v2).norm(), (v2 - v3).norm(), 1e-12);
  EXPECT_NEAR((v1 - v3).norm(), (v2 - v3).norm(), 1e-12);
  EXPECT_FALSE(in_design_space(point_at_chart(0.0, 3.2)));
  EXPECT_FALSE(in_design_space(point_at_chart(-1.6, 0.5)));
  EXPECT_TRUE(in_design_space(point_at_chart(0.0, 1.0)));
}

TEST(Atlas, DesignPointOfThePaperStation) {
  // Table 1: L1 = L2 = 9, L3 = L4 = 15, bases 12.5 apart: D = 36.5 / 3.
  const auto p = design_point(paper_mechanism("index", "lower"));
  ASSERT_TRUE(p);
  EXPECT_NEAR(p->D_mm, 36.5 / 3.0, 1e-12);
  EXPECT_NEAR(p->r1, 9.0 * 3.0 / 36.5, 1e-12);
  EXPECT_NEAR(p->r2, 15.0 * 3.0 / 36.5, 1e-12);
  EXPECT_NEAR(p->r3, 12.5 * 3.0 / 36.5, 1e-12);
  Mechanism skew = paper_mechanism("index", "lower");
  skew.L[3] = 16.0;
  std::string why;
  EXPECT_FALSE(design_point(skew, &why));
  EXPECT_NE(why.find("not symmetric"), std::string::npos) << why;
}

TEST(Atlas, CircleMatchesTheClosedFormOfTwoAnnuli) {
  // Without an assembly restriction the reachable region is the two annuli's overlap, and the
  // largest circle centred on the axis is in closed form (largest_circle) for every design.
  AtlasOptions o = quick(7);
  o.heights = 8;  // both sides of the base line are scanned: keep it quick under a sanitizer
  o.assembly_mode = AssemblyMode::Any;
  const Atlas a = performance_atlas(o);
  std::size_t checked = 0;
  for (const AtlasCell& c : a.cells) {
    if (c.figures.status == AtlasStatus::outside) {
      EXPECT_FALSE(in_design_space(c.point));
      continue;
    }
    const double ref = largest_circle(c.point.r1, c.point.r2, c.point.r3);
    // The legs' annuli overlap only below r3 = 2.
    EXPECT_EQ(c.figures.status == AtlasStatus::ok, c.point.r3 < 2.0) << c.point.r3;
    if (c.figures.status != AtlasStatus::ok) continue;
    ++checked;
    // The height search stops within rel_tol of y_max: s*(y) is 1-Lipschitz in y.
    EXPECT_NEAR(c.figures.scale, ref, 2e-3 * ref + 1e-9) << c.point.r1 << " " << c.point.r2 << " " << c.point.r3;
    EXPECT_LE(c.figures.scale, ref * (1.0 + 1e-9));  // certified inside: never above the truth
  }
  EXPECT_GT(checked, 5u);
}

TEST(Atlas, CoincidentBasesGiveTheAnnulusInscribedCircleAndRadialEllipse) {
  // Coincident bases: both legs reach the annulus |L3 - L1| <= |P| <= L1 + L3 about the base.
  // Its largest inscribed circle has radius (outer - inner) / 2 = min(L1, L3). So has the largest
  // ellipse with its major axis radial (aspect beta <= 1, centre at c on the axis): the squared
  // distance to the base along it is b^2 + (a^2 - b^2) u^2 + 2 a c u + c^2 (u = sin t), convex in u
  // with its vertex at u <= -1 when c >= a, so the extremes are c -+ a, as for the circle.
  for (const auto& [l1, l3] : {std::pair{4.0, 9.0}, std::pair{9.0, 4.0}, std::pair{5.0, 5.5}}) {
    Mechanism m;
    m.name = "lower";
    m.O1 = m.O2 = Vec2(1.5, -2.0);
    m.L = {l1, l1, l3, l3};
    m.working_mode = {-1, +1};
    m.assembly_mode = AssemblyMode::Any;
    AtlasOptions o = quick();
    const InscribedTarget circle = inscribed_target(m, {1.0, 0.0}, o);
    ASSERT_EQ(circle.status, AtlasStatus::ok);
    EXPECT_NEAR(circle.scale, std::min(l1, l3), 1e-3 * std::min(l1, l3)) << l1 << " " << l3;
    EXPECT_NEAR(std::abs(circle.height), std::max(l1, l3), 2e-2 * std::max(l1, l3));
    const InscribedTarget radial = inscribed_target(m, {0.6, 0.5 * std::numbers::pi}, o);
    ASSERT_EQ(radial.status, AtlasStatus::ok);
    EXPECT_NEAR(radial.scale, std::min(l1, l3), 1e-3 * std::min(l1, l3)) << l1 << " " << l3;
  }
}

TEST(Atlas, FiguresAreInvariantUnderScaleAndRigidMotion) {
  // The normalisation: scaling every length by k scales s* and the height by k and leaves the
  // point, the LCI and the tactor angle alone; a rotation and translation of the whole
  // mechanism (the target turning with it) changes nothing.
  const Mechanism paper = paper_mechanism("index", "lower");
  const auto point = design_point(paper);
  ASSERT_TRUE(point);
  const TargetShape shape{12.0 / 15.0, 0.0};
  const AtlasOptions o = quick();
  DesignPoint unit = *point;
  unit.D_mm = 1.0;
  const InscribedTarget ref = inscribed_target(atlas_mechanism(unit, paper.working_mode, paper.assembly_mode), shape, o);
  ASSERT_EQ(ref.status, AtlasStatus::ok);
  for (double k : {1e-3, 1.0, 250.0}) {
    Mechanism m = paper;
    m.O1 *= k;
    m.O2 *= k;
    for (double& l : m.L) l *= k;
    const auto p = design_point(m);
    ASSERT_TRUE(p);
    EXPECT_NEAR(p->r1, point->r1, 1e-12);
    EXPECT_NEAR(p->r2, point->r2, 1e-12);
    EXPECT_NEAR(p->r3, point->r3, 1e-12);
    const InscribedTarget t = inscribed_target(m, shape, o);
    ASSERT_EQ(t.status, AtlasStatus::ok);
    const double D = p->D_mm;
    EXPECT_NEAR(t.scale / D, ref.scale, 1e-3 * ref.scale) << k;
    EXPECT_NEAR(t.height / D, ref.height, 1e-2 * ref.height) << k;
    EXPECT_NEAR(t.min_lci, ref.min_lci, 1e-2) << k;
    EXPECT_NEAR(t.min_transmission_sin, ref.min_transmission_sin, 1e-2) << k;
  }
  // Rigid motion: rotate by 0.7 rad about the origin and move by (30, -12).
  const double c = std::cos(0.7), s = std::sin(0.7);
  const auto move = [&](const Vec2& v) { return Vec2(c * v.x() - s * v.y() + 30.0, s * v.x() + c * v.y() - 12.0); };
  Mechanism turned = paper;
  turned.O1 = move(paper.O1);
  turned.O2 = move(paper.O2);
  const InscribedTarget t = inscribed_target(turned, shape, o);
  ASSERT_EQ(t.status, AtlasStatus::ok);
  EXPECT_NEAR(t.scale / point->D_mm, ref.scale, 1e-3 * ref.scale);
  EXPECT_NEAR(t.target.angle, 0.7, 1e-12);
}

TEST(Atlas, UpperMechanismIsTheMirrorImageOfTheLower) {
  // The paper's upper mechanism is the lower one reflected about a horizontal line (working mode
  // +-, assembly -): its inscribed target is the same size, below its bases.
  const AtlasOptions o = quick();
  const TargetShape shape{0.8, 0.0};
  const InscribedTarget lower = inscribed_target(paper_mechanism("index", "lower"), shape, o);
  const InscribedTarget upper = inscribed_target(paper_mechanism("index", "upper"), shape, o);
  ASSERT_EQ(lower.status, AtlasStatus::ok);
  ASSERT_EQ(upper.status, AtlasStatus::ok);
  EXPECT_NEAR(upper.scale, lower.scale, 1e-3 * lower.scale);
  EXPECT_GT(lower.height, 0.0);
  EXPECT_LT(upper.height, 0.0);
  EXPECT_NEAR(upper.height, -lower.height, 2e-2 * lower.height);
  EXPECT_EQ(upper.limited_by, lower.limited_by);
}

TEST(Atlas, InscribedTargetIsWhatCoverageCertifies) {
  // The station's own figure: the ellipse the search returns is covered by fivebar coverage (the
  // full check: containment, assembly side over the filled ellipse), and 0.2 % larger it is not.
  for (const char* station : {"index", "thumb"}) {
    const Mechanism m = paper_mechanism(station, "lower");
    const double minor = std::string(station) == "index" ? 12.0 : 14.0;
    const TargetShape shape{minor / 15.0, 0.0};
    const InscribedTarget t = inscribed_target(m, shape, quick());
    ASSERT_EQ(t.status, AtlasStatus::ok);
    Ellipse grown = t.target;
    grown.axes *= 1.002;
    const CoverageResult at = coverage(m, t.target);
    const CoverageResult above = coverage(m, grown);
    EXPECT_TRUE(at.covered) << station << ": " << at.reason;
    EXPECT_FALSE(above.covered) << station;
    // The conditioning figure is coverage's min LCI over the ellipse of fraction * s*.
    Ellipse inner = t.target;
    inner.axes *= quick().fraction;
    EXPECT_NEAR(t.min_lci, coverage(m, inner).min_lci, 1e-9);
    // The paper's targets (15 x 12, 15 x 14) fit: s* is at least their semi-major axis.
    EXPECT_GT(t.scale, 7.5) << station;
  }
}

TEST(Atlas, NoCoveredEllipseOnTheAxisIsLargerThanTheInscribedTarget) {
  // A reference by brute force with fivebar coverage alone: at a few heights, the largest covered
  // ellipse of the shape (bisection on coverage().covered); s* is at least the best of them, and
  // the search's own ellipse is covered. The first design has nearly coincident bases: its
  // wrong-side region is a sliver near the bases that samples of a large ellipse miss.
  const TargetShape shape{0.8, 0.0};
  for (const DesignPoint& p : {DesignPoint{1.4789, 1.4789, 0.0422, 1.0}, DesignPoint{0.8264, 0.8264, 1.3472, 1.0},
                               DesignPoint{0.9576, 0.2259, 1.8165, 1.0}}) {
    const Mechanism m = atlas_mechanism(p, {-1, +1}, AssemblyMode::Plus);
    const InscribedTarget t = inscribed_target(m, shape, quick());
    ASSERT_EQ(t.status, AtlasStatus::ok);
    EXPECT_TRUE(coverage(m, t.target).covered) << p.r1 << " " << p.r2 << " " << p.r3;
    double best = 0.0;
    const double top = std::sqrt(std::pow(p.r1 + p.r2, 2) - 0.25 * p.r3 * p.r3);
    for (int k = 0; k < 4; ++k) {
      const double y = top * (k + 0.5) / 4.0;
      const auto at = [&](double s) {
        Ellipse e;
        e.center = Vec2(0.0, y);
        e.axes = Vec2(2.0 * s, 2.0 * shape.aspect * s);
        return e;
      };
      double lo = 0.0, hi = p.r1 + p.r2;
      for (int it = 0; it < 10; ++it) {
        const double mid = 0.5 * (lo + hi);
        (coverage(m, at(mid)).covered ? lo : hi) = mid;
      }
      best = std::max(best, lo);
    }
    EXPECT_GE(t.scale, best * (1.0 - 1e-3)) << p.r1 << " " << p.r2 << " " << p.r3;
  }
}

TEST(Atlas, TransmissionOnTheAxisMatchesTheKiteByHand) {
  // A tiny target centred on the axis at height y: its transmission is the tactor angle there.
  // By hand: the elbow A1 is where the circles |A - O1| = r1 and |A - P| = r2 meet, outward (the
  // smaller x); the distal links are symmetric, so the angle at P is 2 phi with
  // sin phi = |A1.x| / r2 and cos phi = (y - A1.y) / r2, and |sin 2 phi| = 2 |sin phi cos phi|.
  DesignPoint p{0.9, 1.3, 0.8, 1.0};
  const Mechanism m = atlas_mechanism(p, {-1, +1}, AssemblyMode::Any);
  AtlasOptions o = quick();
  o.fraction = 1e-6;
  const InscribedTarget t = inscribed_target(m, {1.0, 0.0}, o);
  ASSERT_EQ(t.status, AtlasStatus::ok);
  const Vec2 O1(-0.4, 0.0), P(0.0, t.height);
  const double d = (P - O1).norm();
  const double along = (d * d + p.r1 * p.r1 - p.r2 * p.r2) / (2.0 * d);
  const double off = std::sqrt(p.r1 * p.r1 - along * along);
  const Vec2 e = (P - O1) / d, nrm(-e.y(), e.x());
  Vec2 A1 = O1 + along * e + off * nrm;
  const Vec2 other = O1 + along * e - off * nrm;
  if (other.x() < A1.x()) A1 = other;
  const double sin_phi = std::abs(A1.x()) / p.r2, cos_phi = (P.y() - A1.y()) / p.r2;
  EXPECT_NEAR(t.min_transmission_sin, std::abs(2.0 * sin_phi * cos_phi), 1e-5);
}

TEST(Atlas, GridStatusesThreadsAndFiles) {
  AtlasOptions o = quick(9);
  o.threads = 1;
  const Atlas one = performance_atlas(o);
  o.threads = 2;
  const Atlas two = performance_atlas(o);
  ASSERT_EQ(one.cells.size(), two.cells.size());
  ASSERT_EQ(one.cells.size(), std::size_t(one.nx) * std::size_t(one.ny));
  for (std::size_t k = 0; k < one.cells.size(); ++k) {
    const InscribedTarget& a = one.cells[k].figures;
    const InscribedTarget& b = two.cells[k].figures;
    EXPECT_EQ(a.status, b.status);
    EXPECT_EQ(a.scale, b.scale);  // bit for bit: each cell is independent of the others
    EXPECT_EQ(a.min_lci, b.min_lci);
    if (a.status == AtlasStatus::ok) {
      EXPECT_GT(a.scale, 0.0);
      EXPECT_GE(a.min_lci, 0.0);
      EXPECT_LE(a.min_lci, 1.0);
      EXPECT_GE(a.min_transmission_sin, 0.0);
      EXPECT_LE(a.min_transmission_sin, 1.0);
      EXPECT_LT(one.cells[k].point.r3, 2.0);
    }
  }
  // Counts: the cells off the triangle, counted here from the chart.
  std::size_t off = 0;
  for (int j = 0; j < one.ny; ++j)
    for (int i = 0; i < one.nx; ++i) {
      const double x = one.x0 + i * one.spacing, y = one.y0 + j * one.spacing;
      if (!(y > 0.0 && y < 3.0 && std::abs(x) < (3.0 - y) / kSqrt3)) ++off;
    }
  EXPECT_EQ(one.count(AtlasStatus::outside), off);
  EXPECT_GT(one.count(AtlasStatus::ok), 0u);
  EXPECT_GT(one.count(AtlasStatus::no_workspace), 0u);

  // The files: CSV rows for the triangle's cells, the .vti read back by VTK, the pictures, JSON.
  testing::ScratchDir dir("fivebar_atlas");
  const auto paths = write_atlas_files(dir.path() / "atlas", one, "family");
  ASSERT_EQ(paths.size(), 5u);
  for (const auto& p : paths) {
    EXPECT_TRUE(std::filesystem::is_regular_file(p)) << p;
    EXPECT_EQ(p.parent_path(), dir.path() / "atlas");
  }
  std::istringstream csv(testing::slurp(dir.path() / "atlas" / "family.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "chart_x,chart_y,r1,r2,r3,status,scale_D,height_D,min_lci,min_transmission_sin,limited_by");
  std::size_t rows = 0, empty_scale = 0;
  while (std::getline(csv, line)) {
    ++rows;
    if (line.find("no_workspace,,") != std::string::npos) ++empty_scale;
    EXPECT_EQ(line.find("nan"), std::string::npos) << line;
  }
  EXPECT_EQ(rows, one.cells.size() - off);
  EXPECT_EQ(empty_scale, one.count(AtlasStatus::no_workspace));

  vtkNew<vtkXMLImageDataReader> reader;
  const std::string vti = (dir.path() / "atlas" / "family.vti").string();
  reader->SetFileName(vti.c_str());
  reader->Update();
  vtkImageData* image = reader->GetOutput();
  ASSERT_NE(image, nullptr);
  int dims[3];
  image->GetDimensions(dims);
  EXPECT_EQ(dims[0], one.nx);
  EXPECT_EQ(dims[1], one.ny);
  vtkDataArray* scale = image->GetPointData()->GetArray("scale_D");
  vtkDataArray* status = image->GetPointData()->GetArray("status");
  ASSERT_NE(scale, nullptr);
  ASSERT_NE(status, nullptr);
  for (std::size_t k = 0; k < one.cells.size(); ++k) {
    const bool ok = one.cells[k].figures.status == AtlasStatus::ok;
    EXPECT_EQ(int(status->GetTuple1(vtkIdType(k))), int(one.cells[k].figures.status));
    if (ok) EXPECT_EQ(scale->GetTuple1(vtkIdType(k)), one.cells[k].figures.scale);
    else EXPECT_TRUE(std::isnan(scale->GetTuple1(vtkIdType(k))));
  }
  auto* names = vtkStringArray::SafeDownCast(image->GetFieldData()->GetAbstractArray("status_names"));
  ASSERT_NE(names, nullptr);
  EXPECT_EQ(names->GetValue(1), "no_workspace");

  const std::string svg = testing::slurp(dir.path() / "atlas" / "family.svg");
  const std::string png = testing::slurp(dir.path() / "atlas" / "family.png");
  EXPECT_NE(svg.find("<svg"), std::string::npos);
  ASSERT_GE(png.size(), 8u);
  EXPECT_EQ(png.substr(1, 3), "PNG");
  const Json j = Json::parse(testing::slurp(dir.path() / "atlas" / "family.json"));
  EXPECT_EQ(j["counts"]["ok"].get<std::size_t>(), one.count(AtlasStatus::ok));
  EXPECT_TRUE(j["station"].is_null());
  expect_json_conventions(j);
  EXPECT_THROW(atlas_files(one, "../escape"), InputError);
}

TEST(Atlas, StationIsMarkedWithItsOwnFigures) {
  Station s;
  s.name = "index";
  s.target.center = Vec2(6.25, 15.5);
  s.target.axes = Vec2(15.0, 12.0);
  s.lower = paper_mechanism("index", "lower");
  s.upper = paper_mechanism("index", "upper");
  const Atlas a = performance_atlas(s, quick(5));
  ASSERT_TRUE(a.station);
  const AtlasStation& st = *a.station;
  EXPECT_EQ(st.mechanism, "lower");
  EXPECT_NEAR(a.options.shape.aspect, 0.8, 1e-12);
  EXPECT_NEAR(st.point.D_mm, 36.5 / 3.0, 1e-12);
  EXPECT_NEAR(st.target_scale, 7.5 / st.point.D_mm, 1e-12);
  // The mark's figure is the mechanism's own, in units of D.
  const InscribedTarget direct = inscribed_target(*s.lower, a.options.shape, quick(5));
  EXPECT_NEAR(st.figures.scale * st.point.D_mm, direct.scale, 1e-3 * direct.scale);
  EXPECT_TRUE(st.target_covered);  // the paper's target is covered (fivebar coverage)
  EXPECT_GT(st.target_min_lci, 0.0);
  const Json j = to_json(a);
  expect_json_conventions(j);
  EXPECT_EQ(j["station"], "index");
  EXPECT_EQ(j["mechanism"], "lower");
  EXPECT_NEAR(j["station_figures"]["inscribed_semi_major_mm"].get<double>(), direct.scale, 1e-3 * direct.scale);
  const auto lines = summary_lines(a);
  ASSERT_GE(lines.size(), 3u);
  EXPECT_NE(lines.back().find("own target: covered"), std::string::npos) << lines.back();

  // A mark: another design on the same chart, its figures those of its point.
  Atlas marked = a;
  ASSERT_TRUE(add_mark(marked, "thumb", paper_mechanism("thumb", "lower")));
  ASSERT_EQ(marked.marks.size(), 1u);
  const auto thumb = design_point(paper_mechanism("thumb", "lower"));
  EXPECT_NEAR(marked.marks[0].point.r2, thumb->r2, 1e-12);
  DesignPoint unit = *thumb;
  unit.D_mm = 1.0;
  const InscribedTarget at_thumb =
      inscribed_target(atlas_mechanism(unit, {-1, +1}, AssemblyMode::Plus), a.options.shape, quick(5));
  EXPECT_EQ(marked.marks[0].figures.scale, at_thumb.scale);
  Mechanism bent = paper_mechanism("thumb", "lower");
  bent.L[0] = 9.5;
  std::string why;
  EXPECT_FALSE(add_mark(marked, "bent", bent, &why));
  EXPECT_NE(why.find("not symmetric"), std::string::npos);
  const Json jm = to_json(marked);
  expect_json_conventions(jm);
  ASSERT_EQ(jm["marks"].size(), 1u);
  EXPECT_EQ(jm["marks"][0]["label"], "thumb");
  EXPECT_NE(summary_lines(marked).back().find("mark thumb"), std::string::npos);
  EXPECT_FALSE(plot_atlas(marked).png.empty());

  // Only the upper mechanism: mirrored, the same point and figure.
  Station up = s;
  up.lower.reset();
  const Atlas b = performance_atlas(up, quick(5));
  ASSERT_TRUE(b.station);
  EXPECT_EQ(b.options.assembly_mode, AssemblyMode::Plus);
  EXPECT_NEAR(b.station->figures.scale, st.figures.scale, 1e-3 * st.figures.scale);

  // Not symmetric: the atlas without a mark, and a note saying why.
  Station skew = s;
  skew.lower->L[3] = 16.0;
  const Atlas c = performance_atlas(skew, quick(5));
  EXPECT_FALSE(c.station);
  EXPECT_NE(c.station_note.find("not symmetric"), std::string::npos);
}

TEST(Atlas, BadOptionsNameTheField) {
  AtlasOptions o;
  o.cells = 2;
  try {
    performance_atlas(o);
    FAIL() << "cells = 2 accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cells"), std::string::npos);
  }
  o = AtlasOptions{};
  o.fraction = 0.0;
  EXPECT_THROW(performance_atlas(o), InputError);
  o = AtlasOptions{};
  o.shape.aspect = 1.5;
  EXPECT_THROW(inscribed_target(paper_mechanism("index", "lower"), o.shape, o), InputError);
}

}  // namespace
}  // namespace fivebar
