// libFuzzer target: the bench's one CSV reader (fivebar/csv_reader.hpp, docs/bench-files.md) on
// arbitrary bytes, alone and under its two strictest users: the identification/device log reader
// and the calibration measurements.
//
// Property: every reader returns, or throws InputError whose message starts with "ORIGIN:" and is
// bounded; a number it returns is finite and within the bound it was asked for; a row has as many
// cells as the header. Any other exception, a crash, a sanitizer report, a hang (-timeout) or a
// memory blow-up (-rss_limit_mb) is a finding. The first byte chooses the reader.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <sstream>
#include <string>
#include <string_view>

#include "fivebar/calibrate/measurements.hpp"
#include "fivebar/csv_reader.hpp"
#include "fivebar/design.hpp"
#include "fivebar/error.hpp"
#include "fivebar/identify/log.hpp"

namespace {

[[noreturn]] void finding(const std::string& what) {
  std::fprintf(stderr, "fuzz_bench_csv: %s\n", what.c_str());
  std::abort();
}

const std::string kOrigin = "fuzz.csv";

// A station with one mechanism (no controller: volts bounded by csv::kMaxBenchValue only).
const fivebar::Design& design() {
  static const fivebar::Design d = fivebar::load_design_from_string(
      "name: fuzz\nstations:\n  index:\n    target: {center: [6.25, 15.5], axes: [15, 12], angle: 0}\n    mechanisms:\n"
      "      lower:\n        bases: [[0, 0], [12.5, 0]]\n        links: [9, 9, 15, 15]\n        working_mode: \"-+\"\n"
      "        assembly_mode: \"+\"\n",
      "fuzz.yaml");
  return d;
}

void raw(const std::string& text) {
  std::istringstream in(text);
  fivebar::csv::Reader r(in, kOrigin, fivebar::csv::Limits{256, 1u << 16, 1000});
  while (r.next()) {
    if (r.cells().size() != r.header().size()) finding("a row with another cell count than the header");
    for (std::size_t c = 0; c < r.cells().size(); ++c) {
      try {
        const double v = r.number(c, 1e6);
        if (!std::isfinite(v) || std::abs(v) > 1e6) finding("number() returned " + std::to_string(v));
      } catch (const fivebar::InputError& e) {
        if (!std::string_view(e.what()).starts_with(kOrigin + ":")) finding(std::string("number(): ") + e.what());
      }
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    switch (data[0] % 3) {
      case 0:
        raw(text);
        break;
      case 1: {
        std::istringstream in(text);
        const auto log = fivebar::identify::read_identify_log(in, kOrigin);
        for (double t : log.time)
          if (!std::isfinite(t)) finding("a non-finite time");
        break;
      }
      default: {
        for (const auto& m : fivebar::calibrate::parse_measurements(text, kOrigin, design())) {
          if (!std::isfinite(m.volts1) || !std::isfinite(m.volts2) || !std::isfinite(m.point.x()) || !std::isfinite(m.point.y())) {
            finding("a non-finite measurement");
          }
        }
      }
    }
  } catch (const fivebar::InputError& e) {
    const std::string_view message = e.what();
    if (!message.starts_with(kOrigin + ":")) finding("InputError without the file name: " + std::string(message));
    if (message.size() > 16384) finding("InputError message of " + std::to_string(message.size()) + " bytes");
  } catch (const std::exception& e) {
    finding(std::string("exception other than InputError: ") + e.what());
  }
  return 0;
}
