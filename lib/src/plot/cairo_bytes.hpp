#pragma once
// Cairo output into memory, shared by the plot files (private to lib/src/plot/): the write callback
// that collects SVG or PNG bytes in a std::string, and the status check that turns a cairo error
// into an exception naming what was being drawn.

#include <cairo.h>

#include <stdexcept>
#include <string>

namespace fivebar::plot_detail {

/// cairo_write_func_t: appends the bytes to the std::string passed as `closure`.
inline cairo_status_t append(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

/// Throws std::runtime_error("cairo: <what>: <cairo's message>") unless `status` is success.
inline void check(cairo_status_t status, const char* what) {
  if (status != CAIRO_STATUS_SUCCESS) {
    throw std::runtime_error(std::string("cairo: ") + what + ": " + cairo_status_to_string(status));
  }
}

}  // namespace fivebar::plot_detail
