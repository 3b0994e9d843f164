// End-to-end tests of `fivebar control`: real processes, stdout, stderr, exit codes and files. The
// expected relations are independent of the library's arithmetic: the index station is mirror
// symmetric about y = 15.5 (so both mechanisms get the same figures, the worst poses mirrored), the
// verdict flips where the reported kp margin says it does (a design whose kp is scaled past it
// exits 1, below it exits 0), and a design without the motors' data is bad input naming the file.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include "cli_test.hpp"

namespace ft = fivebar::testing;
using ft::Outcome;
using nlohmann::json;
using ::testing::HasSubstr;

namespace {

/// Index gains the tuning improves on within kEvaluations evaluations per mechanism (the showcase's
/// tuned ki and kd, kp 5.5 instead of 6.4: every floor met, the tracking worse).
const std::string kSpoilt = "{kp: 5.5, ki: 62.45, kd: 0.1132}";
const std::string kEvaluations = "10";

class CliControl : public ft::CliTest {
 protected:
  CliControl() : CliTest("fivebar_test_cli_control") {}
};

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST_F(CliControl, JsonFilesAndMirrorSymmetryOfTheIndexStation) {
  // The showcase's tuned gains differ a little between the two mechanisms (the optimiser's path
  // follows rounding); the mirror image needs the same gains on both: the lower one's.
  std::string text = read_text(kDesign);
  const std::string lower = "    index:\n      lower: ";
  const std::size_t at = text.find(lower);
  ASSERT_NE(at, std::string::npos);
  const std::size_t from = at + lower.size();
  const std::string gains = text.substr(from, text.find('\n', from) - from);
  const std::size_t up_at = text.find("      upper: ", from);
  ASSERT_NE(up_at, std::string::npos);
  text.replace(up_at + 13, text.find('\n', up_at) - (up_at + 13), gains);
  const std::filesystem::path design = dir_ / "mirror.yaml";
  std::ofstream(design) << text;
  const std::string out = (dir_ / "control").string();
  const Outcome r = run({"control", design.string(), "-s", "index", "--grid", "21", "--field", "31", "--out", out, "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = parse(r);
  ASSERT_EQ(j["stations"].size(), 1u);
  const json& st = j["stations"][0];
  EXPECT_EQ(st["station"], "index");
  EXPECT_TRUE(st["stable"].get<bool>());
  ASSERT_EQ(st["mechanisms"].size(), 2u);
  const json& lo = st["mechanisms"][0];
  const json& up = st["mechanisms"][1];
  EXPECT_EQ(lo["mechanism"], "lower");
  EXPECT_EQ(up["mechanism"], "upper");
  for (const char* key : {"max_rho", "kp_margin", "kd_margin", "oscillatory_damping", "oscillatory_frequency_hz"}) {
    SCOPED_TRACE(key);
    EXPECT_NEAR(lo[key].get<double>(), up[key].get<double>(), 1e-6 * std::abs(lo[key].get<double>()) + 1e-9);
  }
  EXPECT_LT(lo["max_rho"].get<double>(), 1.0);
  EXPECT_GT(lo["kp_margin"].get<double>(), 1.0);
  EXPECT_NEAR(lo["worst_pose_mm"][0].get<double>(), up["worst_pose_mm"][0].get<double>(), 1e-9);
  EXPECT_NEAR(lo["worst_pose_mm"][1].get<double>() + up["worst_pose_mm"][1].get<double>(), 31.0, 1e-9);
  for (const char* f : {"index-stability.svg", "index-stability.png", "index-lower-rho.vti", "index-upper-rho.vti",
                        "index-stability.csv", "index-performance.csv"}) {
    SCOPED_TRACE(f);
    EXPECT_TRUE(std::filesystem::is_regular_file(std::filesystem::path(out) / f));
  }
  const std::string vti = read_text(std::filesystem::path(out) / "index-lower-rho.vti");
  EXPECT_THAT(vti, HasSubstr("<ImageData"));
  EXPECT_THAT(vti, HasSubstr("Name=\"rho\""));
  const std::string csv = read_text(std::filesystem::path(out) / "index-stability.csv");
  EXPECT_EQ(csv.substr(0, csv.find('\n')), "station,mechanism,x_mm,y_mm,status,rho,damping,frequency_hz");
  const std::string perf = read_text(std::filesystem::path(out) / "index-performance.csv");
  EXPECT_EQ(perf.substr(0, perf.find('\n')),
            "station,mechanism,x_mm,y_mm,status,bandwidth_hz,resolution_um_per_count,force_every_direction_N,"
            "tactor_damping_N_s_per_mm,zwidth_N_per_mm,coulomb_friction_N,position_quantum_um,"
            "zwidth_quantisation_N_per_mm,zwidth_abbott_okamura_N_per_mm,loop_rate_for_target_hz");
  const json& pl = st["performance"][0];
  const json& pu = st["performance"][1];
  for (const char* key : {"min_bandwidth_hz", "max_resolution_um_per_count", "min_force_every_direction_N",
                          "min_zwidth_N_per_mm", "min_zwidth_abbott_okamura_N_per_mm", "loop_rate_for_target_hz"}) {
    SCOPED_TRACE(key);
    EXPECT_GT(pl[key].get<double>(), 0.0);
    EXPECT_NEAR(pl[key].get<double>(), pu[key].get<double>(), 1e-6 * pl[key].get<double>());
  }
}

TEST_F(CliControl, TheVerdictFlipsAtTheReportedKpMargin) {
  const Outcome base = run({"control", kDesign, "-s", "index", "--grid", "11", "--field", "5", "--out",
                            (dir_ / "a").string(), "--json"});
  ASSERT_EQ(base.code, 0) << base.err;
  const double margin = parse(base)["stations"][0]["mechanisms"][0]["kp_margin"].get<double>();
  ASSERT_GT(margin, 1.0);
  // The index station's lower mechanism runs the gains of its own scope (the tuned ones): scale its kp.
  std::string text = read_text(kDesign);
  const std::string pid = "    index:\n      lower: {pid: {kp: ";
  const std::size_t at = text.find(pid);
  ASSERT_NE(at, std::string::npos);
  const std::size_t from = at + pid.size();
  const std::size_t to = text.find(',', from);
  const double kp0 = std::stod(text.substr(from, to - from));
  for (const double factor : {0.97, 1.03}) {
    SCOPED_TRACE(factor);
    std::ostringstream kp;
    kp.precision(17);
    kp << kp0 * margin * factor;
    std::string scaled = text;
    scaled.replace(from, to - from, kp.str());
    const std::filesystem::path design = dir_ / "scaled.yaml";
    std::ofstream(design) << scaled;
    const Outcome r = run({"control", design.string(), "-s", "index", "--grid", "11", "--field", "5", "--out",
                           (dir_ / "b").string()});
    if (factor < 1.0) {
      EXPECT_EQ(r.code, 0) << r.err;
      EXPECT_THAT(r.out, HasSubstr("index lower: stable over the target"));
    } else {
      EXPECT_EQ(r.code, 1) << r.err;
      EXPECT_THAT(r.out, HasSubstr("index lower: UNSTABLE over the target"));
      EXPECT_THAT(r.err, HasSubstr("unstable"));
    }
  }
}

TEST_F(CliControl, TuneWritesThePatchAndPrintsBeforeAndAfter) {
  const std::string out = (dir_ / "tune").string();
  const Outcome r = run({"control", kDesign, "-s", "index", "--grid", "9", "--field", "5", "--tune",
                         "--tune-evaluations", "3", "--out", out, "--json"});
  ASSERT_TRUE(r.code == 0 || r.code == 1) << r.err;  // 3 evaluations need not reach the constraint
  const json j = parse(r);
  ASSERT_EQ(j["tuning"]["mechanisms"].size(), 2u);
  bool feasible = true;
  for (const json& m : j["tuning"]["mechanisms"]) {
    EXPECT_EQ(m["station"], "index");
    EXPECT_EQ(m["evaluations"], 3);
    // Started from the design's own gains (the showcase runs an earlier tuning's, not controller.pid).
    EXPECT_NE(m["design"]["gains"]["kp"], 5.0);
    EXPECT_EQ(m["before"]["gains"], m["design"]["gains"]);
    EXPECT_EQ(m["start"]["gains"], m["design"]["gains"]);
    EXPECT_EQ(m["start"]["omega_rad_s"].get<double>(), 0.0);
    // Never worse: either the design's gains exactly, or a lower objective.
    if (m["improved"].get<bool>()) {
      EXPECT_LT(m["after"]["objective_mm"].get<double>(), m["before"]["objective_mm"].get<double>());
    } else {
      EXPECT_EQ(m["after"]["gains"], m["design"]["gains"]);
    }
    EXPECT_EQ(m["before"]["simulated_s"], m["patterns_s"]);  // the whole patterns, within the 30 s budget
    EXPECT_TRUE(m["before"]["not_computed"].empty());
    feasible = feasible && m["feasible"].get<bool>();
  }
  EXPECT_EQ(r.code, feasible ? 0 : 1);
  const std::string patch = read_text(std::filesystem::path(out) / "tuned-controller.yaml");
  EXPECT_THAT(patch, HasSubstr("controller:\n  stations:\n    index:\n      lower: {pid: {kp: "));
  const Outcome text = run({"control", kDesign, "-s", "index", "--grid", "9", "--field", "5", "--tune",
                            "--tune-evaluations", "3", "--out", out});
  EXPECT_THAT(text.out, HasSubstr("gains before"));
  EXPECT_THAT(text.out, HasSubstr("gains after"));
  EXPECT_THAT(text.out, HasSubstr("index/lower    kp 6.376, ki 62.450, kd 0.1132"));  // the design's gains
}

/// The showcase with both index mechanisms' gains replaced (`lower_pid`, `upper_pid`: the flow maps
/// written after `pid: `).
std::string with_index_gains(const std::string& text, const std::string& lower_pid, const std::string& upper_pid) {
  std::string out = text;
  for (const auto& [mech, pid] : {std::pair<std::string, std::string>{"lower", lower_pid}, {"upper", upper_pid}}) {
    const std::size_t at = out.find("      " + mech + ": {pid: {kp: 6.");
    EXPECT_NE(at, std::string::npos);
    const std::size_t from = out.find("{pid: ", at) + 6;
    out.replace(from, out.find('}', from) + 1 - from, pid);
  }
  return out;
}

/// Every number of `text` replaced by '#': what must survive a merge byte for byte.
std::string without_numbers(const std::string& text) {
  std::string out;
  for (std::size_t i = 0; i < text.size();) {
    const char c = text[i];
    const bool starts = std::isdigit(static_cast<unsigned char>(c)) ||
                        (c == '.' && i + 1 < text.size() && std::isdigit(static_cast<unsigned char>(text[i + 1])));
    if (!starts) {
      out += c;
      ++i;
      continue;
    }
    while (i < text.size() && (std::isdigit(static_cast<unsigned char>(text[i])) || text[i] == '.' || text[i] == 'e' ||
                               ((text[i] == '-' || text[i] == '+') && (text[i - 1] == 'e'))))
      ++i;
    out += '#';
  }
  return out;
}

// --merge (docs/control.md): from spoilt index gains the tuning improves; the file then differs
// only in the numbers of the two tuned mechanisms' gains, every comment and other byte kept; the
// merged design holds exactly the tuned gains, and `control --tune` on it reports as its "before"
// the figures the first run reported "after".
TEST_F(CliControl, MergeChangesOnlyTheTunedNumbersAndTheMergedDesignReportsTheTunedFigures) {
  const std::string original = with_index_gains(read_text(kDesign), kSpoilt, kSpoilt);
  const std::filesystem::path design = dir_ / "merge.yaml";
  std::ofstream(design) << original;
  const std::string out = (dir_ / "merge-out").string();
  const Outcome r = run({"control", design.string(), "-s", "index", "--grid", "9", "--field", "5", "--tune",
                         "--tune-evaluations", kEvaluations, "--merge", "--out", out, "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = parse(r);
  ASSERT_TRUE(j["merge"]["written"].get<bool>()) << j["merge"].dump();
  EXPECT_TRUE(j["merge"]["refusals"].empty());
  const std::string merged = read_text(design);
  EXPECT_NE(merged, original);
  EXPECT_EQ(without_numbers(merged), without_numbers(original));  // comments, keys, spacing: byte for byte
  // The changed lines are the two index mechanisms' gains, as the printed diff says.
  ASSERT_EQ(j["merge"]["changes"].size(), 2u);
  for (const json& c : j["merge"]["changes"]) {
    EXPECT_THAT(c["before"].get<std::string>(), HasSubstr("{pid: {kp: "));
    EXPECT_THAT(merged, HasSubstr(c["after"].get<std::string>()));
  }
  // The merged design, tuned again with a single evaluation (its own gains: kept), reports as
  // "before" the gains and figures the first run reported "after".
  const Outcome again = run({"control", design.string(), "-s", "index", "--grid", "9", "--field", "5", "--tune",
                             "--tune-evaluations", "1", "--out", out, "--json"});
  ASSERT_EQ(again.code, 0) << again.err;
  const json k = parse(again);
  for (std::size_t m = 0; m < 2; ++m) {
    const json& first = j["tuning"]["mechanisms"][m];
    const json& second = k["tuning"]["mechanisms"][m];
    SCOPED_TRACE(first["mechanism"].get<std::string>());
    EXPECT_TRUE(first["improved"].get<bool>());
    EXPECT_EQ(second["before"]["gains"], first["after"]["gains"]);
    EXPECT_EQ(second["before"]["gains_theta2"], first["after"]["gains_theta2"]);
    for (const char* figure : {"max_rho", "max_tracking_error_mm", "saturation_fraction", "min_damping", "kp_margin",
                               "kd_margin", "step_overshoot_mm", "objective_mm"}) {
      EXPECT_EQ(second["before"][figure], first["after"][figure]) << figure;
    }
    EXPECT_FALSE(second["improved"].get<bool>());
  }
}

// A merge the export gate's loop checks refuse: exit 1, the reason named, the file unchanged to the byte.
TEST_F(CliControl, ARefusedMergeLeavesTheFileUnchanged) {
  std::string text = with_index_gains(read_text(kDesign), kSpoilt, kSpoilt);
  const std::string key = "max_tracking_error_mm: 0.5";
  const std::size_t at = text.find(key);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, key.size(), "max_tracking_error_mm: 0.01");  // no gains track the patterns that well
  const std::filesystem::path design = dir_ / "refused.yaml";
  std::ofstream(design) << text;
  const Outcome r = run({"control", design.string(), "-s", "index", "--grid", "9", "--field", "5", "--tune",
                         "--tune-evaluations", "2", "--merge", "--out", (dir_ / "refused-out").string()});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_THAT(r.err, HasSubstr("refused"));
  EXPECT_THAT(r.err, HasSubstr("controller.max_tracking_error_mm 0.01"));
  EXPECT_THAT(r.out, HasSubstr("merge into "));
  EXPECT_EQ(read_text(design), text);
  // --merge without --tune is bad input, before anything is computed or written.
  const Outcome bad = run({"control", design.string(), "--merge", "--out", (dir_ / "none").string()});
  EXPECT_EQ(bad.code, 2);
  EXPECT_THAT(bad.err, HasSubstr("--merge"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "none"));
  EXPECT_EQ(read_text(design), text);
}

TEST_F(CliControl, ADesignWithoutMotorsIsBadInputAndWritesNothing) {
  std::string text = read_text(kDesign);
  const std::size_t from = text.find("\nmotor:\n");
  ASSERT_NE(from, std::string::npos);
  std::size_t to = text.find("\n\n", from + 1);
  text.erase(from + 1, to - from);
  const std::filesystem::path design = dir_ / "nomotor.yaml";
  std::ofstream(design) << text;
  const std::filesystem::path out = dir_ / "none";
  const Outcome r = run({"control", design.string(), "--out", out.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("nomotor.yaml"));
  EXPECT_THAT(r.err, HasSubstr("motor:"));
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
