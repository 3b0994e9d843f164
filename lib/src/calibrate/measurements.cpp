// Bench measurement files (fivebar/calibrate/measurements.hpp).
#include "fivebar/calibrate/measurements.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string_view>

#include "fivebar/error.hpp"
#include "fivebar/sections/controller.hpp"

namespace fivebar::calibrate {

namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> cells(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const auto comma = line.find(',', start);
    out.push_back(trim(line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

std::string shown(std::string_view s) {
  std::string out;
  for (const char c : s.substr(0, 40)) out += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? '?' : c;
  return out;
}

}  // namespace

std::vector<Measurement> parse_measurements(const std::string& text, const std::string& origin, const Design& design) {
  static const std::vector<std::string> known{"station", "mechanism", "volts1", "volts2", "counts1",
                                              "counts2", "x_mm",      "y_mm",   "sigma_mm"};
  std::istringstream in(text);
  std::string line;
  int number = 0;
  std::map<std::string, std::size_t, std::less<>> column;
  std::vector<Measurement> out;
  const auto fail = [&](int at, const std::string& what) { throw InputError(origin + ":" + std::to_string(at) + ": " + what); };
  while (std::getline(in, line)) {
    ++number;
    const std::string_view view = trim(line);
    if (view.empty() || view.front() == '#') {
      if (number == 1 && view.empty()) fail(1, "the first line must be the header (station,mechanism,volts1,volts2,x_mm,y_mm[,sigma_mm])");
      continue;
    }
    const auto row = cells(view);
    if (column.empty()) {
      for (std::size_t i = 0; i < row.size(); ++i) {
        const std::string name(row[i]);
        bool ok = false;
        for (const auto& k : known) ok = ok || k == name;
        if (!ok) fail(number, "column " + std::to_string(i + 1) + " '" + shown(row[i]) + "': unknown column (known: station, mechanism, volts1, volts2 or counts1, counts2, x_mm, y_mm, sigma_mm)");
        if (column.count(name) != 0) fail(number, "column '" + name + "' appears twice");
        column[name] = i;
      }
      for (const char* need : {"station", "mechanism", "x_mm", "y_mm"}) {
        if (column.count(need) == 0) fail(number, "column '" + std::string(need) + "' is missing");
      }
      const bool volts = column.count("volts1") != 0 || column.count("volts2") != 0;
      const bool counts = column.count("counts1") != 0 || column.count("counts2") != 0;
      if (volts && counts) fail(number, "give volts1,volts2 or counts1,counts2, not both");
      for (const char* need : counts ? std::array{"counts1", "counts2"} : std::array{"volts1", "volts2"}) {
        if (column.count(need) == 0) fail(number, "column '" + std::string(need) + "' is missing");
      }
      continue;
    }
    if (row.size() != column.size()) {
      fail(number, std::to_string(row.size()) + " cells, the header has " + std::to_string(column.size()));
    }
    const auto cell = [&](const char* name) { return row[column.at(name)]; };
    const auto num = [&](const char* name, const char* unit) {
      const std::string_view c = cell(name);
      double v = 0.0;
      const auto r = std::from_chars(c.data(), c.data() + c.size(), v);
      if (c.empty() || r.ec != std::errc{} || r.ptr != c.data() + c.size() || !std::isfinite(v)) {
        fail(number, "column '" + std::string(name) + "' = '" + shown(c) + "': must be a finite number" +
                         (unit[0] != '\0' ? std::string(" (") + unit + ")" : std::string()));
      }
      return v;
    };
    Measurement m;
    m.line = number;
    m.station = std::string(cell("station"));
    m.mechanism = std::string(cell("mechanism"));
    const Station* s = design.station(m.station);
    if (s == nullptr) fail(number, "column 'station' = '" + shown(m.station) + "': the design has no such station");
    if (s->mechanism(m.mechanism) == nullptr) {
      fail(number, "column 'mechanism' = '" + shown(m.mechanism) + "': station " + m.station + " has no such mechanism (lower or upper)");
    }
    if (column.count("counts1") != 0) {
      const ControllerSettings* c = design.get<ControllerSettings>();
      if (c == nullptr) fail(number, "counts1,counts2 need the design's controller.adc (bits, range_v) to become volts");
      const double q = (c->adc_range_v[1] - c->adc_range_v[0]) / std::ldexp(1.0, c->adc_bits);
      const double full = std::ldexp(1.0, c->adc_bits);
      for (const char* name : {"counts1", "counts2"}) {
        const double k = num(name, "counts");
        if (k < 0.0 || k >= full || k != std::floor(k)) {
          fail(number, "column '" + std::string(name) + "' = '" + shown(cell(name)) + "': must be a whole number in [0, 2^" +
                           std::to_string(c->adc_bits) + ")");
        }
        (name[6] == '1' ? m.volts1 : m.volts2) = c->adc_range_v[0] + k * q;
      }
    } else {
      m.volts1 = num("volts1", "V");
      m.volts2 = num("volts2", "V");
    }
    m.point = Vec2(num("x_mm", "mm"), num("y_mm", "mm"));
    if (column.count("sigma_mm") != 0) {
      m.sigma_mm = num("sigma_mm", "mm");
      if (!(m.sigma_mm > 0.0)) fail(number, "column 'sigma_mm' = '" + shown(cell("sigma_mm")) + "': must be > 0 mm");
    }
    out.push_back(std::move(m));
  }
  if (column.empty()) throw InputError(origin + ": empty file: expected the header station,mechanism,volts1,volts2,x_mm,y_mm");
  if (out.empty()) throw InputError(origin + ": no measurements after the header");
  return out;
}

std::vector<Measurement> read_measurements(const std::filesystem::path& path, const Design& design) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.generic_string() + ": cannot read the measurement file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse_measurements(text.str(), path.generic_string(), design);
}

}  // namespace fivebar::calibrate
