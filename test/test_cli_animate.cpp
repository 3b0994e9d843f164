// End-to-end tests of `fivebar animate`: the SVG it writes holds the pattern's frames (the link
// lengths of the design at every frame), --simulated adds the simulated tactor, --json reports it,
// and bad input exits 2 with a message naming the option and writes nothing.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "cli_test.hpp"

namespace {

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using ft::slurp;
using nlohmann::json;
using ::testing::HasSubstr;

class CliAnimate : public ft::CliTest {
 protected:
  CliAnimate() : CliTest("fivebar_test_cli_animate") {}

  static json frames_of(const std::string& svg) {
    const std::string open = "<metadata class=\"fivebar-animation-data\">";
    const std::size_t a = svg.find(open);
    const std::size_t b = svg.find("</metadata>", a);
    if (a == std::string::npos || b == std::string::npos) return json();
    return json::parse(svg.substr(a + open.size(), b - a - open.size()));
  }
};

TEST_F(CliAnimate, WritesTheFramesOfThePatternWithTheDesignsLinkLengths) {
  const fs::path out = dir_ / "movies" / "thumb-twist.svg";  // --out is the directory
  const Outcome r = run({"animate", kDesign, "--station", "thumb", "--pattern", "twist", "--out", (dir_ / "movies").string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("101 frames over 1.000 s (renderable)"));
  const std::string svg = slurp(out);
  const json d = frames_of(svg);
  ASSERT_TRUE(d.is_object());
  EXPECT_EQ(d["station"], "thumb");
  EXPECT_EQ(d["pattern"], "twist");
  ASSERT_EQ(d["t_s"].size(), 101u);
  // The showcase's thumb: links [9, 9, 17.5, 17.5] for both mechanisms (designs/iros2022.yaml).
  for (const json& m : d["mechanisms"]) {
    EXPECT_EQ(m["links_mm"], json({9.0, 9.0, 17.5, 17.5}));
    for (const json& f : m["frames"]) {
      ASSERT_TRUE(f.is_array());
      const double O1x = m["O1"][0], O1y = m["O1"][1], O2x = m["O2"][0], O2y = m["O2"][1];
      EXPECT_NEAR(std::hypot(f[0].get<double>() - O1x, f[1].get<double>() - O1y), 9.0, 2e-4);
      EXPECT_NEAR(std::hypot(f[4].get<double>() - O2x, f[5].get<double>() - O2y), 9.0, 2e-4);
      EXPECT_NEAR(std::hypot(f[2].get<double>() - f[0].get<double>(), f[3].get<double>() - f[1].get<double>()), 17.5, 2e-4);
      EXPECT_NEAR(std::hypot(f[2].get<double>() - f[4].get<double>(), f[3].get<double>() - f[5].get<double>()), 17.5, 2e-4);
    }
  }
  EXPECT_EQ(tree(dir_ / "movies"), std::vector<std::string>{"thumb-twist.svg"});  // no temporary left behind
}

TEST_F(CliAnimate, SimulatedSeriesAndJson) {
  std::string csv = "t_s,mechanism,x_mm,y_mm\n";
  for (int k = 0; k <= 100; ++k) {
    csv += std::to_string(0.01 * k) + ",upper,6.25," + std::to_string(19.5 + 0.001 * k) + "\n";
  }
  const fs::path sim = write("sim.csv", csv);
  const Outcome r = run({"animate", kDesign, "-s", "index", "--pattern", "stretch", "--simulated", sim.string(), "--out",
                         "a", "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = parse(r);
  EXPECT_EQ(j["command"], "animate");
  EXPECT_EQ(j["frames"], 101);
  EXPECT_EQ(j["simulated"], true);
  EXPECT_EQ(j["renderable"], true);
  const json d = frames_of(slurp(dir_ / "a" / "index-stretch.svg"));
  ASSERT_TRUE(d["mechanisms"][0].contains("simulated"));
  EXPECT_NEAR(d["mechanisms"][0]["simulated"][40][1].get<double>(), 19.54, 1e-4);
}

TEST_F(CliAnimate, BadInputExitsTwoAndWritesNothing) {
  const fs::path no_patterns = design_without("no_patterns.yaml", "patterns:\n", "\n# The ROS controller");
  const fs::path bad_csv = write("bad.csv", "t_s,mechanism,x_mm\n0,upper,1\n");
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const std::vector<Case> cases{
      {{"animate", kDesign, "-s", "index", "--pattern", "wiggle", "--out", "o"}, "--pattern 'wiggle'"},
      {{"animate", kDesign, "-s", "index", "--pattern", "stretch", "--out", "o/a.gif"}, "SVG only"},
      {{"animate", kDesign, "-s", "index", "--pattern", "stretch", "--out", "o/a.svg"}, "is the directory"},
      {{"animate", kDesign, "-s", "ring", "--pattern", "stretch", "--out", "o"}, "unknown station 'ring'"},
      {{"animate", kDesign, "-s", "index", "--pattern", "stretch", "--out", "o", "--width", "nan"}, "--width"},
      {{"animate", no_patterns.string(), "-s", "index", "--pattern", "stretch", "--out", "o"}, "no patterns: section"},
      {{"animate", kDesign, "-s", "index", "--pattern", "stretch", "--out", "o", "--simulated", "none.csv"},
       "--simulated none.csv"},
      {{"animate", kDesign, "-s", "index", "--pattern", "stretch", "--out", "o", "--simulated", bad_csv.string()},
       "bad.csv:1: column 'y_mm' is missing"},
  };
  const std::vector<std::string> before = tree(dir_);
  for (const Case& c : cases) {
    SCOPED_TRACE(c.args[5] + " " + c.args.back());
    const Outcome r = run(c.args);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_THAT(r.err, HasSubstr(c.message));
    EXPECT_EQ(r.out, "");
    EXPECT_EQ(tree(dir_), before);
  }
}

}  // namespace
