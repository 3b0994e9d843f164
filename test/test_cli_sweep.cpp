// End-to-end tests of `fivebar sweep` on the real binary: JSON summary and files, bad input,
// shards concatenating to the serial CSV, SIGINT leaving a valid CSV that --resume completes to
// the uninterrupted result, and an MPI run (mpirun -n 2) equal to the serial one.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <thread>

#include "cli_test.hpp"
#include "fivebar/sweep.hpp"

namespace {

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using ft::slurp;
using nlohmann::json;
using ::testing::HasSubstr;
using ::testing::Not;

/// The paper's design and a scratch directory per test (test/cli_test.hpp); spawn() and wait_for()
/// for the runs that are interrupted or go through mpirun.
class CliSweep : public ft::CliTest {
 protected:
  CliSweep() : CliTest("fivebar_test_cli_sweep") {}

  /// Starts `program args...` (found on PATH unless it holds a '/') in dir_, stdout and stderr
  /// through files there (test/process.hpp); wait_for() collects it.
  ft::Child spawn(const std::string& program, const std::vector<std::string>& args) {
    ft::Child c = ft::spawn(program, args, dir_, dir_);
    if (c.pid <= 0) ADD_FAILURE() << "cannot spawn " << program;
    return c;
  }
  Outcome wait_for(ft::Child& c) {
    Outcome r = ft::wait(c, ft::child_timeout_s(600.0));
    if (r.timed_out) ADD_FAILURE() << "timed out: " << r.err;
    return r;
  }

  std::vector<std::string> sweep_args(const fs::path& out, const std::string& l3 = "L3=11:19:30",
                                      const std::string& l4 = "L4=11:19:30") {
    return {"sweep", kDesign, "--station", "index", "--mechanism", "lower", "--vary", l3, "--vary", l4, "--out",
            out.string(), "--no-plots"};
  }
};

TEST_F(CliSweep, JsonSummaryAndFiles) {
  auto args = sweep_args(dir_ / "a");
  args.push_back("--json");
  const Outcome r = run(args);
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);
  EXPECT_EQ(j["designs"], 900);
  EXPECT_EQ(j["rows"], 900);
  EXPECT_GT(j["covered"].get<int>(), 0);
  EXPECT_GT(j["designs_per_s"].get<double>(), 0.0);
  EXPECT_EQ(j["sample"], "grid");
  ASSERT_TRUE(j["best"].is_object());
  EXPECT_TRUE(j["best"]["covered"].get<bool>());
  EXPECT_FALSE(j["pareto"].empty());
  // One header and 900 rows; the best design file loads.
  const std::string csv = slurp(dir_ / "a" / "sweep.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 901);
  const fivebar::Design best = fivebar::load_design(dir_ / "a" / "best.yaml");
  EXPECT_EQ(best.station("index")->lower->L[2], j["best"]["values"]["L3_mm"].get<double>());
}

TEST_F(CliSweep, BadInputExitsTwoNamingTheProblemAndWritesNothing) {
  for (const auto& [vary, expect] : std::vector<std::pair<std::string, std::string>>{
           {"L3=abc", "--vary 'L3=abc'"}, {"L9=1:2:3", "vary.L9"}, {"L3=5:1:3", "vary.L3"}, {"=1:2:3", "--vary"}}) {
    const Outcome r = run({"sweep", kDesign, "--station", "index", "--vary", vary, "--out", (dir_ / "bad").string()});
    EXPECT_EQ(r.code, 2) << vary << ": " << r.err;
    EXPECT_THAT(r.err, HasSubstr(expect)) << vary;
    EXPECT_FALSE(fs::exists(dir_ / "bad")) << vary;
  }
  const Outcome shard = run({"sweep", kDesign, "--station", "index", "--vary", "L3=11:19:3", "--shard", "2/2", "--out",
                             (dir_ / "bad").string()});
  EXPECT_EQ(shard.code, 2);
  EXPECT_THAT(shard.err, HasSubstr("--shard"));
  const Outcome station = run({"sweep", kDesign, "--station", "pinky", "--vary", "L3=11:19:3", "--out",
                               (dir_ / "bad").string()});
  EXPECT_EQ(station.code, 2);
  EXPECT_THAT(station.err, HasSubstr("pinky"));
}

TEST_F(CliSweep, CollisionFractionColumnForCoveredDesigns) {
  // The showcase has geometry: each covered row carries the colliding fraction of its tactor pairs.
  const auto sweep = [&](const std::string& out, const std::string& spacing) {
    return run({"sweep", kDesign, "--station", "index", "--vary", "L34=13:19:4", "--vary", "L12=8:12:3",
                "--collision-spacing", spacing, "--out", (dir_ / out).string(), "--no-plots"});
  };
  ASSERT_EQ(sweep("on", "2.5").code, 0);
  std::istringstream csv(slurp(dir_ / "on" / "sweep.csv"));
  std::string line;
  std::getline(csv, line);
  ASSERT_TRUE(line.ends_with(",footprint_mm2,collision_fraction,robust_margin_mm")) << line;
  int covered = 0;
  while (std::getline(csv, line)) {
    // The collision fraction is the last column but one (robust_margin_mm, empty without the
    // `robust` objective, is the last).
    ASSERT_TRUE(line.ends_with(",")) << line;
    const std::string body = line.substr(0, line.size() - 1);
    const std::string last = body.substr(body.rfind(',') + 1);
    if (line.find(",covered,1,") != std::string::npos) {
      ++covered;
      const double f = std::stod(last);
      EXPECT_GT(f, 0.0) << line;
      EXPECT_LT(f, 1.0) << line;
    } else {
      EXPECT_EQ(last, "") << line;
    }
  }
  EXPECT_GT(covered, 0);
  ASSERT_EQ(sweep("off", "0").code, 0);
  const std::string off = slurp(dir_ / "off" / "sweep.csv");
  std::istringstream rows(off.substr(off.find('\n') + 1));
  while (std::getline(rows, line)) EXPECT_TRUE(line.ends_with(",,")) << line;
  const Outcome bad = sweep("bad", "-1");
  EXPECT_EQ(bad.code, 2);
  EXPECT_THAT(bad.err, HasSubstr("collision_spacing_mm"));
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
}

TEST_F(CliSweep, ShardsConcatenateToTheSerialRows) {
  ASSERT_EQ(run(sweep_args(dir_ / "serial")).code, 0);
  const std::string serial = slurp(dir_ / "serial" / "sweep.csv");
  std::string joined = serial.substr(0, serial.find('\n') + 1);
  for (int k = 0; k < 4; ++k) {
    auto args = sweep_args(dir_ / "shards");
    args.insert(args.end(), {"--shard", std::to_string(k) + "/4"});
    const Outcome r = run(args);
    ASSERT_EQ(r.code == 0 || r.code == 1, true) << r.err;  // a shard may hold no covered design
    const std::string part = slurp(dir_ / "shards" / ("sweep.shard-" + std::to_string(k) + "-of-4.csv"));
    joined += part.substr(part.find('\n') + 1);
  }
  EXPECT_EQ(joined, serial);
}

TEST_F(CliSweep, InterruptLeavesAValidCsvAndResumeCompletesIt) {
  // 160,000 designs on one thread: long enough to interrupt, and --resume then finishes.
  const std::vector<std::string> grid{"L3=11:19:400", "L4=11:19:400"};
  // Without the collision fraction (250 us per covered design; its own tests are above): this
  // grid must be long enough to interrupt, yet run twice more within the sanitizer build's timeout.
  auto args = sweep_args(dir_ / "cut", grid[0], grid[1]);
  args.insert(args.end(), {"--collision-spacing", "0", "--threads", "1"});
  ft::Child child = spawn(FIVEBAR_BINARY, args);
  ASSERT_GT(child.pid, 0);
  // Interrupt once the sweep has started: its identity file is written before the first row (a
  // fixed delay raced with a slow sanitized start, which the default SIGINT action then ended).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!fs::exists(dir_ / "cut" / "sweep.identity.json") && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  ::kill(child.pid, SIGINT);
  const Outcome cut = wait_for(child);
  if (cut.code == 0) GTEST_SKIP() << "the sweep finished before the interrupt (a very fast machine)";
  ASSERT_EQ(cut.code, 130) << cut.err;
  EXPECT_EQ(cut.signal, 0);
  EXPECT_THAT(cut.err, HasSubstr("--resume"));
  // The CSV holds complete rows with contiguous indices, and no temporary file is left.
  const fivebar::Design design = [&] {
    fivebar::Design d = fivebar::load_design(kDesign);
    d.set(fivebar::SweepSettings{});
    d.get<fivebar::SweepSettings>()->station = "index";
    d.get<fivebar::SweepSettings>()->mechanism = "lower";
    d.get<fivebar::SweepSettings>()->vary = {{"L3", 11, 19, 400}, {"L4", 11, 19, 400}};
    return d;
  }();
  std::uint64_t rows = 0;
  fivebar::read_sweep_csv(dir_ / "cut" / "sweep.csv", *design.get<fivebar::SweepSettings>(), [&](const fivebar::SweepRow& r, const std::string&) {
    EXPECT_EQ(r.index, rows);
    ++rows;
  });
  EXPECT_GT(rows, 0u);
  EXPECT_LT(rows, 160000u);
  for (const auto& e : fs::directory_iterator(dir_ / "cut")) EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos);

  auto resume = args;
  resume.push_back("--resume");
  resume.erase(resume.end() - 3, resume.end() - 1);  // drop --threads 1: every core for the rest
  const Outcome rest = run(resume);
  ASSERT_EQ(rest.code, 0) << rest.err;
  auto whole = sweep_args(dir_ / "whole", grid[0], grid[1]);
  whole.insert(whole.end(), {"--collision-spacing", "0"});
  ASSERT_EQ(run(whole).code, 0);
  EXPECT_EQ(slurp(dir_ / "cut" / "sweep.csv"), slurp(dir_ / "whole" / "sweep.csv"));
  EXPECT_EQ(slurp(dir_ / "cut" / "pareto.csv"), slurp(dir_ / "whole" / "pareto.csv"));
}

TEST_F(CliSweep, MpiRunEqualsTheSerialRun) {
  if (!fivebar::built_with_mpi()) GTEST_SKIP() << "built without MPI (FIVEBAR_WITH_MPI=OFF)";
  if (std::system("command -v mpirun > /dev/null 2>&1") != 0) GTEST_SKIP() << "mpirun not installed";
  ASSERT_EQ(run(sweep_args(dir_ / "serial")).code, 0);
  std::vector<std::string> args{"--allow-run-as-root", "--oversubscribe", "-n", "2", FIVEBAR_BINARY};
  const auto sweep = sweep_args(dir_ / "mpi");
  args.insert(args.end(), sweep.begin(), sweep.end());
  args.push_back("--json");
  ft::Child mpi = spawn("mpirun", args);
  const Outcome r = wait_for(mpi);
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = json::parse(r.out);  // one document: only rank 0 prints
  EXPECT_TRUE(j["mpi"].get<bool>());
  EXPECT_EQ(j["rows"], 900);
  EXPECT_EQ(slurp(dir_ / "mpi" / "sweep.csv"), slurp(dir_ / "serial" / "sweep.csv"));
  EXPECT_EQ(slurp(dir_ / "mpi" / "pareto.csv"), slurp(dir_ / "serial" / "pareto.csv"));
  EXPECT_FALSE(fs::exists(dir_ / "mpi" / "sweep.shard-0-of-2.csv"));
}

}  // namespace

namespace {

// docs/reliability.md "Resume": the CSV a resume reads goes through the one bounded reader. A
// sweep.csv whose second line is 2 GiB of zeros (a hole, no disk) was read into one string and,
// under a 1 GB address space, taken for the end of the file: the sweep started afresh, exit 0.
// Now it is refused at the line, exit 2, having held one bounded line.
class CliSweepResume : public ft::CliTest {
 protected:
  CliSweepResume() : CliTest("fivebar_test_cli_sweep_resume") {}
};

TEST_F(CliSweepResume, AnEndlessLineIsRefusedAtItsLine) {
  const std::vector<std::string> args{"sweep", kDesign, "--station", "index", "--mechanism", "lower", "--vary", "L3=11:19:30",
                                      "--vary", "L4=11:19:30", "--out", "s", "--no-plots"};
  ASSERT_EQ(run(args).code, 0);
  const std::string csv = ft::slurp(dir_ / "s" / "sweep.csv");
  std::ofstream(dir_ / "s" / "sweep.csv", std::ios::binary) << csv.substr(0, csv.find('\n') + 1);
  fs::resize_file(dir_ / "s" / "sweep.csv", std::uintmax_t{2} << 30);
#ifdef FIVEBAR_SANITIZE
  // AddressSanitizer reserves terabytes of address space for its shadow: under `ulimit -v` a
  // sanitized process cannot start. The memory bound is checked by the Release suite.
  std::vector<std::string> limited{"-c", "exec \"$0\" \"$@\"", FIVEBAR_BINARY};
#else
  std::vector<std::string> limited{"-c", "ulimit -v 1000000 && exec \"$0\" \"$@\"", FIVEBAR_BINARY};
#endif
  limited.insert(limited.end(), args.begin(), args.end());
  limited.push_back("--resume");
  const ft::Outcome r = ft::run("/bin/sh", limited, dir_, dir_, ft::child_timeout_s(120.0));
  EXPECT_EQ(r.code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("s/sweep.csv:2: line longer than 65536 bytes"));
  EXPECT_THAT(r.err, Not(HasSubstr("internal error")));
  EXPECT_EQ(fs::file_size(dir_ / "s" / "sweep.csv"), std::uintmax_t{2} << 30) << "the CSV is left as it was";
}

}  // namespace
