// What each validated figure rests on (fivebar/provenance.hpp figure_bases()): the one table, the
// export's fivebar.validation block that carries it, and how measuring a group takes it off a
// figure's line. The references are the designs' own provenance entries, set here group by group.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/error.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/provenance.hpp"
#include "fivebar/provenance/gate.hpp"
#include "fivebar/io.hpp"
#include "fivebar/sha256.hpp"

namespace fivebar {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

const std::filesystem::path kSource = FIVEBAR_SOURCE_DIR;
const Design& paper() {
  static const Design d = load_design(kSource / "designs" / "iros2022.yaml");
  return d;
}

/// `design` with every value of `groups` measured (a provenance entry per key).
Design measured(const Design& design, const std::vector<std::string>& groups) {
  std::vector<MeasuredValue> values;
  for (const std::string& g : groups) {
    for (const std::string& key : assumed_values(design, g)) values.push_back({key, 0.01});
  }
  return with_measured_values(design, values, {"bench.csv", sha256_hex("bench"), "2026-11-26", "test"});
}

TEST(FigureBases, OneWellFormedTableOverTheProvenanceGroups) {
  std::set<std::string> keys;
  const auto& groups = provenance_groups();
  for (const FigureBasis& f : figure_bases()) {
    EXPECT_TRUE(keys.insert(f.key).second) << f.key << " twice";
    EXPECT_FALSE(f.groups.empty()) << f.key;
    EXPECT_FALSE(f.label.empty()) << f.key;
    for (const std::string& g : f.groups) EXPECT_NE(std::find(groups.begin(), groups.end(), g), groups.end()) << f.key << ": " << g;
    // In provenance_groups() order.
    EXPECT_TRUE(std::is_sorted(f.groups.begin(), f.groups.end(), [&](const std::string& a, const std::string& b) {
      return std::find(groups.begin(), groups.end(), a) < std::find(groups.begin(), groups.end(), b);
    })) << f.key;
  }
  // The simulated tracking error rests on the contact and the potentiometers; the stability map does not.
  const auto& tracking = figure_basis("max_tracking_error_m").groups;
  EXPECT_NE(std::find(tracking.begin(), tracking.end(), "contact"), tracking.end());
  EXPECT_NE(std::find(tracking.begin(), tracking.end(), "potentiometer"), tracking.end());
  const auto& rho = figure_basis("max_rho").groups;
  EXPECT_EQ(std::find(rho.begin(), rho.end(), "contact"), rho.end());
  EXPECT_THROW(figure_basis("no_such_figure"), InputError);
}

TEST(FigureBases, MeasuringAGroupTakesItOffEveryFigureThatRestsOnIt) {
  const Design& d = paper();
  // The showcase measures nothing: every figure rests on all of its groups, assumed.
  for (const FigureBasis& f : figure_bases()) EXPECT_EQ(figure_assumed(d, f.key), f.groups) << f.key;
  EXPECT_EQ(rests_on_line(d, "max_tracking_error_m", 1.17e-4),
            "max tracking error 0.117 mm: kinematics, potentiometer, motor, contact, density assumed");
  // The motor measured (identify's patch): off every line, the others stay.
  const Design motor = measured(d, {"motor"});
  EXPECT_THAT(rests_on_text(motor, "max_tracking_error_m"), Not(HasSubstr("motor")));
  EXPECT_THAT(rests_on_text(motor, "max_tracking_error_m"), HasSubstr("contact"));
  EXPECT_EQ(rests_on_text(motor, "max_rho"), "kinematics, density assumed");
  EXPECT_EQ(rests_on_text(motor, "robust_margin_mm"), "kinematics, tolerance assumed");
  // Everything measured: "measured (...)" naming the groups.
  const Design all = measured(d, provenance_groups());
  for (const FigureBasis& f : figure_bases()) {
    EXPECT_TRUE(figure_assumed(all, f.key).empty()) << f.key;
    EXPECT_EQ(rests_on_text(all, f.key).rfind("measured (", 0), 0u) << f.key;
  }
  // One mechanism measured: its own figures no longer rest on assumed kinematics and
  // potentiometers, the other mechanism's still do (a figure of index/lower rests on index/lower).
  std::vector<MeasuredValue> lower;
  for (const std::string& k : calibration_keys(d, "index", "lower")) lower.push_back({k, 0.01});
  const Design one = with_measured_values(d, lower, {"m.csv", sha256_hex("m"), "2026-11-26", "test"});
  EXPECT_EQ(figure_assumed(one, "max_tracking_error_m", "index", "lower"), (std::vector<std::string>{"motor", "contact", "density"}));
  EXPECT_EQ(figure_assumed(one, "max_tracking_error_m", "index", "upper"),
            (std::vector<std::string>{"kinematics", "potentiometer", "motor", "contact", "density"}));
  // A motor override of one joint measured leaves the other joint's motor values assumed.
  const Design joint = with_measured_values(one, {{"motor.coulomb_friction_mNm", 0.01}}, {"m.csv", sha256_hex("m"), "2026-11-26", "test"});
  EXPECT_FALSE(assumed_values(joint, "motor", "index", "lower").empty());
  // One mechanism's links measured is not the kinematics group measured.
  std::vector<MeasuredValue> links;
  for (int i = 0; i < 4; ++i) links.push_back({"stations.index.mechanisms.lower.links[" + std::to_string(i) + "]", 0.01});
  const Design some = with_measured_values(d, links, {"m.csv", sha256_hex("m"), "2026-11-26", "test"});
  EXPECT_THAT(rests_on_text(some, "max_rho"), HasSubstr("kinematics"));
}

TEST(FigureBases, TheExportValidationBlockCarriesWhatEachFigureRestsOn) {
  const Design d = measured(paper(), {"motor"});
  ExportOptions o;
  o.stations = {"index"};
  const auto dir = std::filesystem::temp_directory_path() / ("fivebar_provenance_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  const ExportResult r = export_controller(d, {ExportFormat::json}, dir, o);
  ASSERT_TRUE(r.gate.passed()) << r.gate.reasons().front();
  const Json& v = r.parameters.begin().value()["ros__parameters"]["fivebar"]["validation"];
  for (const char* m : {"lower", "upper"}) {
    SCOPED_TRACE(m);
    const Json& f = v.at("index").at(m);
    ASSERT_TRUE(f.contains("rests_on"));
    int figures = 0;
    for (const auto& [key, value] : f.items()) {
      if (!value.is_number()) continue;  // worst_pose_m is a place, rests_on the lines
      ++figures;
      ASSERT_TRUE(f.at("rests_on").contains(key)) << key;
      EXPECT_EQ(f.at("rests_on").at(key).get<std::string>(), rests_on_text(d, key, "index", m)) << key;
      EXPECT_THAT(f.at("rests_on").at(key).get<std::string>(), Not(HasSubstr("motor"))) << key;
    }
    EXPECT_EQ(figures, 8);
  }
  std::filesystem::remove_all(dir);
}


// The chi-square tail against closed forms (an independent reference): for an even number of
// degrees of freedom 2k, P(X >= x) = exp(-x/2) sum_{i<k} (x/2)^i / i!; for one, erfc(sqrt(x/2)).
TEST(QualityGate, ChiSquareTailMatchesItsClosedForms) {
  for (int k : {1, 2, 5, 20, 60}) {
    for (double x : {0.1, 1.0, 3.0, 10.0, 40.0, 120.0, 200.0}) {
      double sum = 0.0, term = 1.0;
      for (int i = 0; i < k; ++i) {
        sum += term;
        term *= (x / 2) / (i + 1);
      }
      const double exact = std::exp(-x / 2) * sum;
      EXPECT_NEAR(gate::chi_square_sf(x, 2 * k), exact, 1e-12 + 1e-10 * exact) << "dof " << 2 * k << " x " << x;
    }
  }
  for (double x : {0.01, 0.5, 2.0, 9.0, 30.0}) EXPECT_NEAR(gate::chi_square_sf(x, 1), std::erfc(std::sqrt(x / 2)), 1e-12) << x;
  EXPECT_EQ(gate::chi_square_sf(0.0, 3), 1.0);
}

// The test's false-refusal rate under its own noise model is its alpha (Monte Carlo over sums of
// squared normal draws), and a blunder of 10 sigma in 100 residuals is refused.
TEST(QualityGate, ChiSquareTestRefusesAtItsStatedRate) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  const int dof = 40, trials = 20000;
  int refused = 0, refused_at_5pc = 0;
  for (int t = 0; t < trials; ++t) {
    double s = 0.0;
    for (int i = 0; i < dof; ++i) s += std::pow(n(rng), 2);
    refused += gate::chi_square_test(s, dof).passed ? 0 : 1;
    refused_at_5pc += gate::chi_square_test(s, dof, 0.05).passed ? 0 : 1;
  }
  EXPECT_LT(refused, 3 * trials * gate::kAlpha + 5);
  EXPECT_NEAR(refused_at_5pc / static_cast<double>(trials), 0.05, 0.006);
  std::vector<double> z(100);
  for (double& v : z) v = n(rng);
  EXPECT_TRUE(gate::largest_residual_test(z).passed);
  z[17] = 10.0;
  const gate::ResidualTest t = gate::largest_residual_test(z);
  EXPECT_FALSE(t.passed);
  EXPECT_THAT(t.statement, HasSubstr("10.00"));
  EXPECT_FALSE(gate::chi_square_test(0.0, 0).applicable);
}

TEST(QualityGate, EveryConditionRefusesWithItsReasonPerParameter) {
  gate::GateInput in;
  in.fit = "test fit";
  in.solver = {true, "CONVERGENCE", 5};
  in.tests.push_back(gate::chi_square_test(38.0, 40));
  in.parameters.push_back({"a.key", "a", "mm", 1.0, 0.01, 0.1, true, ""});
  in.parameters.push_back({"b.key", "b", "mm", 2.0, 0.5, 0.1, true, ""});
  in.parameters.push_back({"c.key", "c", "V", 3.0, 0.001, std::nan(""), true, ""});
  gate::GateResult g = gate::evaluate(in);
  EXPECT_FALSE(g.passed);
  EXPECT_TRUE(g.parameters[0].passed);
  EXPECT_FALSE(g.parameters[1].passed);
  EXPECT_TRUE(g.parameters[2].passed);
  EXPECT_DOUBLE_EQ(g.parameters[1].sigma_ratio, 5.0);
  ASSERT_EQ(g.refusal_lines().size(), 1u);
  EXPECT_THAT(g.refusal_lines()[0], HasSubstr("b (b.key)"));
  EXPECT_THAT(g.refusal_lines()[0], HasSubstr("5x its prior"));
  // The record of a passed value says so, with its figures; the refused one does not pass.
  EXPECT_TRUE(g.record("a.key").passed);
  EXPECT_FALSE(g.record("b.key").passed);
  EXPECT_EQ(g.record("a.key").solver, "CONVERGENCE");
  EXPECT_NEAR(*g.record("a.key").sigma_ratio, 0.1, 1e-12);
  EXPECT_FALSE(g.record("c.key").sigma_ratio.has_value());
  // A solver that did not converge refuses every value, each with that reason.
  in.parameters.erase(in.parameters.begin() + 1);
  in.solver = {false, "NO_CONVERGENCE", 100};
  g = gate::evaluate(in);
  EXPECT_FALSE(g.passed);
  ASSERT_EQ(g.refusal_lines().size(), 2u);
  for (const std::string& line : g.refusal_lines()) EXPECT_THAT(line, HasSubstr("did not converge (NO_CONVERGENCE)"));
  // Residuals the noise does not explain, and an unidentifiable value.
  in.solver = {true, "CONVERGENCE", 5};
  in.tests = {gate::chi_square_test(400.0, 40)};
  in.parameters[1].identifiable = false;
  in.parameters[1].identifiability = "moves the tactor as a";
  g = gate::evaluate(in);
  EXPECT_THAT(g.refusal_lines()[0], HasSubstr("larger than the stated measurement sigma"));
  EXPECT_THAT(g.refusal_lines()[1], HasSubstr("not identifiable: moves the tactor as a"));
  EXPECT_TRUE(gate::to_json(g).at("parameters").is_array());
}

/// `design` with `key` measured by an entry of the given sha256 and gate.
Design with_entry(const Design& d, const std::string& key, const std::string& sha, std::optional<bool> passed,
                  const std::string& source = "bench.csv") {
  std::vector<GateRecord> gates;
  if (passed) {
    GateRecord r;
    r.passed = *passed;
    r.solver = "CONVERGENCE";
    gates.push_back(r);
  }
  return with_measured_values(d, {{key, 0.01}}, {source, sha, "2026-11-26", "test"}, Eigen::MatrixXd(), gates);
}

TEST(QualityGate, RequireMeasuredTrustsOnlyGatedEntriesWithRealHashesOfUnchangedFiles) {
  const Design& d = paper();
  const std::string key = "stations.index.mechanisms.lower.links[2]";
  const std::string zeros(64, '0');
  // A hand-written entry with an all-zero hash is not a measurement at all.
  EXPECT_FALSE(is_measured(with_entry(d, key, zeros, std::nullopt), key));
  EXPECT_FALSE(is_measured(with_entry(d, key, zeros, true), key));
  // An entry whose gate failed is not a measurement; one without a gate is, but require_measured refuses it.
  EXPECT_FALSE(is_measured(with_entry(d, key, sha256_hex("x"), false), key));
  const Design hand = with_entry(d, key, sha256_hex("x"), std::nullopt);
  EXPECT_TRUE(is_measured(hand, key));
  const auto reason = [&](const Design& x) {
    for (const UntrustedValue& u : untrusted_values(x, "kinematics", {"index"}, "lower")) {
      if (u.key == key) return u.reason;
    }
    return std::string();
  };
  EXPECT_THAT(reason(hand), HasSubstr("no quality gate"));
  EXPECT_THAT(reason(with_entry(d, key, zeros, true)), HasSubstr("all zeros"));
  EXPECT_THAT(reason(with_entry(d, key, sha256_hex("x"), false)), HasSubstr("did not pass"));
  EXPECT_EQ(reason(with_entry(d, key, sha256_hex("x"), true)), "");
  // The source file, when present beside the design, must still have the recorded hash.
  const auto dir = std::filesystem::temp_directory_path() / ("fivebar_gate_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  write_file_atomic(dir / "bench.csv", "the bench file\n");
  Design placed = with_entry(d, key, sha256_hex("the bench file\n"), true);
  placed.source = dir / "d.yaml";
  EXPECT_EQ(reason(placed), "");
  write_file_atomic(dir / "bench.csv", "the bench file, edited\n");
  EXPECT_THAT(reason(placed), HasSubstr("has changed since the fit"));
  std::filesystem::remove_all(dir);
  // Scope: the thumb's values do not count for the index station, nor the upper mechanism's for --mechanism lower.
  std::vector<MeasuredValue> values;
  std::vector<GateRecord> gates;
  GateRecord ok;
  ok.passed = true;
  ok.solver = "CONVERGENCE";
  for (const std::string& k : calibration_keys(d, "index", "lower")) values.push_back({k, 0.01}), gates.push_back(ok);
  const Design lower = with_measured_values(d, values, {"m.csv", sha256_hex("m"), "2026-11-26", "test"}, Eigen::MatrixXd(), gates);
  EXPECT_TRUE(untrusted_values(lower, "kinematics", {"index"}, "lower").empty());
  EXPECT_TRUE(untrusted_values(lower, "potentiometer", {"index"}, "lower").empty());
  EXPECT_FALSE(untrusted_values(lower, "kinematics", {"index"}).empty());
  EXPECT_FALSE(untrusted_values(lower, "kinematics", {}).empty());
  const auto groups = assumed_groups(lower, {"index"}, "lower");
  EXPECT_EQ(std::count(groups.begin(), groups.end(), "kinematics"), 0);
  EXPECT_EQ(std::count(groups.begin(), groups.end(), "potentiometer"), 0);
  const auto thumb = assumed_groups(lower, {"thumb"});
  EXPECT_EQ(std::count(thumb.begin(), thumb.end(), "kinematics"), 1);
}

}  // namespace
}  // namespace fivebar
