// Potentiometer offsets from readings at the hard stops (fivebar/calibrate/hard_stops.hpp).
#include "fivebar/calibrate/hard_stops.hpp"

#include <charconv>
#include <cmath>
#include <map>
#include <sstream>
#include <tuple>
#include <vector>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/export/joint_limits.hpp"
#include "fivebar/sections/controller.hpp"

namespace fivebar::calibrate {

namespace {
std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ')) s.pop_back();
  while (!s.empty() && s.front() == ' ') s.erase(s.begin());
  return s;
}
}  // namespace

CalibrationResult hard_stop_calibration(const Design& design, const std::string& text, const std::string& origin) {
  std::istringstream in(text);
  std::string line;
  int number = 0;
  const auto fail = [&](const std::string& what) { throw InputError(origin + ":" + std::to_string(number) + ": " + what); };
  // (station, mechanism, joint, stop) -> readings
  std::map<std::tuple<std::string, std::string, int, std::string>, std::vector<double>> readings;
  std::vector<std::string> header;
  while (std::getline(in, line)) {
    ++number;
    line = trim(line);
    if (line.empty() || line.front() == '#') continue;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cells.push_back(trim(c));
    if (header.empty()) {
      if (cells != std::vector<std::string>{"station", "mechanism", "joint", "stop", "volts"}) {
        fail("the header must be station,mechanism,joint,stop,volts");
      }
      header = cells;
      continue;
    }
    if (cells.size() != 5) fail(std::to_string(cells.size()) + " cells, the header has 5");
    const Station* s = design.station(cells[0]);
    if (s == nullptr) fail("column 'station' = '" + cells[0] + "': the design has no such station");
    if (s->mechanism(cells[1]) == nullptr) fail("column 'mechanism' = '" + cells[1] + "': no such mechanism in station " + cells[0]);
    if (cells[2] != "1" && cells[2] != "2") fail("column 'joint' = '" + cells[2] + "': must be 1 or 2");
    if (cells[3] != "lo" && cells[3] != "hi") fail("column 'stop' = '" + cells[3] + "': must be lo or hi");
    double v = 0.0;
    const auto r = std::from_chars(cells[4].data(), cells[4].data() + cells[4].size(), v);
    if (cells[4].empty() || r.ec != std::errc{} || r.ptr != cells[4].data() + cells[4].size() || !std::isfinite(v)) {
      fail("column 'volts' = '" + cells[4] + "': must be a finite number (V)");
    }
    readings[{cells[0], cells[1], cells[2][0] - '0', cells[3]}].push_back(v);
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
    if (station != out.station) throw InputError(origin + ": readings of stations " + out.station + " and " + station + ": one station per file");
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
        throw InputError(origin + ": the " + which + " end of " + range.joint + " is set by " + (by.empty() ? std::string("nothing") : by) +
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
      if (std::abs(dv) < 1e-9) throw InputError(origin + ": the lo and hi readings of " + range.joint + " are equal: no sensitivity");
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
