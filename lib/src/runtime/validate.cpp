// Validation of the runtime's configuration (fivebar/runtime/config.hpp Config::validate();
// docs/runtime.md "Configuration"): every rule names the key it checks.

#include <cmath>
#include <initializer_list>
#include <string>

#include "fivebar/runtime/config.hpp"

namespace fivebar::runtime {

namespace {
constexpr double kTwoPi = 2.0 * 3.14159265358979323846;

// The physical bounds of what the loop takes, the design loader's (lib/src/sections/controller.cpp):
// a gain above 1e6 (duty per rad, per rad s, or s per rad) saturates the duty at an error far
// below any potentiometer's resolution, so no motor loop uses one; within these bounds and a loop
// rate of at most 1e5 Hz every term of the PID (p e, i s, d de/dt, with |e| <= pi) is finite, so
// no duty is NaN. A calibration's volts and slope as the loader's.
constexpr double kMaxGain = 1e6;
constexpr const char* kGainRule = "must be in [0, 1000000] (no motor loop uses more; it keeps the duty finite)";
constexpr double kMaxLoopRateHz = 1e5;
constexpr double kMaxVolts = 1000.0;
constexpr double kMinRadPerVolt = 1e-6, kMaxRadPerVolt = 1e6;
constexpr double kMaxVelocity = 1e6;  // rad/s: above any motor's; keeps max_velocity / loop_rate_hz finite

bool gain_ok(double g) { return g >= 0.0 && g <= kMaxGain; }
}  // namespace

namespace {
void require(bool ok, const std::string& key, const std::string& what) {
  if (!ok) throw ConfigError(key + ": " + what);
}
bool finite_all(std::initializer_list<double> v) {
  for (double x : v)
    if (!std::isfinite(x)) return false;
  return true;
}
}  // namespace

void Config::validate() const {
  require(loop_rate_hz > 0.0 && loop_rate_hz <= kMaxLoopRateHz, "loop_rate_hz", "must be in (0, 100000] Hz");
  require(adc_bits >= 1 && adc_bits <= 31, "adc.bits", "must be in [1, 31]");
  require(finite_all({adc_range_v[0], adc_range_v[1]}) && adc_range_v[1] > adc_range_v[0], "adc.range_v",
          "must be two finite volts, low < high");
  const double expected = (adc_range_v[1] - adc_range_v[0]) / std::ldexp(1.0, adc_bits);
  require(std::isfinite(volts_per_count) && volts_per_count > 0.0 &&
              std::fabs(volts_per_count - expected) <= 1e-9 * expected,
          "adc.volts_per_count", "must be (range_v[1] - range_v[0]) / 2^bits");
  require(std::isfinite(joint_margin) && joint_margin >= 0.0, "joint_margin_rad", "must be a finite number >= 0");
  if (collision.checked) {
    const CollisionConfig& c = collision;
    require(std::isfinite(c.min_clearance) && c.min_clearance >= 0.0, "collision.min_clearance_m", "must be >= 0");
    for (std::size_t i = 0; i < 4; ++i) {
      require(std::isfinite(c.link_widths[i]) && c.link_widths[i] > 0.0, "collision.link_widths_m[" + std::to_string(i) + "]",
              "must be > 0");
      require(c.layers[i] >= 0 && c.layers[i] <= 32, "collision.layers[" + std::to_string(i) + "]", "must be in [0, 32]");
    }
    require(finite_all({c.pin_diameter, c.boss_diameter, c.tactor_diameter, c.motor_shaft_diameter}) && c.pin_diameter > 0.0 &&
                c.boss_diameter >= 0.0 && c.tactor_diameter > 0.0 && c.motor_shaft_diameter >= 0.0,
            "collision", "pin, boss, tactor and motor shaft diameters must be finite, pin and tactor > 0");
  }
  require(!stations.empty(), "station_names", "no station");
  for (const StationConfig& s : stations) {
    const std::string sp = "stations." + s.name;
    require(!s.mechanisms.empty() && s.mechanisms.size() <= 2, sp + ".mechanisms", "one or two mechanisms");
    if (s.mechanisms.size() == 2) {
      require(s.mechanisms[0].name != s.mechanisms[1].name, sp + ".mechanisms", "a lower and an upper mechanism");
    }
    for (const MechanismConfig& m : s.mechanisms) {
      const std::string mp = sp + "." + m.name;
      require(m.name == "lower" || m.name == "upper", mp, "a mechanism is \"lower\" or \"upper\"");
      require(finite_all({m.o1[0], m.o1[1], m.o2[0], m.o2[1]}), mp + ".o1_m", "base joints must be finite");
      for (std::size_t i = 0; i < 4; ++i) {
        require(std::isfinite(m.L[i]) && m.L[i] > 0.0, mp + ".link_lengths_m[" + std::to_string(i) + "]", "must be > 0");
      }
      for (std::size_t j = 0; j < 2; ++j) {
        require(m.working_mode[j] == 1 || m.working_mode[j] == -1, mp + ".working_mode", "two signs");
        const JointConfig& jc = m.joints[j];
        const std::string g = "gains." + jc.name;
        require(gain_ok(jc.gains.p), g + ".p", kGainRule);
        require(gain_ok(jc.gains.i), g + ".i", kGainRule);
        require(gain_ok(jc.gains.d), g + ".d", kGainRule);
        require(jc.gains.i_clamp >= 0.0 && jc.gains.i_clamp <= 1.0, g + ".i_clamp", "must be in [0, 1] (a duty)");
        const std::string pp = "potentiometers." + jc.name;
        require(std::fabs(jc.volts_at_zero) <= kMaxVolts, pp + ".volts_at_zero", "must be within [-1000, 1000] V");
        require(std::fabs(jc.rad_per_volt) >= kMinRadPerVolt && std::fabs(jc.rad_per_volt) <= kMaxRadPerVolt,
                pp + ".rad_per_volt", "|rad_per_volt| must be in [1e-6, 1e6] rad/V (never 0)");
        if (jc.has_velocity_limits) {  // the slew limit's step per cycle (controller.cpp slew())
          require(jc.max_velocity > 0.0 && jc.max_velocity <= kMaxVelocity, "joint_limits." + jc.name + ".max_velocity",
                  "must be in (0, 1e6] rad/s (the slew limit: a joint target moves at most this fast)");
        }
        if (jc.has_position_limits) {
          const std::string lp = "joint_limits." + jc.name;
          require(finite_all({jc.min_position, jc.max_position}) && jc.max_position > jc.min_position &&
                      jc.max_position - jc.min_position <= kTwoPi + 1e-12,
                  lp, "min_position < max_position, at most one turn apart");
          require(jc.max_position - jc.min_position > 2.0 * joint_margin, lp,
                  "the range must be wider than twice joint_margin_rad");
        }
      }
    }
  }
}

}  // namespace fivebar::runtime
