// End-to-end tests of `fivebar run`: the summaries, the product list, the output root.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "cli_geometry.hpp"
#include "cli_test.hpp"
#include "json_records.hpp"

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using ft::slurp;
using nlohmann::json;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::IsEmpty;
using ::testing::MatchesRegex;

namespace {

using namespace ::fivebar::testing::paper;  // test/cli_geometry.hpp

/// The paper's design and a scratch directory per test (test/cli_test.hpp).
class Cli : public ft::CliTest {
 protected:
  Cli() : CliTest("fivebar_test_cli") {}
};

// --- run ------------------------------------------------------------------------------------------

TEST_F(Cli, RunWritesTheSummariesAndThePageAndNothingElse) {
  const fs::path out = dir_ / "out";
  // Only kinematics, which writes no files of its own (other products write theirs beside).
  const Outcome r = run({"run", kDesign, "--out", out.string(), "--products", "kinematics"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, AllOf(HasSubstr("kinematics"), HasSubstr("summary.md")));

  const json s = json::parse(slurp(out / "iros2022" / "summary.json"));
  EXPECT_EQ(s["design"], "iros2022");
  EXPECT_TRUE(s["ok"].get<bool>());
  ASSERT_GE(s["built"].size(), 1u);
  EXPECT_EQ(s["built"][0]["name"], "kinematics");
  // Nothing but the summaries, the page and the files the built products list (and their folders).
  std::set<std::string> expected{"iros2022", "iros2022/summary.json", "iros2022/summary.md", "iros2022/index.html"};
  for (const auto& product : s["built"]) {
    for (const auto& f : product["files"]) {
      for (fs::path p = fs::path("iros2022") / f.get<std::string>(); p != "iros2022"; p = p.parent_path()) {
        expected.insert(p.generic_string());
      }
    }
  }
  EXPECT_EQ(tree(out), std::vector<std::string>(expected.begin(), expected.end()));
  const json& stations = s["results"]["kinematics"]["stations"];
  ASSERT_EQ(stations.size(), 2u);
  // The summary's centre pose agrees with `fivebar ik` at the same point.
  const json& lower = stations[0]["mechanisms"][0];
  EXPECT_EQ(lower["mechanism"], "lower");
  EXPECT_EQ(lower["parameters"]["name"], "lower");
  const Outcome ik = run(args({"ik", kDesign}, kIndexLowerArgs, {"--point", "6.25,15.5", "--json"}));
  EXPECT_EQ(lower["centre"]["ik"]["theta_deg"], json::parse(ik.out)["theta_deg"]);
  EXPECT_EQ(lower["axis_ends"].size(), 4u);

  const std::string md = slurp(out / "iros2022" / "summary.md");
  EXPECT_THAT(md, AllOf(HasSubstr("# fivebar scene `iros2022`"), HasSubstr("| `kinematics` | built"),
                        HasSubstr("θ1 (deg)"), HasSubstr("Station `thumb`")));
}
TEST_F(Cli, RunJsonAndDefaultOutputRoot) {
  // Default root is outputs/ relative to the working directory.
  const Outcome r = run({"run", kDesign, "-P", "kinematics", "--json", "--quiet"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.err, IsEmpty());
  const json j = parse(r);
  EXPECT_EQ(j["built"][0]["name"], "kinematics");
  EXPECT_EQ(j["summary_md"], "outputs/iros2022/summary.md");
  EXPECT_EQ(j["index_html"], "outputs/iros2022/index.html");
  EXPECT_TRUE(fs::exists(dir_ / "outputs" / "iros2022" / "summary.json"));
}
TEST_F(Cli, RunProductsOptionAndSceneList) {
  const fs::path out = dir_ / "out";
  const Outcome bogus = run({"run", kDesign, "--out", out.string(), "--products", "kinematics,teleport"});
  EXPECT_EQ(bogus.code, 2);
  EXPECT_THAT(bogus.err, AllOf(HasSubstr("teleport"), HasSubstr("kinematics")));
  EXPECT_FALSE(fs::exists(out));

  const Outcome listed = run({"run", kDesign, "--out", out.string(), "--products", "kinematics", "--json"});
  ASSERT_EQ(listed.code, 0) << listed.err;
  EXPECT_THAT(listed.err, IsEmpty());  // stderr is a file, not a terminal: no progress lines even without --quiet
  const json j = parse(listed);
  EXPECT_TRUE(j["products_listed"].get<bool>());
  EXPECT_TRUE(j["built"][0]["requested"].get<bool>());

  const fs::path scene = design_with("scene.yaml", "name: iros2022", "name: scene\nproducts: [kinematics]");
  const Outcome from_file = run({"run", scene.string(), "--out", out.string(), "--json"});
  ASSERT_EQ(from_file.code, 0) << from_file.err;
  EXPECT_TRUE(json::parse(from_file.out)["products_listed"].get<bool>());
  EXPECT_TRUE(fs::exists(out / "scene" / "summary.md"));
}
TEST_F(Cli, RunIntoAnUnusableOutputRootFailsWithoutPartialFiles) {
  const fs::path file = write("occupied", "not a directory\n");
  const Outcome r = run({"run", kDesign, "--out", file.string()});
  EXPECT_EQ(r.code, 3);
  EXPECT_THAT(r.err, HasSubstr("occupied"));
  EXPECT_EQ(slurp(file), "not a directory\n");
}

}  // namespace

// docs/bench-files.md "Where bench files may be": a bench file outside the design file's folder
// (a '..' path, an absolute path, a link leading out) is refused at the design's line and key
// with nothing created and nothing of the file echoed; `--allow-outside-paths` reads it.
TEST_F(Cli, RunReadsBenchFilesOutsideTheDesignFolderOnlyWithTheFlag) {
  fs::create_directories(dir_ / "d");
  fs::create_directories(dir_ / "elsewhere");
  fs::copy_file(kSource / "designs" / "bench" / "calibration.csv", dir_ / "elsewhere" / "cal.csv");
  fs::create_symlink("../elsewhere/cal.csv", dir_ / "d" / "link.csv");
  const std::string from = "calibration: bench/calibration.csv";
  const std::string text = ft::slurp(kDesign);
  const std::string line = std::to_string(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(text.find(from)), '\n') + 1);
  const std::string absolute = (dir_ / "elsewhere" / "cal.csv").string();
  const std::vector<std::pair<std::string, std::string>> cases{
      {"../elsewhere/cal.csv", "must not leave the design file's folder"},
      {absolute, "must be a path relative to the design file's folder"},
      {"link.csv", "a symbolic link that leads out of the design file's folder"}};
  for (const auto& [name, rule] : cases) {
    SCOPED_TRACE(name);
    design_with("d/b.yaml", from, "calibration: " + name);
    const Outcome refused = run({"run", "d/b.yaml", "--out", "out", "--products", "calibrate"});
    EXPECT_EQ(refused.code, 2) << refused.err;
    EXPECT_THAT(refused.err, HasSubstr("d/b.yaml:" + line + ": bench.calibration = " + name + ": " + rule));
    EXPECT_THAT(refused.err, Not(HasSubstr("station,mechanism")));  // nothing of the file is echoed
    EXPECT_FALSE(fs::exists(dir_ / "out"));
    // Any command that loads the design refuses it the same way, and takes the same flag.
    EXPECT_EQ(run({"fk", "d/b.yaml", "-s", "index", "-m", "lower", "--theta", "60,120"}).code, 2);
    const Outcome read = run({"run", "d/b.yaml", "--out", "out", "--products", "calibrate", "--allow-outside-paths"});
    ASSERT_EQ(read.code, 0) << read.err;
    const json s = json::parse(ft::slurp(dir_ / "out" / "iros2022" / "summary.json"));
    ASSERT_EQ(s["built"].size(), 1u);
    EXPECT_EQ(s["built"][0]["name"], "calibrate");
    EXPECT_TRUE(fs::exists(dir_ / "out" / "iros2022" / "calibrate")) << "the calibration was read and fitted";
    EXPECT_EQ(run({"fk", "d/b.yaml", "-s", "index", "-m", "lower", "--theta", "60,120", "--allow-outside-paths"}).code, 0);
    fs::remove_all(dir_ / "out");
  }
}
