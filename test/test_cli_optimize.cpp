// End-to-end tests of `fivebar optimize` on the real binary: the showcase's optimize: section with a
// small budget (JSON, files, the chosen design re-checked and runnable), shards merged, resume,
// and bad input (exit 2, nothing written).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cstdlib>

#include "cli_test.hpp"
#include "fivebar/sweep.hpp"

namespace {
namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using nlohmann::json;
using ::testing::HasSubstr;

class CliOptimize : public ft::CliTest {
 protected:
  CliOptimize() : CliTest("fivebar_test_cli_optimize") {}
  std::vector<std::string> args(const fs::path& out, std::vector<std::string> more = {}) {
    std::vector<std::string> a{"optimize", kDesign, "--out", out.string(), "--evaluations", "200", "--json"};
    a.insert(a.end(), more.begin(), more.end());
    return a;
  }
};

TEST_F(CliOptimize, JsonFilesAndTheChosenDesign) {
  const Outcome r = run(args(dir_ / "a"));
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = parse(r);
  EXPECT_EQ(j["command"], "optimize");
  EXPECT_EQ(j["design"], "iros2022");
  EXPECT_LE(j["evaluations"].get<int>(), 200);
  EXPECT_EQ(j["stages"]["evaluated"], j["evaluations"]);
  ASSERT_FALSE(j["front"].empty());
  ASSERT_TRUE(j["chosen"].is_object());
  EXPECT_EQ(j["chosen"]["verdict"], "feasible");
  for (const json& c : j["recheck"]) EXPECT_TRUE(c["passed"].get<bool>()) << c.dump();
  EXPECT_EQ(j["recheck"].size(), 3u);  // coverage, collision, pattern
  for (const char* f : {"front.csv", "front.json", "candidates.csv", "chosen.yaml", "hypervolume.svg", "hypervolume.png",
                        "front.svg", "front.png", "checkpoint.json", "iros2022-optimized/summary.md"}) {
    EXPECT_TRUE(fs::exists(dir_ / "a" / f)) << f;
  }
  // The chosen design runs unchanged.
  const Outcome again = run({"run", (dir_ / "a" / "chosen.yaml").string(), "--out", (dir_ / "runs").string(),
                             "--products", "coverage"});
  EXPECT_EQ(again.code, 0) << again.err;
  EXPECT_EQ(j["atlases"].size(), 1u);
  for (const char* f : {"atlas-index.svg", "atlas-index.vti", "atlas-index.csv"}) EXPECT_TRUE(fs::exists(dir_ / "a" / f)) << f;
  // Same seed, same front.
  const Outcome r2 = run(args(dir_ / "b", {"--no-atlas"}));
  ASSERT_EQ(r2.code, 0);
  EXPECT_EQ(ft::slurp(dir_ / "a" / "front.csv"), ft::slurp(dir_ / "b" / "front.csv"));
}

TEST_F(CliOptimize, ShardsAndMerge) {
  for (const char* k : {"0/2", "1/2"}) {
    const Outcome r = run(args(dir_ / "s", {"--shard", k, "--no-plots", "--no-atlas"}));
    ASSERT_EQ(r.code, 0) << r.err;
  }
  const Outcome m = run(args(dir_ / "s", {"--merge", "2", "--no-check", "--no-atlas"}));
  ASSERT_EQ(m.code, 0) << m.err;
  const json j = parse(m);
  EXPECT_FALSE(j["front"].empty());
  EXPECT_TRUE(fs::exists(dir_ / "s" / "chosen.yaml"));
  const Outcome missing = run(args(dir_ / "s", {"--merge", "3"}));
  EXPECT_EQ(missing.code, 2);
  EXPECT_THAT(missing.err, HasSubstr("front.shard-0-of-3.json"));
}

TEST_F(CliOptimize, MpiRunEqualsTheMergedShards) {
  if (!fivebar::built_with_mpi()) GTEST_SKIP() << "built without MPI (FIVEBAR_WITH_MPI=OFF)";
  if (std::system("command -v mpirun > /dev/null 2>&1") != 0) GTEST_SKIP() << "mpirun not installed";
  for (const char* k : {"0/2", "1/2"}) ASSERT_EQ(run(args(dir_ / "s", {"--shard", k, "--no-plots", "--no-atlas"})).code, 0);
  ASSERT_EQ(run(args(dir_ / "s", {"--merge", "2", "--no-check", "--no-plots", "--no-atlas"})).code, 0);
  std::vector<std::string> a{"--allow-run-as-root", "--oversubscribe", "-n", "2", FIVEBAR_BINARY};
  const auto mine = args(dir_ / "mpi", {"--no-check", "--no-plots", "--no-atlas"});
  a.insert(a.end(), mine.begin(), mine.end());
  ft::Child mpi = ft::spawn("mpirun", a, dir_, dir_);
  ASSERT_GT(mpi.pid, 0);
  const Outcome r = ft::wait(mpi, ft::child_timeout_s(600.0));
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);  // one document: only rank 0 prints
  EXPECT_TRUE(j["mpi"].get<bool>());
  EXPECT_EQ(ft::slurp(dir_ / "mpi" / "front.csv"), ft::slurp(dir_ / "s" / "front.csv"));
  EXPECT_EQ(ft::slurp(dir_ / "mpi" / "candidates.csv"), ft::slurp(dir_ / "s" / "candidates.csv"));
}

TEST_F(CliOptimize, BadInputExitsTwoAndWritesNothing) {
  struct Case {
    std::vector<ft::Edit> edits;
    std::string message;
  };
  const std::vector<Case> cases{
      {{{"        - stations.index.mechanisms.lower.links[2]\n", "        - stations.index.mechanisms.lower.lengths[2]\n"}},
       "optimize.variables.lower_L34.keys[0]"},
      {{{"      range: [8, 17]\n    upper_O1x:", "      range: [17, 8]\n    upper_O1x:"}}, "optimize.variables.lower_O2x.range"},
      {{{"  objectives: [margin, min_lci, min footprint]", "  objectives: []"}}, "optimize.objectives"},
      {{{"  objectives: [margin, min_lci, min footprint]", "  objectives: [margin, speed]"}}, "optimize.objectives[1]"},
      {{{"constraints: [\"min_lci >= 0.25\"", "constraints: [\"min_lci >= lots\""}}, "optimize.constraints[0]"},
  };
  int i = 0;
  for (const Case& c : cases) {
    const fs::path design = design_with("bad" + std::to_string(i++) + ".yaml", c.edits);
    const Outcome r = run({"optimize", design.string(), "--out", (dir_ / "never").string()});
    EXPECT_EQ(r.code, 2) << c.message << "\n" << r.err;
    EXPECT_THAT(r.err, HasSubstr(c.message));
    EXPECT_THAT(r.err, HasSubstr(".yaml:"));  // file and line
    EXPECT_FALSE(fs::exists(dir_ / "never")) << c.message;
  }
  // A constraint on a figure whose data the design lacks (no tolerance: for robust).
  const fs::path no_tol = design_without("no_tolerance.yaml", "tolerance:", "sweep:");
  const Outcome r = run({"optimize", no_tol.string(), "--out", (dir_ / "never").string()});
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("optimize.constraints[1]"));
  EXPECT_FALSE(fs::exists(dir_ / "never"));
  // Nothing to resume from.
  const Outcome resume = run({"optimize", kDesign, "--out", (dir_ / "empty").string(), "--resume"});
  EXPECT_EQ(resume.code, 2) << resume.err;
  EXPECT_THAT(resume.err, HasSubstr("no checkpoint"));
}

}  // namespace
