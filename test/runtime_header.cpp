// The runtime configured from the exported C++ header (fivebar/runtime/header_config.hpp), compiled
// as strict C++17 against the header `fivebar export --format header` wrote for
// designs/iros2022.yaml at build time; test_runtime compares it with the JSON's.

#include "fivebar/runtime/header_config.hpp"
#include "iros2022_controller.hpp"

namespace fivebar_test {

fivebar::runtime::Config runtime_config_from_header() {
  namespace fc = fivebar_controller;
  return FIVEBAR_RUNTIME_CONFIG(fc, FIVEBAR_RUNTIME_STATION(fc, index, lower, upper),
                                FIVEBAR_RUNTIME_STATION(fc, thumb, lower, upper));
}

}  // namespace fivebar_test
