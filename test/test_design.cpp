// Tests of the design model (lib/src/design/design.cpp) and the YAML loader (lib/src/yaml/design_loader.cpp):
// the shipped designs against the paper's Table 1, every validate() rule, the malformed-file corpus
// in test/data/malformed/, mode strings and joint ranges.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "fivebar/scene.hpp"
#include "fivebar/design.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/sections/patterns.hpp"
#include "fivebar/sections/print.hpp"
#include "fivebar/sections/sweep.hpp"

namespace fivebar {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::StartsWith;
using ::testing::ThrowsMessage;

constexpr double kPi = std::numbers::pi;
double deg(double degrees) { return degrees * kPi / 180.0; }

const fs::path kSourceDir = FIVEBAR_SOURCE_DIR;

// ---------------------------------------------------------------------------------------------
// Shipped designs against the paper (Table 1 and Section II), numbers typed independently.

void expect_mechanism(const Mechanism* m, const char* name, Vec2 O1, Vec2 O2, std::array<double, 4> L,
                      const char* working, AssemblyMode assembly) {
  ASSERT_NE(m, nullptr) << name;
  SCOPED_TRACE(name);
  EXPECT_EQ(m->name, name);
  EXPECT_EQ(m->O1, O1);
  EXPECT_EQ(m->O2, O2);
  EXPECT_EQ(m->L, L);
  EXPECT_EQ(to_string(m->working_mode), working);
  EXPECT_EQ(m->assembly_mode, assembly);
  EXPECT_FALSE(m->joint_limits.has_value());
  EXPECT_EQ(m->min_lci, 0.0);
}

void expect_index_station(const Station* index) {
  ASSERT_NE(index, nullptr);
  EXPECT_EQ(index->target.center, Vec2(6.25, 15.5));
  EXPECT_EQ(index->target.axes, Vec2(15.0, 12.0));
  EXPECT_EQ(index->target.angle, 0.0);
  expect_mechanism(index->mechanism("lower"), "lower", {0.0, 0.0}, {12.5, 0.0}, {9.0, 9.0, 15.0, 15.0}, "-+",
                   AssemblyMode::Plus);
  expect_mechanism(index->mechanism("upper"), "upper", {0.0, 31.0}, {12.5, 31.0}, {9.0, 9.0, 15.0, 15.0}, "+-",
                   AssemblyMode::Minus);
}

TEST(ShippedDesigns, Iros2022MatchesTable1) {
  const fs::path path = kSourceDir / "designs/iros2022.yaml";
  const Design design = load_design(path);
  EXPECT_EQ(design.name, "iros2022");
  EXPECT_EQ(design.source, path);
  ASSERT_EQ(design.stations.size(), 2u);
  EXPECT_EQ(design.stations[0].name, "index");  // file order
  EXPECT_EQ(design.stations[1].name, "thumb");
  expect_index_station(design.station("index"));

  const Station* thumb = design.station("thumb");
  ASSERT_NE(thumb, nullptr);
  EXPECT_EQ(thumb->target.center, Vec2(6.25, 17.5));
  EXPECT_EQ(thumb->target.axes, Vec2(15.0, 14.0));
  EXPECT_EQ(thumb->target.angle, 0.0);
  expect_mechanism(thumb->mechanism("lower"), "lower", {0.0, 0.0}, {12.5, 0.0}, {9.0, 9.0, 17.5, 17.5}, "-+",
                   AssemblyMode::Plus);
  expect_mechanism(thumb->mechanism("upper"), "upper", {0.0, 35.0}, {12.5, 35.0}, {9.0, 9.0, 17.5, 17.5}, "+-",
                   AssemblyMode::Minus);

  EXPECT_EQ(design.station("middle"), nullptr);
  EXPECT_NO_THROW(design.validate());
}

TEST(ShippedDesigns, TargetsAreCentredBetweenTheFourBaseJoints) {
  const Design design = load_design(kSourceDir / "designs/iros2022.yaml");
  for (const Station& s : design.stations) {
    SCOPED_TRACE(s.name);
    const Vec2 centroid = (s.lower->O1 + s.lower->O2 + s.upper->O1 + s.upper->O2) / 4.0;
    EXPECT_EQ(s.target.center, centroid);
  }
}

TEST(ShippedDesigns, IndexOnly) {
  const Design design = load_design(kSourceDir / "designs/iros2022-index.yaml");
  EXPECT_EQ(design.name, "iros2022-index");
  ASSERT_EQ(design.stations.size(), 1u);
  expect_index_station(design.station("index"));
  EXPECT_EQ(design.station("thumb"), nullptr);
  EXPECT_FALSE(design.products.has_value());
}

// ---------------------------------------------------------------------------------------------
// Malformed corpus: each file states the message substrings (and line) it must produce.

struct MalformedCase {
  fs::path path;
  std::vector<std::string> expects;
  int line = 0;  // 0: not stated
};

std::vector<fs::path> malformed_files() {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(kSourceDir / "test/data/malformed")) {
    if (entry.path().extension() == ".yaml") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

MalformedCase read_case(const fs::path& path) {
  MalformedCase c{path, {}, 0};
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line) && line.starts_with("# expect")) {
    if (line.starts_with("# expect-line: ")) {
      c.line = std::stoi(line.substr(15));
    } else if (line.starts_with("# expect: ")) {
      c.expects.push_back(line.substr(10));
    }
  }
  if (fs::file_size(path) == 0) c.expects.push_back("empty design file");  // no room for a comment
  return c;
}

class Malformed : public ::testing::TestWithParam<fs::path> {};

TEST_P(Malformed, IsRejectedWithFileLineAndKey) {
  const MalformedCase c = read_case(GetParam());
  ASSERT_FALSE(c.expects.empty()) << c.path << " lacks a first line '# expect: ...'";
  try {
    load_scene(c.path);  // with the scene's rule: a `products:` name is checked too
    FAIL() << c.path << " was accepted";
  } catch (const InputError& e) {
    const std::string message = e.what();
    SCOPED_TRACE(message);
    EXPECT_THAT(message, StartsWith(c.path.string() + ":"));
    for (const std::string& expected : c.expects) EXPECT_THAT(message, HasSubstr(expected));
    if (c.line > 0) {
      EXPECT_THAT(message, StartsWith(c.path.string() + ":" + std::to_string(c.line) + ": "));
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Corpus, Malformed, ::testing::ValuesIn(malformed_files()),
                         [](const ::testing::TestParamInfo<fs::path>& info) {
                           std::string name = info.param.stem().string();
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

TEST(MalformedCorpus, IsLargeEnough) { EXPECT_GE(malformed_files().size(), 30u); }

// ---------------------------------------------------------------------------------------------
// Loader details not covered by the corpus.

const std::string kMinimal = R"(name: m
stations:
  s:
    target: {center: [0, 1], axes: [2, 3]}
    mechanisms:
      upper:
        bases: [[0, 0], [1, 0]]
        links: [1, 2, 3, 4]
        working_mode: "++"
)";

TEST(Loader, DefaultsAndUnits) {
  const Design design = load_design_from_string(kMinimal, "<test>");
  EXPECT_TRUE(design.source.empty());
  const Station& s = design.stations.at(0);
  EXPECT_EQ(s.target.angle, 0.0);
  EXPECT_FALSE(s.lower.has_value());
  ASSERT_TRUE(s.upper.has_value());
  EXPECT_EQ(s.upper->assembly_mode, AssemblyMode::Any);
  EXPECT_EQ(s.upper->min_lci, 0.0);
  EXPECT_EQ(s.mechanisms().size(), 1u);
  EXPECT_EQ(s.mechanism("lower"), nullptr);
}

TEST(Loader, DegreesBecomeRadians) {
  const Design design = load_design_from_string(R"(name: m
stations:
  s:
    target: {center: [0, 1], axes: [2, 3], angle: 90}
    mechanisms:
      lower:
        bases: [[0, 0], [0, 0]]   # coincident base joints: degenerate but valid
        links: [1, 2.5, 3e0, +4]  # integers, decimals, exponents and a plus sign
        working_mode: --
        assembly_mode: any
        joint_limits: [[350, 10], [-90, 180]]
        min_lci: 1
)",
                                                "<test>");
  const Station& s = design.stations.at(0);
  EXPECT_DOUBLE_EQ(s.target.angle, kPi / 2);
  const Mechanism& m = *s.lower;
  EXPECT_EQ(m.L, (std::array<double, 4>{1.0, 2.5, 3.0, 4.0}));
  EXPECT_EQ(m.working_mode, (WorkingMode{-1, -1}));
  ASSERT_TRUE(m.joint_limits.has_value());
  EXPECT_DOUBLE_EQ((*m.joint_limits)[0].lo, deg(350));
  EXPECT_DOUBLE_EQ((*m.joint_limits)[0].hi, deg(10));
  EXPECT_DOUBLE_EQ((*m.joint_limits)[1].lo, deg(-90));
  EXPECT_DOUBLE_EQ((*m.joint_limits)[1].hi, deg(180));
  EXPECT_EQ(m.min_lci, 1.0);
}

TEST(Loader, ProductsKeepTheirOrder) {
  const Design design = load_design_from_string("products: [kinematics]\n" + kMinimal, "<test>");
  ASSERT_TRUE(design.products.has_value());
  EXPECT_EQ(*design.products, std::vector<std::string>{"kinematics"});
}

TEST(Loader, OriginNamesTheSource) {
  EXPECT_THAT([] { load_design_from_string("name: [", "<stdin>"); },
              ThrowsMessage<InputError>(StartsWith("<stdin>:1: YAML syntax error")));
}

TEST(Loader, ValidateErrorsGetTheLineOfTheirKey) {
  const std::string text = kMinimal + "        min_lci: 2\n";
  EXPECT_THAT([&] { load_design_from_string(text, "x.yaml"); },
              ThrowsMessage<InputError>(
                  HasSubstr("x.yaml:10: stations.s.mechanisms.upper.min_lci = 2: must be in [0, 1]")));
}

TEST(Loader, MissingFile) {
  const fs::path path = kSourceDir / "test/data/no-such-design.yaml";
  EXPECT_THAT([&] { load_design(path); },
              ThrowsMessage<InputError>(HasSubstr(path.string() + ": no such design file")));
}

TEST(Loader, DirectoryIsNotADesign) {
  const fs::path path = kSourceDir / "designs";
  EXPECT_THAT([&] { load_design(path); }, ThrowsMessage<InputError>(HasSubstr(path.string() + ": is a directory")));
}

TEST(Loader, UnreadableFile) {
  const fs::path path = fs::temp_directory_path() / "fivebar-test-design-unreadable.yaml";
  { std::ofstream(path) << kMinimal; }
  fs::permissions(path, fs::perms::none);
  std::ifstream probe(path);
  if (probe.good()) {  // root reads anything
    fs::remove(path);
    GTEST_SKIP() << "running with permissions that read mode-000 files";
  }
  EXPECT_THAT([&] { load_design(path); },
              ThrowsMessage<InputError>(HasSubstr(path.string() + ": cannot read the design file")));
  fs::remove(path);
}

// ---------------------------------------------------------------------------------------------
// validate(): one test per rule, on hand-built values.

Mechanism valid_mechanism() {
  Mechanism m;
  m.name = "lower";
  m.O1 = {0.0, 0.0};
  m.O2 = {12.5, 0.0};
  m.L = {9.0, 9.0, 15.0, 15.0};
  m.working_mode = {-1, +1};
  m.assembly_mode = AssemblyMode::Plus;
  return m;
}

Station valid_station() {
  Station s;
  s.name = "index";
  s.target.center = {6.25, 15.5};
  s.target.axes = {15.0, 12.0};
  s.lower = valid_mechanism();
  return s;
}

Design valid_design() {
  Design d;
  d.name = "d";
  d.stations = {valid_station()};
  return d;
}

template <class T, class Edit>
void expect_invalid(T value, Edit edit, const std::string& message) {
  edit(value);
  EXPECT_THAT([&] { value.validate(); }, ThrowsMessage<InputError>(HasSubstr(message)));
}

TEST(MechanismValidate, AcceptsThePaperAndCoincidentBases) {
  EXPECT_NO_THROW(valid_mechanism().validate());
  Mechanism m = valid_mechanism();
  m.O2 = m.O1;
  EXPECT_NO_THROW(m.validate());
}

TEST(MechanismValidate, Links) {
  auto m = valid_mechanism();
  expect_invalid(m, [](Mechanism& x) { x.L[2] = -3; }, "links[2] = -3 mm: must be > 0");
  expect_invalid(m, [](Mechanism& x) { x.L[0] = 0; }, "links[0] = 0 mm: must be > 0");
  expect_invalid(m, [](Mechanism& x) { x.L[3] = 1e13; }, "links[3] = 1e+13 mm: must be <= 1e12");
  expect_invalid(m, [](Mechanism& x) { x.L[1] = std::nan(""); }, "links[1] = nan mm: must be finite");
  expect_invalid(m, [](Mechanism& x) { x.L[1] = INFINITY; }, "links[1] = inf mm: must be finite");
  m.L[3] = 1e12;
  EXPECT_NO_THROW(m.validate());
}

TEST(MechanismValidate, ThrowsValidationErrorWithRelativeKey) {
  Mechanism m = valid_mechanism();
  m.L[2] = -3;
  EXPECT_THAT([&] { m.validate(); }, ThrowsMessage<InputError>(HasSubstr("links[2]")));
  try {
    m.validate();
    FAIL();
  } catch (const ValidationError& e) {
    EXPECT_EQ(e.key(), "links[2]");
    EXPECT_EQ(e.rule(), "= -3 mm: must be > 0");
    EXPECT_STREQ(e.what(), "links[2] = -3 mm: must be > 0");
  }
}

TEST(MechanismValidate, Bases) {
  const auto m = valid_mechanism();
  expect_invalid(m, [](Mechanism& x) { x.O1.y() = std::nan(""); }, "bases[0][1] = nan mm: must be finite");
  expect_invalid(m, [](Mechanism& x) { x.O2.x() = -INFINITY; }, "bases[1][0] = -inf mm: must be finite");
  expect_invalid(m, [](Mechanism& x) { x.O2.x() = -2e12; }, "bases[1][0] = -2e+12 mm: must be within");
}

TEST(MechanismValidate, Modes) {
  const auto m = valid_mechanism();
  expect_invalid(m, [](Mechanism& x) { x.working_mode.sign2 = 0; }, "working_mode = (-1, 0): both signs must be");
  expect_invalid(m, [](Mechanism& x) { x.assembly_mode = static_cast<AssemblyMode>(7); }, "assembly_mode = 7");
}

TEST(MechanismValidate, JointLimits) {
  auto m = valid_mechanism();
  m.joint_limits = std::array<JointRange, 2>{JointRange{deg(350), deg(10)}, JointRange{deg(0), deg(180)}};
  EXPECT_NO_THROW(m.validate());
  expect_invalid(m, [](Mechanism& x) { (*x.joint_limits)[1].hi = deg(0); },
                 "joint_limits[1] = [0, 0] deg: lo and hi must differ (mod 360)");
  expect_invalid(m, [](Mechanism& x) { (*x.joint_limits)[0] = {deg(-90), deg(270)}; },
                 "joint_limits[0] = [-90, 270] deg: lo and hi must differ (mod 360)");
  expect_invalid(m, [](Mechanism& x) { (*x.joint_limits)[0].lo = std::nan(""); },
                 "joint_limits[0][0] = nan deg: must be finite");
  expect_invalid(m, [](Mechanism& x) { (*x.joint_limits)[1].hi = INFINITY; },
                 "joint_limits[1][1] = inf deg: must be finite");
}

TEST(MechanismValidate, MinLci) {
  const auto m = valid_mechanism();
  expect_invalid(m, [](Mechanism& x) { x.min_lci = 1.5; }, "min_lci = 1.5: must be in [0, 1]");
  expect_invalid(m, [](Mechanism& x) { x.min_lci = -0.25; }, "min_lci = -0.25: must be in [0, 1]");
  expect_invalid(m, [](Mechanism& x) { x.min_lci = std::nan(""); }, "min_lci = nan: must be in [0, 1]");
}

TEST(MechanismValidate, LengthScale) {
  Mechanism m = valid_mechanism();
  EXPECT_EQ(m.length_scale(), 15.0);
  m.O2 = {30.0, 40.0};
  EXPECT_EQ(m.length_scale(), 50.0);
}

TEST(EllipseValidate, Rules) {
  const Ellipse e = valid_station().target;
  EXPECT_NO_THROW(e.validate());
  expect_invalid(e, [](Ellipse& x) { x.axes.x() = 0; }, "axes[0] = 0 mm: must be > 0");
  expect_invalid(e, [](Ellipse& x) { x.axes.y() = -1; }, "axes[1] = -1 mm: must be > 0");
  expect_invalid(e, [](Ellipse& x) { x.center.x() = INFINITY; }, "center[0] = inf mm: must be finite");
  expect_invalid(e, [](Ellipse& x) { x.angle = std::nan(""); }, "angle = nan deg: must be finite");
}

TEST(EllipseValidate, BoundaryPoint) {
  Ellipse e;
  e.center = {1.0, 2.0};
  e.axes = {4.0, 2.0};
  e.angle = kPi / 2;
  const Vec2 end_of_major = e.boundary_point(0.0);  // major axis (length 4) turned to +y
  EXPECT_NEAR(end_of_major.x(), 1.0, 1e-15);
  EXPECT_NEAR(end_of_major.y(), 4.0, 1e-15);
  const Vec2 end_of_minor = e.boundary_point(kPi / 2);
  EXPECT_NEAR(end_of_minor.x(), 0.0, 1e-15);
  EXPECT_NEAR(end_of_minor.y(), 2.0, 1e-15);
}

TEST(StationValidate, Rules) {
  const Station s = valid_station();
  EXPECT_NO_THROW(s.validate());
  expect_invalid(s, [](Station& x) { x.lower.reset(); }, "mechanisms: must contain at least one of lower, upper");
  expect_invalid(s, [](Station& x) { x.lower->L[2] = -3; }, "mechanisms.lower.links[2] = -3 mm");
  expect_invalid(s, [](Station& x) { x.upper = valid_mechanism(); x.upper->min_lci = 2; },
                 "mechanisms.upper.min_lci = 2");
  expect_invalid(s, [](Station& x) { x.target.axes.y() = 0; }, "target.axes[1] = 0 mm");
}

TEST(DesignValidate, Names) {
  const Design d = valid_design();
  EXPECT_NO_THROW(d.validate());
  for (const char* bad : {"", ".", "..", "../../x", "a/b", ".hidden", "-rf", "a b", "x\ny"}) {
    SCOPED_TRACE(bad);
    expect_invalid(d, [&](Design& x) { x.name = bad; }, "must be a safe file name");
  }
  expect_invalid(d, [](Design& x) { x.name = "../../x"; }, "name = '../../x': must be a safe file name");
  expect_invalid(d, [](Design& x) { x.name = std::string(65, 'a'); }, "must be a safe file name");
  Design ok = d;
  ok.name = std::string(64, 'a');
  EXPECT_NO_THROW(ok.validate());
  ok.name = "iros2022-v1.2_b";
  EXPECT_NO_THROW(ok.validate());
}

TEST(DesignValidate, Stations) {
  const Design d = valid_design();
  expect_invalid(d, [](Design& x) { x.stations.clear(); }, "stations: must contain at least one station");
  expect_invalid(d, [](Design& x) { x.stations[0].name = "a/b"; }, "stations[\"a/b\"]: station name 'a/b' must be");
  expect_invalid(d, [](Design& x) { x.stations.push_back(x.stations[0]); },
                 "stations.index: station name 'index' is used twice");
  expect_invalid(d, [](Design& x) { x.stations[0].lower->L[2] = -3; },
                 "stations.index.mechanisms.lower.links[2] = -3 mm: must be > 0");
}

TEST(Design, SelectsStationsByNameOrEveryOneWithAMechanism) {
  Design d = valid_design();
  Station thumb = valid_station();
  thumb.name = "thumb";
  Station bare = valid_station();  // a station without mechanisms: nothing to compute there
  bare.name = "bare";
  bare.lower.reset();
  d.stations = {bare, valid_station(), thumb};

  EXPECT_EQ(&d.require_station("thumb"), &d.stations[2]);
  EXPECT_THAT([&] { d.require_station("pinky"); },
              ThrowsMessage<InputError>(HasSubstr("unknown station 'pinky' in design 'd' (it has: bare, index, thumb)")));

  const auto named = d.select_stations("bare");  // named explicitly: taken even without a mechanism
  ASSERT_EQ(named.size(), 1u);
  EXPECT_EQ(named[0], &d.stations[0]);
  const auto all = d.select_stations("");
  ASSERT_EQ(all.size(), 2u);  // file order, the bare station left out
  EXPECT_EQ(all[0]->name, "index");
  EXPECT_EQ(all[1]->name, "thumb");
  EXPECT_THROW(d.select_stations("pinky"), InputError);
}

TEST(DesignValidate, Products) {
  const Design d = valid_design();
  // The design checks the list's form; the names are the scene's (validate_products), above core.
  Design unknown = d;
  unknown.products = std::vector<std::string>{"kinematics", "nope"};
  EXPECT_NO_THROW(unknown.validate());
  EXPECT_THAT([&] { validate_products(unknown); },
              ThrowsMessage<ValidationError>(HasSubstr("products[1] = 'nope': unknown product")));
  EXPECT_THAT([&] { load_scene_from_string("products: [kinematics, nope]\n" + kMinimal, "s.yaml"); },
              ThrowsMessage<InputError>(HasSubstr("s.yaml:1: products[1] = 'nope': unknown product")));
  expect_invalid(d, [](Design& x) { x.products = std::vector<std::string>{"kinematics", "kinematics"}; },
                 "products[1] = 'kinematics': listed twice");
  Design ok = d;
  ok.products = known_products();
  EXPECT_NO_THROW(ok.validate());
  ok.products = std::vector<std::string>{};
  EXPECT_NO_THROW(ok.validate());
}

TEST(DesignValidate, KnownProductsStartWithKinematics) {
  ASSERT_FALSE(known_products().empty());
  EXPECT_EQ(known_products().front(), "kinematics");
}

// ---------------------------------------------------------------------------------------------
// Modes and joint ranges.

TEST(Modes, WorkingModeRoundTrip) {
  const std::array<const char*, 4> texts{"++", "+-", "-+", "--"};
  const auto modes = all_working_modes();
  for (std::size_t i = 0; i < 4; ++i) {
    EXPECT_EQ(to_string(modes[i]), texts[i]);
    EXPECT_EQ(parse_working_mode(texts[i]), modes[i]);
  }
  EXPECT_EQ(parse_working_mode("-+"), (WorkingMode{-1, +1}));
  EXPECT_EQ(WorkingMode{}, (WorkingMode{-1, +1}));
  for (const char* bad : {"", "+", "+++", "+x", "x-", " +-", "+ -", "pm"}) {
    EXPECT_FALSE(parse_working_mode(bad).has_value()) << bad;
  }
}

TEST(Modes, AssemblyModeRoundTrip) {
  for (const AssemblyMode mode : {AssemblyMode::Plus, AssemblyMode::Minus, AssemblyMode::Any}) {
    EXPECT_EQ(parse_assembly_mode(to_string(mode)), mode);
  }
  EXPECT_EQ(to_string(AssemblyMode::Plus), "+");
  EXPECT_EQ(to_string(AssemblyMode::Minus), "-");
  EXPECT_EQ(to_string(AssemblyMode::Any), "any");
  for (const char* bad : {"", "ANY", "+-", "up", "0"}) EXPECT_FALSE(parse_assembly_mode(bad).has_value()) << bad;
}

TEST(JointRange, WrappedArc) {
  const JointRange r{deg(350), deg(10)};
  EXPECT_NEAR(r.span(), deg(20), 1e-14);
  EXPECT_TRUE(r.contains(0.0));
  EXPECT_TRUE(r.contains(deg(5)));
  EXPECT_TRUE(r.contains(deg(355)));
  EXPECT_TRUE(r.contains(deg(-5)));
  EXPECT_TRUE(r.contains(deg(365)));  // any representative
  EXPECT_TRUE(r.contains(deg(-715)));
  EXPECT_FALSE(r.contains(deg(180)));
  EXPECT_FALSE(r.contains(deg(11)));
  EXPECT_FALSE(r.contains(deg(349)));
  EXPECT_TRUE(r.contains(r.lo));
  EXPECT_TRUE(r.contains(r.hi));
}

TEST(JointRange, Tolerance) {
  const JointRange r{deg(350), deg(10)};
  EXPECT_FALSE(r.contains(deg(10.5)));
  EXPECT_TRUE(r.contains(deg(10.5), deg(1)));
  EXPECT_FALSE(r.contains(deg(349.5)));
  EXPECT_TRUE(r.contains(deg(349.5), deg(1)));
}

TEST(JointRange, PlainAndLargeArcs) {
  const JointRange half{0.0, kPi};
  EXPECT_NEAR(half.span(), kPi, 1e-15);
  EXPECT_TRUE(half.contains(kPi / 2));
  EXPECT_FALSE(half.contains(-kPi / 2));
  const JointRange most{deg(10), deg(0)};  // ccw from 10 deg round to 0 deg: all but 10 degrees
  EXPECT_NEAR(most.span(), deg(350), 1e-14);
  EXPECT_TRUE(most.contains(deg(180)));
  EXPECT_FALSE(most.contains(deg(5)));
  const JointRange negative{deg(-90), deg(90)};
  EXPECT_NEAR(negative.span(), kPi, 1e-15);
  EXPECT_TRUE(negative.contains(0.0));
  EXPECT_FALSE(negative.contains(kPi));
}

TEST(KeyedErrors, ComposeReadsAsAKeyValueRule) {
  EXPECT_EQ(ValidationError::compose("links[2]", "= -3 mm: must be > 0"), "links[2] = -3 mm: must be > 0");
  EXPECT_EQ(ValidationError::compose("stations", "must contain at least one station"),
            "stations: must contain at least one station");
}

}  // namespace
}  // namespace fivebar

namespace fivebar {
namespace {

TEST(Loader, GeometryAndPrintSectionsWithDefaults) {
  const std::string stations = R"(stations:
  s:
    target: {center: [6.25, 15.5], axes: [15, 12]}
    mechanisms:
      lower: {bases: [[0, 0], [12.5, 0]], links: [9, 9, 15, 15], working_mode: "-+"}
)";
  // A bare section takes every default; a scalar width applies to all four links.
  const Design bare = load_design_from_string("name: g\ngeometry:\nprint:\n" + stations, "<test>");
  ASSERT_TRUE(bare.get<Geometry>() && bare.get<PrintSettings>());
  EXPECT_EQ(bare.get<Geometry>()->link_width, (std::array<double, 4>{4.0, 4.0, 4.0, 4.0}));
  EXPECT_EQ(bare.get<PrintSettings>()->pin_clearance, 0.15);
  const Design set = load_design_from_string(
      "name: g\ngeometry: {link_width: 3.5, layers: [0, 1, 2, 3], pin_diameter: 1.5}\n"
      "print: {fn: 64, material: Grey V4, pin_clearance: 0.2}\n" + stations,
      "<test>");
  EXPECT_EQ(set.get<Geometry>()->link_width, (std::array<double, 4>{3.5, 3.5, 3.5, 3.5}));
  EXPECT_EQ(set.get<Geometry>()->layers, (std::array<int, 4>{0, 1, 2, 3}));
  EXPECT_EQ(set.get<Geometry>()->pin_diameter, 1.5);
  EXPECT_EQ(set.get<PrintSettings>()->fn, 64);
  EXPECT_EQ(set.get<PrintSettings>()->material, "Grey V4");
  EXPECT_EQ(set.get<PrintSettings>()->pin_clearance, 0.2);
  const Design none = load_design_from_string("name: g\n" + stations, "<test>");
  EXPECT_FALSE(none.has<Geometry>());
  EXPECT_FALSE(none.has<PrintSettings>());
}

TEST(GeometryValidate, Rules) {
  Geometry g;
  EXPECT_NO_THROW(g.validate());
  g.link_width[3] = 0.0;
  EXPECT_THAT([&] { g.validate(); }, testing::ThrowsMessage<InputError>(testing::HasSubstr("link_width[3]")));
  g = Geometry{};
  g.motor_shaft_flat = 2.0;
  EXPECT_THAT([&] { g.validate(); }, testing::ThrowsMessage<InputError>(testing::HasSubstr("motor_shaft_flat")));
  PrintSettings p;
  EXPECT_NO_THROW(p.validate());
  p.pin_clearance = -0.1;
  EXPECT_THAT([&] { p.validate(); }, testing::ThrowsMessage<InputError>(testing::HasSubstr("pin_clearance")));
}

}  // namespace
}  // namespace fivebar

// ---------------------------------------------------------------------------------------------
// Input limits (design.hpp kMaxDesignFileBytes, kMaxDesignNesting; README "Hardening"): checked
// before yaml-cpp parses; real designs, however written, must never trip them.

namespace fivebar {
namespace {

using ::testing::Not;

std::string message_of(const std::string& text) {
  try {
    load_design_from_string(text, "lim.yaml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::string repeat(std::string_view s, std::size_t n) {
  std::string out;
  for (std::size_t i = 0; i < n; ++i) out += s;
  return out;
}

TEST(DesignLimits, NestingIsCountedAcrossIndentationItemsAndBrackets) {
  // `products:` sits at the first indentation level; each bracket adds one: 1 + k levels.
  const auto products_nested = [](std::size_t k) {
    return kMinimal + "products: " + repeat("[", k) + "kinematics" + repeat("]", k) + "\n";
  };
  EXPECT_THAT(message_of(products_nested(kMaxDesignNesting - 1)), Not(HasSubstr("nested")));
  EXPECT_THAT(message_of(products_nested(kMaxDesignNesting - 1)), HasSubstr("lim.yaml:10: products[0]"));
  EXPECT_THAT(message_of(products_nested(kMaxDesignNesting)),
              StartsWith("lim.yaml:10: nested more than 64 levels deep"));
  // Items: "products:" (1) then 63 compact "- " on the next line, one of them indented (level 2).
  const std::string items = kMinimal + "products:\n  " + repeat("- ", kMaxDesignNesting - 1) + "kinematics\n";
  EXPECT_THAT(message_of(items), StartsWith("lim.yaml:11: nested more than 64 levels deep"));
  const std::string fewer = kMinimal + "products:\n  " + repeat("- ", kMaxDesignNesting - 2) + "kinematics\n";
  EXPECT_THAT(message_of(fewer), Not(HasSubstr("nested")));
  // Indentation alone: line k + 2 holds key k at depth k + 1 (stations: is depth 1).
  std::string indented = "name: m\nstations:\n";
  for (int i = 1; i <= 70; ++i) indented += std::string(static_cast<std::size_t>(i), ' ') + "k" + std::to_string(i) + ":\n";
  EXPECT_THAT(message_of(indented), StartsWith("lim.yaml:66: nested more than 64 levels deep"));
}

TEST(DesignLimits, BracketsOutsideFlowCollectionsAreNotNesting) {
  // Plain and quoted scalars, comments and block scalars may hold any number of brackets.
  const std::string many = repeat("[{", 40);
  const std::string text = "# " + many + " \"unbalanced ' quotes in a comment\n" + kMinimal +
                           "print:\n"
                           "  material: Tough 2000 " + many + "   # plain scalar with brackets\n";
  EXPECT_EQ(message_of(text), "");
  const std::string block = kMinimal + "print:\n  material: |\n    " + many + "\n    \"never closed\n      {[\n";
  EXPECT_EQ(message_of(block), "");
  const std::string quoted = kMinimal + "print:\n  material: \"a " + many + "\n    continued \\\" [[[ \"\n";
  EXPECT_EQ(message_of(quoted), "");
  EXPECT_EQ(load_design_from_string(quoted, "q.yaml").get<PrintSettings>()->material.substr(0, 4), "a [{");
  const std::string single = kMinimal + "print:\n  material: 'it''s [[[ {{{'\n";
  EXPECT_EQ(load_design_from_string(single, "s.yaml").get<PrintSettings>()->material, "it's [[[ {{{");
}

TEST(DesignLimits, UnclosedQuoteIsNamedWhereItOpens) {
  EXPECT_THAT(message_of(kMinimal + "print:\n  material: 'tough\n"),
              StartsWith("lim.yaml:11: the quoted string that starts at column 13 is never closed"));
  EXPECT_THAT(message_of("name: m\nproducts: [\"kin, x]\n"),
              StartsWith("lim.yaml:2: the quoted string that starts at column 12 is never closed"));
}

TEST(DesignLimits, SizeLimitIsExact) {
  const auto padded = [](std::size_t total) {
    std::string text = kMinimal + "# ";
    text += std::string(total - text.size() - 1, 'x');
    return text + "\n";
  };
  EXPECT_EQ(padded(kMaxDesignFileBytes).size(), kMaxDesignFileBytes);
  EXPECT_EQ(message_of(padded(kMaxDesignFileBytes)), "");
  EXPECT_EQ(message_of(padded(kMaxDesignFileBytes + 1)),
            "lim.yaml: 1048577 bytes: a design file may have at most 1048576 bytes (1 MiB)");
}

TEST(DesignLimits, SizeLimitOnFilesAndEndlessDevices) {
  const fs::path path = fs::temp_directory_path() / ("fivebar-test-design-big-" + std::to_string(::getpid()) + ".yaml");
  { std::ofstream(path) << kMinimal; }
  fs::resize_file(path, kMaxDesignFileBytes + 10);  // sparse: refused from its size, before reading
  EXPECT_THAT([&] { load_design(path); },
              ThrowsMessage<InputError>(StartsWith(path.string() + ": 1048586 bytes: a design file may have at most")));
  fs::remove(path);
  EXPECT_THAT([] { load_design("/dev/zero"); },
              ThrowsMessage<InputError>(StartsWith("/dev/zero: more than 1048576 bytes")));
}

TEST(DesignLimits, Utf8IsRequiredAndValidated) {
  // Accepted: multi-byte characters, a byte-order mark, CRLF line ends, tabs inside values.
  EXPECT_EQ(message_of("\xEF\xBB\xBF# caf\xC3\xA9 \xE2\x9C\x93 \xF0\x9F\x96\x90\r\n" + kMinimal), "");
  std::string crlf;
  for (char c : kMinimal) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  EXPECT_EQ(message_of(crlf), "");
  EXPECT_EQ(message_of(kMinimal + "print: {material: \"a\tb\"}\n"), "");
  // Refused, with line and column (in characters): overlong, surrogate, beyond U+10FFFF, cut short.
  EXPECT_EQ(message_of("name: m\n# \xC3\xA9\xC0\xAF\n"),
            "lim.yaml:2: byte 0xC0 at column 4 is not UTF-8: design files must be UTF-8 text");
  EXPECT_THAT(message_of("# \xED\xA0\x80\n"), StartsWith("lim.yaml:1: byte 0xED at column 3 is not UTF-8"));
  EXPECT_THAT(message_of("# \xF4\x90\x80\x80\n"), StartsWith("lim.yaml:1: byte 0xF4 at column 3 is not UTF-8"));
  EXPECT_THAT(message_of("name: m\n# \xE2\x82"), StartsWith("lim.yaml:2: byte 0xE2 at column 3 is not UTF-8"));
  EXPECT_THAT(message_of("\xFF\xFEn\0"), StartsWith("lim.yaml: the file is UTF-16 encoded"));
  EXPECT_THAT(message_of(std::string("\0\0\xFE\xFF", 4)), StartsWith("lim.yaml: the file is UTF-32 encoded"));
  // Characters YAML excludes: C0 controls but tab and line breaks, DEL, C1 controls.
  EXPECT_EQ(message_of("name: a\x7F"),
            "lim.yaml:1: character U+007F at column 8 is a control character, which YAML does not allow "
            "(only tab and line breaks)");
  EXPECT_THAT(message_of("name: \xC2\x80"), StartsWith("lim.yaml:1: character U+0080 at column 7"));
  EXPECT_THAT(message_of(std::string("name: m\0", 8)), StartsWith("lim.yaml:1: character U+0000 at column 8"));
}

TEST(DesignLimits, MessagesStayShortWhateverTheInput) {
  const std::string name(100000, 'n');
  const std::string m = message_of("name: " + name + "\nstations: {}\n");
  EXPECT_THAT(m, HasSubstr("'" + std::string(97, 'n') + "...' (100000 bytes)"));
  EXPECT_LT(m.size(), 400u);
  const std::string key(300, 'k');
  const std::string k = message_of(kMinimal + key + ": 1\n");
  EXPECT_THAT(k, StartsWith("lim.yaml:10: key '"));
  EXPECT_THAT(k, HasSubstr("(300 bytes) is too long for a key of a design file (at most 128 bytes)"));
  EXPECT_LT(k.size(), 400u);
  // A long value cut in the middle of a multi-byte character keeps whole characters.
  const std::string accents = repeat("\xC3\xA9", 200);
  const std::string a = message_of("name: " + accents + "\nstations: {}\n");
  EXPECT_THAT(a, HasSubstr("..."));
  for (std::size_t i = 0; i + 1 < a.size(); ++i) {
    if (static_cast<unsigned char>(a[i]) == 0xC3) EXPECT_EQ(static_cast<unsigned char>(a[i + 1]), 0xA9);
  }
}

TEST(DesignLimits, NamesFromAFileCannotInjectLinesOrTerminalEscapes) {
  // YAML escapes in a quoted key produce control characters; messages show them escaped.
  const std::string text = "name: m\nstations:\n  \"a\\nfivebar: internal error\\e[31m\": {target: 1}\n";
  const std::string m = message_of(text);
  EXPECT_THAT(m, HasSubstr("stations[\"a\\x0afivebar: internal error\\x1b[31m\"]"));
  EXPECT_EQ(m.find('\n'), std::string::npos);
  EXPECT_EQ(m.find('\x1b'), std::string::npos);
}

}  // namespace
}  // namespace fivebar

namespace fivebar {
namespace {

/// The paper's two stations as a `stations:` block, for sections that name them (patterns, controller).
const std::string kPaperStations = R"(stations:
  index:
    target: {center: [6.25, 15.5], axes: [15, 12]}
    mechanisms:
      lower: {bases: [[0, 0], [12.5, 0]], links: [9, 9, 15, 15], working_mode: "-+"}
      upper: {bases: [[0, 31], [12.5, 31]], links: [9, 9, 15, 15], working_mode: "+-"}
  thumb:
    target: {center: [6.25, 17.5], axes: [15, 14]}
    mechanisms:
      lower: {bases: [[0, 0], [12.5, 0]], links: [9, 9, 17.5, 17.5], working_mode: "-+"}
)";

TEST(Loader, PatternsSectionDefaultsUnitsAndPerStationEntries) {
  // A bare section: the four kinds with their defaults, at 100 Hz, 360 deg/s.
  const Design bare = load_design_from_string("name: p\npatterns:\n" + kPaperStations, "<test>");
  ASSERT_TRUE(bare.has<PatternSettings>());
  EXPECT_EQ(bare.get<PatternSettings>()->rate_hz, 100.0);
  EXPECT_DOUBLE_EQ(bare.get<PatternSettings>()->max_joint_speed, 2.0 * kPi);
  ASSERT_EQ(bare.get<PatternSettings>()->global.size(), 4u);
  EXPECT_EQ(bare.get<PatternSettings>()->global[3].kind, PatternKind::pivot);
  EXPECT_EQ(bare.get<PatternSettings>()->global[3].duration_s, 2.0);
  EXPECT_DOUBLE_EQ(bare.get<PatternSettings>()->global[3].pivot_amplitude, deg(20));

  const Design d = load_design_from_string(R"(name: p
patterns:
  rate_hz: 50
  max_joint_speed_deg_s: 90
  stretch: {amplitude_mm: 2.5, separation_mm: 7, center: [6, 16]}
  pivot: {amplitude_deg: 30, frequency_hz: 2, contact_points: [[1, 3], [-1, -3]]}
  stations:
    thumb:
      stretch: {duration_s: 0.5}
      twist: {amplitude_mm: 5}
)" + kPaperStations,
                                           "<test>");
  const PatternSettings& p = *d.get<PatternSettings>();
  EXPECT_EQ(p.rate_hz, 50.0);
  EXPECT_DOUBLE_EQ(p.max_joint_speed, deg(90));
  // The index has the two top-level kinds; the section's rate is their default.
  const auto index = p.for_station("index");
  ASSERT_EQ(index.size(), 2u);
  EXPECT_EQ(index[0].kind, PatternKind::stretch);
  EXPECT_EQ(index[0].amplitude_mm, 2.5);
  EXPECT_EQ(index[0].separation_mm, 7.0);
  EXPECT_EQ(index[0].rate_hz, 50.0);
  EXPECT_EQ(index[0].centre, Vec2(6, 16));
  EXPECT_EQ(index[0].duration_s, 1.0);
  EXPECT_EQ(index[1].kind, PatternKind::pivot);
  EXPECT_DOUBLE_EQ(index[1].pivot_amplitude, deg(30));
  EXPECT_EQ(index[1].pivot_frequency_hz, 2.0);
  ASSERT_TRUE(index[1].contact_points.has_value());
  EXPECT_EQ((*index[1].contact_points)[1], Vec2(-1, -3));
  // The thumb's stretch keeps the top-level keys it does not give; its twist exists only there.
  const auto thumb = p.for_station("thumb");
  ASSERT_EQ(thumb.size(), 3u);
  EXPECT_EQ(thumb[0].kind, PatternKind::stretch);
  EXPECT_EQ(thumb[0].duration_s, 0.5);
  EXPECT_EQ(thumb[0].amplitude_mm, 2.5);
  EXPECT_EQ(thumb[0].separation_mm, 7.0);
  EXPECT_EQ(thumb[1].kind, PatternKind::twist);
  EXPECT_EQ(thumb[1].amplitude_mm, 5.0);
  EXPECT_EQ(thumb[1].rate_hz, 50.0);
  EXPECT_EQ(thumb[2].kind, PatternKind::pivot);
  EXPECT_TRUE(p.for_station("nowhere").size() == 2u);  // the top-level kinds apply to any station

  const Design none = load_design_from_string("name: p\n" + kPaperStations, "<test>");
  EXPECT_FALSE(none.has<PatternSettings>());
}

TEST(Loader, ShowcasePatternsCoverTheFourKindsOnBothStations) {
  const Design d = load_design(kSourceDir / "designs/iros2022.yaml");
  ASSERT_TRUE(d.has<PatternSettings>());
  for (const char* station : {"index", "thumb"}) {
    const auto specs = d.get<PatternSettings>()->for_station(station);
    ASSERT_EQ(specs.size(), 4u) << station;
    for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(specs[i].kind, all_pattern_kinds()[i]) << station;
  }
  EXPECT_EQ(d.get<PatternSettings>()->for_station("thumb")[2].amplitude_mm, 5.5);
  EXPECT_EQ(d.get<PatternSettings>()->for_station("index")[2].amplitude_mm, 4.0);
}

TEST(PatternValidate, Rules) {
  PatternSpec s;
  EXPECT_NO_THROW(s.validate());
  const auto bad = [](auto edit, const std::string& message) {
    PatternSpec p;
    edit(p);
    EXPECT_THAT([&] { p.validate(); }, ThrowsMessage<InputError>(HasSubstr(message))) << message;
  };
  bad([](PatternSpec& p) { p.amplitude_mm = 0; }, "amplitude_mm = 0 mm: must be > 0");
  bad([](PatternSpec& p) { p.duration_s = -1; }, "duration_s = -1 s: must be > 0");
  bad([](PatternSpec& p) { p.rate_hz = 1e5; }, "rate_hz = 100000 Hz: must be > 0 and <= 10000 Hz");
  bad([](PatternSpec& p) { p.separation_mm = -0.5; }, "separation_mm = -0.5 mm");
  bad([](PatternSpec& p) { p.centre = Vec2(std::nan(""), 0); }, "centre[0] = nan mm: must be finite");
  bad([](PatternSpec& p) { p.kind = PatternKind::twist, p.separation_mm = 0; }, "twist turns the tactors");
  bad([](PatternSpec& p) { p.kind = PatternKind::pivot, p.pivot_amplitude = deg(190); }, "amplitude_deg = 190 deg");
  bad([](PatternSpec& p) { p.kind = PatternKind::pivot, p.pivot_frequency_hz = 0; }, "frequency_hz = 0 Hz");
  // A pivot does not use amplitude_mm.
  PatternSpec pivot;
  pivot.kind = PatternKind::pivot;
  pivot.amplitude_mm = -1;
  EXPECT_NO_THROW(pivot.validate());

  PatternSettings settings;
  settings.max_joint_speed = 0;
  EXPECT_THAT([&] { settings.validate(); }, ThrowsMessage<InputError>(HasSubstr("max_joint_speed_deg_s = 0 deg/s")));
  settings = PatternSettings{};
  PatternSpec zero;
  zero.amplitude_mm = 0;
  settings.overrides.emplace_back("index", zero);
  EXPECT_THAT([&] { settings.validate(); }, ThrowsMessage<InputError>(HasSubstr("stations.index.stretch.amplitude_mm")));
}

TEST(PatternKinds, RoundTrip) {
  for (PatternKind kind : all_pattern_kinds()) EXPECT_EQ(parse_pattern_kind(to_string(kind)), kind);
  EXPECT_EQ(to_string(PatternKind::twist), "twist");
  EXPECT_FALSE(parse_pattern_kind("Stretch").has_value());
  EXPECT_FALSE(parse_pattern_kind("").has_value());
}

// A station's patterns are overrides at the station scope of controller: and motor:
// (fivebar/sections/scope.hpp): they cover that station's pair only, win over the top-level entry
// of their kind, and a later one of the same station and kind wins over an earlier one.
TEST(PatternSettings, StationEntriesAreStationScopedOverrides) {
  PatternSettings p;
  PatternSpec stretch;
  stretch.amplitude_mm = 3.0;
  p.global.push_back(stretch);
  stretch.amplitude_mm = 4.0;
  p.overrides.emplace_back("index", stretch);
  stretch.amplitude_mm = 5.0;
  p.overrides.emplace_back("index", stretch);
  PatternSpec slip;
  slip.kind = PatternKind::slip;
  slip.amplitude_mm = 2.0;
  p.overrides.emplace_back("thumb", slip);

  const PatternOverride& index = p.overrides.front();
  EXPECT_EQ(index.key(), "stations.index");
  EXPECT_EQ(index.level(), 2);  // stations.S: narrower than mechanisms.M, wider than stations.S.M
  EXPECT_TRUE(index.covers("index", "lower", 1));
  EXPECT_TRUE(index.covers("index", "upper", 2));
  EXPECT_FALSE(index.covers("thumb", "lower", 1));

  const auto on_index = p.for_station("index");
  ASSERT_EQ(on_index.size(), 1u);
  EXPECT_EQ(on_index[0].amplitude_mm, 5.0);
  const auto on_thumb = p.for_station("thumb");
  ASSERT_EQ(on_thumb.size(), 2u);
  EXPECT_EQ(on_thumb[0].kind, PatternKind::stretch);
  EXPECT_EQ(on_thumb[0].amplitude_mm, 3.0);
  EXPECT_EQ(on_thumb[1].kind, PatternKind::slip);
  EXPECT_EQ(on_thumb[1].amplitude_mm, 2.0);
}

TEST(DesignValidate, PatternStationsMustExist) {
  Design d = valid_design();
  d.set<PatternSettings>(PatternSettings{});
  PatternSpec spec;
  d.get<PatternSettings>()->overrides.emplace_back("middle", spec);
  EXPECT_THAT([&] { d.validate(); },
              ThrowsMessage<InputError>(HasSubstr("patterns.stations.middle: no such station in this design (stations: index)")));
  d.get<PatternSettings>()->overrides.front().station = "";  // a key "" is no station, not every one
  EXPECT_THAT([&] { d.validate(); },
              ThrowsMessage<InputError>(HasSubstr("patterns.stations[\"\"]: no such station in this design")));
  d.get<PatternSettings>()->overrides.front().station = "index";
  EXPECT_NO_THROW(d.validate());
}

}  // namespace
}  // namespace fivebar

// ---------------------------------------------------------------------------------------------
// The controller section (loader, rules, overrides) and the design writer's round trip.

namespace fivebar {
namespace {

TEST(Loader, ControllerSectionAloneTakesEveryDefault) {
  const Design d = load_design_from_string("name: c\ncontroller:\n" + kPaperStations, "<test>");
  ASSERT_TRUE(d.has<ControllerSettings>());
  const ControllerSettings& c = *d.get<ControllerSettings>();
  EXPECT_EQ(c.node, "fivebar_controller");
  EXPECT_EQ(c.loop_rate_hz, 100.0);  // paper: PID at 100 Hz
  EXPECT_EQ(c.pwm_hz, 1000.0);       // paper: 1 kHz PWM
  EXPECT_EQ(c.adc_bits, 16);         // paper: 16-bit DAQ
  EXPECT_EQ(c.adc_range_v, (std::array<double, 2>{-10.0, 10.0}));
  EXPECT_DOUBLE_EQ(c.max_velocity, deg(360));
  EXPECT_EQ(c.collision_priority, "upper");
  EXPECT_TRUE(c.overrides.empty());
  // 5 V over 300 deg of travel: 60 deg per volt.
  EXPECT_DOUBLE_EQ(c.potentiometer.rad_per_volt, deg(60));
  const Design none = load_design_from_string("name: c\n" + kPaperStations, "<test>");
  EXPECT_FALSE(none.has<ControllerSettings>());
}

TEST(Loader, ControllerUnitsAndOverridesFromTheWidestScopeToTheJoint) {
  const Design d = load_design_from_string(R"(name: c
controller:
  node: haptics_node
  loop_rate_hz: 250
  pwm_hz: 20000
  adc: {bits: 12, range_v: [0, 5]}
  max_velocity_deg_s: 90
  min_lci: 0.1
  pid: {kp: 5, ki: 1, kd: 0.05, i_clamp: 0.2}
  potentiometer: {volts_at_zero: 2.5, volts_per_rad: 0.5}
  stations:
    index:
      pid: {kp: 4}
      lower:
        pid: {kp: 3, ki: 0.7}
        theta2:
          pid: {kp: 2}
          potentiometer: {volts_at_zero: 1.25, rad_per_volt: -4}
)" + kPaperStations,
                                           "<test>");
  const ControllerSettings& c = *d.get<ControllerSettings>();
  EXPECT_EQ(c.node, "haptics_node");
  EXPECT_EQ(c.loop_rate_hz, 250.0);
  EXPECT_EQ(c.pwm_hz, 20000.0);
  EXPECT_EQ(c.adc_bits, 12);
  EXPECT_EQ(c.adc_range_v, (std::array<double, 2>{0.0, 5.0}));
  EXPECT_DOUBLE_EQ(c.max_velocity, kPi / 2);
  EXPECT_EQ(c.min_lci, 0.1);
  EXPECT_EQ(c.potentiometer.rad_per_volt, 2.0);  // 1 / (0.5 V/rad)
  // The joint's own keys, then its mechanism's, then its station's, then the defaults.
  const JointControl j = c.joint("index", "lower", 2);
  EXPECT_EQ(j.pid.kp, 2.0);
  EXPECT_EQ(j.pid.ki, 0.7);
  EXPECT_EQ(j.pid.kd, 0.05);
  EXPECT_EQ(j.potentiometer.volts_at_zero, 1.25);
  EXPECT_EQ(j.potentiometer.rad_per_volt, -4.0);
  EXPECT_EQ(c.joint("index", "lower", 1).pid.kp, 3.0);
  EXPECT_EQ(c.joint("index", "lower", 1).potentiometer.rad_per_volt, 2.0);
  EXPECT_EQ(c.joint("index", "upper", 1).pid.kp, 4.0);
  EXPECT_EQ(c.joint("index", "upper", 1).pid.ki, 1.0);
  EXPECT_EQ(c.joint("thumb", "lower", 2).pid.kp, 5.0);

  // The precedence is by scope, not by position in the list: reversed, the same gains.
  ControllerSettings reversed = c;
  std::reverse(reversed.overrides.begin(), reversed.overrides.end());
  for (const char* m : {"lower", "upper"}) {
    for (int k = 1; k <= 2; ++k) {
      EXPECT_EQ(reversed.joint("index", m, k).pid.kp, c.joint("index", m, k).pid.kp) << m << k;
      EXPECT_EQ(reversed.joint("index", m, k).pid.ki, c.joint("index", m, k).pid.ki) << m << k;
    }
  }
}

// A station key "" would read as the scope of every station: controller: and motor: refuse it at
// its own line, as patterns: does.
TEST(Loader, AnEmptyStationNameIsRefusedAtItsLineInControllerAndMotor) {
  for (const std::string section : {"controller", "motor"}) {
    const std::string override = section == "controller" ? "{pid: {kp: 4}}" : "{terminal_resistance_ohm: 3}";
    const std::string text = "name: c\n" + section + ":\n  stations:\n    \"\": " + override + "\n" + kPaperStations;
    EXPECT_THAT([&] { (void)load_design_from_string(text, "d.yaml"); },
                ThrowsMessage<InputError>(HasSubstr("d.yaml:4: " + section + ".stations[\"\"]: a station name must not be empty")))
        << section;
  }
}

TEST(Loader, ControllerMechanismScopesApplyToEveryStationBelowAnyStationScope) {
  const Design d = load_design_from_string(R"(name: c
controller:
  pid: {kp: 5}
  mechanisms:
    lower:
      pid: {kp: 3, kd: 0.01}
      theta1: {pid: {kp: 2.5}, potentiometer: {volts_at_zero: 0.25}}
    upper: {pid: {ki: 0.5}}
  stations:
    index: {pid: {kp: 4}}
)" + kPaperStations,
                                           "<test>");
  const ControllerSettings& c = *d.get<ControllerSettings>();
  // A scope naming a station beats every station-less one, however narrow.
  EXPECT_EQ(c.joint("index", "lower", 1).pid.kp, 4.0);
  EXPECT_EQ(c.joint("index", "lower", 1).pid.kd, 0.01);  // not given by the station: the mechanisms'
  EXPECT_EQ(c.joint("index", "lower", 1).potentiometer.volts_at_zero, 0.25);
  EXPECT_EQ(c.joint("thumb", "lower", 1).pid.kp, 2.5);
  EXPECT_EQ(c.joint("thumb", "lower", 2).pid.kp, 3.0);
  EXPECT_EQ(c.joint("thumb", "lower", 2).potentiometer.volts_at_zero, 2.5);
  EXPECT_EQ(c.joint("index", "upper", 2).pid.ki, 0.5);
  EXPECT_EQ(c.joint("index", "upper", 2).pid.kp, 4.0);
  // The thumb has no upper mechanism: a rule for every upper mechanism is simply unused there.
  const Design back = load_design_from_string(to_yaml(d), "<to_yaml>");
  EXPECT_EQ(to_yaml(back), to_yaml(d));
  EXPECT_EQ(back.get<ControllerSettings>()->joint("thumb", "lower", 1).pid.kp, 2.5);
  EXPECT_EQ(back.get<ControllerSettings>()->joint("index", "lower", 1).pid.kp, 4.0);
}

TEST(Loader, PatternsTakeTheControllersRateAndTheOneSpeedLimit) {
  const Design d = load_design_from_string(R"(name: c
patterns:
  stretch: {}
  twist: {rate_hz: 50}
controller:
  loop_rate_hz: 200
  max_velocity_deg_s: 90
)" + kPaperStations,
                                           "<test>");
  ASSERT_TRUE(d.has<PatternSettings>());
  EXPECT_EQ(d.get<PatternSettings>()->rate_hz, 200.0);
  EXPECT_DOUBLE_EQ(d.get<PatternSettings>()->max_joint_speed, kPi / 2);
  EXPECT_EQ(d.get<PatternSettings>()->max_joint_speed, d.get<ControllerSettings>()->max_velocity);
  const auto specs = d.get<PatternSettings>()->for_station("index");
  ASSERT_EQ(specs.size(), 2u);
  EXPECT_EQ(specs[0].rate_hz, 200.0);  // the loop rate, unless the pattern says otherwise
  EXPECT_EQ(specs[1].rate_hz, 50.0);
}

TEST(ControllerValidate, Rules) {
  EXPECT_NO_THROW(ControllerSettings{}.validate());
  const auto bad = [](auto edit, const std::string& message) {
    ControllerSettings c;
    edit(c);
    EXPECT_THAT([&] { c.validate(); }, ThrowsMessage<InputError>(HasSubstr(message))) << message;
  };
  bad([](ControllerSettings& c) { c.node = "a-b"; }, "node = 'a-b': must be a ROS 2 node name");
  bad([](ControllerSettings& c) { c.node = ""; }, "node = '': must be a ROS 2 node name");
  bad([](ControllerSettings& c) { c.loop_rate_hz = 0; }, "loop_rate_hz = 0 Hz: must be > 0");
  bad([](ControllerSettings& c) { c.pwm_hz = std::nan(""); }, "pwm_hz = nan Hz");
  bad([](ControllerSettings& c) { c.adc_bits = 0; }, "adc.bits = 0: must be 1 ... 32");
  bad([](ControllerSettings& c) { c.adc_range_v = {1.0, 1.0}; }, "adc.range_v = [1, 1] V");
  bad([](ControllerSettings& c) { c.max_velocity = -1; }, "max_velocity_deg_s");
  bad([](ControllerSettings& c) { c.min_lci = -0.1; }, "min_lci = -0.1: must be in [0, 1]");
  bad([](ControllerSettings& c) { c.pid.kd = 2e6; }, "pid.kd = 2000000 s per rad");
  bad([](ControllerSettings& c) { c.pid.i_clamp = -0.5; }, "pid.i_clamp = -0.5: must be in [0, 1]");
  bad([](ControllerSettings& c) { c.potentiometer.rad_per_volt = 0; }, "potentiometer.rad_per_volt = 0 rad/V");
  bad([](ControllerSettings& c) { c.potentiometer.volts_at_zero = 1e4; }, "potentiometer.volts_at_zero = 10000 V");
  bad(
      [](ControllerSettings& c) {
        ControlOverride o;
        o.station = "index", o.mechanism = "lower", o.joint = 1, o.kp = -2;
        c.overrides.push_back(o);
      },
      "stations.index.lower.theta1.pid.kp = -2 per rad");
  bad(
      [](ControllerSettings& c) {
        ControlOverride o;
        o.station = "index", o.joint = 2;  // a joint needs its mechanism
        c.overrides.push_back(o);
      },
      "joint 2 must be 1 or 2 within a mechanism");
  // A reversed potentiometer (negative slope) is fine.
  ControllerSettings reversed;
  reversed.potentiometer.rad_per_volt = -1.0;
  EXPECT_NO_THROW(reversed.validate());
  EXPECT_TRUE(is_ros_node_name("_private9"));
  EXPECT_FALSE(is_ros_node_name("9lives"));
  EXPECT_FALSE(is_ros_node_name("with space"));
}

TEST(DesignValidate, OneJointSpeedLimitWithAController) {
  Design d = valid_design();
  d.set<ControllerSettings>(ControllerSettings{});
  d.set<PatternSettings>(PatternSettings{});
  EXPECT_NO_THROW(d.validate());  // both 360 deg/s by default
  d.get<PatternSettings>()->max_joint_speed = deg(180);
  EXPECT_THAT([&] { d.validate(); },
              ThrowsMessage<InputError>(HasSubstr("patterns.max_joint_speed_deg_s = 180 deg/s: differs from "
                                                  "controller.max_velocity_deg_s (360 deg/s)")));
  d.get<ControllerSettings>()->max_velocity = deg(180);
  EXPECT_NO_THROW(d.validate());
  ControlOverride o;
  o.station = "index", o.mechanism = "upper";  // valid_design() has only the lower mechanism
  d.get<ControllerSettings>()->overrides.push_back(o);
  EXPECT_THAT([&] { d.validate(); }, ThrowsMessage<InputError>(HasSubstr("controller.stations.index.upper: station "
                                                                           "'index' has no upper mechanism")));
}

// The writer: every section, read back, is the same design (to_yaml is canonical, so equal text
// means equal values), and the values that matter are checked one by one as well.
TEST(DesignWriter, ShowcaseRoundTripsWithPatternsAndController) {
  const Design d = load_design(kSourceDir / "designs/iros2022.yaml");
  ASSERT_TRUE(d.get<PatternSettings>() && d.get<ControllerSettings>());
  const std::string text = to_yaml(d);
  EXPECT_THAT(text, HasSubstr("patterns:"));
  EXPECT_THAT(text, HasSubstr("controller:"));
  EXPECT_THAT(text, ::testing::Not(HasSubstr("max_joint_speed_deg_s")));  // the controller owns the limit
  const Design back = load_design_from_string(text, "<to_yaml>");
  EXPECT_EQ(to_yaml(back), text);
  ASSERT_TRUE(back.get<PatternSettings>() && back.get<ControllerSettings>());
  EXPECT_EQ(back.get<PatternSettings>()->max_joint_speed, d.get<PatternSettings>()->max_joint_speed);
  for (const char* station : {"index", "thumb"}) {
    const auto a = d.get<PatternSettings>()->for_station(station), b = back.get<PatternSettings>()->for_station(station);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].kind, b[i].kind);
      EXPECT_EQ(a[i].amplitude_mm, b[i].amplitude_mm);
      EXPECT_EQ(a[i].duration_s, b[i].duration_s);
      EXPECT_EQ(a[i].rate_hz, b[i].rate_hz);
      EXPECT_EQ(a[i].separation_mm, b[i].separation_mm);
      EXPECT_EQ(a[i].pivot_amplitude, b[i].pivot_amplitude);
      EXPECT_EQ(a[i].pivot_frequency_hz, b[i].pivot_frequency_hz);
    }
    for (const char* m : {"lower", "upper"}) {
      for (int j = 1; j <= 2; ++j) {
        const JointControl x = d.get<ControllerSettings>()->joint(station, m, j), y = back.get<ControllerSettings>()->joint(station, m, j);
        EXPECT_EQ(x.pid.kp, y.pid.kp);
        EXPECT_EQ(x.pid.ki, y.pid.ki);
        EXPECT_EQ(x.pid.kd, y.pid.kd);
        EXPECT_EQ(x.pid.i_clamp, y.pid.i_clamp);
        EXPECT_EQ(x.potentiometer.volts_at_zero, y.potentiometer.volts_at_zero);
        EXPECT_EQ(x.potentiometer.rad_per_volt, y.potentiometer.rad_per_volt);
      }
    }
  }
  EXPECT_EQ(back.get<PatternSettings>()->for_station("thumb")[2].amplitude_mm, 5.5);  // the thumb's own twist
  EXPECT_EQ(back.get<ControllerSettings>()->node, d.get<ControllerSettings>()->node);
  EXPECT_EQ(back.get<ControllerSettings>()->max_velocity, d.get<ControllerSettings>()->max_velocity);
  EXPECT_EQ(back.get<ControllerSettings>()->adc_range_v, d.get<ControllerSettings>()->adc_range_v);
  EXPECT_EQ(back.get<ControllerSettings>()->joint("index", "upper", 1).potentiometer.volts_at_zero, 4.75);
}

TEST(DesignWriter, PatternsWithoutControllerKeepTheirSpeedAndPivotContactPoints) {
  Design d = load_design_from_string("name: w\n" + kPaperStations, "<test>");
  PatternSettings ps;
  ps.rate_hz = 50.0;
  ps.max_joint_speed = deg(123.5);
  PatternSpec pivot;
  pivot.kind = PatternKind::pivot;
  pivot.rate_hz = 50.0;
  pivot.pivot_amplitude = deg(12.5);
  pivot.contact_points = std::array<Vec2, 2>{Vec2(0.1, 3.3), Vec2(-0.7, -2.9)};
  pivot.centre = Vec2(6.0, 15.0);
  ps.global.push_back(pivot);
  PatternSpec slip;
  slip.kind = PatternKind::slip;
  slip.amplitude_mm = 0.1 + 0.2;  // not a short decimal: must still come back bit for bit
  ps.overrides.emplace_back("thumb", slip);
  d.set<PatternSettings>(ps);
  d.validate();
  const Design back = load_design_from_string(to_yaml(d), "<to_yaml>");
  ASSERT_TRUE(back.has<PatternSettings>());
  EXPECT_EQ(back.get<PatternSettings>()->rate_hz, 50.0);
  EXPECT_EQ(back.get<PatternSettings>()->max_joint_speed, deg(123.5));
  ASSERT_EQ(back.get<PatternSettings>()->global.size(), 1u);
  const PatternSpec& p = back.get<PatternSettings>()->global[0];
  EXPECT_EQ(p.pivot_amplitude, deg(12.5));
  ASSERT_TRUE(p.contact_points.has_value());
  EXPECT_EQ((*p.contact_points)[1], Vec2(-0.7, -2.9));
  EXPECT_EQ(p.centre, Vec2(6.0, 15.0));
  const auto thumb = back.get<PatternSettings>()->for_station("thumb");
  ASSERT_EQ(thumb.size(), 2u);
  EXPECT_EQ(thumb[0].kind, PatternKind::slip);
  EXPECT_EQ(thumb[0].amplitude_mm, 0.1 + 0.2);
  EXPECT_EQ(to_yaml(back), to_yaml(d));
}

}  // namespace
}  // namespace fivebar
