// What each validated figure rests on (fivebar/provenance.hpp figure_bases()): the one table, the
// export's fivebar.validation block that carries it, and how measuring a group takes it off a
// figure's line. The references are the designs' own provenance entries, set here group by group.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "fivebar/design.hpp"
#include "fivebar/error.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/provenance.hpp"
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

}  // namespace
}  // namespace fivebar
