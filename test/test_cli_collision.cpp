// End-to-end tests of `fivebar collision` and the collision and pattern products of `fivebar run`:
// real processes, their output, files and exit codes. Expected values are
// derived here from the paper's geometry (Table 1) and the showcase's `geometry:` (pin bosses 5 mm,
// min_clearance 0.3 mm), independently of the library.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "cli_geometry.hpp"
#include "cli_test.hpp"
#include "json_records.hpp"

namespace {

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using ft::slurp;
using nlohmann::json;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

using namespace ::fivebar::testing::paper;  // test/cli_geometry.hpp

/// The paper's design and a scratch directory per test (test/cli_test.hpp).
class CliTactors : public ft::CliTest {
 protected:
  CliTactors() : CliTest("fivebar_test_cli_tactors") {}
};

// --- collision: a pair of points --------------------------------------------------------------------

TEST_F(CliTactors, PairClearOfEachOther) {
  // Index: tactors 8 mm apart on the vertical through the centre; the P bosses (2.5 + 2.5) leave 3 mm.
  const Outcome r = run({"collision", kDesign, "--station", "index", "--upper", "6.25,19.5", "--lower", "6.25,11.5"});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, AllOf(HasSubstr("no collision"), HasSubstr("3.0000 mm"), HasSubstr("plane 1")));
  EXPECT_THAT(r.err, IsEmpty());

  const Outcome j = run({"collision", kDesign, "-s", "index", "--upper", "6.25,19.5", "--lower", "6.25,11.5", "--json"});
  EXPECT_EQ(j.code, 0);
  const json doc = parse(j);
  EXPECT_FALSE(doc["collides"].get<bool>());
  EXPECT_EQ(doc["status"], "clear");
  EXPECT_NEAR(doc["before"]["min_clearance_mm"].get<double>(), 3.0, 1e-9);
  EXPECT_EQ(doc["moved_mm"].get<double>(), 0.0);
  EXPECT_EQ(xy(doc["lower_point_mm"]), (std::array<double, 2>{6.25, 11.5}));
}
TEST_F(CliTactors, PairCollidingMovesTheLowerAndExitsOne) {
  // Both targets at the index centre: the lower moves 5.3 mm (boss radii 2.5 + 2.5 + clearance 0.3).
  const Outcome r = run({"collision", kDesign, "--station", "index", "--upper", "6.25,15.5", "--lower", "6.25,15.5"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.out, AllOf(HasSubstr("COLLISION"), HasSubstr("upper.L3 vs lower.L3"), HasSubstr("upper.tactor vs lower.tactor"),
                           HasSubstr("lower target moved to")));
  EXPECT_THAT(r.err, HasSubstr("collide"));

  const json doc = parse(run({"collision", kDesign, "-s", "index", "--upper", "6.25,15.5", "--lower", "6.25,15.5", "--json"}));
  EXPECT_TRUE(doc["collides"].get<bool>());
  EXPECT_EQ(doc["status"], "moved");
  EXPECT_DOUBLE_EQ(doc["before"]["min_clearance_mm"].get<double>(), -5.0);
  const auto moved = xy(doc["lower_point_mm"]);
  const double d = std::hypot(moved[0] - 6.25, moved[1] - 15.5);
  EXPECT_NEAR(d, 5.3, 1e-3);
  EXPECT_NEAR(doc["moved_mm"].get<double>(), d, 1e-12);
  EXPECT_FALSE(doc["after"]["collides"].get<bool>());
  EXPECT_GE(doc["after"]["min_clearance_mm"].get<double>(), 0.3);
  // The upper keeps its IK solution: the same angles `fivebar ik` gives.
  const json ik = parse(run({"ik", kDesign, "-s", "index", "-m", "upper", "--point", "6.25,15.5", "--json"}));
  EXPECT_EQ(ft::record(doc["mechanisms"], "mechanism", "upper")["theta_deg"], ik["theta_deg"]);
}
TEST_F(CliTactors, NegativeCoordinatesAndUnreachableTargets) {
  // A negative coordinate after --upper is a value, not an option; (-30, 15.5) is out of reach.
  const Outcome r = run({"collision", kDesign, "-s", "index", "--upper", "-30,15.5", "--lower", "6.25,11.5"});
  EXPECT_EQ(r.code, 1);
  EXPECT_THAT(r.out, HasSubstr("unreachable"));
  EXPECT_THAT(r.err, HasSubstr("the upper target cannot be held"));
}
TEST_F(CliTactors, BadInputExitsTwo) {
  const Outcome only_one = run({"collision", kDesign, "-s", "index", "--upper", "6.25,15.5"});
  EXPECT_EQ(only_one.code, 2);
  EXPECT_THAT(only_one.err, HasSubstr("give both --upper X,Y and --lower X,Y"));
  const Outcome bad_pair = run({"collision", kDesign, "-s", "index", "--upper", "6.25", "--lower", "1,2"});
  EXPECT_EQ(bad_pair.code, 2);
  EXPECT_THAT(bad_pair.err, HasSubstr("--upper '6.25'"));
  const Outcome station = run({"collision", kDesign, "-s", "middle"});
  EXPECT_EQ(station.code, 2);
  EXPECT_THAT(station.err, AllOf(HasSubstr("middle"), HasSubstr("index, thumb")));
  const Outcome choose = run({"collision", kDesign});
  EXPECT_EQ(choose.code, 2);
  EXPECT_THAT(choose.err, HasSubstr("--station"));

  const fs::path no_geometry = design_without("no-geometry.yaml", "geometry:\n", "# Resin printing");
  const Outcome g = run({"collision", no_geometry.string(), "-s", "index"});
  EXPECT_EQ(g.code, 2);
  EXPECT_THAT(g.err, HasSubstr("has no geometry"));
  const Outcome index_only = run({"collision", (kSource / "designs" / "iros2022-index.yaml").string()});
  EXPECT_EQ(index_only.code, 2);  // that design has no geometry section either
}

// --- collision: the map ------------------------------------------------------------------------------

TEST_F(CliTactors, MapWritesThePictureAndReportsTheSeparations) {
  const fs::path out = dir_ / "maps";
  const Outcome r = run({"collision", kDesign, "-s", "thumb", "--spacing", "1.0", "--out", out.string(), "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json doc = parse(r);
  EXPECT_EQ(doc["station"], "thumb");
  EXPECT_EQ(doc["spacing_mm"].get<double>(), 1.0);
  EXPECT_GT(doc["colliding_fraction"].get<double>(), 0.0);
  EXPECT_LT(doc["colliding_fraction"].get<double>(), 1.0);
  // No collision-free pair can be closer than the two P bosses allow: 2.5 + 2.5 + 0.3 mm.
  EXPECT_GE(doc["min_free_separation_mm"].get<double>(), 5.3);
  const auto pair = doc["min_free_pair_mm"];
  const auto u = xy(pair[0]), l = xy(pair[1]);
  EXPECT_NEAR(std::hypot(u[0] - l[0], u[1] - l[1]), doc["min_free_separation_mm"].get<double>(), 1e-9);
  // Grid points lie on the 1 mm lattice through the ellipse centre (6.25, 17.5).
  EXPECT_NEAR(std::remainder(u[0] - 6.25, 1.0), 0.0, 1e-9);
  EXPECT_NEAR(std::remainder(u[1] - 17.5, 1.0), 0.0, 1e-9);
  for (const char* f : {"thumb.svg", "thumb.png"}) {
    EXPECT_TRUE(fs::exists(out / f)) << f;
    EXPECT_GT(fs::file_size(out / f), 1000u) << f;
  }
  EXPECT_EQ(slurp(out / "thumb.png").substr(1, 3), "PNG");

  const Outcome text = run({"collision", kDesign, "-s", "thumb", "--spacing", "1.0", "--out", out.string()});
  EXPECT_EQ(text.code, 0);
  EXPECT_THAT(text.out, AllOf(HasSubstr("collision map"), HasSubstr("closest free pair"), HasSubstr("priority, both at centre"),
                              HasSubstr("thumb.png")));
}
TEST_F(CliTactors, MapDefaultsToTheOutputsFolder) {
  const Outcome r = run({"collision", kDesign, "-s", "index", "--spacing", "1.5"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "outputs" / "iros2022" / "collision" / "index.png"));
}

// --- run ----------------------------------------------------------------------------------------------

TEST_F(CliTactors, RunBuildsBothProductsWithTheirFiles) {
  const fs::path out = dir_ / "out";
  const Outcome r = run({"run", kDesign, "--out", out.string(), "--products", "collision,pattern", "--json", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json s = parse(r);
  std::vector<std::string> built;
  for (const auto& b : s["built"]) built.push_back(b["name"]);
  EXPECT_EQ(built, (std::vector<std::string>{"collision", "pattern"}));
  const fs::path scene = out / "iros2022";
  for (const char* f : {"collision/index.png", "collision/thumb.svg", "patterns/index.png", "patterns/thumb.svg",
                        "patterns/index-stretch.csv", "patterns/thumb-pivot.csv"}) {
    EXPECT_TRUE(fs::exists(scene / f)) << f;
  }
  const json& patterns = s["results"]["pattern"]["stations"];
  ASSERT_EQ(patterns.size(), 2u);
  EXPECT_EQ(patterns[0]["patterns"].size(), 4u);
  const std::string md = slurp(scene / "summary.md");
  EXPECT_THAT(md, AllOf(HasSubstr("## Collision of the two tactors"), HasSubstr("## Skin-deformation patterns"),
                        HasSubstr("![patterns of station index](patterns/index.png)")));
}
TEST_F(CliTactors, RunLeavesTheProductsOutAndSaysWhy) {
  const fs::path out = dir_ / "out";
  // Without geometry: both left out for that reason.
  const fs::path no_geometry = design_without("no-geometry.yaml", "geometry:\n", "# Resin printing");
  const json a = parse(run({"run", no_geometry.string(), "--out", out.string(), "--json", "--quiet"}));
  std::map<std::string, std::string> reasons;
  for (const auto& l : a["left_out"]) reasons[l["name"]] = l["reason"];
  EXPECT_THAT(reasons["collision"], HasSubstr("geometry"));
  EXPECT_THAT(reasons["pattern"], HasSubstr("geometry"));

  // Without the upper mechanisms: no station has both.
  std::string text = slurp(kDesign);
  for (const char* upper : {"      upper:                              # Table 1: O3, O4; the mirror image of the lower one\n"
                            "        bases: [[0, 31], [12.5, 31]]\n        links: [9, 9, 15, 15]\n"
                            "        working_mode: \"+-\"                # elbows outward for a tactor below its bases\n"
                            "        assembly_mode: \"-\"                # tactor below the elbow line A1A2\n",
                            "      upper:\n        bases: [[0, 35], [12.5, 35]]\n        links: [9, 9, 17.5, 17.5]\n"
                            "        working_mode: \"+-\"\n        assembly_mode: \"-\"\n"}) {
    const auto pos = text.find(upper);
    ASSERT_NE(pos, std::string::npos) << upper;
    text.erase(pos, std::strlen(upper));
  }
  // The optimize: section names the upper mechanisms' numbers: without them it goes too.
  const auto opt = text.find("optimize:\n"), opt_end = text.find("# Skin-deformation patterns");
  ASSERT_TRUE(opt != std::string::npos && opt_end != std::string::npos);
  text.erase(opt, opt_end - opt);
  // ... and the controller's tuned gains of the upper mechanisms (controller.stations.<s>.upper).
  for (std::size_t at = text.find("      upper: {pid: {kp: "); at != std::string::npos;
       at = text.find("      upper: {pid: {kp: ")) {
    text.erase(at, text.find('\n', at) + 1 - at);
  }
  const fs::path lower_only = dir_ / "lower-only.yaml";
  std::ofstream(lower_only) << text;
  const Outcome b = run({"run", lower_only.string(), "--out", out.string(), "--json", "--quiet"});
  ASSERT_EQ(b.code, 0) << b.err;
  reasons.clear();
  const json bj = parse(b);
  for (const auto& l : bj["left_out"]) reasons[l["name"]] = l["reason"];
  EXPECT_THAT(reasons["collision"], HasSubstr("both a lower and an upper"));
  EXPECT_THAT(reasons["pattern"], HasSubstr("both a lower and an upper"));

  // Without patterns: only the pattern product is left out.
  const fs::path no_patterns = design_without("no-patterns.yaml", "patterns:\n", "# The ROS controller on the device");
  const json c = parse(run({"run", no_patterns.string(), "--out", out.string(), "--json", "--quiet", "--products",
                            "collision,pattern"}));
  EXPECT_EQ(c["built"][0]["name"], "collision");
  EXPECT_EQ(c["missing"], json::array({"pattern"}));
  std::string pattern_reason;
  for (const auto& l : c["left_out"]) {
    if (l["name"] == "pattern") pattern_reason = l["reason"].get<std::string>();
  }
  EXPECT_THAT(pattern_reason, HasSubstr("patterns:"));
}

}  // namespace
