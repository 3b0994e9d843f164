// Potentiometer offsets from readings at the hard stops (fivebar/calibrate/hard_stops.hpp).
#include "fivebar/calibrate/hard_stops.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>
#include <tuple>
#include <vector>

#include "fivebar/calibrate/measurements.hpp"
#include "fivebar/csv_reader.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/device/joint_limits.hpp"
#include "fivebar/sections/controller.hpp"

namespace fivebar::calibrate {

CalibrationResult hard_stop_calibration(const Design& design, const std::string& text, const std::string& origin) {
  std::istringstream in(text);
  // The bench's one reader (fivebar/csv_reader.hpp, docs/bench-files.md).
  csv::Reader reader(in, origin, kMeasurementLimits);
  if (reader.header() != std::vector<std::string>{"station", "mechanism", "joint", "stop", "volts"}) {
    throw InputError(reader.where() + "the header must be station,mechanism,joint,stop,volts");
  }
  const ControllerSettings* adc = design.get<ControllerSettings>();
  // (station, mechanism, joint, stop) -> readings, and the line of the first one (for messages)
  std::map<std::tuple<std::string, std::string, int, std::string>, std::vector<double>> readings;
  std::map<std::tuple<std::string, std::string, int>, std::size_t> first_line;
  while (reader.next()) {
    const std::vector<std::string>& cells = reader.cells();
    const Station* s = design.station(cells[0]);
    if (s == nullptr) throw InputError(reader.at(0) + "the design has no such station");
    if (s->mechanism(cells[1]) == nullptr) throw InputError(reader.at(1) + "no such mechanism in station " + csv::shown(cells[0]));
    if (cells[2] != "1" && cells[2] != "2") throw InputError(reader.at(2) + "must be 1 or 2");
    if (cells[3] != "lo" && cells[3] != "hi") throw InputError(reader.at(3) + "must be lo or hi");
    const double v = reader.number(4, csv::kMaxBenchValue, "V");
    // A reading outside the converter's input range is a fault, as in the runtime.
    if (adc != nullptr && (v < adc->adc_range_v[0] || v > adc->adc_range_v[1])) {
      throw InputError(reader.at(4) + "outside controller.adc.range_v [" + format::shortest(adc->adc_range_v[0]) + ", " +
                       format::shortest(adc->adc_range_v[1]) + "] V: not a reading of the converter");
    }
    readings[{cells[0], cells[1], cells[2][0] - '0', cells[3]}].push_back(v);
    first_line.emplace(std::tuple{cells[0], cells[1], cells[2][0] - '0'}, reader.line());
  }
  if (readings.empty()) throw InputError(origin + ": no readings (header station,mechanism,joint,stop,volts)");
  CalibrationResult out;
  const ControllerSettings* c = design.get<ControllerSettings>();
  std::vector<std::string> single;  // stops read once: no spread, no sigma
  std::map<std::tuple<std::string, std::string, int>, bool> done;
  for (const auto& [key, values] : readings) {
    const auto& [station, mechanism, joint, stop] = key;
    if (done.count({station, mechanism, joint}) != 0) continue;
    done[{station, mechanism, joint}] = true;
    if (out.station.empty()) out.station = station;
    const std::string at = origin + ":" + std::to_string(first_line.at({station, mechanism, joint})) + ": ";
    if (station != out.station) throw InputError(at + "readings of stations " + out.station + " and " + station + ": one station per file");
    const Station& st = *design.station(station);
    const Mechanism& m = *st.mechanism(mechanism);
    const UsableRange range = usable_ranges(design, st, m)[static_cast<std::size_t>(joint - 1)];
    const Potentiometer pot = c ? c->joint(station, mechanism, joint).potentiometer : Potentiometer{};
    struct Stop {
      bool have = false;
      double theta = 0.0, mean = 0.0, sigma = 0.0;
    };
    std::array<Stop, 2> stops;
    for (int e = 0; e < 2; ++e) {
      const std::string which = e == 0 ? "lo" : "hi";
      const auto it = readings.find({station, mechanism, joint, which});
      if (it == readings.end()) continue;
      const std::string& by = e == 0 ? range.lo_by : range.hi_by;
      if (by.rfind("hard stop", 0) != 0) {
        throw InputError(at + "the " + which + " end of " + range.joint + " is set by " + (by.empty() ? std::string("nothing") : by) +
                         ", not a hard stop: its angle is not known from the geometry");
      }
      Stop& s = stops[static_cast<std::size_t>(e)];
      s.have = true;
      s.theta = e == 0 ? range.lo : range.hi;
      for (double v : it->second) s.mean += v;
      s.mean /= static_cast<double>(it->second.size());
      double ss = 0.0;
      for (double v : it->second) ss += (v - s.mean) * (v - s.mean);
      const auto n = static_cast<double>(it->second.size());
      s.sigma = n > 1 ? std::sqrt(ss / (n - 1) / n) : 0.0;
      if (n < 2) single.push_back(station + "/" + mechanism + "/theta" + std::to_string(joint) + " " + which);
    }
    const std::string base = "controller.stations." + station + "." + mechanism + ".theta" + std::to_string(joint) + ".potentiometer.";
    Parameter v0, k;
    v0.mechanism = k.mechanism = mechanism;
    v0.name = "theta" + std::to_string(joint) + ".volts_at_zero";
    k.name = "theta" + std::to_string(joint) + ".rad_per_volt";
    v0.key = base + "volts_at_zero";
    k.key = base + "rad_per_volt";
    v0.unit = "V";
    k.unit = "rad/V";
    v0.design = pot.volts_at_zero;
    k.design = pot.rad_per_volt;
    v0.requested = k.requested = true;
    if (stops[0].have && stops[1].have) {
      const double dv = stops[1].mean - stops[0].mean;
      if (std::abs(dv) < 1e-9) throw InputError(at + "the lo and hi readings of " + range.joint + " are equal: no sensitivity");
      k.value = (stops[1].theta - stops[0].theta) / dv;
      k.sigma = std::abs(k.value / dv) * std::hypot(stops[0].sigma, stops[1].sigma);
      k.identified = true;
      v0.value = stops[0].mean - stops[0].theta / k.value;
      // V0 = V_lo - theta_lo (V_hi - V_lo) / (theta_hi - theta_lo): linear in both means.
      const double a = stops[0].theta / (stops[1].theta - stops[0].theta);
      v0.sigma = std::hypot((1.0 + a) * stops[0].sigma, a * stops[1].sigma);
    } else {
      const Stop& s = stops[0].have ? stops[0] : stops[1];
      k.value = pot.rad_per_volt;
      k.note = "one stop only: held at the design value";
      v0.value = s.mean - s.theta / k.value;
      // The held slope is not exact: its prior (prior_sigma(), 1 % of k) enters V0 = V - theta/k
      // through dV0/dk = theta / k^2.
      const double sk = prior_sigma(9, MechanismVector::Constant(k.value));
      v0.sigma = std::hypot(s.sigma, s.theta / (k.value * k.value) * sk);
    }
    v0.identified = true;
    out.parameters.push_back(v0);
    out.parameters.push_back(k);
    if (std::find(out.mechanisms.begin(), out.mechanisms.end(), mechanism) == out.mechanisms.end()) out.mechanisms.push_back(mechanism);
  }
  // The quality gate (fivebar/provenance/gate.hpp): a closed form; the readings must repeat (one
  // reading has no spread and so no sigma); each value's sigma within its prior.
  gate::GateInput gi;
  gi.fit = "fivebar calibrate --hard-stops";
  gi.solver = {true, "closed form", 0};
  gate::ResidualTest repeat;
  repeat.name = "repeated readings";
  repeat.passed = single.empty();
  repeat.statement = single.empty() ? "repeated readings: every stop read at least twice (the sigma is the spread of the mean)"
                                    : "repeated readings: " + format::join(single) +
                                          " read once: no spread to give a sigma (repeat each reading)";
  gi.tests.push_back(repeat);
  for (const Parameter& p : out.parameters) {
    if (!p.identified) continue;
    const bool volts = p.unit == "V";
    MechanismVector q = MechanismVector::Constant(volts ? out.parameters[&p - out.parameters.data() + 1].value : p.value);
    gi.parameters.push_back({p.key, p.mechanism + "." + p.name, p.unit, p.value, p.sigma, prior_sigma(volts ? 8 : 9, q), true, ""});
  }
  out.gate = gate::evaluate(gi);
  return out;
}

}  // namespace fivebar::calibrate
