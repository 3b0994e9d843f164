// End-to-end tests of `fivebar tolerance`: real processes, stdout, stderr and exit codes. The
// expected relations are independent of the library's arithmetic: the index station is mirror
// symmetric about y = 15.5 (lower bases at y = 0, upper at y = 31, target centre at y = 15.5), the
// first-order figures scale linearly with the tolerances and the resolution with 2^-bits, zero
// tolerances give zero error, and the Monte Carlo spread agrees with the first order.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <sstream>
#include <fstream>
#include <filesystem>
#include <string>
#include <vector>

#include "cli_test.hpp"
#include "json_records.hpp"

namespace fs = std::filesystem;
namespace ft = fivebar::testing;
using ft::Outcome;
using nlohmann::json;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

namespace {

class CliTolerance : public ft::CliTest {
 protected:
  CliTolerance() : CliTest("fivebar_test_cli_tol") {}

  /// The paper's design with its tolerance: section replaced by `section`.
  fs::path design_with_tolerance(const std::string& name, const std::string& section) {
    std::string text = ft::slurp(kDesign);
    const auto a = text.find("tolerance:\n");
    const auto b = text.find("# A small link-dimension sweep", a);
    EXPECT_TRUE(a != std::string::npos && b != std::string::npos);
    if (a != std::string::npos && b != std::string::npos) text.replace(a, b - a, section + "\n");
    return write(name, text);
  }
};

TEST_F(CliTolerance, JsonShapeMirrorSymmetryAndMonteCarloAgreement) {
  const Outcome r = run({"tolerance", kDesign, "--json"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = parse(r);
  EXPECT_EQ(j["tolerance"]["source"], "design");
  EXPECT_THAT(j["tolerance"]["resolution_source"].get<std::string>(), HasSubstr("controller"));
  EXPECT_EQ(j["command"], "tolerance");
  ASSERT_EQ(ft::record_names(j["stations"], "station"), (std::vector<std::string>{"index", "thumb"}));
  const json& lo = ft::mechanism(ft::station(j, "index"), "lower");
  const json& up = ft::mechanism(ft::station(j, "index"), "upper");
  for (const char* key : {"centre_3sigma_first_order_mm", "centre_3sigma_minor_first_order_mm", "centre_worst_case_mm",
                          "centre_worst_case_first_order_mm", "centre_resolution_um", "target_worst_3sigma_first_order_mm",
                          "target_worst_case_mm", "target_worst_case_first_order_mm"}) {
    SCOPED_TRACE(key);
    EXPECT_NEAR(lo[key].get<double>(), up[key].get<double>(), 1e-9 * lo[key].get<double>());
    EXPECT_GT(lo[key].get<double>(), 0.0);
  }
  // The worst points mirror about y = 15.5.
  EXPECT_NEAR(lo["target_worst_case_at_mm"][0].get<double>(), up["target_worst_case_at_mm"][0].get<double>(), 1e-9);
  EXPECT_NEAR(lo["target_worst_case_at_mm"][1].get<double>() + up["target_worst_case_at_mm"][1].get<double>(), 31.0,
              1e-9);
  for (const char* station : {"index", "thumb"}) {
    for (const char* which : {"lower", "upper"}) {
      SCOPED_TRACE(std::string(station) + " " + which);
      const json& m = ft::mechanism(ft::station(j, station), which);
      EXPECT_EQ(m["centre_status"], "ok");
      EXPECT_EQ(m["target_points_not_ok"], 0);
      EXPECT_EQ(m["monte_carlo_samples_used"], 10000);
      // Worst case (every parameter at 3 sigma, worst sign) bounds the 3-sigma semi-axis, to first
      // order; the nonlinear corner is the headline.
      EXPECT_GE(m["centre_worst_case_first_order_mm"].get<double>(), m["centre_3sigma_first_order_mm"].get<double>());
      EXPECT_GE(m["target_worst_3sigma_first_order_mm"].get<double>(), m["centre_3sigma_first_order_mm"].get<double>());
      EXPECT_GE(m["target_worst_case_mm"].get<double>(), m["centre_worst_case_mm"].get<double>());
      // 10,000 devices: the spread's relative standard error is ~1/sqrt(2 n) = 0.7 %; the
      // tolerances (0.06 mm, 0.5 deg on 9 to 17.5 mm links) leave the first order a few per mille.
      EXPECT_NEAR(m["centre_monte_carlo_3sigma_mm"].get<double>(), m["centre_3sigma_first_order_mm"].get<double>(),
                  0.04 * m["centre_3sigma_first_order_mm"].get<double>());
    }
  }
}

TEST_F(CliTolerance, FiguresScaleWithTolerancesAndCounts) {
  // Linearity 0: the sigmas are exactly the ones given, so they double with the file's numbers.
  const auto single = design_with_tolerance("single.yaml",
                                            "tolerance:\n  link_sigma_mm: 0.05\n  pin_sigma_mm: 0.025\n"
                                            "  base_sigma_mm: 0.1\n  angle_sigma_deg: 0.5\n  adc_bits: 16\n"
                                            "  linearity_percent: 0");
  const auto doubled = design_with_tolerance("doubled.yaml",
                                             "tolerance:\n  link_sigma_mm: 0.1\n  pin_sigma_mm: 0.05\n"
                                             "  base_sigma_mm: 0.2\n  angle_sigma_deg: 1.0\n  adc_bits: 12\n"
                                             "  linearity_percent: 0");
  const Outcome base = run({"tolerance", single.string(), "--station", "thumb", "--json", "--no-files"});
  const Outcome twice = run({"tolerance", doubled.string(), "--station", "thumb", "--json", "--no-files"});
  ASSERT_EQ(base.code, 0) << base.err;
  ASSERT_EQ(twice.code, 0) << twice.err;
  const json a = parse(base);
  const json b = parse(twice);
  EXPECT_EQ(b["stations"].size(), 1u);
  for (const char* which : {"lower", "upper"}) {
    SCOPED_TRACE(which);
    const json& x = ft::mechanism(ft::station(a, "thumb"), which);
    const json& y = ft::mechanism(ft::station(b, "thumb"), which);
    // The first-order figures are linear in the sigmas (the nonlinear corners are not).
    for (const char* key : {"centre_3sigma_first_order_mm", "centre_worst_case_first_order_mm", "target_worst_3sigma_first_order_mm",
                            "target_worst_case_first_order_mm"}) {
      EXPECT_NEAR(y[key].get<double>(), 2.0 * x[key].get<double>(), 1e-9 * x[key].get<double>()) << key;
    }
    // 12 bits instead of 16: each count is 16 times the angle.
    EXPECT_NEAR(y["centre_resolution_um"].get<double>(), 16.0 * x["centre_resolution_um"].get<double>(),
                1e-9 * y["centre_resolution_um"].get<double>());
  }
}

TEST_F(CliTolerance, ZeroTolerancesGiveZeroError) {
  const auto zero = design_with_tolerance("zero.yaml",
                                          "tolerance:\n  link_sigma_mm: 0\n  pin_sigma_mm: 0\n  base_sigma_mm: 0\n"
                                          "  angle_sigma_deg: 0\n  linearity_percent: 0\n  pin_play_mm: 0\n"
                                          "  shaft_play_mm: 0\n  backlash_deg: 0");
  const Outcome r = run({"tolerance", zero.string(), "--json", "--no-files"});
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = parse(r);
  for (const json& st : j["stations"]) {
    for (const json& m : st["mechanisms"]) {
      SCOPED_TRACE(st["station"].get<std::string>() + " " + m["mechanism"].get<std::string>());
      EXPECT_EQ(m["centre_3sigma_first_order_mm"].get<double>(), 0.0);
      EXPECT_EQ(m["centre_worst_case_first_order_mm"].get<double>(), 0.0);
      EXPECT_EQ(m["target_worst_case_first_order_mm"].get<double>(), 0.0);
      // The one "corner" of no spread is the design itself: FK of its IK, to rounding.
      EXPECT_NEAR(m["centre_worst_case_mm"].get<double>(), 0.0, 1e-12);
      EXPECT_NEAR(m["target_worst_case_mm"].get<double>(), 0.0, 1e-12);
      EXPECT_EQ(m["centre_monte_carlo_3sigma_mm"].get<double>(), 0.0);
      EXPECT_GT(m["centre_resolution_um"].get<double>(), 0.0);
      EXPECT_EQ(m["centre_play_mm"].get<double>(), 0.0);
      EXPECT_EQ(m["target_worst_play_mm"].get<double>(), 0.0);
      // No spread: every printed device is the design, and the margin is the design's.
      EXPECT_EQ(m["robust_coverage"]["margin_sigma_first_order_mm"].get<double>(), 0.0);
      EXPECT_EQ(m["robust_coverage"]["robust_margin_first_order_mm"], m["robust_coverage"]["margin_mm"]);
      EXPECT_EQ(m["robust_coverage"]["fraction_monte_carlo"].get<double>(), 1.0);
    }
  }
}

TEST_F(CliTolerance, TextSaysWhereTheTolerancesComeFrom) {
  const Outcome r = run({"tolerance", kDesign, "--station", "index"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_THAT(r.out, HasSubstr("tolerances from the design"));
  EXPECT_THAT(r.out, HasSubstr("station index"));
  EXPECT_THAT(r.out, HasSubstr("worst case"));
  const auto bare = design_without("bare.yaml", "tolerance:\n", "# A small link-dimension sweep");
  {
    // The optimize: section's robust constraint needs tolerance: too.
    std::string text = ft::slurp(bare);
    const auto a = text.find("# Dimensional synthesis"), b = text.find("# Skin-deformation patterns");
    ASSERT_TRUE(a != std::string::npos && b != std::string::npos);
    text.erase(a, b - a);
    std::ofstream(bare) << text;
  }
  const Outcome d = run({"tolerance", bare.string(), "--station", "index"});
  ASSERT_EQ(d.code, 0) << d.err;
  EXPECT_THAT(d.out, HasSubstr("by default (assumptions to replace)"));
}

TEST_F(CliTolerance, BadInputIsExitTwoNamingFileLineAndKey) {
  const auto bad = design_with("bad.yaml", "  samples: 10000 ", "  adc_bits: 40\n  samples: 10000 ");
  const Outcome r = run({"tolerance", bad.string()});
  EXPECT_EQ(r.code, 2);
  EXPECT_THAT(r.out, IsEmpty());
  EXPECT_THAT(r.err, HasSubstr("bad.yaml:"));
  EXPECT_THAT(r.err, HasSubstr("tolerance.adc_bits"));
  const Outcome s = run({"tolerance", kDesign, "--station", "pinky"});
  EXPECT_EQ(s.code, 2);
  EXPECT_THAT(s.out, IsEmpty());
  EXPECT_THAT(s.err, HasSubstr("pinky"));
}

TEST_F(CliTolerance, ExportRefusesATargetThatPrintedDevicesLose) {
  // tolerance.export_gate (on in the showcase): a 17 x 14 mm index target is covered by the
  // design (0.0165 mm) but not by 99.7 % of printed devices, so export refuses, naming the
  // mechanism and the figure, and writes nothing; without the gate the same design exports.
  const fs::path out = dir_ / "exp";
  const auto big = design_with("big.yaml", "axes: [15, 12]", "axes: [17, 14]");
  const Outcome r = run({"export", big.string(), "--station", "index", "--out", out.string()});
  EXPECT_EQ(r.code, 1) << r.err;
  EXPECT_THAT(r.out + r.err, HasSubstr("robust_coverage"));
  EXPECT_THAT(r.out + r.err, HasSubstr("index/lower"));
  EXPECT_THAT(r.out + r.err, HasSubstr("printed devices lose the target"));
  EXPECT_FALSE(fs::exists(out));
  const auto off = design_with("off.yaml", {{"axes: [15, 12]", "axes: [17, 14]"}, {"export_gate: true", "export_gate: false"}});
  const Outcome ok = run({"export", off.string(), "--station", "index", "--out", out.string()});
  EXPECT_THAT(ok.out + ok.err, ::testing::Not(HasSubstr("robust_coverage")));
}

TEST_F(CliTolerance, DevicesCsvHoldsTheMonteCarlosPrintedDevices) {
  // --devices: a row per sampled device. The devices are the Monte Carlo's (same seed and draws),
  // so the spread of their tactor errors, computed here from the CSV, is the JSON's Monte Carlo
  // 3-sigma, and every device whose own margin is >= 0 is counted as covering.
  const fs::path out = dir_ / "dev";
  const Outcome r = run({"tolerance", kDesign, "--station", "thumb", "--devices", "--json", "--out", out.string()});
  ASSERT_EQ(r.code, 0) << r.err;
  const json j = parse(r);
  std::ifstream in(out / "thumb-lower-devices.csv");
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "device,dL1_mm,dL2_mm,dL3_mm,dL4_mm,dO1x_mm,dO1y_mm,dO2x_mm,dO2y_mm,dtheta1_deg,dtheta2_deg,status,"
                  "error_x_mm,error_y_mm,margin_mm,covers");
  double n = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sxy = 0, covering = 0;
  while (std::getline(in, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) f.push_back(cell);
    ASSERT_EQ(f.size(), 16u) << line;
    ASSERT_EQ(f[11], "ok") << line;
    const double x = std::stod(f[12]), y = std::stod(f[13]);
    n += 1, sx += x, sy += y, sxx += x * x, syy += y * y, sxy += x * y;
    covering += std::stod(f[15]);
    EXPECT_EQ(f[15] == "1", std::stod(f[14]) >= 0.0) << line;
  }
  ASSERT_EQ(n, 10000.0);
  const double cxx = (sxx - sx * sx / n) / (n - 1), cyy = (syy - sy * sy / n) / (n - 1), cxy = (sxy - sx * sy / n) / (n - 1);
  const double major = 3.0 * std::sqrt(0.5 * (cxx + cyy) + std::hypot(0.5 * (cxx - cyy), cxy));
  const json& m = ft::mechanism(ft::station(j, "thumb"), "lower");
  EXPECT_NEAR(major, m["centre_monte_carlo_3sigma_mm"].get<double>(), 1e-9);
  EXPECT_EQ(covering / n, m["robust_coverage"]["fraction_monte_carlo"].get<double>());
}

}  // namespace
