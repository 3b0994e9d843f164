#pragma once
// Shared by `fivebar collision` and `fivebar pattern`: the station with both tactors, the
// geometry they need and where their files go.

#include <filesystem>
#include <string>

#include "common.hpp"
#include "fivebar/error.hpp"
#include "fivebar/design/pair_station.hpp"
#include "fivebar/io.hpp"

namespace fivebar::cli {

/// The --station choice (empty: the only station), which must have both mechanisms
/// (fivebar/design/pair_station.hpp); InputError otherwise, naming what is missing.
inline const Station& select_pair_station(const Design& design, const std::string& station) {
  if (station.empty() && design.stations.size() > 1) {
    std::string names;
    for (const Station& st : design.stations) names += (names.empty() ? "" : ", ") + st.name;
    throw InputError("design '" + design.name + "' has stations " + names + ": choose one with --station");
  }
  return pair_station(design, station);
}

/// --out, or outputs/<design name>/<sub> by default; created.
inline std::filesystem::path output_dir(const Design& design, const std::string& out, const std::string& sub) {
  const std::filesystem::path dir = command_output_dir(out, design.name, sub);
  make_directories(dir);
  return dir;
}

}  // namespace fivebar::cli
