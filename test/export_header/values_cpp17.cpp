// Compiled as C++17 with -Wall -Wextra -pedantic -Werror (test/CMakeLists.txt) against the header
// that the built `fivebar export --format header` wrote for designs/iros2022.yaml at build time.
// Compile-time checks against the paper (Table 1, Sec. II-D), typed here, and the values handed to
// test_export_header.cpp for the run-time comparison with the loaded design.

#include <type_traits>

#include "header_values.hpp"
#include "iros2022_controller.hpp"

namespace fc = fivebar_controller;

namespace {

constexpr bool same(const char* a, const char* b) {
  while (*a != '\0' && *a == *b) ++a, ++b;
  return *a == *b;
}
template <class T, std::size_t N>
constexpr std::size_t count(const T (&)[N]) {
  return N;
}

// Types: doubles are double, integers long long, flags bool (ROS's double, int64, bool).
static_assert(std::is_same_v<decltype(fc::loop_rate_hz), const double>);
static_assert(std::is_same_v<decltype(fc::adc::bits), const long long>);
static_assert(std::is_same_v<decltype(fc::joint_limits::index_lower_theta1::has_velocity_limits), const bool>);
// Paper, Sec. II-D: PID at 100 Hz, 1 kHz PWM, 16-bit DAQ.
static_assert(fc::loop_rate_hz == 100.0);
static_assert(fc::pwm_hz == 1000.0);
static_assert(fc::adc::bits == 16);
// Table 1 in metres.
static_assert(fc::stations::index::lower::link_lengths_m[0] == 9.0 / 1000);
static_assert(fc::stations::index::lower::link_lengths_m[2] == 15.0 / 1000);
static_assert(fc::stations::thumb::upper::link_lengths_m[3] == 17.5 / 1000);
static_assert(fc::stations::index::upper::o2_m[0] == 12.5 / 1000 && fc::stations::index::upper::o2_m[1] == 31.0 / 1000);
static_assert(fc::stations::thumb::upper::o1_m[1] == 35.0 / 1000);
static_assert(fc::stations::index::target::axes_m[0] == 15.0 / 1000 && fc::stations::index::target::axes_m[1] == 12.0 / 1000);
static_assert(fc::stations::thumb::target::axes_m[1] == 14.0 / 1000);
static_assert(same(fc::stations::index::lower::working_mode, "-+") && same(fc::stations::index::upper::working_mode, "+-"));
static_assert(same(fc::fivebar::design, "iros2022"));
static_assert(same(fc::collision::priority, "upper"));
static_assert(count(fc::joint_names) == 8 && count(fc::station_names) == 2);
static_assert(same(fc::joint_names[0], "index_lower_theta1") && same(fc::joint_names[7], "thumb_upper_theta2"));
static_assert(fc::joint_limits::thumb_upper_theta2::has_position_limits);  // potentiometer travel, hard stops
static_assert(fc::collision::layers[0] == 0 && fc::collision::layers[3] == 1);

}  // namespace

#define FIVEBAR_JOINT(J)                                                                 \
  [] {                                                                                   \
    namespace g = fc::gains::J;                                                          \
    namespace pot = fc::potentiometers::J;                                               \
    namespace lim = fc::joint_limits::J;                                                 \
    fivebar_test::HeaderJoint j;                                                         \
    j.name = #J;                                                                         \
    j.has_position_limits = lim::has_position_limits;                                    \
    j.has_velocity_limits = lim::has_velocity_limits;                                    \
    j.max_velocity = lim::max_velocity;                                                  \
    j.p = g::p, j.i = g::i, j.d = g::d, j.i_clamp = g::i_clamp;                          \
    j.volts_at_zero = pot::volts_at_zero, j.rad_per_volt = pot::rad_per_volt;            \
    return j;                                                                            \
  }()

#define FIVEBAR_MECHANISM(S, M)                                                                             \
  [] {                                                                                                      \
    namespace m = fc::stations::S::M;                                                                       \
    fivebar_test::HeaderMechanism out;                                                                      \
    out.station = #S, out.name = #M;                                                                        \
    for (const char* n : m::joint_names) out.joint_names.push_back(n);                                      \
    for (int k = 0; k < 2; ++k) out.o1[k] = m::o1_m[k], out.o2[k] = m::o2_m[k];                            \
    for (int k = 0; k < 4; ++k) out.links[k] = m::link_lengths_m[k];                                        \
    out.working_mode = m::working_mode, out.assembly_mode = m::assembly_mode, out.min_lci = m::min_lci;     \
    return out;                                                                                             \
  }()

#define FIVEBAR_STATION(S)                                                                               \
  [] {                                                                                                   \
    namespace t = fc::stations::S::target;                                                               \
    fivebar_test::HeaderStation out;                                                                     \
    out.name = #S;                                                                                       \
    for (int k = 0; k < 2; ++k) out.center[k] = t::center_m[k], out.axes[k] = t::axes_m[k];              \
    out.angle = t::angle_rad;                                                                            \
    return out;                                                                                          \
  }()

namespace fivebar_test {

HeaderValues header_values() {
  HeaderValues v;
  v.node = "fivebar_controller";
  v.design = fc::fivebar::design;
  v.design_hash = fc::fivebar::design_hash;
  v.tool_version = fc::fivebar::tool_version;
  v.format_version = fc::fivebar::format_version;
  v.loop_rate_hz = fc::loop_rate_hz;
  v.pwm_hz = fc::pwm_hz;
  v.adc_bits = fc::adc::bits;
  v.adc_range[0] = fc::adc::range_v[0], v.adc_range[1] = fc::adc::range_v[1];
  v.volts_per_count = fc::adc::volts_per_count;
  for (const char* s : fc::station_names) v.station_names.push_back(s);
  for (const char* j : fc::joint_names) v.joint_names.push_back(j);
  v.stations = {FIVEBAR_STATION(index), FIVEBAR_STATION(thumb)};
  v.mechanisms = {FIVEBAR_MECHANISM(index, lower), FIVEBAR_MECHANISM(index, upper), FIVEBAR_MECHANISM(thumb, lower),
                  FIVEBAR_MECHANISM(thumb, upper)};
  v.joints = {FIVEBAR_JOINT(index_lower_theta1), FIVEBAR_JOINT(index_lower_theta2), FIVEBAR_JOINT(index_upper_theta1),
              FIVEBAR_JOINT(index_upper_theta2), FIVEBAR_JOINT(thumb_lower_theta1), FIVEBAR_JOINT(thumb_lower_theta2),
              FIVEBAR_JOINT(thumb_upper_theta1), FIVEBAR_JOINT(thumb_upper_theta2)};
  v.collision_priority = fc::collision::priority;
  v.min_clearance = fc::collision::min_clearance_m;
  for (int k = 0; k < 4; ++k) v.link_widths[k] = fc::collision::link_widths_m[k], v.layers[k] = fc::collision::layers[k];
  return v;
}

}  // namespace fivebar_test
