#pragma once
/// One resource rule for every study (docs/reliability.md "Resource bounds"): a run estimates its
/// wall time, memory and disk from the request before it starts, states the estimate, and is
/// refused beyond the documented bounds unless confirmed (the command's `--yes`).

#include <string>
#include <string_view>

namespace fivebar {

/// What a run will cost, estimated from its request before it starts.
struct ResourceEstimate {
  std::string what;           ///< "tolerance.samples = 100000000 over 2 mechanisms"
  double seconds = 0.0;       ///< wall time
  double memory_bytes = 0.0;  ///< peak memory held for the run's data
  double disk_bytes = 0.0;    ///< files written
  /// "about 8.0 min, 9.6 GB of memory and 0 B of files".
  std::string text() const;
};

/// Beyond these a run starts only when confirmed.
inline constexpr double kConfirmSeconds = 3600.0;      ///< one hour
inline constexpr double kConfirmMemoryBytes = 2e9;     ///< two gigabytes
inline constexpr double kConfirmDiskBytes = 1e9;       ///< one gigabyte of files

/// True when the estimate is within every bound.
bool within_bounds(const ResourceEstimate& e);
/// Throws InputError "<what> is large: <estimate> (bounds: ...); <how_to_confirm>" when the
/// estimate exceeds a bound and the run is not confirmed.
void check_budget(const ResourceEstimate& e, bool confirmed, std::string_view how_to_confirm);

/// Bytes as "512 B", "3.2 kB", "9.6 GB" (decimal units).
std::string bytes_text(double bytes);

}  // namespace fivebar
