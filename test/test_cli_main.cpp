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
#include <regex>
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

// --- help, -V, suggestions, completion and man pages (cli/help.hpp, docs/install.md) ---------------

namespace {

/// The commands of cli/commands.def, read from the file.
std::vector<std::string> table_commands() {
  std::vector<std::string> out;
  std::istringstream in(slurp(fs::path(FIVEBAR_SOURCE_DIR) / "cli" / "commands.def"));
  const std::regex line(R"(^FIVEBAR_COMMAND\((\w+)\))");
  for (std::string l; std::getline(in, l);) {
    std::smatch m;
    if (std::regex_search(l, m, line)) out.push_back(m[1]);
  }
  return out;
}

/// The long options a help text lists, one per option line ("  -t,--theta FLOAT ..."), in order.
std::vector<std::string> long_options(const std::string& help) {
  std::vector<std::string> out;
  const std::regex option(R"(^\s+(?:-[A-Za-z0-9],)?(--[a-z][a-z0-9-]*))");
  std::istringstream in(help);
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (std::regex_search(line, m, option)) out.push_back(m[1]);
  }
  return out;
}

}  // namespace

TEST_F(Cli, HelpCommandEqualsTheHelpFlagOfEveryCommand) {
  const std::vector<std::string> commands = table_commands();
  ASSERT_GE(commands.size(), 10u);
  for (const std::string& cmd : commands) {
    const Outcome via_help = run({"help", cmd});
    const Outcome via_flag = run({cmd, "--help"});
    EXPECT_EQ(via_help.code, 0) << cmd;
    EXPECT_EQ(via_help.out, via_flag.out) << cmd;
  }
  EXPECT_EQ(run({"help", "report", "accuracy"}).out, run({"report", "accuracy", "--help"}).out);
  EXPECT_EQ(run({"help"}).out, run({"--help"}).out);
  const Outcome unknown = run({"help", "fkk"});
  EXPECT_EQ(unknown.code, 2);
  EXPECT_THAT(unknown.err, HasSubstr("fivebar help: error: unknown subcommand 'fkk' (did you mean 'fk'?)"));
}

TEST_F(Cli, ShortVersionFlagPrintsTheVersionOfCMakeLists) {
  const std::string cmake = slurp(fs::path(FIVEBAR_SOURCE_DIR) / "CMakeLists.txt");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(cmake, m, std::regex(R"(project\(fivebar VERSION ([0-9.]+))")));
  const Outcome v = run({"-V"});
  EXPECT_EQ(v.code, 0);
  EXPECT_EQ(v.out, "fivebar " + m[1].str() + "\n");
  EXPECT_EQ(run({"--version"}).out, v.out);
}

TEST_F(Cli, UnknownOptionsAndSubcommandsNameTheNearestOne) {
  const Outcome option = run({"fk", kDesign, "--thetta", "100,80"});
  EXPECT_EQ(option.code, 2);
  EXPECT_THAT(option.out, IsEmpty());
  EXPECT_THAT(option.err, HasSubstr("fivebar fk: error: unknown option '--thetta' (did you mean '--theta'?)\n"));
  EXPECT_THAT(option.err, HasSubstr("'fivebar help fk'"));
  const Outcome nested = run({"report", "accuracy", kDesign, "--jsn"});
  EXPECT_EQ(nested.code, 2);
  EXPECT_THAT(nested.err, HasSubstr("fivebar report accuracy: error: unknown option '--jsn' (did you mean '--json'?)"));
  const Outcome far = run({"fk", kDesign, "--zzzzzzzzzz"});
  EXPECT_EQ(far.code, 2);
  EXPECT_THAT(far.err, HasSubstr("fivebar fk: error: unknown option '--zzzzzzzzzz'\n"));
  const Outcome sub = run({"simulat", kDesign});
  EXPECT_EQ(sub.code, 2);
  EXPECT_THAT(sub.err, HasSubstr("unknown subcommand 'simulat' (did you mean 'simulate'?)"));
  // Other parse errors carry the same prefix.
  const Outcome missing = run({"fk"});
  EXPECT_EQ(missing.code, 2);
  EXPECT_THAT(missing.err, HasSubstr("fivebar fk: error: "));
  EXPECT_TRUE(tree(dir_).empty()) << "usage errors write nothing";
}

TEST_F(Cli, CompletionAndManPagesListEveryOptionTheHelpLists) {
  const Outcome bash = run({"help", "--completion", "bash"});
  const Outcome zsh = run({"help", "--completion", "zsh"});
  ASSERT_EQ(bash.code, 0);
  ASSERT_EQ(zsh.code, 0);
  EXPECT_THAT(bash.out, HasSubstr("complete -o default -F _fivebar fivebar"));
  EXPECT_THAT(zsh.out, ::testing::StartsWith("#compdef fivebar\n"));
  for (const std::string& cmd : table_commands()) {
    SCOPED_TRACE(cmd);
    const std::string help = run({cmd, "--help"}).out;
    // bash: the command's case line holds each of its options.
    const std::size_t at = bash.out.find("    \"" + cmd + "\") opts=\"");
    ASSERT_NE(at, std::string::npos);
    const std::string line = bash.out.substr(at, bash.out.find('\n', at) - at);
    const Outcome man = run({"help", "--man", cmd});
    EXPECT_EQ(man.code, 0);
    std::string upper = cmd;
    std::transform(upper.begin(), upper.end(), upper.begin(), [](unsigned char c) { return char(std::toupper(c)); });
    EXPECT_THAT(man.out, HasSubstr(".TH FIVEBAR\\-" + upper + " 1 "));
    for (const std::string& option : long_options(help)) {
      if (option == "--help") continue;
      EXPECT_THAT(line, HasSubstr(" " + option)) << option;
      EXPECT_THAT(zsh.out, HasSubstr("'" + option + "[")) << option;
      std::string escaped;
      for (const char c : option) escaped += c == '-' ? std::string("\\-") : std::string(1, c);
      EXPECT_THAT(man.out, HasSubstr(escaped)) << option;
    }
  }
  EXPECT_EQ(run({"help", "--completion", "fish"}).code, 2);
  EXPECT_EQ(run({"help", "--man", "nope"}).code, 2);
}
