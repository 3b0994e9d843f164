// Reliability under hostile use (docs/reliability.md), end to end on the real binary: outputs that
// never escape the output folder or destroy what they point at, streams that report failure,
// numbers at any magnitude (a correct status or exit 2, never a NaN or a wrong verdict), sweeps
// that cannot mix runs or start blindly, temporaries of killed runs cleaned up, and messages that
// name the right key and never echo terminal escapes. Each case reproduces a failure of an
// earlier fivebar.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_test.hpp"
#include "json_records.hpp"

namespace fivebar::testing {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

class Reliability : public CliTest {
 protected:
  Reliability() : CliTest("fivebar_test_reliability") {}

  /// The binary with its stdout redirected by the shell (`redirect`: ">/dev/full", ">&-").
  Outcome run_redirected(const std::string& redirect, const std::vector<std::string>& args) {
    std::vector<std::string> sh{"-c", "exec \"$0\" \"$@\" " + redirect, FIVEBAR_BINARY};
    sh.insert(sh.end(), args.begin(), args.end());
    return ::fivebar::testing::run("/bin/sh", sh, dir_, dir_, child_timeout_s(600.0));
  }

  fs::path points_csv() { return write("p.csv", "x_mm,y_mm\n6.25,15.5\n13.75,15.5\n"); }

  std::vector<std::string> ik_batch(const std::string& output) {
    return {"ik", kDesign, "-s", "index", "-m", "lower", "--point-file", points_csv().string(), "--output", output};
  }
};

// --- 1. --output writes through what is not a regular file ------------------------------------

TEST_F(Reliability, OutputToDevStdoutWritesThroughTheTerminalStream) {
  const Outcome r = run(ik_batch("/dev/stdout"));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("x_mm,y_mm,theta1_deg"));
  EXPECT_THAT(r.out, HasSubstr("6.25,15.5,131.3085315490517"));
}

TEST_F(Reliability, OutputToDevNullLeavesTheDeviceADevice) {
  const Outcome r = run(ik_batch("/dev/null"));
  EXPECT_EQ(r.code, 0) << r.err;
  struct stat st {};
  ASSERT_EQ(::stat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode)) << "/dev/null was replaced by a regular file";
}

TEST_F(Reliability, OutputIntoAFifoIsWrittenThroughAndTheFifoStays) {
  const fs::path fifo = dir_ / "pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] {
    std::ifstream in(fifo);
    std::stringstream ss;
    ss << in.rdbuf();
    received = ss.str();
  });
  const Outcome r = run(ik_batch(fifo.string()));
  reader.join();
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(received, HasSubstr("13.75,15.5,88.5168647976099"));
  EXPECT_TRUE(fs::is_fifo(fifo));
}

TEST_F(Reliability, OutputThroughASymlinkUpdatesItsTargetAndKeepsTheLink) {
  write("real.csv", "old\n");
  fs::create_symlink("real.csv", dir_ / "link.csv");
  const Outcome r = run(ik_batch("link.csv"));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(dir_ / "link.csv"));
  EXPECT_THAT(slurp(dir_ / "real.csv"), HasSubstr("x_mm,y_mm"));
}

// --- 2. --out cannot be escaped through a symbolic link ----------------------------------------

TEST_F(Reliability, ASymlinkInsideOutCannotCarryAWriteOutOfIt) {
  fs::create_directories(dir_ / "out");
  fs::create_directories(dir_ / "v");
  write("v/summary.md", "notes\n");
  fs::create_symlink("../v", dir_ / "out" / "iros2022");
  const Outcome r = run({"run", kDesign, "-P", "kinematics", "--out", "out"});
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_THAT(r.err, HasSubstr("outside the output directory"));
  EXPECT_EQ(slurp(dir_ / "v" / "summary.md"), "notes\n");
  EXPECT_EQ(tree(dir_ / "v"), std::vector<std::string>{"summary.md"});
}

TEST_F(Reliability, ASymlinkedFileInACommandsOutIsNotWrittenThrough) {
  fs::create_directories(dir_ / "ws");
  fs::create_directories(dir_ / "elsewhere");
  write("elsewhere/keep.svg", "keep\n");
  fs::create_symlink("../elsewhere/keep.svg", dir_ / "ws" / "index-workspace.svg");
  const Outcome r = run({"workspace", kDesign, "-s", "index", "--out", "ws"});
  EXPECT_EQ(r.code, 3) << r.err;
  EXPECT_THAT(r.err, HasSubstr("a symbolic link leads it to"));
  EXPECT_EQ(slurp(dir_ / "elsewhere" / "keep.svg"), "keep\n");
}

// --- 3. a failed write to stdout is an error ----------------------------------------------------

TEST_F(Reliability, AFullDiskOnStdoutIsExit3WithAMessage) {
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"ik", kDesign, "-s", "index", "-m", "lower", "--point", "6,15"},
        std::vector<std::string>{"coverage", kDesign, "--json"}, std::vector<std::string>{"--help"},
        std::vector<std::string>{"ik", kDesign, "-s", "index", "-m", "lower", "--point-file", points_csv().string()}}) {
    const Outcome r = run_redirected(">/dev/full", args);
    SCOPED_TRACE(args[0]);
    EXPECT_EQ(r.code, 3);
    EXPECT_THAT(r.err, HasSubstr("cannot write standard output"));
  }
}

TEST_F(Reliability, AClosedStdoutIsExit3WithAMessage) {
  const Outcome r = run_redirected(">&-", {"coverage", kDesign, "--json"});
  EXPECT_EQ(r.code, 3);
  EXPECT_THAT(r.err, HasSubstr("cannot write standard output"));
  const Outcome help = run_redirected(">&-", {"--help"});
  EXPECT_EQ(help.code, 3);
}

// --- 4. resource bounds and needle targets -------------------------------------------------------

TEST_F(Reliability, ThreadCountsBeyondTheBoundAreRefusedBeforeAnyWrite) {
  for (const char* threads : {"100000", "2147483647", "-3"}) {
    const Outcome r = run({"sweep", kDesign, "--threads", threads, "--out", "s"});
    EXPECT_EQ(r.code, 2) << threads << ": " << r.err;
  }
  const Outcome env = run_with_env({"sweep", kDesign, "--out", "s"}, {"OMP_NUM_THREADS=100000"});
  EXPECT_EQ(env.code, 2) << env.err;
  EXPECT_THAT(env.err, HasSubstr("OMP_NUM_THREADS"));
  EXPECT_FALSE(fs::exists(dir_ / "s"));
}

TEST_F(Reliability, NeedleEllipsesGiveAVerdictOrExit2NeverACrash) {
  struct Case {
    const char* ellipse;
    int code;
  };
  for (const Case& c : {Case{"6.25,15.5,1e-20,100,0", 2}, Case{"6.25,15.5,1e-300,1e12,0", 2},
                        Case{"6.25,15.5,1e-9,1,0", 0}, Case{"6.25,15.5,1,1e-9,33", 0},
                        Case{"6.25,15.5,1e-9,1e12,0", 1}}) {
    const Outcome r = run({"coverage", kDesign, "-s", "index", "--ellipse", c.ellipse, "--json"});
    SCOPED_TRACE(c.ellipse);
    EXPECT_EQ(r.signal, 0);
    EXPECT_EQ(r.code, c.code) << r.err;
    EXPECT_THAT(r.out, Not(HasSubstr("nan")));
  }
}

// --- 5 and 6. magnitudes: one range for files and flags; scale-free answers inside it -----------

TEST_F(Reliability, FarPointsAreBadInputNotSingularPoses) {
  const Outcome ik = run({"ik", kDesign, "-s", "index", "-m", "lower", "--point", "1e200,1e200"});
  EXPECT_EQ(ik.code, 2);
  EXPECT_THAT(ik.err, HasSubstr("must be within [-1e12, 1e12]"));
  EXPECT_THAT(ik.out + ik.err, Not(HasSubstr("nan")));
  const Outcome col = run({"collision", kDesign, "-s", "index", "--upper", "1e200,1e200", "--lower", "6,10"});
  EXPECT_EQ(col.code, 2);
  EXPECT_THAT(col.out, Not(HasSubstr("inf")));
  write("far.csv", "x_mm,y_mm\n6,15\n1e300,-1e300\n");
  const Outcome batch = run({"ik", kDesign, "-s", "index", "-m", "lower", "--point-file", "far.csv"});
  EXPECT_EQ(batch.code, 2);
  EXPECT_THAT(batch.err, HasSubstr("far.csv:3"));
  // At the edge of the range the answer is a status, not a number out of thin air.
  const Outcome edge = run({"ik", kDesign, "-s", "index", "-m", "lower", "--point", "1e12,-1e12"});
  EXPECT_EQ(edge.code, 1);
  EXPECT_THAT(edge.out, HasSubstr("unreachable"));
}

/// The paper's index station scaled by `s` (lengths, bases and target).
std::string scaled_design(double s) {
  auto f = [s](double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v * s);
    return std::string(buf);
  };
  return "name: scaled\nstations:\n  index:\n    target: {center: [" + f(6.25) + ", " + f(15.5) + "], axes: [" + f(15) +
         ", " + f(12) + "], angle: 0}\n    mechanisms:\n      lower: {bases: [[0, 0], [" + f(12.5) +
         ", 0]], links: [" + f(9) + ", " + f(9) + ", " + f(15) + ", " + f(15) +
         "], working_mode: \"-+\", assembly_mode: \"+\"}\n      upper: {bases: [[0, " + f(31) + "], [" + f(12.5) +
         ", " + f(31) + "]], links: [" + f(9) + ", " + f(9) + ", " + f(15) + ", " + f(15) +
         "], working_mode: \"+-\", assembly_mode: \"-\"}\n";
}

TEST_F(Reliability, EveryScaleGivesTheScaleFreeAnswerOrExit2) {
  write("unit.yaml", scaled_design(1.0));
  const Outcome unit = run({"coverage", "unit.yaml", "--json"});
  ASSERT_EQ(unit.code, 0) << unit.err;
  const auto ref = station(parse(unit), "index")["shared"];
  for (const double s : {1e-300, 1e-200, 1e-155, 1e-60, 1e-30, 1e-12, 1e-9, 1e-6, 1e-3, 1e3, 1e6, 1e10, 1e11, 1e30, 1e300}) {
    SCOPED_TRACE(s);
    write("s.yaml", scaled_design(s));
    const Outcome r = run({"coverage", "s.yaml", "--json"});
    EXPECT_EQ(r.signal, 0);
    EXPECT_THAT(r.out, Not(HasSubstr("nan")));
    const bool in_range = 9.0 * s >= 1e-9 && 31.0 * s <= 1e12;
    if (!in_range) {
      EXPECT_EQ(r.code, 2) << r.err;
      EXPECT_THAT(r.err, HasSubstr("s.yaml:"));
      continue;
    }
    ASSERT_EQ(r.code, 0) << r.err;
    const auto got = station(parse(r), "index")["shared"];
    EXPECT_EQ(got["covered"], true);
    // LCI is scale-free; the margin scales with the design.
    EXPECT_NEAR(got["min_lci"].get<double>(), ref["min_lci"].get<double>(), 1e-12);
    EXPECT_NEAR(got["margin_mm"].get<double>() / s, ref["margin_mm"].get<double>(), 1e-9 * ref["margin_mm"].get<double>());
  }
}

/// The point components of an `ik`/`fk` JSON answer.
std::vector<double> point_of(const nlohmann::json& j) { return j["point_mm"].get<std::vector<double>>(); }

TEST_F(Reliability, IkAndFkAtEveryScaleAreScaleFreeOrExit2) {
  // Reference: the unscaled station. IK angles and LCI are scale-free; FK points scale with s.
  write("unit.yaml", scaled_design(1.0));
  const Outcome ik1 = run({"ik", "unit.yaml", "-s", "index", "-m", "lower", "--point", "6.25,15.5", "--json"});
  ASSERT_EQ(ik1.code, 0) << ik1.err;
  const auto ref_ik = parse(ik1);
  const Outcome fk1 = run({"fk", "unit.yaml", "-s", "index", "-m", "lower", "--theta", "100,80", "--json"});
  ASSERT_EQ(fk1.code, 0) << fk1.err;
  const auto ref_fk = parse(fk1);
  const auto coord = [](double v) {
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return std::string(buf);
  };
  for (const double s : {1e-300, 1e-200, 1e-60, 1e-30, 1e-9, 1e-6, 1e-3, 1e3, 1e6, 1e10, 1e11, 1e30, 1e300}) {
    SCOPED_TRACE(s);
    write("s.yaml", scaled_design(s));
    const bool in_range = 9.0 * s >= 1e-9 && 31.0 * s <= 1e12;
    const std::string p = coord(6.25 * s) + "," + coord(15.5 * s);
    const Outcome ik = run({"ik", "s.yaml", "-s", "index", "-m", "lower", "--point", p, "--json"});
    const Outcome fk = run({"fk", "s.yaml", "-s", "index", "-m", "lower", "--theta", "100,80", "--json"});
    for (const Outcome* r : {&ik, &fk}) {
      EXPECT_EQ(r->signal, 0);
      EXPECT_THAT(r->out, Not(HasSubstr("nan")));
      EXPECT_THAT(r->out, Not(HasSubstr("inf")));
    }
    if (!in_range) {
      for (const Outcome* r : {&ik, &fk}) {
        EXPECT_EQ(r->code, 2) << r->err;
        EXPECT_THAT(r->err, HasSubstr("s.yaml:"));
      }
      continue;
    }
    ASSERT_EQ(ik.code, 0) << ik.err;
    const auto j = parse(ik);
    EXPECT_EQ(j["status"], "ok");
    for (int k = 0; k < 2; ++k) {
      EXPECT_NEAR(j["theta_deg"][k].get<double>(), ref_ik["theta_deg"][k].get<double>(), 1e-9);
    }
    EXPECT_NEAR(j["lci"].get<double>(), ref_ik["lci"].get<double>(), 1e-12);
    ASSERT_EQ(fk.code, 0) << fk.err;
    const auto f = parse(fk);
    EXPECT_EQ(f["status"], "ok");
    const auto got = point_of(f);
    const auto want = point_of(ref_fk);
    for (int k = 0; k < 2; ++k) EXPECT_NEAR(got[k] / s, want[k], 1e-12 * std::abs(want[k]) + 1e-12);
    EXPECT_NEAR(f["lci"].get<double>(), ref_fk["lci"].get<double>(), 1e-12);
  }
}

TEST_F(Reliability, PointsAndAnglesAtTheExtremesOfDoubleGiveAStatusOrExit2) {
  // A point at 1e-300 mm sits on the lower mechanism's first base: inside no leg's annulus
  // (|L1 - L3| = 6 mm > 0), so unreachable, exit 1.
  const Outcome tiny = run({"ik", kDesign, "-s", "index", "-m", "lower", "--point", "1e-300,-1e-300", "--json"});
  EXPECT_EQ(tiny.code, 1) << tiny.err;
  EXPECT_EQ(parse(tiny)["status"], "unreachable");
  for (const char* far : {"1e300,0", "-1e-300,1e300", "1e12,1.0000001e12"}) {
    const Outcome r = run({"ik", kDesign, "-s", "index", "-m", "lower", "--point", far});
    SCOPED_TRACE(far);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_THAT(r.out + r.err, Not(HasSubstr("nan")));
  }
  // Angles are any finite number of degrees: 1e16 deg (an exact integer, 10^16 = 280 mod 360) is
  // the pose at -80 deg, and so is 1e16 + 360 (both were poses of a rounded multiple of pi, and
  // different ones). The reduction here is independent of the code's: integer arithmetic.
  const Outcome huge = run({"fk", kDesign, "-s", "index", "-m", "lower", "--theta", "1e16,10000000000000360", "--json"});
  const char* buf = "-80,-80";
  const Outcome same = run({"fk", kDesign, "-s", "index", "-m", "lower", "--theta", buf, "--json"});
  ASSERT_EQ(huge.code, same.code) << huge.err << same.err;
  EXPECT_THAT(huge.out, Not(HasSubstr("nan")));
  const auto a = parse(huge);
  const auto b = parse(same);
  EXPECT_EQ(a["status"], b["status"]);
  if (b["status"] == "ok") {
    for (int k = 0; k < 2; ++k) EXPECT_NEAR(point_of(a)[k], point_of(b)[k], 1e-12);
  }
  EXPECT_EQ(a["status"], "ok");
  // 1e300 deg: its exact remainder, computed by the independent formula of std::fmod.
  double reduced = std::fmod(1e300, 360.0);
  if (reduced > 180.0) reduced -= 360.0;
  char text[64];
  std::snprintf(text, sizeof text, "%.17g,%.17g", reduced, -reduced);
  const Outcome far = run({"fk", kDesign, "-s", "index", "-m", "lower", "--theta", "1e300,-1e300", "--json"});
  const Outcome near = run({"fk", kDesign, "-s", "index", "-m", "lower", "--theta", text, "--json"});
  ASSERT_EQ(far.code, near.code) << far.err;
  EXPECT_EQ(parse(far)["status"], parse(near)["status"]);
  if (parse(near)["status"] == "ok") {
    for (int k = 0; k < 2; ++k) EXPECT_NEAR(point_of(parse(far))[k], point_of(parse(near))[k], 1e-12);
  }
}

// --- 7 and 8. sweeps that cannot mix runs or start blindly -------------------------------------

TEST_F(Reliability, ResumeRefusesARowOfAnotherGridAndContinuesItsOwn) {
  const std::vector<std::string> grid40{"sweep", kDesign, "--vary", "L3=11:19:40", "--vary", "L4=11:19:40", "--out", "sw"};
  ASSERT_EQ(run(grid40).code, 0);
  // Keep the first 100 rows, as an interrupted run would have.
  std::istringstream in(slurp(dir_ / "sw" / "sweep.csv"));
  std::string cut, line;
  for (int i = 0; i < 101 && std::getline(in, line); ++i) cut += line + "\n";
  write("sw/sweep.csv", cut);

  std::vector<std::string> grid41 = grid40;
  grid41[3] = "L3=11:19:41";
  grid41.push_back("--resume");
  const Outcome mixed = run(grid41);
  EXPECT_EQ(mixed.code, 2);
  EXPECT_THAT(mixed.err, HasSubstr("not the same sweep"));
  EXPECT_EQ(slurp(dir_ / "sw" / "sweep.csv"), cut);

  // The same grid under another design (a longer L1) is another sweep too.
  const fs::path other = design_with("other.yaml", "links: [9, 9, 15, 15]", "links: [9.5, 9, 15, 15]");
  std::vector<std::string> moved = grid40;
  moved[1] = other.string();
  moved.push_back("--resume");
  EXPECT_EQ(run(moved).code, 2);

  std::vector<std::string> same = grid40;
  same.push_back("--resume");
  const Outcome resumed = run(same);
  EXPECT_EQ(resumed.code, 0) << resumed.err;
  std::istringstream all(slurp(dir_ / "sw" / "sweep.csv"));
  int rows = 0;
  while (std::getline(all, line)) ++rows;
  EXPECT_EQ(rows, 1 + 40 * 40);
}

TEST_F(Reliability, AResumedRowWithOtherValuesIsRefused) {
  const std::vector<std::string> grid{"sweep", kDesign, "--vary", "L3=11:19:20", "--out", "sw"};
  ASSERT_EQ(run(grid).code, 0);
  std::string csv = slurp(dir_ / "sw" / "sweep.csv");
  const auto second_row = csv.find("\n1,") + 3;
  csv.replace(second_row, csv.find(',', second_row) - second_row, "12.5");  // not the grid's value at index 1
  write("sw/sweep.csv", csv.substr(0, csv.find("\n5,") + 1));
  std::vector<std::string> resume = grid;
  resume.push_back("--resume");
  const Outcome r = run(resume);
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("row 1 holds other swept values"));
}

TEST_F(Reliability, AnAbsurdSweepIsRefusedWithItsEstimateBeforeAnyWrite) {
  const Outcome r = run({"sweep", kDesign, "--vary", "L3=10:20:1000000", "--vary", "L4=10:20:1000000", "--out", "big"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("1e+12 designs"));
  EXPECT_THAT(r.err, HasSubstr("--yes"));
  EXPECT_FALSE(fs::exists(dir_ / "big"));
}

// --- 9. temporaries of killed runs are removed by the next run -----------------------------------

TEST_F(Reliability, TheNextRunRemovesTemporariesOfDeadProcessesOnly) {
  fs::create_directories(dir_ / "out");
  // A process id that cannot be alive (above the kernel's pid_max of 4194304), and ours, alive.
  const fs::path dead = dir_ / "out" / ".result.csv.tmp.99999999.0123456789abcdef";
  const fs::path live = dir_ / "out" / (".result.csv.tmp." + std::to_string(::getpid()) + ".0123456789abcdef");
  write("out/" + dead.filename().string(), "half a file");
  write("out/" + live.filename().string(), "being written");
  const Outcome r = run(ik_batch("out/result.csv"));
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_FALSE(fs::exists(dead));
  EXPECT_TRUE(fs::exists(live));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "result.csv"));
}

// --- 10. messages ----------------------------------------------------------------------------------

TEST_F(Reliability, AZeroSpeedLimitIsReportedAtItsOwnKeyAndLine) {
  const fs::path d = design_with("v.yaml", "max_velocity_deg_s: 360", "max_velocity_deg_s: 0");
  const Outcome r = run({"fk", d.string(), "-s", "index", "-m", "lower", "--theta", "100,80"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("controller.max_velocity_deg_s = 0"));
  std::istringstream in(slurp(d));
  std::string line;
  int n = 0, at = 0;
  while (std::getline(in, line)) {
    ++n;
    if (line.find("max_velocity_deg_s: 0") != std::string::npos) at = n;
  }
  EXPECT_THAT(r.err, HasSubstr("v.yaml:" + std::to_string(at) + ":"));
}

TEST_F(Reliability, LoneCarriageReturnsAreLineBreaks) {
  write("cr.yaml",
        "name: cr\rstations:\r  s:\r    target: {center: [5, 18], axes: [2, 2]}\r    mechanisms:\r      lower: "
        "{bases: [[0, 0], [10, 0]], links: [8, 8, 12, 12], working_mode: \"-+\"}\r");
  const Outcome r = run({"ik", "cr.yaml", "--point", "5,18"});
  EXPECT_EQ(r.code, 0) << r.err;
  write("cr-bad.yaml", "name: cr\rstations:\r  s:\r    target: {center: [5, 18], axes: [2, -2]}\r");
  const Outcome bad = run({"ik", "cr-bad.yaml", "--point", "5,18"});
  EXPECT_EQ(bad.code, 2);
  EXPECT_THAT(bad.err, HasSubstr("cr-bad.yaml:4:"));
}

TEST_F(Reliability, NamesFromTheUserNeverBringTerminalEscapes) {
  const Outcome r = run({"fk", kDesign, "-s", "\x1b[31mred", "--theta", "1,2"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, Not(HasSubstr("\x1b")));
  EXPECT_THAT(r.err, HasSubstr("\\x1b[31mred"));
  const Outcome sub = run({"\x1b]0;title\x07"});
  EXPECT_EQ(sub.code, 2);
  EXPECT_THAT(sub.err, Not(HasSubstr("\x1b")));
}

TEST_F(Reliability, AHugeWholeNumberNamesItsRange) {
  const fs::path d = design_with("fn.yaml", "fn: 96", "fn: 18446744073709551617");
  const Outcome r = run({"parts", d.string(), "--out", "p"});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("print.fn = 18446744073709551617: must be 8 ... 1024"));
}

TEST_F(Reliability, SmallAndHugeNumbersAreNotPrintedAsZeroOrAsLongIntegers) {
  const Outcome r = run({"coverage", kDesign, "-s", "index", "--ellipse", "6.25,15.5,1e-6,1,0"});
  EXPECT_THAT(r.out, HasSubstr("1e-06 x 1.000 mm"));
  const Outcome far = run({"ik", kDesign, "-s", "index", "-m", "lower", "--point", "1e308,0"});
  EXPECT_EQ(far.code, 2);
  EXPECT_THAT(far.err, HasSubstr("1e+308"));
  EXPECT_THAT(far.out + far.err, Not(HasSubstr("0000000000000000")));
}

}  // namespace
}  // namespace fivebar::testing
