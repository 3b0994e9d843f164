#pragma once
/// Reads the JSON file `fivebar export` writes (fivebar/export/export.hpp) into a runtime Config:
/// a small self-contained JSON reader (C++17, standard library), nothing else. Allocates; call it
/// at initialisation only.

#include <string>
#include <string_view>

#include "fivebar/runtime/config.hpp"

namespace fivebar::runtime {

/// Parses and validates. ConfigError "ORIGIN: KEY: problem" for text that is not JSON
/// ("ORIGIN:LINE: ..."), a missing key, a wrong type, a non-finite or out-of-range number, a joint
/// without gains or potentiometer calibration.
Config parse_config_json(std::string_view text, const std::string& origin = "config");
/// Reads `path` and parses it; ConfigError also when the file cannot be read.
Config load_config_json(const std::string& path);

}  // namespace fivebar::runtime
