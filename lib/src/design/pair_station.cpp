#include "fivebar/design/pair_station.hpp"

#include "fivebar/error.hpp"

namespace fivebar {

const Station& pair_station(const Design& design, const std::string& station) {
  std::string names;
  for (const Station& st : design.stations) names += (names.empty() ? "" : ", ") + st.name;
  const Station* s = nullptr;
  if (station.empty()) {
    if (design.stations.size() != 1) throw InputError("design '" + design.name + "' has stations " + names + ": choose one (station)");
    s = &design.stations.front();
  } else {
    s = design.station(station);
    if (s == nullptr) throw InputError("unknown station '" + station + "' in design '" + design.name + "' (it has: " + names + ")");
  }
  if (!s->lower || !s->upper) {
    throw InputError("station '" + s->name + "' has only the " + (s->lower ? "lower" : "upper") +
                     " mechanism: collision and patterns need both");
  }
  return *s;
}

const Geometry& require_geometry(const Design& design) {
  if (!design.get<Geometry>()) {
    throw InputError("design '" + design.name + "' has no geometry: section: link widths, pins and planes are "
                     "needed to check collisions (see designs/iros2022.yaml)");
  }
  return *design.get<Geometry>();
}

}  // namespace fivebar
