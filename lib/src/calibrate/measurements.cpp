// Bench measurement files (fivebar/calibrate/measurements.hpp).
#include "fivebar/calibrate/measurements.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string_view>
#include <tuple>

#include "fivebar/csv_reader.hpp"
#include "fivebar/error.hpp"
#include "fivebar/format.hpp"
#include "fivebar/sections/controller.hpp"

namespace fivebar::calibrate {

std::vector<Measurement> parse_measurements(const std::string& text, const std::string& origin, const Design& design) {
  std::istringstream in(text);
  // The bench's one reader (fivebar/csv_reader.hpp): bounded, strict cells, duplicates refused.
  csv::Reader reader(in, origin, kMeasurementLimits);
  const auto fail = [&](std::size_t at, const std::string& what) { throw InputError(origin + ":" + std::to_string(at) + ": " + what); };
  static const std::vector<std::string> known{"station", "mechanism", "volts1", "volts2", "counts1",
                                              "counts2", "x_mm",      "y_mm",   "sigma_mm"};
  const std::size_t header_line = reader.header_line();
  for (std::size_t i = 0; i < reader.header().size(); ++i) {
    if (std::find(known.begin(), known.end(), reader.header()[i]) == known.end()) {
      fail(header_line, "column " + std::to_string(i + 1) + " '" + csv::shown(reader.header()[i]) +
                            "': unknown column (known: station, mechanism, volts1, volts2 or counts1, counts2, x_mm, y_mm, sigma_mm)");
    }
  }
  const auto has = [&](const char* name) { return reader.column(name) >= 0; };
  for (const char* need : {"station", "mechanism", "x_mm", "y_mm"}) reader.require(need);
  const bool counts = has("counts1") || has("counts2");
  if (counts && (has("volts1") || has("volts2"))) fail(header_line, "give volts1,volts2 or counts1,counts2, not both");
  for (const char* need : counts ? std::array{"counts1", "counts2"} : std::array{"volts1", "volts2"}) reader.require(need);
  const ControllerSettings* c = design.get<ControllerSettings>();
  if (counts && c == nullptr) fail(header_line, "counts1,counts2 need the design's controller.adc (bits, range_v) to become volts");
  std::vector<Measurement> out;
  std::map<std::tuple<std::string, std::string, double, double, double, double>, int> seen;  // -> line
  while (reader.next()) {
    const auto col = [&](const char* name) { return reader.require(name); };
    Measurement m;
    m.line = static_cast<int>(reader.line());
    m.station = reader.cell(col("station"));
    m.mechanism = reader.cell(col("mechanism"));
    const Station* s = design.station(m.station);
    if (s == nullptr) throw InputError(reader.at(col("station")) + "the design has no such station");
    const Mechanism* mech = s->mechanism(m.mechanism);
    if (mech == nullptr) throw InputError(reader.at(col("mechanism")) + "station " + csv::shown(m.station) + " has no such mechanism (lower or upper)");
    if (counts) {
      const double q = (c->adc_range_v[1] - c->adc_range_v[0]) / std::ldexp(1.0, c->adc_bits);
      const double full = std::ldexp(1.0, c->adc_bits);
      for (const char* name : {"counts1", "counts2"}) {
        const double k = reader.number(col(name), csv::kMaxBenchValue, "counts");
        if (k < 0.0 || k >= full || k != std::floor(k)) {
          throw InputError(reader.at(col(name)) + "must be a whole number in [0, 2^" + std::to_string(c->adc_bits) + ")");
        }
        (name[6] == '1' ? m.volts1 : m.volts2) = c->adc_range_v[0] + k * q;
      }
    } else {
      for (const char* name : {"volts1", "volts2"}) {
        const double v = reader.number(col(name), csv::kMaxBenchValue, "V");
        // A reading outside the converter's input range is a fault, as in the runtime.
        if (c != nullptr && (v < c->adc_range_v[0] || v > c->adc_range_v[1])) {
          throw InputError(reader.at(col(name)) + "outside controller.adc.range_v [" + format::shortest(c->adc_range_v[0]) + ", " +
                           format::shortest(c->adc_range_v[1]) + "] V: not a reading of the converter");
        }
        (name[5] == '1' ? m.volts1 : m.volts2) = v;
      }
    }
    // No instrument frame is a thousand linkages away from the mechanism: beyond that the fit would
    // only lose digits (docs/bench-files.md).
    const double reach = kMaxPointScale * mech->length_scale();
    const double x = reader.number(col("x_mm"), std::min(reach, csv::kMaxBenchValue), "mm; 1000 times the mechanism's largest length");
    const double y = reader.number(col("y_mm"), std::min(reach, csv::kMaxBenchValue), "mm; 1000 times the mechanism's largest length");
    m.point = Vec2(x, y);
    if (has("sigma_mm")) {
      m.sigma_mm = reader.number(col("sigma_mm"), reach, "mm");
      if (!(m.sigma_mm > 0.0)) throw InputError(reader.at(col("sigma_mm")) + "must be > 0 mm");
    }
    // An exact copy of an earlier row (readings and measured point to every digit) is no second
    // measurement: an instrument's noise never repeats all digits, and copies would shrink the
    // residual sigma towards 0 (12 copies of one row gave +- 1.9e-15 mm).
    const auto key = std::make_tuple(m.station, m.mechanism, m.volts1, m.volts2, m.point.x(), m.point.y());
    if (const auto [it, added] = seen.emplace(key, m.line); !added) {
      throw InputError(reader.where() + "a copy of line " + std::to_string(it->second) +
                       " (the same readings and point to every digit): a copy is no second measurement");
    }
    out.push_back(std::move(m));
  }
  if (out.empty()) throw InputError(origin + ": no measurements after the header");
  return out;
}

std::vector<Measurement> read_measurements(const std::filesystem::path& path, const Design& design) {
  const std::string text = csv::read_bounded(path, kMeasurementLimits.max_bytes, "measurement file");
  return parse_measurements(text, path.generic_string(), design);
}

}  // namespace fivebar::calibrate
