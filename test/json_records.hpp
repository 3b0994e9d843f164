#pragma once
// Records of the --json documents (docs/conventions.md "JSON documents"): stations and mechanisms
// are lists of records named by "station" and "mechanism", never objects keyed by name. These find
// one by its name, so a test reads `mechanism(station(doc, "index"), "lower")["margin_mm"]`.

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace fivebar::testing {

/// The record of `list` whose `key` is `name`; a test failure and a null value when there is none.
template <class J>
const J& record(const J& list, const std::string& key, const std::string& name) {
  static const J kNull;
  if (list.is_array()) {
    for (const J& r : list)
      if (r.is_object() && r.contains(key) && r[key] == name) return r;
  }
  ADD_FAILURE() << "no record with " << key << " = " << name << " in " << list.dump().substr(0, 300);
  return kNull;
}

/// The names of a list of records, in order.
template <class J>
std::vector<std::string> record_names(const J& list, const std::string& key) {
  std::vector<std::string> out;
  for (const J& r : list) out.push_back(r.at(key).template get<std::string>());
  return out;
}

/// doc["stations"]'s record of station `name`.
template <class J>
const J& station(const J& doc, const std::string& name) {
  return record(doc["stations"], "station", name);
}

/// station["mechanisms"]'s record of mechanism `name`.
template <class J>
const J& mechanism(const J& station_record, const std::string& name) {
  return record(station_record["mechanisms"], "mechanism", name);
}

}  // namespace fivebar::testing
