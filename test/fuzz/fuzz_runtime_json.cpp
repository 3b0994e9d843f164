// libFuzzer target: the runtime's JSON configuration reader (fivebar/runtime/json_config.hpp, the
// file `fivebar export --format json` writes and the device loads) on arbitrary bytes, then one
// controller built from what it accepted and driven through a few cycles.
//
// Property: parse_config_json() returns, or throws ConfigError whose message starts with the
// origin ("fuzz.json") and is bounded; a configuration it returns builds a Controller (it was
// validated: the constructor must not refuse it), and every cycle, on readings at the middle of the
// potentiometer's range, at a rail, non-finite, or on radians, leaves each duty finite and within
// [-1, 1]. Any other exception, a crash, a sanitizer report, a hang (-timeout) or a memory blow-up
// (-rss_limit_mb) is a finding.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "fivebar/runtime/config.hpp"
#include "fivebar/runtime/controller.hpp"
#include "fivebar/runtime/json_config.hpp"

namespace {

[[noreturn]] void finding(const std::string& what) {
  std::fprintf(stderr, "fuzz_runtime_json: %s\n", what.c_str());
  std::abort();
}

const std::string kOrigin = "fuzz.json";

void drive(fivebar::runtime::Controller& c) {
  namespace rt = fivebar::runtime;
  const std::size_t n = c.joint_count();
  std::vector<double> readings(n), targets(n);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int step = 0; step < 6; ++step) {
    rt::Reading kind = rt::Reading::volts;
    for (std::size_t j = 0; j < n; ++j) {
      switch (step) {
        case 0: readings[j] = 0.0; break;
        case 1: readings[j] = 2.5; break;
        case 2: readings[j] = 1e308; break;
        case 3: readings[j] = nan; break;
        case 4: readings[j] = 0.3 * static_cast<double>(j % 3); kind = rt::Reading::radians; break;
        default: readings[j] = -1e-320; break;
      }
      targets[j] = step == 3 ? nan : 0.006 + 0.001 * static_cast<double>(j % 2);
    }
    c.cycle(readings.data(), kind, targets.data());
    const double* d = c.duties();
    for (std::size_t j = 0; j < n; ++j) {
      if (!std::isfinite(d[j]) || d[j] < -1.0 || d[j] > 1.0) finding("a duty outside [-1, 1] or not finite at step " + std::to_string(step));
    }
  }
  c.cycle(nullptr, rt::Reading::volts, nullptr);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  fivebar::runtime::Config config;
  try {
    config = fivebar::runtime::parse_config_json(text, kOrigin);
  } catch (const fivebar::runtime::ConfigError& e) {
    const std::string_view what(e.what());
    if (what.rfind(kOrigin, 0) != 0) finding("a ConfigError without its origin: " + std::string(what.substr(0, 200)));
    if (what.size() > 4096) finding("a ConfigError of " + std::to_string(what.size()) + " bytes");
    return 0;
  } catch (const std::exception& e) {
    finding(std::string("an exception other than ConfigError: ") + e.what());
  }
  try {
    fivebar::runtime::Controller c(std::move(config));
    drive(c);
  } catch (const std::exception& e) {
    finding(std::string("a configuration the reader accepted is refused by the controller: ") + e.what());
  }
  return 0;
}
