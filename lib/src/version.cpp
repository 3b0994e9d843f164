#include "fivebar/version.hpp"

#ifndef FIVEBAR_VERSION
#error "FIVEBAR_VERSION must be defined by the build (lib/CMakeLists.txt)"
#endif

namespace fivebar {

std::string_view version() noexcept { return FIVEBAR_VERSION; }

}  // namespace fivebar
