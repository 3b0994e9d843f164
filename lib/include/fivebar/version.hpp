#pragma once
/// The library's version, as set by the top-level CMake project (MAJOR.MINOR.PATCH).

#include <string_view>

namespace fivebar {

/// Version string of the library the program is linked against, e.g. "0.1.0".
std::string_view version() noexcept;

}  // namespace fivebar
