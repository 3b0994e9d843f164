// End-to-end tests of what every subcommand shares: --help and --version, usage errors, station
// and mechanism choices, malformed designs (docs/conventions.md "Exit codes").
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

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using ft::slurp;
using nlohmann::json;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::IsEmpty;
using ::testing::MatchesRegex;

namespace {

using namespace ::fivebar::testing::paper;  // test/cli_geometry.hpp

/// The paper's design and a scratch directory per test (test/cli_test.hpp).
class Cli : public ft::CliTest {
 protected:
  Cli() : CliTest("fivebar_test_cli") {}
};

// --- General --------------------------------------------------------------------------------------

TEST_F(Cli, VersionAndHelp) {
  const Outcome v = run({"--version"});
  EXPECT_EQ(v.code, 0);
  EXPECT_THAT(v.out, MatchesRegex("fivebar [0-9]+\\.[0-9]+\\.[0-9]+\n"));

  const Outcome h = run({"--help"});
  EXPECT_EQ(h.code, 0);
  EXPECT_THAT(h.out, AllOf(HasSubstr("fk"), HasSubstr("ik"), HasSubstr("run"), HasSubstr("Exit status")));
  for (const char* cmd : {"fk", "ik", "run"}) {
    const Outcome sub = run({cmd, "--help"});
    EXPECT_EQ(sub.code, 0) << cmd;
    EXPECT_THAT(sub.out, HasSubstr("Usage: fivebar " + std::string(cmd))) << cmd;
  }
  EXPECT_THAT(run({"fk", "--help"}).out, AllOf(HasSubstr("degrees"), HasSubstr("--theta-file")));
  EXPECT_THAT(run({"ik", "--help"}).out, AllOf(HasSubstr("mm"), HasSubstr("--point-file"), HasSubstr("--all")));
}
TEST_F(Cli, UsageErrorsExitTwoWithAMessageOnStderr) {
  const std::vector<std::vector<std::string>> cases{
      {},
      {"frobnicate"},
      {"fk"},
      {"fk", kDesign, "--frobnicate"},
      {"fk", kDesign, "-s", "index", "-m", "middle", "--theta", "1,2"},
      {"fk", kDesign, "-s", "index", "-m", "lower", "--theta", "1,2", "--theta-file", "x.csv"},
      {"fk", kDesign, "-s", "index", "-m", "lower", "--theta-file", "x.csv", "--json"},
      {"fk", kDesign, "-s", "index", "-m", "lower", "--branch", "up", "--theta", "1,2"},
      {"fk", kDesign, "-s", "index", "-m", "lower"},
      {"ik", kDesign, "-s", "index", "-m", "lower", "--point", "1,2", "--mode", "+"},
      {"ik", kDesign, "-s", "index", "-m", "lower", "--point", "1,2", "--all", "--mode", "+-"},
      {"ik", kDesign, "-s", "index", "-m", "lower", "--point", "1,2", "--output", "x.csv"},
      {"run"},
  };
  for (const auto& c : cases) {
    std::string line;
    for (const auto& a : c) line += a + " ";
    SCOPED_TRACE("fivebar " + line);
    const Outcome r = run(c);
    EXPECT_EQ(r.code, 2);
    EXPECT_THAT(r.out, IsEmpty());
    EXPECT_FALSE(r.err.empty());
  }
  EXPECT_TRUE(tree(dir_).empty()) << "usage errors write nothing";
}

// --- station / mechanism choice --------------------------------------------------------------------

TEST_F(Cli, StationAndMechanismChoices) {
  const Outcome unknown = run({"fk", kDesign, "--station", "pinky", "--mechanism", "lower", "--theta", "100,80"});
  EXPECT_EQ(unknown.code, 2);
  EXPECT_THAT(unknown.err, AllOf(HasSubstr("pinky"), HasSubstr("index"), HasSubstr("thumb")));

  const Outcome ambiguous = run({"fk", kDesign, "--theta", "100,80"});
  EXPECT_EQ(ambiguous.code, 2);
  EXPECT_THAT(ambiguous.err, AllOf(HasSubstr("--station"), HasSubstr("index"), HasSubstr("thumb")));

  const Outcome no_mech = run({"fk", kDesign, "--station", "thumb", "--theta", "100,80"});
  EXPECT_EQ(no_mech.code, 2);
  EXPECT_THAT(no_mech.err, AllOf(HasSubstr("--mechanism"), HasSubstr("lower"), HasSubstr("upper")));

  // A design with one station and one mechanism needs neither option.
  const fs::path single = write("single.yaml",
                                "name: single\n"
                                "stations:\n"
                                "  index:\n"
                                "    target: {center: [6.25, 15.5], axes: [15, 12], angle: 0}\n"
                                "    mechanisms:\n"
                                "      lower:\n"
                                "        bases: [[0, 0], [12.5, 0]]\n"
                                "        links: [9, 9, 15, 15]\n"
                                "        working_mode: \"-+\"\n"
                                "        assembly_mode: \"+\"\n");
  const Outcome ok = run({"ik", single.string(), "--point", "6.25,15.5", "--json"});
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_EQ(json::parse(ok.out)["mechanism"], "lower");
  const Outcome absent = run({"ik", single.string(), "--mechanism", "upper", "--point", "6.25,15.5"});
  EXPECT_EQ(absent.code, 2);
  EXPECT_THAT(absent.err, AllOf(HasSubstr("upper"), HasSubstr("lower")));
}

// --- design errors --------------------------------------------------------------------------------

TEST_F(Cli, MalformedDesignExitsTwoNamingTheKeyAndWritesNothing) {
  const fs::path bad = design_with("bad.yaml", "links: [9, 9, 15, 15]", "links: [9, 9, -15, 15]");
  for (const auto& cmd : std::vector<std::vector<std::string>>{
           {"fk", bad.string(), "-s", "index", "-m", "lower", "--theta", "100,80"},
           {"ik", bad.string(), "-s", "index", "-m", "lower", "--point", "6,15", "--json"},
           {"run", bad.string(), "--out", (dir_ / "out").string()}}) {
    SCOPED_TRACE(cmd[0]);
    const Outcome r = run(cmd);
    EXPECT_EQ(r.code, 2);
    EXPECT_THAT(r.out, IsEmpty());
    EXPECT_THAT(r.err, AllOf(HasSubstr("bad.yaml"), HasSubstr("links[2]")));
  }
  EXPECT_FALSE(fs::exists(dir_ / "out")) << "no output for a bad design";

  const Outcome missing = run({"run", (dir_ / "nope.yaml").string(), "--out", (dir_ / "out").string()});
  EXPECT_EQ(missing.code, 2);
  EXPECT_THAT(missing.err, HasSubstr("nope.yaml"));
  EXPECT_FALSE(fs::exists(dir_ / "out"));
}

}  // namespace
