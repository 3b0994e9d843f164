// The priors of a joint of a design (fivebar/identify/model.hpp joint_prior()).
#include "fivebar/error.hpp"
#include "fivebar/identify/model.hpp"
#include "fivebar/sections/controller.hpp"
#include "fivebar/sections/motor.hpp"

namespace fivebar::identify {

JointPrior joint_prior(const Design& design, const std::string& station, const std::string& mechanism, int joint,
                        double load_inertia, bool need_motor) {
  JointPrior p;
  const MotorSettings* ms = design.get<MotorSettings>();
  if (ms == nullptr && need_motor) {
    throw InputError(design.name + ": the design has no `motor:` section (motor.terminal_resistance_ohm, ...): the priors "
                                   "of a duty, voltage or current drive");
  }
  const ControllerSettings* cs = design.get<ControllerSettings>();
  if (!station.empty()) {
    const Station& s = design.require_station(station);
    if (s.mechanism(mechanism) == nullptr) {
      throw InputError("joint '" + station + "_" + mechanism + "_theta" + std::to_string(joint) + "': station '" + station +
                       "' has no mechanism '" + mechanism + "'");
    }
    if (ms) p.motor = ms->joint(station, mechanism, joint);
    if (cs) {
      const JointControl jc = cs->joint(station, mechanism, joint);
      p.volts_at_zero = jc.potentiometer.volts_at_zero;
      p.rad_per_volt = jc.potentiometer.rad_per_volt;
    }
    p.motor_key = "motor.stations." + station + "." + mechanism + ".theta" + std::to_string(joint);
  } else {
    if (ms) p.motor = ms->defaults;
    if (cs) {
      p.volts_at_zero = cs->potentiometer.volts_at_zero;
      p.rad_per_volt = cs->potentiometer.rad_per_volt;
    }
  }
  if (cs) {
    p.adc_bits = cs->adc_bits;
    p.adc_lo_v = cs->adc_range_v[0];
    p.adc_hi_v = cs->adc_range_v[1];
  }
  p.load_inertia = load_inertia;
  return p;
}

}  // namespace fivebar::identify
