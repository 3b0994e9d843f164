// End-to-end tests of `fivebar parts`: real processes, stdout, stderr, exit codes and the files
// written (test/cli_test.hpp). The library's plan, meshes and checks are tested in test_parts.cpp;
// here what the command adds: --out as the parts' directory, --no-render, the missing-tool hint,
// bad input with file, line and key, and a mesh that misses the design failing the run.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli_test.hpp"

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using ft::slurp;
using ::testing::AllOf;
using ::testing::HasSubstr;

namespace {

constexpr int kFn = 24;  // $fn of the renders: coarse, so that OpenSCAD is quick

class CliParts : public ft::CliTest {
 protected:
  CliParts() : CliTest("fivebar_test_cli_parts") {}

  /// The paper's design file with `edits` applied, $fn lowered to kFn.
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
};

TEST_F(CliParts, SourcesOnlyMissingOpenscadAndBadInput) {
  const std::string file = design_with("d.yaml").string();
  const std::string out = (dir_ / "out").string();

  // openscad missing: a clear message, exit 1, nothing written.
  const Outcome missing = run_with_env({"parts", file, "--out", out}, {"FIVEBAR_OPENSCAD=/nonexistent/openscad"});
  EXPECT_EQ(missing.code, 1);
  EXPECT_THAT(missing.err, AllOf(HasSubstr("openscad"), HasSubstr("not found"), HasSubstr("--no-render")));
  EXPECT_FALSE(fs::exists(out));

  // --no-render still writes the sources: both stations, 10 parts.
  const Outcome sources = run_with_env({"parts", file, "--out", out, "--no-render", "--json"},
                                       {"FIVEBAR_OPENSCAD=/nonexistent/openscad"});
  ASSERT_EQ(sources.code, 0) << sources.err;
  const auto j = nlohmann::json::parse(sources.out);
  EXPECT_EQ(j["command"], "parts");
  EXPECT_FALSE(j["rendered"].get<bool>());
  EXPECT_EQ(j["parts"].size(), 10u);
  EXPECT_TRUE(fs::exists(dir_ / "out" / "thumb" / "distal_link_tactor_17.5mm.scad"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "thumb" / "distal_link_tactor_17.5mm.stl"));

  // Bad input: exit 2 with file, line and key; an unknown station.
  const fs::path bad = design_with("bad.yaml", {{"links: [9, 9, 17.5, 17.5]", "links: [9, 4, 17.5, 17.5]"}});
  const Outcome refused = run({"parts", bad.string(), "--out", (dir_ / "bad").string()});
  EXPECT_EQ(refused.code, 2);
  EXPECT_THAT(refused.err, HasSubstr(bad.string() + ":" + std::to_string(line_of(bad, "links: [9, 4")) +
                                     ": stations.thumb.mechanisms.lower.links[1] = 4 mm"));
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
  const Outcome station = run({"parts", file, "--station", "pinky", "--out", out});
  EXPECT_EQ(station.code, 2);
  EXPECT_THAT(station.err, HasSubstr("no station 'pinky'"));
}

TEST_F(CliParts, RendersChecksAndFailsWhenAMeshMissesTheDesign) {
  const std::string file = design_with("d.yaml").string();
  const std::string out = (dir_ / "out").string();
  const Outcome ok = run({"parts", file, "--station", "index", "--out", out});
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_THAT(ok.out, AllOf(HasSubstr("proximal_link_9mm"), HasSubstr("9.0000"), HasSubstr("15.0000"),
                            HasSubstr("5 rendered, 0 up to date, 0 failed"), HasSubstr("bom.csv")));
  EXPECT_EQ(ok.err, "");  // progress only on a terminal

  // A library that puts the tactor-end hole of every distal link 0.05 mm too far: it renders
  // cleanly, but the measured pin-centre distance gives it away (exit 1).
  const fs::path lib = dir_ / "lib";
  fs::create_directories(lib);
  std::string text = slurp(kSource / "scad" / "fivebar.scad");
  const std::string from = "translate([length, 0, -1]) linear_extrude(height = top + 2)";
  ASSERT_NE(text.find(from), std::string::npos);
  text.replace(text.find(from), from.size(), "translate([length + 0.05, 0, -1]) linear_extrude(height = top + 2)");
  std::ofstream(lib / "fivebar.scad") << text;
  const Outcome off = run_with_env({"parts", file, "--station", "index", "--out", out, "--json"},
                                   {"FIVEBAR_SCAD_DIR=" + lib.string()});
  EXPECT_EQ(off.code, 1);
  const auto j = nlohmann::json::parse(off.out);
  EXPECT_FALSE(j["passed"].get<bool>());
  EXPECT_EQ(j["renders"]["rendered"], 5);  // the library changed: everything rendered again
  for (const auto& p : j["parts"]) {
    if (p["kind"] == "distal_link") {
      EXPECT_FALSE(p["passed"].get<bool>()) << p["name"];
      EXPECT_NEAR(p["centre_distance_mm"].get<double>(), 15.05, 1e-3);
      EXPECT_THAT(p["problems"].dump(), HasSubstr("pin-centre distance measured 15.0500 mm, link length 15.0000 mm"));
    } else {
      EXPECT_TRUE(p["passed"].get<bool>()) << p["name"];
    }
  }
}

}  // namespace
