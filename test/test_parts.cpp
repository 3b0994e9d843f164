// Printable parts (fivebar/parts.hpp): the OpenSCAD library renders every module without a
// warning, the meshes pass the CGAL checks, and the design intent holds on the meshes: pin-centre
// distances equal the link lengths of the paper's stations (Table 1) and follow a changed length
// exactly; holes are pin + 2 x clearance. Also: bad designs are refused before any rendering,
// unchanged parts are not rendered again, the BOM agrees with the meshes, the `parts` product and
// the `fivebar parts` command.
//
// Renders are kept small: the index station (5 parts) at $fn = 24. Expected values are derived
// here from the paper's numbers and the design file, independently of the library: the test
// parses the STL files itself and measures volumes (divergence theorem), bounding boxes and hole
// centres (centroid of the hole-wall vertices) on its own.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <numbers>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include "cli_test.hpp"
#include "process.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/sections/print.hpp"
#include "fivebar/design.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"
#include "fivebar/parts.hpp"
#include "fivebar/scene.hpp"

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using ft::slurp;
using namespace fivebar;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;

namespace {

// Paper Table 1 and designs/iros2022.yaml's geometry/print sections, restated.
constexpr double kL1 = 9.0, kL3Index = 15.0, kL3Thumb = 17.5;
constexpr double kPin = 2.0, kClearance = 0.15, kShaft = 3.0;
constexpr double kHole = kPin + 2 * kClearance;     // 2.3
constexpr double kShaftBore = kShaft + 2 * kClearance;  // 3.3
constexpr double kThickness = 2.5, kBoss = 5.0, kWidth = 4.0, kTactorHeight = 6.0;
constexpr int kFn = 24;

// --- An STL reader and measurements of the test's own ---------------------------------------------

using P3 = std::array<double, 3>;
struct Stl {
  std::vector<std::array<P3, 3>> triangles;
  std::vector<P3> points() const {
    std::set<P3> s;
    for (const auto& t : triangles) s.insert(t.begin(), t.end());
    return {s.begin(), s.end()};
  }
  P3 lo() const {
    P3 r{1e300, 1e300, 1e300};
    for (const auto& p : points()) for (int i = 0; i < 3; ++i) r[i] = std::min(r[i], p[i]);
    return r;
  }
  P3 hi() const {
    P3 r{-1e300, -1e300, -1e300};
    for (const auto& p : points()) for (int i = 0; i < 3; ++i) r[i] = std::max(r[i], p[i]);
    return r;
  }
  double extent(int axis) const { return hi()[axis] - lo()[axis]; }
  /// Divergence theorem: sum of signed tetrahedra (origin, triangle).
  double volume() const {
    double v = 0.0;
    for (const auto& t : triangles) {
      const P3 &a = t[0], &b = t[1], &c = t[2];
      v += a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
    }
    return v / 6.0;
  }
};

Stl parse_stl(const fs::path& p) {
  const std::string d = slurp(p);
  Stl s;
  if (d.size() < 84) {
    ADD_FAILURE() << p << " is not a binary STL";
    return s;
  }
  std::uint32_t n = 0;
  std::memcpy(&n, d.data() + 80, 4);
  EXPECT_EQ(d.size(), 84u + 50u * n) << p;
  for (std::uint32_t i = 0; i < n && 84 + 50 * (i + 1) <= d.size(); ++i) {
    float f[12];
    std::memcpy(f, d.data() + 84 + 50 * i, 48);
    s.triangles.push_back({P3{f[3], f[4], f[5]}, P3{f[6], f[7], f[8]}, P3{f[9], f[10], f[11]}});
  }
  return s;
}

/// Centre of a round hole: centroid of the distinct (x, y) of the vertices whose distance from
/// the nominal axis is in the band around the hole radius. Exact for a regular polygon.
std::optional<std::array<double, 2>> hole_centroid(const Stl& s, double cx, double cy, double r) {
  std::set<std::pair<double, double>> xy;
  for (const auto& p : s.points()) {
    const double d = std::hypot(p[0] - cx, p[1] - cy);
    if (d > 0.85 * r && d < 1.25 * r) xy.emplace(p[0], p[1]);
  }
  if (xy.size() < 6) return std::nullopt;
  double x = 0, y = 0;
  for (const auto& [a, b] : xy) x += a, y += b;
  return std::array<double, 2>{x / xy.size(), y / xy.size()};
}

// --- BOM ----------------------------------------------------------------------------------------

std::vector<std::map<std::string, std::string>> read_csv(const fs::path& p) {
  std::istringstream in(slurp(p));
  std::string line;
  std::vector<std::string> header;
  std::vector<std::map<std::string, std::string>> rows;
  const auto split = [](const std::string& l) {
    std::vector<std::string> out;
    std::stringstream ss(l);
    std::string cell;
    while (std::getline(ss, cell, ',')) out.push_back(cell);
    if (!l.empty() && l.back() == ',') out.emplace_back();
    return out;
  };
  if (!std::getline(in, line)) return rows;
  header = split(line);
  while (std::getline(in, line)) {
    const auto cells = split(line);
    EXPECT_EQ(cells.size(), header.size()) << line;
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < cells.size(); ++i) row[header[i]] = cells[i];
    rows.push_back(row);
  }
  return rows;
}

// --- Fixture ------------------------------------------------------------------------------------

/// A scratch directory per test and the binary (test/cli_test.hpp), with the design at $fn 24.
class Parts : public ft::CliTest {
 protected:
  Parts() : CliTest("fivebar_test_parts") {}

  /// The paper's design file as a path: messages are checked against kDesign.string().
  static inline const fs::path kDesign = CliTest::kDesign;

  /// The paper's design file with `from` replaced by `to` (each must occur), $fn lowered to 24.
  fs::path design_with(const std::string& name, std::vector<ft::Edit> edits = {}) {
    edits.emplace_back("fn: 96", "fn: " + std::to_string(kFn));
    return CliTest::design_with(name, edits);
  }
  /// 1-based line of the first line of `file` containing `needle`.
  static int line_of(const fs::path& file, const std::string& needle) {
    std::istringstream in(slurp(file));
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
      if (line.find(needle) != std::string::npos) return n;
    }
    return -1;
  }

  /// The paper's device at $fn 24, tip sizes pinned so that the expected post height is known here.
  Design paper() {
    Design d = load_design(kDesign);
    d.get<PrintSettings>()->fn = kFn;
    return d;
  }
  PartsOptions options(const fs::path& out, std::optional<std::string> station = "index") {
    PartsOptions o;
    o.out_dir = out;
    o.station = std::move(station);
    o.hardware.tip_flange_height = 1.0;
    o.hardware.tip_dome_height = 1.0;
    return o;
  }
  static const PartResult& part(const PartsReport& r, const std::string& name) {
    for (const auto& p : r.parts) {
      if (p.spec.name == name) return p;
    }
    ADD_FAILURE() << "no part " << name;
    static const PartResult none;
    return none;
  }
};

// --- Meshes and fits on synthetic data (no openscad) ------------------------------------------------

/// A closed, outward axis-aligned box [x0,x1] x [y0,y1] x [z0,z1].
TriangleMesh box(double x0, double y0, double z0, double x1, double y1, double z1) {
  TriangleMesh m;
  for (int i = 0; i < 8; ++i) {
    m.vertices.emplace_back((i & 1) ? x1 : x0, (i & 2) ? y1 : y0, (i & 4) ? z1 : z0);
  }
  // Faces counter-clockwise seen from outside.
  const std::uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : q) {
    m.triangles.push_back({f[0], f[1], f[2]});
    m.triangles.push_back({f[0], f[2], f[3]});
  }
  return m;
}

TriangleMesh merge(const TriangleMesh& a, const TriangleMesh& b) {
  TriangleMesh m = a;
  const auto offset = static_cast<std::uint32_t>(a.vertices.size());
  m.vertices.insert(m.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto t : b.triangles) m.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return m;
}

TEST(MeshChecks, AClosedOutwardBoxPasses) {
  const MeshCheck c = check_mesh(box(0, 0, 0, 2, 3, 4));
  EXPECT_TRUE(c.passed()) << ::testing::PrintToString(c.problems);
  EXPECT_TRUE(c.manifold);
  EXPECT_TRUE(c.closed);
  EXPECT_FALSE(c.self_intersects);
  EXPECT_TRUE(c.outward);
  EXPECT_EQ(c.components, 1u);
  EXPECT_NEAR(c.volume_mm3, 24.0, 1e-12);
  EXPECT_EQ(c.bbox_max_mm, Eigen::Vector3d(2, 3, 4));
}

TEST(MeshChecks, EachDefectIsReported) {
  TriangleMesh open = box(0, 0, 0, 1, 1, 1);
  open.triangles.pop_back();
  const MeshCheck o = check_mesh(open);
  EXPECT_FALSE(o.closed);
  EXPECT_THAT(o.problems, ::testing::Contains(HasSubstr("not closed: 3 border edges")));

  TriangleMesh inside_out = box(0, 0, 0, 1, 1, 1);
  for (auto& t : inside_out.triangles) std::swap(t[1], t[2]);
  const MeshCheck i = check_mesh(inside_out);
  EXPECT_TRUE(i.closed);
  EXPECT_FALSE(i.outward);
  EXPECT_NEAR(i.volume_mm3, -1.0, 1e-12);
  EXPECT_THAT(i.problems, ::testing::Contains(HasSubstr("inward")));

  const MeshCheck two = check_mesh(merge(box(0, 0, 0, 1, 1, 1), box(3, 0, 0, 4, 1, 1)));
  EXPECT_EQ(two.components, 2u);
  EXPECT_FALSE(two.self_intersects);
  EXPECT_THAT(two.problems, ::testing::ElementsAre(HasSubstr("2 separate shells, expected 1")));
  EXPECT_TRUE(check_mesh(merge(box(0, 0, 0, 1, 1, 1), box(3, 0, 0, 4, 1, 1)), 2).passed());

  const MeshCheck overlap = check_mesh(merge(box(0, 0, 0, 2, 2, 2), box(1, 1, 1, 3, 3, 3)));
  EXPECT_TRUE(overlap.self_intersects);

  TriangleMesh fan = box(0, 0, 0, 1, 1, 1);
  fan.triangles.push_back(fan.triangles.front());  // an edge in three faces
  EXPECT_FALSE(check_mesh(fan).manifold);
  EXPECT_FALSE(check_mesh(TriangleMesh{}).passed());
}

/// Vertices of an n-gon circumscribed about the circle of diameter d (a polyhole), at two heights.
void add_polyhole(TriangleMesh& m, double cx, double cy, double d, int n, double flat_y = 1e9) {
  const double R = 0.5 * d / std::cos(std::numbers::pi / n);
  for (double z : {0.0, 2.5}) {
    for (int i = 0; i < n; ++i) {
      const double a = 2 * std::numbers::pi * i / n;
      const double y = R * std::sin(a);
      if (y > flat_y) continue;
      m.vertices.emplace_back(cx + R * std::cos(a), cy + y, z);
    }
  }
}

TEST(CircleFit, FindsTheRealAxisAndTheNarrowestWidth) {
  TriangleMesh m;
  add_polyhole(m, 3.0, 4.0, 2.3, 24);
  const CircleFit f = fit_circle_wall(m, {"pin", {3.0, 4.0}, 2.3});
  ASSERT_TRUE(f.found);
  EXPECT_NEAR(f.center_mm.x(), 3.0, 1e-12);
  EXPECT_NEAR(f.center_mm.y(), 4.0, 1e-12);
  EXPECT_NEAR(f.diameter_mm, 2.3, 1e-12);  // the polygon's narrowest width, not its vertex circle
  EXPECT_NEAR(f.vertex_radius_mm, 1.15 / std::cos(std::numbers::pi / 24), 1e-12);
  EXPECT_EQ(f.points, 24u);

  // A hole 0.05 mm away from where the design puts it is measured where it is.
  const CircleFit shifted = fit_circle_wall(m, {"pin", {3.05, 4.0}, 2.3});
  ASSERT_TRUE(shifted.found);
  EXPECT_NEAR(shifted.center_mm.x(), 3.0, 1e-12);
  // Far away: not found, rather than invented.
  EXPECT_FALSE(fit_circle_wall(m, {"pin", {5.0, 4.0}, 2.3}).found);
  // A peg reports its widest diameter.
  EXPECT_NEAR(fit_circle_wall(m, {"peg", {3.0, 4.0}, 2.3, true}).diameter_mm, 2.0 * f.vertex_radius_mm, 1e-12);
  // Only vertices in the z range count.
  EXPECT_FALSE(fit_circle_wall(m, {"pin", {3.0, 4.0}, 2.3, false, 5.0, 6.0}).found);
}

TEST(CircleFit, ADBoreIsCentredOnItsArcNotOnItsFlat) {
  // A 3.3 mm D-bore with its flat 1.15 mm from the axis (3 mm shaft, 0.5 mm flat, 0.15 clearance),
  // plus the two corners where the flat meets the arc, which are not on the circle.
  TriangleMesh m;
  add_polyhole(m, -1.0, 2.0, 3.3, 24, 1.15);
  const double R = 1.65 / std::cos(std::numbers::pi / 24);
  const double cx = std::sqrt(R * R - 1.15 * 1.15) * 0.995;  // on a polygon edge, inside the circle
  for (double z : {0.0, 2.5}) {
    m.vertices.emplace_back(-1.0 + cx, 2.0 + 1.15, z);
    m.vertices.emplace_back(-1.0 - cx, 2.0 + 1.15, z);
  }
  const CircleFit f = fit_circle_wall(m, {"shaft", {-1.0, 2.0}, 3.3});
  ASSERT_TRUE(f.found);
  EXPECT_NEAR(f.center_mm.x(), -1.0, 1e-9);
  EXPECT_NEAR(f.center_mm.y(), 2.0, 1e-9);
  EXPECT_NEAR(f.diameter_mm, 3.3, 1e-9);
}

TEST(ReadStl, RefusesWhatIsNotABinaryStl) {
  const fs::path dir = fs::temp_directory_path() / ("fivebar_test_stl_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "ascii.stl") << "solid x\nendsolid x\n";
  EXPECT_THAT([&] { (void)read_stl(dir / "ascii.stl"); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("not a binary STL")));
  std::string truncated(84, '\0');
  truncated[80] = 2;  // two triangles announced, none present
  std::ofstream(dir / "short.stl", std::ios::binary) << truncated;
  EXPECT_THAT([&] { (void)read_stl(dir / "short.stl"); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("should be 184 bytes, is 84")));
  EXPECT_THROW((void)read_stl(dir / "missing.stl"), IoError);
  fs::remove_all(dir);
}

// --- Planning (no openscad) -------------------------------------------------------------------------

TEST_F(Parts, PlanOfThePaperIndexStation) {
  const auto plan = plan_parts(paper(), options(dir_ / "out"));
  // Both mechanisms of the index station have L1 = L2 = 9 and L3 = L4 = 15 (Table 1): four equal
  // proximal links, two distal links with the tactor post (L3: layers 1 and 1 tie, L3 carries),
  // two without, two tips, one base.
  std::map<std::string, int> counts;
  for (const auto& p : plan) counts[p.name] = p.count;
  EXPECT_EQ(counts, (std::map<std::string, int>{{"proximal_link_9mm", 4},
                                                {"distal_link_tactor_15mm", 2},
                                                {"distal_link_15mm", 2},
                                                {"tactor_tip", 2},
                                                {"station_base", 1}}));
  for (const auto& p : plan) {
    EXPECT_EQ(p.station, "index");
    EXPECT_THAT(p.scad, AllOf(HasSubstr("use <../scad/fivebar.scad>"), HasSubstr("$fn = 24;")));
    if (p.name == "proximal_link_9mm") {
      EXPECT_EQ(p.uses, (std::vector<std::string>{"lower/L1", "lower/L2", "upper/L1", "upper/L2"}));
      EXPECT_EQ(p.mechanisms, "lower+upper");
      EXPECT_THAT(p.scad, AllOf(HasSubstr("proximal_link(length = 9, width = 4, thickness = 2.5, boss_d = 5"),
                                HasSubstr("pin_d = 2, shaft_d = 3, shaft_flat = 0.5, clearance = 0.15")));
    }
    if (p.name == "distal_link_tactor_15mm") {
      // Tip (1 + 1 mm) on a post: tactor_height 6 above the link's top face -> a 4 mm post.
      EXPECT_THAT(p.scad, HasSubstr("distal_link(length = 15, width = 4, thickness = 2.5, boss_d = 5, pin_d = 2, "
                                    "clearance = 0.15, post_height = 4, post_d = 5);"));
      EXPECT_EQ(p.uses, (std::vector<std::string>{"lower/L3", "upper/L3"}));
    }
    if (p.name == "station_base") {
      EXPECT_THAT(p.scad, HasSubstr("motor_positions = [[0, 0], [12.5, 0], [0, 31], [12.5, 31]]"));
    }
  }
  EXPECT_EQ(plan_parts(paper(), options(dir_ / "out", std::nullopt)).size(), 10u);
  EXPECT_FALSE(fs::exists(dir_ / "out"));  // planning writes nothing
}

TEST_F(Parts, LayersChooseWhichDistalLinkCarriesTheTactor) {
  Design d = paper();
  d.get<Geometry>()->layers = {0, 0, 1, 2};  // L4 above L3: the post must not pass through L3
  const auto plan = plan_parts(d, options(dir_ / "out"));
  for (const auto& p : plan) {
    if (p.name.starts_with("distal_link_tactor")) {
      EXPECT_EQ(p.uses, (std::vector<std::string>{"lower/L4", "upper/L4"}));
    }
  }
}

// --- Bad designs are refused before anything is rendered or written ---------------------------------

TEST_F(Parts, TooShortLinkIsRejectedBeforeRendering) {
  // In the file: the loader refuses it with file, line and key.
  const fs::path file = design_with("short.yaml", {{"links: [9, 9, 15, 15]", "links: [4.5, 9, 15, 15]"}});
  const std::string where = file.string() + ":" + std::to_string(line_of(file, "links: [4.5")) + ": ";
  EXPECT_THAT([&] { (void)load_design(file); },
              ::testing::ThrowsMessage<InputError>(HasSubstr(where + "stations.index.mechanisms.lower.links[0] = 4.5 mm: "
                                                                     "shorter than geometry.boss_diameter (5 mm)")));

  // Built by hand (bypassing the loader): build_parts refuses it the same way, naming the line of
  // the key in the design's source file, and neither renders nor writes anything.
  Design d = paper();
  d.stations[0].lower->L[0] = 4.5;
  const fs::path out = dir_ / "out";
  EXPECT_THAT([&] { (void)build_parts(d, options(out)); },
              ::testing::ThrowsMessage<InputError>(
                  HasSubstr(kDesign.string() + ":" + std::to_string(line_of(kDesign, "links: [9, 9, 15, 15]")) +
                            ": stations.index.mechanisms.lower.links[0] = 4.5 mm: shorter than geometry.boss_diameter")));
  EXPECT_FALSE(fs::exists(out));

  // Long enough for the loader, too short for a proximal link: a 4 mm shaft needs a hub of
  // 2 x ((4.3 / 2) / cos(7.5 deg) + 0.8) / cos(7.5 deg) = 6.0 mm, so hub and pin boss need
  // (6.0 + 5) / 2 = 5.5 mm between the axes.
  const fs::path hub = design_with("hub.yaml", {{"motor_shaft_diameter: 3", "motor_shaft_diameter: 4"},
                                                {"links: [9, 9, 15, 15]", "links: [5.2, 9, 15, 15]"}});
  const Design hd = load_design(hub);
  const double c = std::cos(std::numbers::pi / kFn);
  const double hub_d = 2 * (2.15 / c + 0.8) / c;
  std::ostringstream need;
  need << std::fixed << std::setprecision(3) << 0.5 * (hub_d + kBoss);
  EXPECT_THAT([&] { (void)build_parts(hd, options(out)); },
              ::testing::ThrowsMessage<InputError>(AllOf(
                  HasSubstr(hub.string() + ":" + std::to_string(line_of(hub, "links: [5.2")) +
                            ": stations.index.mechanisms.lower.links[0] = 5.2 mm: too short to print"),
                  HasSubstr("at least " + need.str() + " mm"))));
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(Parts, OtherUnprintableNumbersNameTheirKey) {
  const fs::path out = dir_ / "out";
  // The 2 mm tip on a 2.5 mm tactor height leaves a 0.5 mm post, under print.min_wall 0.8.
  const fs::path low = design_with("low.yaml", {{"tactor_height: 6", "tactor_height: 2.5"}});
  EXPECT_THAT([&] { (void)build_parts(load_design(low), options(out)); },
              ::testing::ThrowsMessage<InputError>(
                  HasSubstr(low.string() + ":" + std::to_string(line_of(low, "tactor_height: 2.5")) +
                            ": geometry.tactor_height = 2.5 mm: leaves a tactor post of 0.500 mm")));
  // Base joints 8 mm apart cannot both hold a 10 mm motor.
  const fs::path close = design_with("close.yaml", {{"bases: [[0, 0], [12.5, 0]]", "bases: [[0, 0], [8, 0]]"}});
  EXPECT_THAT([&] { (void)build_parts(load_design(close), options(out)); },
              ::testing::ThrowsMessage<InputError>(
                  HasSubstr(close.string() + ":" + std::to_string(line_of(close, "bases: [[0, 0], [8, 0]]")) +
                            ": stations.index.mechanisms.lower.bases[1] = [8, 0] mm: only 8.000 mm from "
                            "stations.index.mechanisms.lower.bases[0]")));
  // No geometry section, an unknown station.
  Design bare = paper();
  bare.reset<Geometry>();
  EXPECT_THAT([&] { (void)build_parts(bare, options(out)); },
              ::testing::ThrowsMessage<InputError>(HasSubstr("no geometry: section")));
  EXPECT_THAT([&] { (void)build_parts(paper(), options(out, "pinky")); },
              ::testing::ThrowsMessage<InputError>(AllOf(HasSubstr("no station 'pinky'"), HasSubstr("index, thumb"))));
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(Parts, WithoutOpenscadNothingIsWrittenAndNoRenderWritesSources) {
  PartsOptions o = options(dir_ / "out");
  o.openscad = (dir_ / "no" / "openscad").string();
  // The library names no command-line flag; it says what can be done, and the CLI words it.
  try {
    (void)build_parts(paper(), o);
    ADD_FAILURE() << "no ToolError";
  } catch (const ToolError& e) {
    EXPECT_THAT(std::string(e.what()), AllOf(HasSubstr("not found"), HasSubstr("without rendering"),
                                             ::testing::Not(HasSubstr("--no-render"))));
    EXPECT_EQ(e.remedy(), fivebar::Remedy::without_rendering);
  }
  EXPECT_FALSE(fs::exists(dir_ / "out"));

  o.render = false;
  const PartsReport r = build_parts(paper(), o);
  EXPECT_TRUE(r.passed());
  ASSERT_EQ(r.parts.size(), 5u);
  for (const auto& p : r.parts) {
    EXPECT_EQ(p.render, RenderState::not_requested);
    EXPECT_EQ(slurp(dir_ / "out" / p.scad_file), p.spec.scad);
    EXPECT_FALSE(fs::exists(dir_ / "out" / p.stl_file));
  }
  EXPECT_EQ(slurp(dir_ / "out" / "scad" / "fivebar.scad"), slurp(kSource / "scad" / "fivebar.scad"));
  const auto bom = read_csv(dir_ / "out" / "bom.csv");
  ASSERT_EQ(bom.size(), 5u);
  EXPECT_EQ(bom[0].at("part"), "proximal_link_9mm");
  EXPECT_EQ(bom[0].at("count"), "4");
  EXPECT_EQ(bom[0].at("volume_mm3"), "");
}

// --- Renders -------------------------------------------------------------------------------------

/// A program on PATH, or empty.
fs::path on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const fs::path p = fs::path(dir) / name;
    if (!dir.empty() && ::access(p.c_str(), X_OK) == 0) return p;
  }
  return {};
}

// PrusaSlicer (Debian prusa-slicer, installed by ./test.sh) slices every part of the index
// station for a resin printer, without supports or pad so that the resin is the part's own; the
// .sl1 archive's config.ini states the resin used (usedMaterial, ml). It agrees with the BOM's
// volume to the staircase of 0.05 mm layers on parts 2.5 mm thick (a few per cent).
TEST_F(Parts, EveryPartSlicesInPrusaSlicerAndUsesTheResinTheBomSays) {
  const fs::path slicer = on_path("prusa-slicer"), unzip = on_path("unzip");
  if (slicer.empty() || unzip.empty())
    GTEST_SKIP() << "prusa-slicer or unzip not installed (./test.sh installs both): slicer check not run";
  const fs::path out = dir_ / "out";
  const PartsReport r = build_parts(paper(), options(out));
  ASSERT_TRUE(r.passed());
  ASSERT_EQ(r.parts.size(), 5u);
  for (const PartResult& p : r.parts) {
    SCOPED_TRACE(p.spec.name);
    ASSERT_TRUE(p.mesh.has_value());
    const fs::path sl1 = dir_ / (p.spec.name + ".sl1");
    const Outcome sliced =
        fivebar::testing::run(slicer.string(),
                              {"--export-sla", "--printer-technology", "SLA", "--no-supports-enable", "--no-pad-enable",
                               "--output", sl1.string(), (out / p.stl_file).string()},
                              dir_, dir_, 120.0);
    ASSERT_EQ(sliced.code, 0) << sliced.out << sliced.err;
    EXPECT_THAT(sliced.out + sliced.err, ::testing::Not(::testing::HasSubstr("error")));
    const Outcome ini = fivebar::testing::run(unzip.string(), {"-p", sl1.string(), "config.ini"}, dir_, dir_, 30.0);
    ASSERT_EQ(ini.code, 0) << ini.err;
    const auto at = ini.out.find("usedMaterial = ");
    ASSERT_NE(at, std::string::npos) << ini.out;
    const double used_ml = std::strtod(ini.out.c_str() + at + std::strlen("usedMaterial = "), nullptr);
    const double bom_ml = p.mesh->volume_mm3 / 1000.0;
    RecordProperty(p.spec.name + "_slicer_ml", std::to_string(used_ml));
    RecordProperty(p.spec.name + "_bom_ml", std::to_string(bom_ml));
    EXPECT_NEAR(used_ml, bom_ml, 0.06 * bom_ml + 0.002) << "slicer " << used_ml << " ml, BOM " << bom_ml << " ml";
  }
}


TEST_F(Parts, PaperIndexStationRendersWithoutWarningsAndKeepsTheDesignOnTheMesh) {
  const fs::path out = dir_ / "out";
  const PartsReport r = build_parts(paper(), options(out));
  ASSERT_EQ(r.parts.size(), 5u);
  for (const auto& p : r.parts) {
    SCOPED_TRACE(p.spec.name);
    // --hardwarnings: a single warning would have failed the render.
    EXPECT_EQ(p.render, RenderState::rendered) << p.render_error;
    EXPECT_TRUE(p.render_error.empty());
    ASSERT_TRUE(p.mesh.has_value());
    EXPECT_TRUE(p.mesh->closed);
    EXPECT_FALSE(p.mesh->self_intersects);
    EXPECT_TRUE(p.mesh->outward);
    EXPECT_EQ(p.mesh->components, 1u);
    EXPECT_GT(p.mesh->volume_mm3, 0.0);
    EXPECT_TRUE(p.passed()) << ::testing::PrintToString(p.problems);
  }
  EXPECT_TRUE(r.passed());

  // Pin-centre distances measured by the test itself: centroids of the hole-wall vertices.
  const Stl plain = parse_stl(out / "index" / "distal_link_15mm.stl");
  const auto a = hole_centroid(plain, 0.0, 0.0, 0.5 * kHole);
  const auto b = hole_centroid(plain, kL3Index, 0.0, 0.5 * kHole);
  ASSERT_TRUE(a && b);
  EXPECT_NEAR(std::hypot((*b)[0] - (*a)[0], (*b)[1] - (*a)[1]), kL3Index, 1e-4);
  // Outline: the bosses reach boss/2 beyond both pins; plate thickness.
  EXPECT_NEAR(plain.extent(0), kL3Index + kBoss, 1e-5);
  EXPECT_NEAR(plain.extent(1), kBoss, 1e-5);
  EXPECT_NEAR(plain.extent(2), kThickness, 1e-6);
  const Stl carrier = parse_stl(out / "index" / "distal_link_tactor_15mm.stl");
  EXPECT_NEAR(carrier.extent(2), kThickness + (kTactorHeight - 2.0), 1e-5);  // post under a 2 mm tip

  // The library's fits agree: distances equal the lengths, holes are pin + 2 clearance.
  EXPECT_NEAR(*part(r, "proximal_link_9mm").centre_distance_mm, kL1, 0.01);
  EXPECT_NEAR(*part(r, "distal_link_15mm").centre_distance_mm, kL3Index, 0.01);
  EXPECT_NEAR(*part(r, "distal_link_tactor_15mm").centre_distance_mm, kL3Index, 0.01);
  const auto& prox = part(r, "proximal_link_9mm");
  ASSERT_EQ(prox.holes.size(), 2u);
  EXPECT_NEAR(prox.holes[0].diameter_mm, kShaftBore, 0.01);  // the D-bore's arc
  EXPECT_NEAR(prox.holes[1].diameter_mm, kHole, 0.01);
  EXPECT_NEAR(part(r, "tactor_tip").holes.at(0).diameter_mm, kPin, 0.01);  // the peg
  // The base holds the four motors at Table 1's base joints.
  const auto& base = part(r, "station_base");
  const std::array<std::array<double, 2>, 4> joints{{{0, 0}, {12.5, 0}, {0, 31}, {12.5, 31}}};
  ASSERT_EQ(base.holes.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    ASSERT_TRUE(base.holes[i].found);
    EXPECT_NEAR(base.holes[i].center_mm.x(), joints[i][0], 0.01);
    EXPECT_NEAR(base.holes[i].center_mm.y(), joints[i][1], 0.01);
  }

  // BOM: one row per part, positive volumes equal to the meshes' (divergence theorem, here).
  const auto bom = read_csv(out / "bom.csv");
  ASSERT_EQ(bom.size(), 5u);
  for (const auto& row : bom) {
    SCOPED_TRACE(row.at("part"));
    const Stl s = parse_stl(out / row.at("stl"));
    const double volume = std::stod(row.at("volume_mm3"));
    EXPECT_GT(volume, 0.0);
    EXPECT_NEAR(volume, s.volume(), 1e-3 + 1e-6 * volume);
    EXPECT_NEAR(std::stod(row.at("resin_ml")), std::stoi(row.at("count")) * volume / 1000.0, 1e-4);
    EXPECT_EQ(row.at("station"), "index");
  }
  EXPECT_EQ(bom[2].at("part"), "distal_link_15mm");
  EXPECT_EQ(bom[2].at("bbox_mm"), "20.000x5.000x2.500");
  // The plain distal link against its analytic volume (true circles): a 15 x 4 bar, two 5 mm bosses
  // (each adds its disk minus the part inside the bar's strip), two 2.3 mm holes; 2.5 mm thick.
  // $fn = 24 polygons change the areas by about 1 %.
  const double r_b = 0.5 * kBoss, h = 0.5 * kWidth;
  const double disk_in_strip_half = h * std::sqrt(r_b * r_b - h * h) + r_b * r_b * std::asin(h / r_b);
  const double area = kL3Index * kWidth + 2 * (std::numbers::pi * r_b * r_b - disk_in_strip_half) -
                      2 * std::numbers::pi * 0.25 * kHole * kHole;
  EXPECT_NEAR(std::stod(bom[2].at("volume_mm3")), area * kThickness, 0.02 * area * kThickness);
}

TEST_F(Parts, PaperThumbStationLinksMeasureTheirLengths) {
  const PartsReport r = build_parts(paper(), options(dir_ / "out", "thumb"));
  EXPECT_TRUE(r.passed());
  EXPECT_NEAR(*part(r, "proximal_link_9mm").centre_distance_mm, kL1, 0.01);
  EXPECT_NEAR(*part(r, "distal_link_17.5mm").centre_distance_mm, kL3Thumb, 0.01);
  EXPECT_NEAR(*part(r, "distal_link_tactor_17.5mm").centre_distance_mm, kL3Thumb, 0.01);
  const Stl s = parse_stl(dir_ / "out" / "thumb" / "distal_link_17.5mm.stl");
  const auto a = hole_centroid(s, 0.0, 0.0, 0.5 * kHole);
  const auto b = hole_centroid(s, kL3Thumb, 0.0, 0.5 * kHole);
  ASSERT_TRUE(a && b);
  EXPECT_NEAR(std::hypot((*b)[0] - (*a)[0], (*b)[1] - (*a)[1]), kL3Thumb, 1e-4);
}

TEST_F(Parts, UnchangedPartsAreNotRenderedAgainAndAChangedL3LengthensItsLinkBy2mm) {
  const fs::path out = dir_ / "out";
  const PartsReport first = build_parts(paper(), options(out));
  ASSERT_EQ(first.count(RenderState::rendered), 5u);
  const auto stamp = fs::last_write_time(out / "index" / "distal_link_tactor_15mm.stl");

  // Same inputs: nothing rendered, the checks still run on the kept meshes.
  const PartsReport again = build_parts(paper(), options(out));
  EXPECT_EQ(again.count(RenderState::rendered), 0u);
  EXPECT_EQ(again.count(RenderState::up_to_date), 5u);
  EXPECT_TRUE(again.passed());
  EXPECT_EQ(fs::last_write_time(out / "index" / "distal_link_tactor_15mm.stl"), stamp);
  // A missing STL is rendered again, alone.
  fs::remove(out / "index" / "tactor_tip.stl");
  EXPECT_EQ(build_parts(paper(), options(out)).count(RenderState::rendered), 1u);

  // The lower mechanism's L3 2 mm longer: only its new link and the base (whose finger rest moves
  // out of the longer reach) are rendered.
  Design longer = paper();
  longer.stations[0].lower->L[2] = kL3Index + 2.0;
  const PartsReport r = build_parts(longer, options(out));
  EXPECT_TRUE(r.passed());
  std::set<std::string> rendered;
  for (const auto& p : r.parts) {
    if (p.render == RenderState::rendered) rendered.insert(p.spec.name);
  }
  EXPECT_EQ(rendered, (std::set<std::string>{"distal_link_tactor_17mm", "station_base"}));
  EXPECT_EQ(part(r, "distal_link_tactor_17mm").spec.uses, std::vector<std::string>{"lower/L3"});
  EXPECT_EQ(part(r, "distal_link_tactor_15mm").spec.uses, std::vector<std::string>{"upper/L3"});
  EXPECT_EQ(part(r, "distal_link_tactor_15mm").render, RenderState::up_to_date);

  // Measured on the meshes: exactly 2 mm longer, centre to centre and end to end.
  const Stl s15 = parse_stl(out / "index" / "distal_link_tactor_15mm.stl");
  const Stl s17 = parse_stl(out / "index" / "distal_link_tactor_17mm.stl");
  EXPECT_NEAR(s17.extent(0) - s15.extent(0), 2.0, 1e-5);
  EXPECT_NEAR(s17.extent(1), s15.extent(1), 1e-6);
  EXPECT_NEAR(s17.extent(2), s15.extent(2), 1e-6);
  // Only the bar between the bosses grew: 2 mm x 4 mm wide x 2.5 mm thick.
  EXPECT_NEAR(s17.volume() - s15.volume(), 2.0 * kWidth * kThickness, 1e-3);
  const auto a = hole_centroid(s17, 0.0, 0.0, 0.5 * kHole);
  const auto b = hole_centroid(s17, kL3Index + 2.0, 0.0, 0.5 * kHole);
  ASSERT_TRUE(a && b);
  EXPECT_NEAR(std::hypot((*b)[0] - (*a)[0], (*b)[1] - (*a)[1]), kL3Index + 2.0, 1e-4);
  EXPECT_NEAR(*part(r, "distal_link_tactor_17mm").centre_distance_mm -
                  *part(r, "distal_link_tactor_15mm").centre_distance_mm,
              2.0, 1e-4);
  // The 15 mm files of the lower mechanism's old L3 are still needed by the upper one; nothing
  // else is left behind.
  std::set<std::string> files;
  for (const auto& e : fs::directory_iterator(out / "index")) files.insert(e.path().filename().string());
  EXPECT_EQ(files.size(), 18u);  // 6 parts x (.scad, .stl, .stl.hash)
}

TEST_F(Parts, AFailedRenderReportsOpenscadsMessageAndLeavesNoStl) {
  // A library whose proximal_link reads an undefined variable: OpenSCAD warns, --hardwarnings fails.
  const fs::path lib = dir_ / "lib";
  fs::create_directories(lib);
  std::string text = slurp(kSource / "scad" / "fivebar.scad");
  const std::string from = "linear_extrude(height = thickness) fb_link_outline(length, width, hub_d, boss_d);";
  ASSERT_NE(text.find(from), std::string::npos);
  text.replace(text.find(from), from.size(),
               "linear_extrude(height = thickness + undefined_height) fb_link_outline(length, width, hub_d, boss_d);");
  std::ofstream(lib / "fivebar.scad") << text;
  PartsOptions o = options(dir_ / "out");
  o.scad_dir = lib;
  const PartsReport r = build_parts(paper(), o);
  EXPECT_FALSE(r.passed());
  const auto& p = part(r, "proximal_link_9mm");
  EXPECT_EQ(p.render, RenderState::failed);
  EXPECT_THAT(p.render_error, AllOf(HasSubstr("WARNING"), HasSubstr("undefined_height")));
  EXPECT_THAT(p.problems, ::testing::Contains(HasSubstr("openscad failed")));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "index" / "proximal_link_9mm.stl"));
  EXPECT_EQ(part(r, "distal_link_15mm").render, RenderState::rendered);  // the others are unaffected
  // No temporary is left behind.
  for (const auto& e : fs::directory_iterator(dir_ / "out" / "index")) {
    EXPECT_THAT(e.path().filename().string(), Not(HasSubstr(".tmp.")));
  }
}

TEST_F(Parts, PartsWithTheSameSourceAreRenderedOnceAndTheOthersCopyThatStl) {
  // A stand-in for openscad that logs each call and writes an STL naming the .scad it was made
  // from (an 80-byte header, no triangle): the thumb's proximal link and tactor tip have the same
  // source as the index station's (L1 = L2 = 9 mm in both, Table 1), the other parts differ.
  const fs::path log = dir_ / "calls.log";
  const fs::path fake = dir_ / "fake-openscad";
  std::ofstream(fake) << "#!/bin/sh\necho \"$@\" >> '" << log.string()
                      << "'\nout=; prev=; last=\nfor a in \"$@\"; do [ \"$prev\" = -o ] && out=\"$a\"; prev=\"$a\"; "
                         "last=\"$a\"; done\n{ printf '%-80.80s' \"$(basename \"$(dirname \"$last\")\")/$(basename \"$last\")\"; "
                         "head -c 4 /dev/zero; } > \"$out\"\n";
  fs::permissions(fake, fs::perms::owner_all);
  PartsOptions o = options(dir_ / "out", std::nullopt);
  o.openscad = fake.string();
  const PartsReport r = build_parts(paper(), o);
  ASSERT_EQ(r.parts.size(), 10u);
  std::istringstream calls(slurp(log));
  std::size_t n = 0;
  for (std::string line; std::getline(calls, line);) ++n;
  EXPECT_EQ(n, 8u);  // 10 parts, 8 distinct sources
  for (const PartResult& p : r.parts) {
    const bool twin = p.spec.station == "thumb" && (p.spec.name == "proximal_link_9mm" || p.spec.name == "tactor_tip");
    EXPECT_EQ(p.render, RenderState::rendered) << p.spec.label() << ": " << p.render_error;
    EXPECT_EQ(p.copied_from, twin ? "index/" + p.spec.name : "") << p.spec.label();
    // Each STL names the source it was rendered from: the twins' that of their index counterpart.
    const std::string stl = slurp(dir_ / "out" / p.stl_file);
    ASSERT_EQ(stl.size(), 84u) << p.spec.label();
    const std::string from = (twin ? std::string("index") : p.spec.station) + "/" + p.spec.name + ".scad";
    EXPECT_EQ(stl.substr(0, from.size()), from) << p.spec.label();
    EXPECT_TRUE(fs::exists(dir_ / "out" / (p.stl_file.string() + ".hash"))) << p.spec.label();
  }
  // A second build finds every part up to date, the copies included, and calls openscad no more.
  const PartsReport again = build_parts(paper(), o);
  EXPECT_EQ(again.count(RenderState::up_to_date), 10u);
  std::istringstream after(slurp(log));
  n = 0;
  for (std::string line; std::getline(after, line);) ++n;
  EXPECT_EQ(n, 8u);
}

// --- The product ------------------------------------------------------------------------------------

TEST_F(Parts, ProductBuildsTheSceneStationsOrSaysWhyNot) {
  const auto& known = known_products();
  const auto at = [&](const std::string& n) { return std::find(known.begin(), known.end(), n); };
  ASSERT_NE(at("parts"), known.end());
  EXPECT_LT(at("kinematics"), at("parts"));
  for (const char* later : {"export", "report"}) {
    if (at(later) != known.end()) EXPECT_LT(at("parts"), at(later));
  }
  for (const char* earlier : {"workspace", "coverage", "collision", "pattern", "sweep"}) {
    if (at(earlier) != known.end()) EXPECT_LT(at(earlier), at("parts"));
  }

  Design d = paper();
  d.stations.pop_back();  // the scene has the index station only
  if (d.get<PatternSettings>()) {       // and so no per-station pattern settings for the thumb
    std::erase_if(d.get<PatternSettings>()->overrides, [](const PatternOverride& o) { return o.station == "thumb"; });
  }
  if (d.get<ControllerSettings>()) {  // nor the controller's gains for it (controller.stations.thumb)
    std::erase_if(d.get<ControllerSettings>()->overrides, [](const ControlOverride& o) { return o.station == "thumb"; });
  }
  SceneOptions so;
  so.out_root = dir_ / "scene";
  so.products = std::vector<std::string>{"parts"};
  const SceneReport r = run_scene(d, so);
  const ProductOutcome* parts = nullptr;
  for (const auto& p : r.products) {
    if (p.name == "parts") parts = &p;
  }
  ASSERT_NE(parts, nullptr);
  ASSERT_EQ(parts->state, ProductOutcome::State::built) << parts->reason;
  EXPECT_TRUE(parts->passed) << parts->check;
  EXPECT_EQ(parts->result["parts"].size(), 5u);
  EXPECT_FALSE(fs::exists(r.out_dir / "parts" / "thumb"));
  EXPECT_THAT(parts->files, ::testing::Contains(fs::path("parts/bom.csv")));
  EXPECT_THAT(parts->files, ::testing::Contains(fs::path("parts/index/station_base.stl")));
  for (const auto& f : parts->files) EXPECT_TRUE(fs::exists(r.out_dir / f)) << f;
  EXPECT_THAT(r.to_markdown(), AllOf(HasSubstr("## Printable parts"), HasSubstr("`distal_link_tactor_15mm`")));

  // Left out, with the reason: no geometry; openscad not installed.
  Design bare = paper();
  bare.reset<Geometry>();
  so.products.reset();
  for (const auto& p : run_scene(bare, so).products) {
    if (p.name == "parts") EXPECT_THAT(p.reason, HasSubstr("geometry"));
  }
  ::setenv("FIVEBAR_OPENSCAD", (dir_ / "no-openscad").c_str(), 1);
  const SceneReport without = run_scene(d, so);
  ::unsetenv("FIVEBAR_OPENSCAD");
  for (const auto& p : without.products) {
    if (p.name == "parts") {
      EXPECT_EQ(p.state, ProductOutcome::State::left_out);
      EXPECT_THAT(p.reason, HasSubstr("openscad is not installed"));
    }
  }
}

}  // namespace
