// The exported C++17 header, compiled: test/export_header/values_cpp17.cpp includes the header the
// build generated with the built `fivebar export --format header designs/iros2022.yaml` (its
// static_asserts check the paper's numbers at compile time) and hands every value over; here they
// are compared with the design loaded from the same file.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/geometry.hpp"
#include "fivebar/export/export.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/version.hpp"
#include "header_values.hpp"

namespace fivebar {
namespace {

namespace fs = std::filesystem;
const fs::path kSource = FIVEBAR_SOURCE_DIR;

TEST(ExportedHeader, EveryCompiledValueEqualsTheDesign) {
  const Design d = load_design(kSource / "designs" / "iros2022.yaml");
  const ControllerSettings& c = *d.get<ControllerSettings>();
  const fivebar_test::HeaderValues v = fivebar_test::header_values();
  EXPECT_EQ(v.design, d.name);
  EXPECT_EQ(v.design_hash, design_hash(d, {}));
  EXPECT_EQ(v.tool_version, std::string(version()));
  EXPECT_EQ(v.format_version, 1);
  EXPECT_EQ(v.loop_rate_hz, c.loop_rate_hz);
  EXPECT_EQ(v.pwm_hz, c.pwm_hz);
  EXPECT_EQ(v.adc_bits, c.adc_bits);
  EXPECT_EQ(v.adc_range[0], c.adc_range_v[0]);
  EXPECT_EQ(v.adc_range[1], c.adc_range_v[1]);
  EXPECT_EQ(v.volts_per_count, (c.adc_range_v[1] - c.adc_range_v[0]) / 65536.0);
  EXPECT_EQ(v.station_names, (std::vector<std::string>{"index", "thumb"}));

  ASSERT_EQ(v.stations.size(), d.stations.size());
  for (std::size_t i = 0; i < v.stations.size(); ++i) {
    const Station& s = d.stations[i];
    EXPECT_EQ(v.stations[i].name, s.name);
    EXPECT_EQ(v.stations[i].center[0], s.target.center.x() / 1000);
    EXPECT_EQ(v.stations[i].center[1], s.target.center.y() / 1000);
    EXPECT_EQ(v.stations[i].axes[0], s.target.axes.x() / 1000);
    EXPECT_EQ(v.stations[i].axes[1], s.target.axes.y() / 1000);
    EXPECT_EQ(v.stations[i].angle, s.target.angle);
  }
  ASSERT_EQ(v.mechanisms.size(), 4u);
  std::vector<std::string> joints;
  for (const auto& hm : v.mechanisms) {
    SCOPED_TRACE(hm.station + "/" + hm.name);
    const Mechanism* m = d.station(hm.station)->mechanism(hm.name);
    ASSERT_NE(m, nullptr);
    EXPECT_EQ(hm.o1[0], m->O1.x() / 1000);
    EXPECT_EQ(hm.o1[1], m->O1.y() / 1000);
    EXPECT_EQ(hm.o2[0], m->O2.x() / 1000);
    EXPECT_EQ(hm.o2[1], m->O2.y() / 1000);
    for (int k = 0; k < 4; ++k) EXPECT_EQ(hm.links[k], m->L[k] / 1000) << k;
    EXPECT_EQ(hm.working_mode, to_string(m->working_mode));
    EXPECT_EQ(hm.assembly_mode, to_string(m->assembly_mode));
    EXPECT_EQ(hm.min_lci, m->min_lci);
    EXPECT_EQ(hm.joint_names,
              (std::vector<std::string>{hm.station + "_" + hm.name + "_theta1", hm.station + "_" + hm.name + "_theta2"}));
    joints.insert(joints.end(), hm.joint_names.begin(), hm.joint_names.end());
  }
  EXPECT_EQ(v.joint_names, joints);
  ASSERT_EQ(v.joints.size(), 8u);
  for (std::size_t i = 0; i < v.joints.size(); ++i) {
    const auto& hj = v.joints[i];
    SCOPED_TRACE(hj.name);
    EXPECT_EQ(hj.name, joints[i]);
    const auto& hm = v.mechanisms[i / 2];
    const JointControl jc = c.joint(hm.station, hm.name, int(i % 2) + 1);
    EXPECT_EQ(hj.p, jc.pid.kp);
    EXPECT_EQ(hj.i, jc.pid.ki);
    EXPECT_EQ(hj.d, jc.pid.kd);
    EXPECT_EQ(hj.i_clamp, jc.pid.i_clamp);
    EXPECT_EQ(hj.volts_at_zero, jc.potentiometer.volts_at_zero);
    EXPECT_EQ(hj.rad_per_volt, jc.potentiometer.rad_per_volt);
    EXPECT_EQ(hj.has_position_limits,
              with_usable_limits(d, *d.station(hm.station)).mechanism(hm.name)->joint_limits.has_value());
    EXPECT_TRUE(hj.has_velocity_limits);
    EXPECT_EQ(hj.max_velocity, joint_speed_limit(d, *d.station(hm.station), *d.station(hm.station)->mechanism(hm.name),
                                                 int(i % 2) + 1));
  }
  EXPECT_EQ(v.collision_priority, "upper");
  EXPECT_EQ(v.min_clearance, d.get<Geometry>()->min_clearance / 1000);
  for (int k = 0; k < 4; ++k) {
    EXPECT_EQ(v.link_widths[k], d.get<Geometry>()->link_width[k] / 1000);
    EXPECT_EQ(v.layers[k], d.get<Geometry>()->layers[k]);
  }
}

TEST(ExportedHeader, TheGeneratedFilePassesCheck) {
  const Design d = load_design(kSource / "designs" / "iros2022.yaml");
  const ExportCheck c = check_export_file(FIVEBAR_EXPORTED_HEADER, d);
  EXPECT_EQ(c.format, "header");
  EXPECT_TRUE(c.matches()) << ::testing::PrintToString(c.differences.size());
}

TEST(ExportedHeader, CheckComparesTheCopyTheRuntimeReads) {
  // The header holds each value twice: a constant and, in runtime_json, the text the runtime
  // reads. An edit of the JSON copy alone (a gain the constants do not show) is named with its key.
  const Design d = load_design(kSource / "designs" / "iros2022.yaml");
  std::ifstream in(FIVEBAR_EXPORTED_HEADER);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string text = ss.str();
  const Json params = controller_parameters(d, {});
  const double p = params.begin().value()["ros__parameters"]["gains"]["index_lower_theta1"]["p"].get<double>();
  // In runtime_json the gains read `\"p\": <value>` (quotes escaped, newlines octal).
  const std::string key = "\\\"p\\\": " + format_double(p).substr(0, format_double(p).find('.'));
  const std::size_t at = text.find("runtime_json");
  ASSERT_NE(at, std::string::npos);
  const std::size_t hit = text.find(key, at);
  ASSERT_NE(hit, std::string::npos) << key;
  text.insert(hit + key.size() - 1, "9");  // one more leading digit: 10x or more
  const ExportCheck c = check_export(text, ExportFormat::header, d, "edited.hpp");
  ASSERT_EQ(c.differences.size(), 1u);
  EXPECT_EQ(c.differences[0].path, "runtime_json.fivebar_controller.ros__parameters.gains.index_lower_theta1.p");
  // The constants alone are unchanged: the same text without runtime_json passes as before.
}

}  // namespace
}  // namespace fivebar
