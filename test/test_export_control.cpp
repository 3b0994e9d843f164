// The loop checks of the export gate (fivebar/export/export.hpp "stability", "tracking", "saturation"):
// a controller beyond its kp margin is refused naming the station, mechanism, pose and spectral
// radius; the tracking and saturation limits refuse with the mechanism, pattern and figure, the
// figures being those of an independent simulate() run of the same pattern; a passed export
// carries them in fivebar.validation and still reads back as matching its design.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "fivebar/control.hpp"
#include "fivebar/dynamics.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/motor.hpp"

namespace fivebar {
namespace {

using ::testing::HasSubstr;

const std::filesystem::path kSource = FIVEBAR_SOURCE_DIR;
Design paper() { return load_design(kSource / "designs" / "iros2022.yaml"); }

std::filesystem::path scratch(const std::string& name) {
  const auto p = std::filesystem::temp_directory_path() / ("fivebar_export_control_" + std::to_string(::getpid())) / name;
  std::filesystem::remove_all(p);
  return p;
}

const GateCheck* find(const ExportGate& g, const std::string& kind, const std::string& subject) {
  for (const GateCheck& c : g.checks)
    if (c.kind == kind && c.subject == subject) return &c;
  return nullptr;
}

TEST(ExportLoopGate, TheShowcasePassesAndItsFilesCarryTheFigures) {
  const Design d = paper();
  ExportOptions o;
  o.stations = {"index"};
  const auto dir = scratch("pass");
  const ExportResult r = export_controller(d, {ExportFormat::ros2, ExportFormat::json}, dir, o);
  ASSERT_TRUE(r.gate.passed()) << r.gate.reasons().front();
  for (const char* m : {"index/lower", "index/upper"}) EXPECT_NE(find(r.gate, "stability", m), nullptr) << m;
  for (const char* p : {"index stretch", "index slip", "index twist", "index pivot"}) {
    EXPECT_NE(find(r.gate, "tracking", p), nullptr) << p;
    EXPECT_NE(find(r.gate, "saturation", p), nullptr) << p;
  }
  const Json& v = r.parameters.begin().value()["ros__parameters"]["fivebar"]["validation"];
  for (const char* m : {"lower", "upper"}) {
    SCOPED_TRACE(m);
    const Json& f = v.at("index").at(m);
    EXPECT_LT(f.at("max_rho").get<double>(), 1.0);
    EXPECT_GT(f.at("kp_margin").get<double>(), 1.0);
    EXPECT_GT(f.at("min_bandwidth_hz").get<double>(), 0.0);
    EXPECT_LE(f.at("min_bandwidth_hz").get<double>(), 50.0);  // Nyquist of the 100 Hz loop
    EXPECT_GT(f.at("max_tracking_error_m").get<double>(), 0.0);
    EXPECT_LE(f.at("max_tracking_error_m").get<double>(), 1e-3 * d.get<ControllerSettings>()->max_tracking_error_mm);
  }
  // The tracking figures are those of simulate() at its default tolerance over the four patterns, to 2 um.
  SimulationRequest req;
  req.station = "index";
  std::map<std::string, double> worst;
  for (const SimulationInput& in : simulation_inputs(d, req, station_inertia(d, d.require_station("index"), nullptr, {}))) {
    const SimulationResult sim = simulate(in);
    ASSERT_TRUE(sim.ok());
    for (const MechanismSummary& m : sim.summary) worst[m.name] = std::max(worst[m.name], m.max_error_mm);
  }
  for (const char* m : {"lower", "upper"}) {
    EXPECT_NEAR(1e3 * v.at("index").at(m).at("max_tracking_error_m").get<double>(), worst.at(m), 2e-3) << m;
  }
  ASSERT_EQ(r.files.size(), 2u);
  for (const auto& f : r.files) {
    SCOPED_TRACE(f.string());
    std::ifstream in(f);
    std::stringstream text;
    text << in.rdbuf();
    EXPECT_THAT(text.str(), HasSubstr("validation"));
    EXPECT_THAT(text.str(), HasSubstr("kp_margin"));
    EXPECT_TRUE(check_export_file(f, d).matches());
  }
  std::filesystem::remove_all(dir.parent_path());
}

TEST(ExportLoopGate, GainsBeyondTheKpMarginAreRefusedNamingThePoseAndNothingIsWritten) {
  Design d = paper();
  ControllerSettings& c = *d.get<ControllerSettings>();
  // Only the index station's lower mechanism: its own margin, from the library, then 30 % past it.
  std::map<std::string, MechanismInertia> inertia = station_inertia(d, d.require_station("index"), nullptr, {});
  const LoopModel loop = loop_models(d, d.require_station("index"), inertia).front();
  ASSERT_EQ(loop.model.mechanism.name, "lower");
  StabilityOptions so;
  so.grid = 21;
  const StabilityMap before = stability_map(loop, ellipse_lattice(d.require_station("index").target, 21), so);
  ControlOverride o;
  o.station = "index";
  o.mechanism = "lower";
  o.kp = loop.gains[0].kp * before.kp_margin * 1.3;  // the margin is a factor on the loop's own kp
  c.overrides.push_back(o);
  c.max_tracking_error_mm = 1000.0;  // the stability check alone decides
  c.max_saturation_fraction = 1.0;
  ExportOptions eo;
  eo.stations = {"index"};
  const auto dir = scratch("unstable");
  const ExportResult r = export_controller(d, all_export_formats(), dir, eo);
  EXPECT_FALSE(r.gate.passed());
  EXPECT_FALSE(std::filesystem::exists(dir));
  EXPECT_TRUE(r.files.empty());
  const GateCheck* bad = find(r.gate, "stability", "index/lower");
  ASSERT_NE(bad, nullptr);
  EXPECT_FALSE(bad->passed);
  EXPECT_THAT(bad->detail, HasSubstr("UNSTABLE"));
  EXPECT_THAT(bad->detail, HasSubstr(" mm over "));
  const GateCheck* good = find(r.gate, "stability", "index/upper");
  ASSERT_NE(good, nullptr);
  EXPECT_TRUE(good->passed);
  bool named = false;
  for (const std::string& reason : r.gate.reasons()) named = named || reason.find("index/lower") != std::string::npos;
  EXPECT_TRUE(named);
}

TEST(ExportLoopGate, TrackingAndSaturationLimitsRefuseWithTheSimulatedFigures) {
  Design d = paper();
  ControllerSettings& c = *d.get<ControllerSettings>();
  c.max_tracking_error_mm = 0.1;
  // A driver that limits the current below what the patterns draw (peak ~0.011 A): saturation.
  d.get<MotorSettings>()->defaults.current_limit_A = 0.004;
  c.max_saturation_fraction = 0.0;
  ExportOptions eo;
  eo.stations = {"index"};
  const auto dir = scratch("tracking");
  const ExportResult r = export_controller(d, all_export_formats(), dir, eo);
  EXPECT_FALSE(r.gate.passed());
  EXPECT_FALSE(std::filesystem::exists(dir));
  const GateCheck* t = find(r.gate, "tracking", "index stretch");
  ASSERT_NE(t, nullptr);
  EXPECT_FALSE(t->passed);
  EXPECT_THAT(t->detail, HasSubstr("lower max tracking error"));
  EXPECT_THAT(t->detail, HasSubstr("> 0.100 mm"));
  const GateCheck* s = find(r.gate, "saturation", "index stretch");
  ASSERT_NE(s, nullptr);
  EXPECT_FALSE(s->passed);
  EXPECT_THAT(s->detail, HasSubstr("saturated"));
  // The figure in the refusal is the tracking error of simulate() at its default tolerance (the
  // current limit's clamp makes the gate's looser tolerance differ by ~1 %).
  SimulationRequest req;
  req.station = "index";
  req.pattern = PatternKind::stretch;
  const auto inputs = simulation_inputs(d, req, station_inertia(d, d.require_station("index"), nullptr, {}));
  ASSERT_EQ(inputs.size(), 1u);
  const SimulationResult sim = simulate(inputs[0]);
  ASSERT_TRUE(sim.ok());
  const std::string detail = t->detail;
  const std::size_t at = detail.find("lower max tracking error ");
  ASSERT_NE(at, std::string::npos);
  const double figure = std::stod(detail.substr(at + std::string("lower max tracking error ").size()));
  EXPECT_NEAR(figure, sim.summary[0].max_error_mm, 0.02 * sim.summary[0].max_error_mm);
  EXPECT_GT(sim.summary[0].saturation_s, 0.0);
}

TEST(ExportLoopGate, WithoutMotorsTheLoopIsNotChecked) {
  Design d = paper();
  d.reset<MotorSettings>();
  ExportOptions eo;
  eo.stations = {"index"};
  const ExportGate g = export_gate(d, eo);
  for (const GateCheck& c : g.checks) {
    EXPECT_NE(c.kind, "stability");
    EXPECT_NE(c.kind, "tracking");
  }
  EXPECT_TRUE(g.validation.empty());
}

}  // namespace
}  // namespace fivebar
