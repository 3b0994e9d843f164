// One resource rule for every study (fivebar/resources/budget.hpp).
#include "fivebar/resources/budget.hpp"

#include <cmath>

#include "fivebar/error.hpp"
#include "fivebar/format.hpp"

namespace fivebar {

std::string bytes_text(double bytes) {
  if (!(bytes >= 0.0) || !std::isfinite(bytes)) return "an unbounded amount";
  static const char* const units[] = {"B", "kB", "MB", "GB", "TB", "PB", "EB"};
  int u = 0;
  while (bytes >= 1000.0 && u < 6) bytes /= 1000.0, ++u;
  return (u == 0 ? format::fixed(bytes, 0) : format::fixed(bytes, 1)) + " " + units[u];
}

namespace {

std::string time_text(double s) {
  if (!(s >= 0.0) || !std::isfinite(s)) return "an unbounded time";
  if (s >= 3600.0) return format::fixed(s / 3600.0, 1) + " h";
  if (s >= 60.0) return format::fixed(s / 60.0, 1) + " min";
  return format::fixed(s, 1) + " s";
}

}  // namespace

std::string ResourceEstimate::text() const {
  std::string parts;
  const auto add = [&](const std::string& part) { parts += (parts.empty() ? "" : ", ") + part; };
  if (seconds > 0.0 || !std::isfinite(seconds)) add(time_text(seconds));
  if (memory_bytes > 0.0 || !std::isfinite(memory_bytes)) add(bytes_text(memory_bytes) + " of memory");
  if (disk_bytes > 0.0 || !std::isfinite(disk_bytes)) add(bytes_text(disk_bytes) + " of files");
  return "about " + (parts.empty() ? std::string("nothing") : parts);
}

bool within_bounds(const ResourceEstimate& e) {
  return e.seconds <= kConfirmSeconds && e.memory_bytes <= kConfirmMemoryBytes && e.disk_bytes <= kConfirmDiskBytes;
}

void check_budget(const ResourceEstimate& e, bool confirmed, std::string_view how_to_confirm) {
  if (confirmed || within_bounds(e)) return;
  throw InputError(e.what + " is large: " + e.text() + " (the bounds: " + time_text(kConfirmSeconds) + ", " +
                   bytes_text(kConfirmMemoryBytes) + " of memory, " + bytes_text(kConfirmDiskBytes) + " of files); " +
                   std::string(how_to_confirm));
}

}  // namespace fivebar
