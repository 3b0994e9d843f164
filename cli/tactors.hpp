#pragma once
// Shared by `fivebar collision` and `fivebar pattern`: the station with both tactors, the
// geometry they need and where their files go.

#include <filesystem>
#include <string>

#include "common.hpp"
#include "fivebar/error.hpp"
#include "fivebar/io.hpp"

namespace fivebar::cli {

/// The --station choice (empty: the only station), which must have both mechanisms; InputError
/// otherwise, naming what is missing.
inline const Station& select_pair_station(const Design& design, const std::string& station) {
  std::string names;
  for (const Station& st : design.stations) names += (names.empty() ? "" : ", ") + st.name;
  const Station* s = nullptr;
  if (station.empty()) {
    if (design.stations.size() != 1) {
      throw InputError("design '" + design.name + "' has stations " + names + ": choose one with --station");
    }
    s = &design.stations.front();
  } else {
    s = design.station(station);
    if (s == nullptr) {
      throw InputError("unknown station '" + station + "' in design '" + design.name + "' (it has: " + names + ")");
    }
  }
  if (!s->lower || !s->upper) {
    throw InputError("station '" + s->name + "' has only the " + (s->lower ? "lower" : "upper") +
                     " mechanism: collision and patterns need both");
  }
  return *s;
}

/// The design's geometry; InputError when the design has none.
inline const Geometry& require_geometry(const Design& design) {
  if (!design.get<Geometry>()) {
    throw InputError("design '" + design.name + "' has no geometry: section: link widths, pins and planes are "
                     "needed to check collisions (see designs/iros2022.yaml)");
  }
  return *design.get<Geometry>();
}

/// --out, or outputs/<design name>/<sub> by default; created.
inline std::filesystem::path output_dir(const Design& design, const std::string& out, const std::string& sub) {
  const std::filesystem::path dir = command_output_dir(out, design.name, sub);
  make_directories(dir);
  return dir;
}

}  // namespace fivebar::cli
