// End-to-end tests of `fivebar simulate`: the time series closes the paper's loops (test/cli_geometry.hpp,
// written independently of the library), the step reference moves by the step, the summary agrees with
// the series, bad input is exit 2 with nothing written.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
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

using namespace ::fivebar::testing::paper;  // test/cli_geometry.hpp

class CliSimulate : public ft::CliTest {
 protected:
  CliSimulate() : CliTest("fivebar_test_cli_simulate") {}
};

constexpr const char* kHeader =
    "t_s,mechanism,theta1_ref_deg,theta2_ref_deg,theta1_deg,theta2_deg,w1_deg_s,w2_deg_s,i1_A,i2_A,duty1,duty2,"
    "x_ref_mm,y_ref_mm,x_mm,y_mm,fx_N,fy_N,slipping";

TEST_F(CliSimulate, StretchOnTheIndexTracksAndItsSeriesClosesThePaperLoops) {
  const fs::path out = dir_ / "sim";
  const Outcome r = run({"simulate", kDesign, "--station", "index", "--pattern", "stretch", "--no-render", "--json",
                         "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const json doc = parse(r);
  ASSERT_EQ(doc["runs"].size(), 1u);
  const json& run0 = doc["runs"][0];
  EXPECT_EQ(run0["status"], "ok");
  EXPECT_EQ(run0["reference"], "stretch");
  EXPECT_EQ(ft::record(doc["mass"], "mechanism", "lower")["source"], "closed_form");
  // The picture beside the series: paths on the fingertip, currents and forces over time.
  const std::string svg = slurp(out / "index-stretch.svg");
  EXPECT_THAT(svg, HasSubstr("<svg"));
  EXPECT_GT(fs::file_size(out / "index-stretch.png"), 10000u);
  EXPECT_EQ(run0["picture"], (out / "index-stretch.svg").generic_string());
  const std::string text = slurp(out / "index-stretch.csv");
  const auto rows = parse_csv(text);
  ASSERT_GT(rows.size(), 3u);
  EXPECT_EQ(text.substr(0, text.find('\n')), kHeader);
  // 1 s of pattern at 100 Hz plus 0.2 s to settle: 121 samples, two rows each.
  EXPECT_EQ(rows.size() - 1, 2u * 121u);
  double worst_loop = 0.0, max_error = 0.0, peak_current = 0.0;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto& c = rows[i];
    const Linkage& m = c[1] == "lower" ? kIndexLower : kIndexUpper;
    const P2 P{std::stod(c[14]), std::stod(c[15])};
    const P2 A1 = elbow(m.O1, m.L[0], std::stod(c[4]));
    const P2 A2 = elbow(m.O2, m.L[1], std::stod(c[5]));
    worst_loop = std::max({worst_loop, std::abs(dist(A1, P) - m.L[2]), std::abs(dist(A2, P) - m.L[3])});
    max_error = std::max(max_error, std::hypot(P[0] - std::stod(c[12]), P[1] - std::stod(c[13])));
    peak_current = std::max({peak_current, std::abs(std::stod(c[8])), std::abs(std::stod(c[9]))});
  }
  EXPECT_LT(worst_loop, 1e-9);
  // The summary's error is the same maximum over these samples; the current peak is taken at every
  // integrator step, so at least the samples' peak.
  double summary_error = 0.0, summary_current = 0.0;
  for (const json& m : run0["mechanisms"]) {
    summary_error = std::max(summary_error, m["max_error_mm"].get<double>());
    summary_current = std::max(summary_current, m["peak_current_A"].get<double>());
  }
  EXPECT_NEAR(summary_error, max_error, 1e-9);
  EXPECT_GE(summary_current, peak_current);
  // The reference ends 3 mm apart from the start (stretch amplitude) and the tactors follow it.
  EXPECT_LT(max_error, 1.0);
}

TEST_F(CliSimulate, StepMovesTheReferenceByOneMillimetreAndPrintsTheSummary) {
  const fs::path out = dir_ / "step";
  const Outcome r = run({"simulate", kDesign, "-s", "index", "--step", "--no-render", "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, AllOf(HasSubstr("index  step: ok"), HasSubstr("lower: tracking error max"),
                           HasSubstr("mass properties index/lower: closed form")));
  const auto rows = parse_csv(slurp(out / "index-step.csv"));
  ASSERT_GT(rows.size(), 5u);
  // Rows 1, 2 are t = 0 (lower, upper), rows 3, 4 are t = 0.01 s.
  for (std::size_t k = 0; k < 2; ++k) {
    EXPECT_NEAR(std::stod(rows[3 + k][12]) - std::stod(rows[1 + k][12]), 1.0, 1e-12);
    EXPECT_NEAR(std::stod(rows[3 + k][13]) - std::stod(rows[1 + k][13]), 0.0, 1e-12);
  }
  // Before the step nothing moves: the first duty is the PID's answer to the ADC's rounding only.
  EXPECT_LT(std::abs(std::stod(rows[3][10])), 1e-2);
}

TEST_F(CliSimulate, ExplicitIntegratorAndSwitchedPwmWithTheDenseOutput) {
  // The step under ARKODE's explicit RK and the 1 kHz switched PWM; the dense CSV every 0.1 ms
  // sees the PWM ripple the 100 Hz series cannot: the current changes within each 10 ms sample.
  const fs::path out = dir_ / "erk";
  const Outcome r = run({"simulate", kDesign, "-s", "index", "--step", "--no-render", "--integrator", "erk", "--pwm",
                         "switched", "--dense", "1e-4", "--json", "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const json doc = parse(r);
  EXPECT_EQ(doc["pwm"], "switched");
  EXPECT_THAT(doc["integrator"].get<std::string>(), HasSubstr("ARKODE"));
  ASSERT_EQ(doc["runs"][0]["status"], "ok");
  const std::string text = slurp(out / "index-step-dense.csv");
  EXPECT_EQ(text.substr(0, text.find('\n')), kHeader);
  const auto rows = parse_csv(text);
  // 0.7 s (0.5 s held + 0.2 s settling) every 0.1 ms: 7001 instants, two rows each.
  ASSERT_EQ(rows.size() - 1, 2u * 7001u);
  // The step is read at t = 0.01 s and its duty applied a period later: within (0.02, 0.03) s the
  // lower joint 1's current ripples.
  double lo = 1e9, hi = -1e9;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const double t = std::stod(rows[i][0]);
    if (rows[i][1] != "lower" || t <= 0.0205 || t >= 0.0295) continue;
    lo = std::min(lo, std::stod(rows[i][8]));
    hi = std::max(hi, std::stod(rows[i][8]));
  }
  EXPECT_GT(hi - lo, 0.1);  // A: the ripple of a 100 us winding under a 1 ms square wave
}

TEST_F(CliSimulate, ChirpGivesTheBodeMagnitudeAndBandwidth) {
  // The hand-set gains (the showcase's tuned controller.stations scopes taken out): their -3 dB
  // bandwidth (~10.5 Hz) lies inside the chirp's band; the tuned gains' lies beyond it.
  std::string text = slurp(kDesign);
  const auto tuned = text.find("  stations:\n    index:\n      lower: {pid:");
  ASSERT_NE(tuned, std::string::npos);
  text.erase(tuned, text.find("\n\n", tuned) + 1 - tuned);
  const fs::path design = dir_ / "hand-set.yaml";
  std::ofstream(design) << text;
  const fs::path out = dir_ / "chirp";
  const Outcome r = run({"simulate", design.string(), "-s", "index", "--chirp", "--no-render", "--json", "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const json doc = parse(r);
  const json& run0 = doc["runs"][0];
  EXPECT_EQ(run0["reference"], "chirp");
  ASSERT_EQ(run0["status"], "ok");
  // One record per mechanism (docs/reliability.md: never an object keyed by the mechanisms' names).
  ASSERT_TRUE(run0["bandwidth"].is_array());
  ASSERT_EQ(run0["bandwidth"].size(), 2u);
  EXPECT_FALSE(run0.contains("bandwidth_hz"));
  for (const char* m : {"lower", "upper"}) {
    const json* rec = nullptr;
    for (const json& b : run0["bandwidth"]) {
      if (b["mechanism"] == m) rec = &b;
    }
    ASSERT_NE(rec, nullptr) << m;
    ASSERT_TRUE((*rec)["bandwidth_hz"].is_number()) << m;
    const double bw = (*rec)["bandwidth_hz"].get<double>();
    EXPECT_GT(bw, 0.62);  // within the estimated band
    EXPECT_LT(bw, 20.0);
  }
  const auto rows = parse_csv(slurp(out / "index-chirp-bode.csv"));
  ASSERT_EQ(rows.size(), 41u);
  EXPECT_EQ(rows[0][0], "f_hz");
  // At the lowest frequency the tactor follows its command (within 10 %).
  EXPECT_NEAR(std::stod(rows[1][1]), 1.0, 0.1);
  EXPECT_TRUE(fs::exists(out / "index-chirp-bode.svg"));
  EXPECT_TRUE(fs::exists(out / "index-chirp-bode.png"));
  // --chirp excludes --step and --pattern.
  EXPECT_EQ(run({"simulate", kDesign, "--chirp", "--step", "--no-render", "--out", (dir_ / "never").string()}).code, 2);
}

TEST_F(CliSimulate, MassesFromTheRenderedParts) {
  const fs::path design = design_with("fn24.yaml", "fn: 96", "fn: 24");
  const fs::path out = dir_ / "stl";
  const Outcome r = run({"simulate", design.string(), "-s", "index", "--pattern", "twist", "--json", "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const json doc = parse(r);
  EXPECT_EQ(ft::record(doc["mass"], "mechanism", "upper")["source"], "stl");
  EXPECT_TRUE(fs::exists(out / "parts" / "index" / "proximal_link_9mm.stl"));
  EXPECT_EQ(doc["runs"][0]["status"], "ok");
}

TEST_F(CliSimulate, BadInputIsExitTwoAndWritesNothing) {
  const fs::path out = dir_ / "never";
  // No motor: section.
  const fs::path no_motor = design_without("no_motor.yaml", "motor:\n", "# The fingertip under each tactor");
  Outcome r = run({"simulate", no_motor.string(), "--no-render", "--out", out.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("no_motor.yaml"), HasSubstr("`motor:`")));
  // A bad value: file, line, key.
  const fs::path bad = design_with("bad.yaml", "  supply_voltage_V: 6 ", "  supply_voltage_V: -6 ");
  r = run({"simulate", bad.string(), "--no-render", "--out", out.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, AllOf(HasSubstr("bad.yaml:"), HasSubstr("motor.supply_voltage_V = -6")));
  // Flags.
  r = run({"simulate", kDesign, "--step", "--pattern", "slip", "--out", out.string()});
  EXPECT_EQ(r.code, 2);
  r = run({"simulate", kDesign, "--pattern", "wobble", "--no-render", "--out", out.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("wobble"));
  r = run({"simulate", kDesign, "--rtol", "0", "--no-render", "--out", out.string()});
  EXPECT_EQ(r.code, 2);
  r = run({"simulate", kDesign, "--integrator", "euler", "--no-render", "--out", out.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--integrator 'euler'"));
  r = run({"simulate", kDesign, "--pwm", "pulsed", "--no-render", "--out", out.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.err, HasSubstr("--pwm 'pulsed'"));
  r = run({"simulate", kDesign, "--dense", "0", "--no-render", "--out", out.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
